//! No allocation on the data path once a transfer has started: response
//! buffers exist from `MailboxServer::new`, a transfer's buffer is reserved
//! at its initiate and reused by later transfers (DEVELOPERS.md, "sans-IO
//! contract").

mod support;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use drivebus_base::{Duration, Instant};
use drivebus_coe::{AlState, FileHandler, FoeError, FoeProgress, MailboxConfig, MailboxServer, NoFiles};
use drivebus_od::{NoHooks, ObjectDictionary};
use support::{mbx, pattern, test_od};

struct Counting;

thread_local! {
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards to the system allocator; only counts calls.
#[allow(unsafe_code)]
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        COUNT.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        COUNT.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

fn allocations() -> usize {
    COUNT.with(Cell::get)
}

/// A server, a device and a clock, driven with prepared buffers only.
struct Wire {
    s: MailboxServer,
    dev: (ObjectDictionary, NoHooks),
    now: Instant,
}

impl Wire {
    fn new() -> Wire {
        Wire {
            s: MailboxServer::new(MailboxConfig::default()).unwrap(),
            dev: (test_od(), NoHooks),
            now: Instant::ZERO,
        }
    }
    /// Hand in a request; return the first byte of the CoE command/opcode
    /// of the answer (no allocation here: the answer is only inspected).
    fn x<F: FileHandler>(&mut self, req: &[u8], files: &mut F) -> u8 {
        self.now += Duration::from_micros(100);
        self.s.handle_request(req, self.now, AlState::PreOp, &mut self.dev, files);
        self.s.next_response(self.now).map_or(0xFF, |m| m[8])
    }
}

/// Requests with counters 1..=7 in turn, built before measuring.
fn requests(bodies: &[Vec<u8>], t: u8) -> Vec<Vec<u8>> {
    bodies.iter().enumerate().map(|(k, b)| mbx(t, (k % 7) as u8 + 1, b)).collect()
}

fn sdo(cmd: u8, index: u16, data: &[u8]) -> Vec<u8> {
    let i = index.to_le_bytes();
    let mut b = vec![0x00, 0x20, cmd, i[0], i[1], 0];
    b.extend_from_slice(data);
    b.resize(b.len().max(10), 0);
    b
}

#[test]
fn sdo_transfers_do_not_allocate_once_warm() {
    let mut w = Wire::new();
    let data = pattern(300, 3);
    // Segmented download (112 + 119 + 69) then upload (112 + 119 + 69),
    // an expedited upload and download, a complete access, twice over.
    let mut bodies = vec![{
        let mut b = sdo(0x21, 0x2000, &300u32.to_le_bytes());
        b.extend_from_slice(&data[..112]);
        b
    }];
    bodies.push([&[0x00, 0x20, 0x00][..], &data[112..231]].concat());
    bodies.push([&[0x00, 0x20, 0x11][..], &data[231..]].concat());
    bodies.push(sdo(0x40, 0x2000, &[]));
    bodies.push(sdo(0x60, 0, &[]));
    bodies.push(sdo(0x70, 0, &[]));
    bodies.push(sdo(0x40, 0x1000, &[]));
    bodies.push(sdo(0x2B, 0x2003, &[9, 0]));
    bodies.push(sdo(0x50, 0x3000, &[]));
    bodies.push(sdo(0x60, 0, &[]));
    bodies.push(sdo(0x70, 0, &[]));
    let reqs = requests(&bodies, 3);
    let want = [0x60, 0x20, 0x30, 0x41, 0x00, 0x11, 0x43, 0x60, 0x51, 0x00, 0x11];
    // Warm-up: the transfer buffer grows to its largest size once.
    for (r, want) in reqs.iter().zip(want) {
        assert_eq!(w.x(r, &mut NoFiles), want);
    }
    let before = allocations();
    for _ in 0..3 {
        for (r, want) in reqs.iter().zip(want) {
            assert_eq!(w.x(r, &mut NoFiles), want);
        }
    }
    assert_eq!(allocations() - before, 0, "allocations on warm transfers");
    assert_eq!(w.dev.0.get(0x2000, 0).unwrap().bytes(), data);
}

#[test]
fn segments_and_fragments_never_allocate() {
    // Cold server: the initiate may reserve, what follows may not.
    let mut w = Wire::new();
    let reqs = requests(&[sdo(0x40, 0x2000, &[]), sdo(0x60, 0, &[]), sdo(0x70, 0, &[])], 3);
    assert_eq!(w.x(&reqs[0], &mut NoFiles), 0x41);
    let before = allocations();
    assert_eq!((w.x(&reqs[1], &mut NoFiles), w.x(&reqs[2], &mut NoFiles)), (0x00, 0x11));
    assert_eq!(allocations() - before, 0);
    // An OD list in fragments (32-byte mailbox), and an emergency.
    let mut s = MailboxServer::new(MailboxConfig::with_sizes(32, 32)).unwrap();
    let req = mbx(3, 4, &[0x00, 0x80, 0x01, 0, 0, 0, 0x01, 0x00]);
    s.handle_request(&req, w.now, AlState::PreOp, &mut w.dev, &mut NoFiles);
    s.queue_emergency(0x1000, 1, [0; 5]).unwrap();
    let before = allocations();
    let mut n = 0;
    while let Some(m) = s.next_response(w.now) {
        n += usize::from(m[8] == 0x82 || m[8] == 0x02);
    }
    assert_eq!(allocations() - before, 0);
    assert_eq!(n, (2 + 2 * w.dev.0.objects().len()).div_ceil(20));
}

/// Takes a file into a buffer reserved up front.
struct Sink(Vec<u8>);
impl FileHandler for Sink {
    fn begin_write(&mut self, _: &[u8], _: u32, _: AlState, _: Instant) -> Result<(), FoeError> {
        self.0.clear();
        Ok(())
    }
    fn write(&mut self, _: u32, data: &[u8], _: Instant) -> Result<FoeProgress, FoeError> {
        self.0.extend_from_slice(data);
        Ok(FoeProgress::Ready)
    }
    fn finish_write(&mut self, _: Instant) -> Result<FoeProgress, FoeError> {
        Ok(FoeProgress::Ready)
    }
}

#[test]
fn foe_packets_do_not_allocate() {
    let mut w = Wire::new();
    let mut files = Sink(Vec::with_capacity(4096));
    let mut bodies = vec![[&[2u8, 0, 0, 0, 0, 0][..], b"FOESW_A.bin"].concat()];
    for n in 1..=20u32 {
        let len = if n == 20 { 7 } else { 116 };
        bodies.push([&[3u8, 0][..], &n.to_le_bytes(), &pattern(len, n as u8)].concat());
    }
    let reqs = requests(&bodies, 4);
    assert_eq!(w.x(&reqs[0], &mut files), 0);
    let before = allocations();
    for (n, r) in reqs[1..].iter().enumerate() {
        assert_eq!(w.x(r, &mut files), n as u8 + 1, "ACK n");
    }
    assert_eq!(allocations() - before, 0);
    assert_eq!(files.0.len(), 19 * 116 + 7);
}
