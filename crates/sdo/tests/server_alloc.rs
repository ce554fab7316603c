//! No allocation on the frame path once a transfer has started: buffers
//! are reserved at initiate and reused (DEVELOPERS.md, "sans-IO contract").

mod server_support;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use drivebus_sdo::server::ServerConfig;
use server_support::{Wire, pattern, test_od};

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

/// Allocations made by the server during `f`, with the scripted client's
/// own vectors made beforehand.
#[test]
fn transfers_do_not_allocate_once_warm() {
    const LEN: usize = 10 * 1024;
    let mut w = Wire::new(test_od(LEN), ServerConfig::default());
    let data = pattern(LEN, 7);
    let i = 0x2000u16.to_le_bytes();
    // Warm up: the first transfers size the server's buffer.
    w.download(0x2000, 0, &data).unwrap();
    w.upload(0x2000, 0).unwrap();

    // Segmented upload, frame by frame (the client keeps nothing).
    w.send([0x40, i[0], i[1], 0, 0, 0, 0, 0]);
    let before = allocations();
    let mut toggle = 0;
    loop {
        let r = w.send_no_alloc([0x60 | toggle, 0, 0, 0, 0, 0, 0, 0]);
        if r[0] & 1 != 0 {
            break;
        }
        toggle ^= 0x10;
    }
    assert_eq!(allocations() - before, 0, "segmented upload");

    // Segmented download including the final write into the dictionary
    // (same length as the stored value).
    let s = (LEN as u32).to_le_bytes();
    w.send_no_alloc([0x21, i[0], i[1], 0, s[0], s[1], s[2], s[3]]);
    let before = allocations();
    let mut toggle = 0;
    for (k, c) in data.chunks(7).enumerate() {
        let last = k == LEN.div_ceil(7) - 1;
        let mut f = [toggle | (((7 - c.len()) as u8) << 1) | u8::from(last), 0, 0, 0, 0, 0, 0, 0];
        f[1..1 + c.len()].copy_from_slice(c);
        assert_eq!(w.send_no_alloc(f)[0], 0x20 | toggle);
        toggle ^= 0x10;
    }
    assert_eq!(allocations() - before, 0, "segmented download");

    // Block download: initiate, all segments, end with CRC.
    w.send_no_alloc([0xC6, i[0], i[1], 0, s[0], s[1], s[2], s[3]]);
    let before = allocations();
    for (k, c) in data.chunks(7).enumerate() {
        let last = k == LEN.div_ceil(7) - 1;
        let mut f = [(k % 127 + 1) as u8 | (u8::from(last) << 7), 0, 0, 0, 0, 0, 0, 0];
        f[1..1 + c.len()].copy_from_slice(c);
        w.send_no_alloc(f);
    }
    let n = (LEN.div_ceil(7) * 7 - LEN) as u8;
    let crc = drivebus_sdo::crc::crc16(&data).to_le_bytes();
    assert_eq!(w.send_no_alloc([0xC1 | (n << 2), crc[0], crc[1], 0, 0, 0, 0, 0])[0], 0xA1);
    assert_eq!(allocations() - before, 0, "block download");

    // Block upload: start, acks, end.
    w.send_no_alloc([0xA4, i[0], i[1], 0, 127, 0, 0, 0]);
    let before = allocations();
    let mut cmd = [0xA3, 0, 0, 0, 0, 0, 0, 0];
    loop {
        let (count, last) = w.send_count(cmd);
        cmd = [0xA2, count as u8, 127, 0, 0, 0, 0, 0];
        if last[0] & 0x80 != 0 {
            break;
        }
    }
    assert_eq!(w.send_no_alloc(cmd)[0] & 0xE3, 0xC1);
    w.send_count([0xA1, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(allocations() - before, 0, "block upload");
    assert!(w.server.is_idle());
}
