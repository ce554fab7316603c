//! Table test of every standard homing method (CiA 402-2 §6.7, 6098h
//! methods 1–14, 17–30, 33, 34, 35, 37) on the motor model, from start
//! positions left of, on and right of the switch. The expected home position
//! is worked out here from the geometry (switch edges, index pulses at
//! 0.3 rad + k·rev) following the method figures, not from the engine.

mod homing_support;

use homing_support::*;

const NLS: f64 = -1000.0;
const PLS: f64 = 1000.0;
const STOPS: (Option<f64>, Option<f64>) = (Some(-1200.0), Some(1200.0));
/// Momentary home switch for 7–14 / 23–30: active in [LO, HI].
const LO: f64 = 100.0;
const HI: f64 = 500.0;
/// Single-edge home switches for 3–6 / 19–22 have their edge at EDGE.
const EDGE: f64 = 100.0;

#[derive(Debug, Clone, Copy)]
enum Geometry {
    /// Limit switches only.
    Limits,
    /// Home switch active on the positive side of EDGE (methods 3, 4).
    PositiveHome,
    /// Home switch active on the negative side of EDGE (methods 5, 6).
    NegativeHome,
    /// Momentary home switch [LO, HI] plus the limit switches (7–14).
    Momentary,
}

fn params(g: Geometry, start: f64) -> drivebus_cia402::model::DriveParams {
    let home = match g {
        Geometry::Limits => None,
        Geometry::PositiveHome => Some((EDGE, 1.0e6)),
        Geometry::NegativeHome => Some((-1.0e6, EDGE)),
        Geometry::Momentary => Some((LO, HI)),
    };
    axis(Some(NLS), Some(PLS), home, STOPS, start)
}

/// Where the reference is for a method: (geometry, edge, final side is
/// positive, uses the index pulse), straight from the method descriptions.
fn rule(method: i8) -> (Geometry, f64, bool, bool) {
    use Geometry::*;
    let (g, edge, positive) = match method {
        1 | 17 => (Limits, NLS, true),  // right of where NLS goes inactive
        2 | 18 => (Limits, PLS, false), // left of where PLS goes inactive
        3 | 19 => (PositiveHome, EDGE, false),
        4 | 20 => (PositiveHome, EDGE, true),
        5 | 21 => (NegativeHome, EDGE, true),
        6 | 22 => (NegativeHome, EDGE, false),
        7 | 23 => (Momentary, LO, false), // left of the lower edge
        8 | 24 => (Momentary, LO, true),  // right of the lower edge
        9 | 25 => (Momentary, HI, false), // left of the upper edge
        10 | 26 => (Momentary, HI, true), // right of the upper edge
        11 | 27 => (Momentary, HI, true),
        12 | 28 => (Momentary, HI, false),
        13 | 29 => (Momentary, LO, true),
        14 | 30 => (Momentary, LO, false),
        _ => unreachable!(),
    };
    (g, edge, positive, method <= 14)
}

fn expected(method: i8, start: f64) -> f64 {
    match method {
        33 => index_left_of(start),
        34 => index_right_of(start),
        35 | 37 => start,
        _ => {
            let (_, edge, positive, index) = rule(method);
            match (index, positive) {
                (false, _) => edge,
                (true, true) => index_right_of(edge),
                (true, false) => index_left_of(edge),
            }
        }
    }
}

fn starts(method: i8) -> Vec<f64> {
    match method {
        // On the limit switch, and on either side of the home switch region.
        1 | 17 => vec![-1050.0, -300.0, 300.0],
        2 | 18 => vec![1050.0, 300.0, -300.0],
        33 | 34 | 35 | 37 => vec![-300.0, 300.0],
        // Left of, on and right of the home switch.
        _ => vec![-300.0, 300.0, 700.0],
    }
}

fn geometry(method: i8) -> Geometry {
    match method {
        33 | 34 | 35 | 37 => Geometry::Limits,
        _ => rule(method).0,
    }
}

