//! Fastscan (CiA 305 v3.0.0 Fig. 46) of one and of three unconfigured
//! slaves on a tiny simulated wire: every master frame reaches every slave,
//! every answer reaches the master. Identical answers to the same frame merge
//! as on CAN (wired-AND), unless a test asks to deliver each copy.

use drivebus_can::{Duration, Frame, Instant};
use drivebus_lss::codec::LssField;
use drivebus_lss::{FastScan, FastScanOutcome, Identity, LssEvent, LssMode, LssSlave, master};

const TIMEOUT: Duration = Duration::from_millis(10);

// DDS6041 (DC) units with consecutive serial numbers, a DDS6278A (AC) unit
// (`seed004-dds6-objects.tsv` 1018h) and a Kollmorgen KC1 (vendor 6Ah,
// product "M006", `seed000-kc1-objects.tsv` 1018h).
const DDS6_A: Identity = Identity::new(0x0000_030C, 0x0060_4100, 0x0001_0002, 0x0000_1234);
const DDS6_B: Identity = Identity::new(0x0000_030C, 0x0060_4100, 0x0001_0002, 0x0000_1235);
const DDS6_AC: Identity = Identity::new(0x0000_030C, 0x0062_7801, 0x0001_0000, 0x0000_0001);
const KC1: Identity = Identity::new(0x0000_006A, u32::from_le_bytes(*b"M006"), 0x0014_0000, 0x0A21_5678);

struct Wire {
    slaves: Vec<LssSlave>,
    now: Instant,
    merge: bool,
    /// Every frame the master sent, in order.
    log: Vec<Frame>,
    /// Events the slaves returned, with the slave's position.
    events: Vec<(usize, LssEvent)>,
}

impl Wire {
    fn new(slaves: Vec<LssSlave>) -> Wire {
        Wire { slaves, now: Instant::ZERO, merge: true, log: Vec::new(), events: Vec::new() }
    }

    /// Deliver one master frame to every slave; return their answers.
    fn broadcast(&mut self, f: Frame) -> Vec<Frame> {
        self.log.push(f);
        let mut answers = Vec::new();
        for (i, s) in self.slaves.iter_mut().enumerate() {
            if let Some(ev) = s.handle_frame(&f, self.now, &mut answers) {
                self.events.push((i, ev));
            }
        }
        if self.merge {
            answers.dedup();
        }
        answers
    }

    /// Run a fastscan to its end on simulated time.
    fn scan(&mut self, mut scan: FastScan) -> (FastScanOutcome, usize) {
        let first = self.log.len();
        let mut tx = Vec::new();
        scan.start(self.now, &mut tx);
        loop {
            while !tx.is_empty() {
                for f in std::mem::take(&mut tx) {
                    for answer in self.broadcast(f) {
                        scan.handle_frame(&answer, self.now, &mut tx);
                    }
                }
            }
            // Nothing due before the deadline; then the next question goes out.
            let Some(deadline) = scan.poll(self.now, &mut tx) else { break };
            assert!(tx.is_empty(), "poll before the deadline must do nothing");
            self.now = deadline;
            scan.poll(self.now, &mut tx);
        }
        (scan.outcome().expect("scan ended"), self.log.len() - first)
    }

    /// Configure the node-ID of the slave(s) in configuration, then switch
    /// all back to waiting; return the answers to the configure request.
    fn assign(&mut self, node_id: u8) -> Vec<Frame> {
        let answers = self.broadcast(master::configure_node_id(node_id));
        self.broadcast(master::switch_state_global(LssMode::Waiting));
        answers
    }

    fn in_configuration(&self) -> Vec<Identity> {
        self.slaves.iter().filter(|s| s.mode() == LssMode::Configuration).map(|s| *s.identity()).collect()
    }
}

fn unconfigured(addr: Identity) -> LssSlave {
    LssSlave::new(addr, 0xFF, 4)
}

