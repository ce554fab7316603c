//! The EtherCAT side of the control interface (`drivebus ethercat serve
//! --control ADDR`, docs/control.md): the same requests as on CAN, with
//! `node` a slave's position from 1. Inputs and machine faults go to a
//! drive twin's machine schedule (`DriveApp::change_machine`); bus rules
//! and power are faults of the line, kept in the segment
//! (`drivebus_esc::segment::LineFault`) so every transport sees them.

use crate::control::ControlRequest;
use anyhow::{anyhow, bail};
use drivebus_ethercat::Host;
use drivebus_ethercat::drive::with_drive;
use drivebus_personality::machine::Change;

/// Carries out `req` on the line; the error names the cause first, then
/// what to do.
pub fn handle(host: &Host, req: ControlRequest) -> anyhow::Result<()> {
    let slaves = host.with_segment(|s| s.len());
    match req {
        ControlRequest::Input { node, input, line, value, duration } => {
            let c = Change::input(&input, line, value).map_err(|e| anyhow!("input: {e}"))?;
            change(host, slaves, node, c, duration)
        }
        ControlRequest::Fault { node, kind, switch, duration } => {
            let c = Change::fault(&kind, switch.as_deref()).map_err(|e| anyhow!("fault: {e}"))?;
            change(host, slaves, node, c, duration)
        }
        ControlRequest::Bus { rule } if rule == "clear" => {
            host.with_segment(|s| s.clear_faults());
            Ok(())
        }
        ControlRequest::Bus { rule } => {
            let (fault, seed) = crate::fault::parse_line(&rule, slaves)?;
            host.with_segment(|s| {
                if let Some(seed) = seed {
                    s.set_fault_seed(seed);
                }
                s.add_fault(fault);
            });
            Ok(())
        }
        ControlRequest::Link { .. } => bail!(
            "an EtherCAT slave has no bus-off: break the line behind a slave (drivebus control bus break \
             --after N) or cut its power (drivebus control power N off)"
        ),
        ControlRequest::Power { node, on } => {
            let i = position(slaves, node)?;
            host.with_segment(|s| if on { s.power_on(i) } else { s.power_off(i) });
            Ok(())
        }
    }
}

/// The 0-based index of the slave at `node` (from 1).
fn position(slaves: usize, node: u8) -> anyhow::Result<usize> {
    if node == 0 || usize::from(node) > slaves {
        bail!(
            "no slave {node} on the line: use 1..{slaves} (positions from 1, as drivebus ethercat scan lists them)"
        );
    }
    Ok(usize::from(node) - 1)
}

fn change(host: &Host, slaves: usize, node: u8, c: Change, duration: Option<f64>) -> anyhow::Result<()> {
    let i = position(slaves, node)?;
    if !host.with_segment(|s| s.is_powered(i)) {
        bail!("slave {node} is powered off: power it on first (drivebus control power {node} on)");
    }
    let now = host.clock().now();
    match with_drive(host, i, |d| d.app_mut().change_machine(now, c, duration)) {
        Some(r) => r.map_err(|e| anyhow!("slave {node}: {e}")),
        None => bail!(
            "slave {node}: kind: a device from an SII image or ESI file has no machine inputs or faults (only \
             drives have)"
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_can::Instant;
    use drivebus_ethercat::Clock;
    use drivebus_ethercat::drive::DriveLine;
    use drivebus_personality::Profile;

    fn ask(host: &Host, json: &str) -> anyhow::Result<()> {
        handle(host, serde_json::from_str(json).unwrap())
    }

    #[test]
    fn requests_reach_the_line_and_bad_ones_say_why() {
        let host = DriveLine::new()
            .drive(Profile::Ipos)
            .drive(Profile::Generic)
            .host(Clock::simulated(Instant::from_millis(1)))
            .unwrap();
        ask(&host, r#"{"op":"bus","rule":"break:1"}"#).unwrap();
        assert_eq!(host.with_segment(|s| s.faults().len()), 1);
        ask(&host, r#"{"op":"bus","rule":"lose,every=3,seed=5"}"#).unwrap();
        ask(&host, r#"{"op":"bus","rule":"clear"}"#).unwrap();
        assert!(host.with_segment(|s| s.faults().is_empty()));
        ask(&host, r#"{"op":"power","node":2,"on":false}"#).unwrap();
        assert!(!host.with_segment(|s| s.is_powered(1)));
        let e = ask(&host, r#"{"op":"fault","node":2,"kind":"encoder"}"#).unwrap_err().to_string();
        assert!(e.contains("powered off"), "{e}");
        ask(&host, r#"{"op":"power","node":2,"on":true}"#).unwrap();
        ask(&host, r#"{"op":"fault","node":1,"kind":"encoder"}"#).unwrap();
        ask(&host, r#"{"op":"input","node":1,"input":"digital","line":3,"value":1}"#).unwrap();
        let e = ask(&host, r#"{"op":"input","node":3,"input":"digital","line":3,"value":1}"#).unwrap_err();
        assert!(e.to_string().contains("no slave 3 on the line: use 1..2"), "{e}");
        let e = ask(&host, r#"{"op":"link","node":1,"bus_off":true}"#).unwrap_err();
        assert!(e.to_string().contains("no bus-off"), "{e}");
        assert!(
            ask(&host, r#"{"op":"bus","rule":"break:2"}"#).unwrap_err().to_string().contains("bad EtherCAT")
        );
    }
}