#[test]
fn every_standard_method_from_every_side() {
    let methods: Vec<i8> = (1..=14).chain(17..=30).chain([33, 34, 35, 37]).collect();
    let mut rows = 0;
    for &m in &methods {
        for start in starts(m) {
            let mut rig = Rig::new(params(geometry(m), start), config(m));
            let status = rig.run(20.0);
            let want = expected(m, start);
            let got = rig.reference_raw();
            assert_eq!(
                status,
                0x1400,
                "method {m} from {start}: status {status:#06x}, {:?}",
                rig.homing.state()
            );
            assert!(
                (got - want).abs() <= COUNT_DEG,
                "method {m} from {start}: reference {got} expected {want}"
            );
            // The actual position frame: the true shaft position relative
            // to the home position, plus the home offset (one count of
            // encoder quantisation).
            let truth = rig.model.rad_to_units(rig.model.position()) - want + HOME_OFFSET;
            assert!((rig.actual() - truth).abs() <= COUNT_DEG, "method {m} from {start}: frame");
            assert_eq!(rig.resets, 1);
            let seq: &[u16] =
                if matches!(m, 35 | 37) { &[0x0400, 0x1400] } else { &[0x0400, 0x0000, 0x1000, 0x1400] };
            assert_eq!(rig.statuses, seq, "method {m} from {start}");
            rows += 1;
        }
    }
    assert_eq!(rows, 24 * 3 + 4 * 3 + 4 * 2);
}

#[test]
fn expected_values_of_the_table() {
    // Spot checks of the geometry helpers against hand-computed numbers:
    // index pulses at 17.188 733 9° + k·360°.
    assert!((INDEX_DEG - 17.188_733_853_924_7).abs() < 1e-9);
    assert!((expected(1, 0.0) - (INDEX_DEG - 720.0)).abs() < 1e-9);
    assert!((expected(2, 0.0) - (INDEX_DEG + 720.0)).abs() < 1e-9);
    assert!((expected(7, 0.0) - INDEX_DEG).abs() < 1e-9);
    assert!((expected(10, 0.0) - (INDEX_DEG + 720.0)).abs() < 1e-9);
    assert!((expected(12, 0.0) - (INDEX_DEG + 360.0)).abs() < 1e-9);
    assert_eq!(expected(25, 0.0), HI);
    assert!((expected(33, 300.0) - INDEX_DEG).abs() < 1e-9);
}

/// Methods 3–6 / 19–22 on a cam home switch (active over [LO, HI] only,
/// as on a machine that also serves 7–14): from right of the cam the
/// switch reads inactive, so 3/4 start positive, meet the positive limit
/// switch, reverse once and take the lower edge (the one with the active
/// side positive); 5/6 mirror that on the upper edge. The reference is the
/// same as from the other starts.
#[test]
fn single_edge_methods_on_a_cam_switch_from_every_side() {
    let mut rows = 0;
    for m in (3..=6).chain(19..=22) {
        let (edge, positive) = match m {
            3 | 19 => (LO, false),
            4 | 20 => (LO, true),
            5 | 21 => (HI, true),
            _ => (HI, false),
        };
        let want = match (m <= 14, positive) {
            (false, _) => edge,
            (true, true) => index_right_of(edge),
            (true, false) => index_left_of(edge),
        };
        for start in [-1050.0, -300.0, 300.0, 700.0, 1050.0] {
            let mut rig = Rig::new(params(Geometry::Momentary, start), config(m));
            let status = rig.run(20.0);
            assert_eq!(status, 0x1400, "method {m} from {start}: {:?}", rig.homing.state());
            let got = rig.reference_raw();
            assert!(
                (got - want).abs() <= COUNT_DEG,
                "method {m} from {start}: reference {got}, expected {want}"
            );
            rows += 1;
        }
    }
    assert_eq!(rows, 8 * 5);
}