#[test]
fn one_slave_is_found_frame_exact() {
    let mut wire = Wire::new(vec![unconfigured(DDS6_A)]);
    let (outcome, sent) = wire.scan(FastScan::new(TIMEOUT));
    assert_eq!(outcome, FastScanOutcome::Found(DDS6_A));
    // Reset + 4 parts × (32 bit questions + 1 confirm).
    assert_eq!(sent, 1 + 4 * 33);
    let log: Vec<String> = wire.log.iter().map(|f| format!("{f}")).collect();
    assert_eq!(log[0], "7E5#5100000000800000", "reset / confirm presence");
    assert_eq!(log[1], "7E5#51000000001F0000", "vendor bit 31, LSSNext = LSSSub");
    assert_eq!(log[32], "7E5#510C030000000000", "vendor bit 0, bits 31..1 already found");
    // Vendor 030Ch confirmed, next part product.
    assert_eq!(log[33], "7E5#510C030000000001");
    assert_eq!(log[66], "7E5#5100416000000102");
    assert_eq!(log[99], "7E5#5102000100000203");
    // Serial confirmed with LSSNext wrapping to 0: the slave enters configuration.
    assert_eq!(log[132], "7E5#5134120000000300");
    assert_eq!(wire.in_configuration(), vec![DDS6_A]);
    assert_eq!(wire.events, vec![(0, LssEvent::EnteredConfiguration)]);
    // Simulated time: one timeout per question (answers are evaluated at the deadline).
    assert_eq!(wire.now, Instant::ZERO + TIMEOUT * 133);

    // Assign node-ID 7: the device leaves LSS-only operation.
    assert_eq!(wire.assign(7), vec![Frame::new8(0x7E4, [0x11, 0, 0, 0, 0, 0, 0, 0])]);
    assert_eq!(wire.events[2], (0, LssEvent::ResetCommunication { node_id: 7 }));
    assert_eq!(wire.slaves[0].reset_communication(), 7);
    // Nobody left to find.
    assert_eq!(wire.scan(FastScan::new(TIMEOUT)), (FastScanOutcome::NoneFound, 1));
}

fn three_slaves(merge: bool, early: bool) {
    // A configured bystander (node 5) must never take part.
    let mut wire = Wire::new(vec![
        unconfigured(DDS6_B),
        LssSlave::new(DDS6_AC, 5, 4),
        unconfigured(KC1),
        unconfigured(DDS6_A),
    ]);
    wire.merge = merge;
    // The scan converges on the lowest address first.
    let mut expected = vec![KC1, DDS6_A, DDS6_B];
    for (k, want) in expected.drain(..).enumerate() {
        let (outcome, sent) = wire.scan(FastScan::new(TIMEOUT).with_early_advance(early));
        assert_eq!(outcome, FastScanOutcome::Found(want), "round {k}");
        assert_eq!(sent, 133);
        assert_eq!(wire.in_configuration(), vec![want], "only the found slave is selected");
        let node_id = 10 + k as u8;
        assert_eq!(wire.assign(node_id), vec![Frame::new8(0x7E4, [0x11, 0, 0, 0, 0, 0, 0, 0])]);
        let i = wire.slaves.iter().position(|s| *s.identity() == want).unwrap();
        assert_eq!(wire.events.last(), Some(&(i, LssEvent::ResetCommunication { node_id })));
        assert_eq!(wire.slaves[i].reset_communication(), node_id);
    }
    assert_eq!(wire.scan(FastScan::new(TIMEOUT)).0, FastScanOutcome::NoneFound);
    let ids: Vec<u8> = wire.slaves.iter().map(|s| s.active_node_id()).collect();
    assert_eq!(ids, vec![12, 5, 10, 11]);
}

#[test]
fn three_slaves_found_in_turn() {
    three_slaves(true, false);
}

#[test]
fn three_slaves_with_every_answer_delivered() {
    // Without merging, the master still only needs "an answer".
    three_slaves(false, false);
}

#[test]
fn three_slaves_with_early_advance() {
    three_slaves(true, true);
}

