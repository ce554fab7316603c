//! No input makes the ip or cyclic engines panic; finite inputs give finite
//! set-points.

use drivebus_cia402::interp::{Cyclic, CyclicConfig, CyclicKind, Ip, IpConfig, IpRecord, SubMode};
use proptest::prelude::*;

fn any_f64() -> impl Strategy<Value = f64> {
    prop_oneof![-1e6f64..1e6, Just(0.0), Just(f64::NAN), Just(f64::INFINITY), Just(-1e300)]
}

proptest! {
    #[test]
    fn ip_never_panics(
        max in 0usize..20,
        ops in prop::collection::vec((0u8..8, any_f64(), any::<u16>(), -3i16..1, any_f64()), 1..200),
    ) {
        let mut ip = Ip::new(max);
        ip.enter(0.0, 0);
        for (op, v, cw, sub, dt) in ops {
            let c = IpConfig {
                sub_mode: SubMode::from_code(sub).unwrap_or(SubMode::Linear),
                period: if v.is_finite() { v.abs() * 1e-6 } else { v },
                halt_deceleration: v,
            };
            match op {
                0 => { let _ = ip.write_data((v.abs() as u8) % 4, v); }
                1 => { let _ = ip.push(IpRecord { position: v, velocity: v, time: v }); }
                2 => ip.on_sync(cw, &c),
                3 => { ip.buffer_mut().set_size(v.abs() as usize % 24); }
                4 => { ip.buffer_mut().set_organisation(v.abs() as u8 % 3); }
                5 => { ip.buffer_mut().set_clear(v.abs() as u8 % 3); ip.buffer_mut().set_position(v.abs() as usize % 24); }
                _ => {
                    let out = ip.step(cw, &c, dt);
                    prop_assert!(out.position.is_finite() && out.velocity.is_finite());
                }
            }
        }
    }

    #[test]
    fn cyclic_never_panics(
        kind in 0u8..3,
        ops in prop::collection::vec((any::<bool>(), any_f64(), any_f64(), any::<u16>(), any_f64()), 1..200),
    ) {
        let kind = [CyclicKind::Position, CyclicKind::Velocity, CyclicKind::Torque][kind as usize];
        let cfg = CyclicConfig { period: 1e-3, following_window: Some(10.0), following_timeout: 0.01, halt_deceleration: 1e4 };
        let mut c = Cyclic::new(kind, 0.0, &cfg);
        for (sync, a, b, cw, dt) in ops {
            if sync {
                c.sync(a, b, a, &cfg);
            } else {
                let out = c.step(cw, a, &cfg, dt);
                prop_assert!(out.demand.is_finite() && out.feed_forward.is_finite());
            }
        }
    }
}