#[test]
fn known_parts_are_only_confirmed() {
    let mut wire = Wire::new(vec![unconfigured(KC1), unconfigured(DDS6_B), unconfigured(DDS6_A)]);
    let scan =
        FastScan::new(TIMEOUT).with_known(LssField::Vendor, 0x30C).with_known(LssField::Product, 0x0060_4100);
    let (outcome, sent) = wire.scan(scan);
    // KC1 is lower but has another vendor-ID: it drops out at the confirm.
    assert_eq!(outcome, FastScanOutcome::Found(DDS6_A));
    assert_eq!(sent, 1 + 1 + 1 + 33 + 33);
    // A known part nobody has: the confirm goes unanswered.
    let (outcome, sent) = wire.scan(FastScan::new(TIMEOUT).with_known(LssField::Vendor, 0x1A3));
    assert_eq!((outcome, sent), (FastScanOutcome::Lost(LssField::Vendor), 2));
}

#[test]
fn empty_bus_and_configured_slaves_give_none_found() {
    let mut wire = Wire::new(vec![]);
    assert_eq!(wire.scan(FastScan::new(TIMEOUT)), (FastScanOutcome::NoneFound, 1));
    let mut wire = Wire::new(vec![LssSlave::new(DDS6_A, 1, 4), LssSlave::new(KC1, 2, 4)]);
    assert_eq!(wire.scan(FastScan::new(TIMEOUT)), (FastScanOutcome::NoneFound, 1));
    assert!(wire.in_configuration().is_empty());
}

#[test]
fn slaves_in_configuration_do_not_take_part() {
    // A slave already in configuration (e.g. left there by a selective
    // switch) ignores fastscan: fastscan is a waiting-state service.
    let mut wire = Wire::new(vec![unconfigured(DDS6_A)]);
    wire.broadcast(master::switch_state_global(LssMode::Configuration));
    assert_eq!(wire.scan(FastScan::new(TIMEOUT)).0, FastScanOutcome::NoneFound);
}

#[test]
fn a_vanishing_slave_is_reported_lost() {
    let mut scan = FastScan::new(TIMEOUT);
    let mut tx = Vec::new();
    let mut now = Instant::ZERO;
    scan.start(now, &mut tx);
    // Answer the reset, then stay silent: every bit reads 1, and the
    // vendor confirm (all ones) goes unanswered.
    let answer = Frame::new8(0x7E4, [0x4F, 0, 0, 0, 0, 0, 0, 0]);
    scan.handle_frame(&answer, now, &mut tx);
    while let Some(deadline) = scan.poll(now, &mut tx) {
        now = deadline;
    }
    assert_eq!(scan.outcome(), Some(FastScanOutcome::Lost(LssField::Vendor)));
    assert_eq!(tx.len(), 34);
    assert_eq!(format!("{}", tx[33]), "7E5#51FFFFFFFF000001");
    // Ended: further frames and polls do nothing.
    assert_eq!(scan.handle_frame(&answer, now, &mut tx), None);
    assert_eq!(scan.poll(now + TIMEOUT, &mut tx), None);
    assert_eq!(tx.len(), 34);
}

#[test]
fn other_frames_are_not_answers() {
    let mut scan = FastScan::new(TIMEOUT).with_early_advance(true);
    let mut tx = Vec::new();
    scan.start(Instant::ZERO, &mut tx);
    for f in [
        Frame::new8(0x7E5, [0x4F, 0, 0, 0, 0, 0, 0, 0]),
        Frame::new8(0x7E4, [0x50, 0, 0, 0, 0, 0, 0, 0]),
        Frame::new(0x7E4, &[0x4F]),
        Frame::new8(0x704, [0x4F, 0, 0, 0, 0, 0, 0, 0]),
    ] {
        assert_eq!(scan.handle_frame(&f, Instant::ZERO, &mut tx), None);
    }
    assert_eq!(tx.len(), 1);
    assert_eq!(scan.poll(Instant::ZERO + TIMEOUT, &mut tx), None);
    assert_eq!(scan.outcome(), Some(FastScanOutcome::NoneFound));
}
