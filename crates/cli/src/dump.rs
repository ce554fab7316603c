//! `drivebus dump`: a live decoded trace, or candump log lines.

use std::io::Write;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use drivebus_can::{CanId, Frame};
use drivebus_eds::Eds;
use drivebus_od::SdoAbort;

use crate::args::{DumpArgs, Global};
use crate::eds_cmd::{load_global_eds, object_name};
use crate::link::Link;

/// Runs the trace until `--count`, `--seconds`, SIGINT/SIGTERM or the bus closes.
pub async fn run(g: &Global, a: &DumpArgs) -> anyhow::Result<()> {
    let eds = load_global_eds(g)?;
    let mut link = Link::open(g).await?;
    let start = tokio::time::Instant::now();
    let end = a.seconds.map(|s| start + Duration::from_secs_f64(s.max(0.0)));
    let far = start + Duration::from_secs(86_400 * 365);
    let mut n = 0u64;
    let stop = crate::serve::wait_for_signal();
    tokio::pin!(stop);
    let mut out = std::io::stdout().lock();
    loop {
        if a.count.is_some_and(|c| n >= c) {
            break;
        }
        let f = tokio::select! {
            r = link.recv_until(end.unwrap_or(far)) => match r? {
                Some(f) => f,
                None => break,
            },
            _ = &mut stop => break,
        };
        n += 1;
        let line = if a.candump {
            let us = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_micros() as u64);
            let mut s = format!("({}.{:06}) can0 ", us / 1_000_000, us % 1_000_000);
            let _ = drivebus_bus::candump::write_frame(&mut s, &f);
            s
        } else if g.json {
            serde_json::json!({"t": start.elapsed().as_secs_f64(), "id": f.id().raw(), "data": crate::sdo_cmd::hex(f.data()), "decoded": decode(&f, eds.as_ref())})
                .to_string()
        } else {
            let mut raw = String::new();
            let _ = drivebus_bus::candump::write_frame(&mut raw, &f);
            format!("{:>10.6}  {raw:<24} {}", start.elapsed().as_secs_f64(), decode(&f, eds.as_ref()))
        };
        // A closed pipe (`| head`) ends the trace quietly.
        if writeln!(out, "{line}").and_then(|()| out.flush()).is_err() {
            break;
        }
    }
    Ok(())
}

fn name(eds: Option<&Eds>, index: u16, sub: u8) -> String {
    match eds.and_then(|e| object_name(e, index, sub)) {
        Some(n) => format!("{index:04X}h:{sub:02X} ({n})"),
        None => format!("{index:04X}h:{sub:02X}"),
    }
}

fn u32_at(d: &[u8; 8], i: usize) -> u32 {
    u32::from_le_bytes([d[i], d[i + 1], d[i + 2], d[i + 3]])
}

/// One frame in CANopen words (pre-defined connection set, CiA 301 §7.3.5).
pub fn decode(f: &Frame, eds: Option<&Eds>) -> String {
    let id = match f.id() {
        CanId::Standard(id) => id,
        CanId::Extended(id) => return format!("extended frame {id:08X}"),
    };
    let d = f.raw_data();
    let len = f.len();
    let node = id & 0x7F;
    if f.is_rtr() {
        return match id {
            0x701..=0x77F => format!("node guarding request to node {node}"),
            _ => format!("remote request {id:03X}"),
        };
    }
    match id {
        0x000 => {
            let cs = match d[0] {
                0x01 => "start",
                0x02 => "stop",
                0x80 => "enter pre-operational",
                0x81 => "reset node",
                0x82 => "reset communication",
                _ => "unknown command",
            };
            let who = if d[1] == 0 { "all nodes".to_owned() } else { format!("node {}", d[1]) };
            format!("NMT {cs} → {who}")
        }
        0x080 if len == 0 => "SYNC".to_owned(),
        0x080 => format!("SYNC counter {}", d[0]),
        0x081..=0x0FF => {
            let code = u16::from_le_bytes([d[0], d[1]]);
            if code == 0 {
                return format!("EMCY node {node}: error reset / no error");
            }
            let text = drivebus_emcy::describe(code).unwrap_or("manufacturer specific");
            format!("EMCY node {node}: {code:04X}h {text}, register {:02X}h", d[2])
        }
        0x100 => "TIME".to_owned(),
        0x180..=0x57F => {
            let (kind, n) = match id & 0x780 {
                0x180 => ("TPDO1", node),
                0x200 => ("RPDO1", node),
                0x280 => ("TPDO2", node),
                0x300 => ("RPDO2", node),
                0x380 => ("TPDO3", node),
                0x400 => ("RPDO3", node),
                0x480 => ("TPDO4", node),
                _ => ("RPDO4", node),
            };
            let hex: Vec<String> = f.data().iter().map(|b| format!("{b:02X}")).collect();
            format!("{kind} node {n}: {}", hex.join(" "))
        }
        0x581..=0x5FF => format!("SDO node {node} → master: {}", sdo(d, true, eds)),
        0x601..=0x67F => format!("SDO master → node {node}: {}", sdo(d, false, eds)),
        0x701..=0x77F => {
            let st = match d[0] & 0x7F {
                0x00 => "boot-up",
                0x04 => "stopped",
                0x05 => "operational",
                0x7F => "pre-operational",
                _ => "unknown state",
            };
            if d[0] == 0 { format!("boot-up node {node}") } else { format!("heartbeat node {node}: {st}") }
        }
        0x7E4 => format!("LSS slave → master cs {:02X}h", d[0]),
        0x7E5 => format!("LSS master → slave cs {:02X}h", d[0]),
        _ => format!("frame {id:03X}"),
    }
}

fn sdo(d: &[u8; 8], from_server: bool, eds: Option<&Eds>) -> String {
    let idx = u16::from_le_bytes([d[1], d[2]]);
    let sub = d[3];
    if d[0] == 0x80 {
        let a = SdoAbort(u32_at(d, 4));
        return format!(
            "abort {} code 0x{:08X} {}",
            name(eds, idx, sub),
            a.0,
            a.description().unwrap_or("unknown abort code")
        );
    }
    let cs = d[0] >> 5;
    let expedited_len = |d0: u8| if d0 & 0x03 == 0x03 { 4 - usize::from((d0 >> 2) & 3) } else { 0 };
    match (from_server, cs) {
        (false, 1) => {
            if d[0] & 0x02 != 0 {
                let n = expedited_len(d[0]).max(1);
                let hex: Vec<String> = d[4..4 + n].iter().map(|b| format!("{b:02X}")).collect();
                format!("write {} = {}", name(eds, idx, sub), hex.join(" "))
            } else {
                format!("write {} ({} bytes, segmented)", name(eds, idx, sub), u32_at(d, 4))
            }
        }
        (false, 2) => format!("read {}", name(eds, idx, sub)),
        (false, 0) => "download segment".to_owned(),
        (false, 3) => "upload segment request".to_owned(),
        (false, 5) => "block upload".to_owned(),
        (false, 6) => format!("block download {}", name(eds, idx, sub)),
        (true, 2) => {
            if d[0] & 0x02 != 0 {
                let n = expedited_len(d[0]).max(1);
                let mut b = [0u8; 4];
                b[..n].copy_from_slice(&d[4..4 + n]);
                let v = u32::from_le_bytes(b);
                format!("{} = {v} (0x{v:0w$X})", name(eds, idx, sub), w = n * 2)
            } else {
                format!("{} is {} bytes (segmented)", name(eds, idx, sub), u32_at(d, 4))
            }
        }
        (true, 3) => format!("written {}", name(eds, idx, sub)),
        (true, 0) => "upload segment".to_owned(),
        (true, 1) => "download segment ack".to_owned(),
        (true, 5) => "block download response".to_owned(),
        (true, 6) => "block upload response".to_owned(),
        _ => format!("cs {:02X}h", d[0]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_the_predefined_connection_set() {
        let d = |id: u16, data: &[u8]| decode(&Frame::new(id, data), None);
        assert_eq!(d(0x000, &[0x01, 0x05]), "NMT start → node 5");
        assert_eq!(d(0x000, &[0x81, 0x00]), "NMT reset node → all nodes");
        assert_eq!(d(0x080, &[]), "SYNC");
        assert_eq!(d(0x080, &[7]), "SYNC counter 7");
        assert_eq!(d(0x705, &[0x00]), "boot-up node 5");
        assert_eq!(d(0x705, &[0x7F]), "heartbeat node 5: pre-operational");
        assert_eq!(d(0x705, &[0x05]), "heartbeat node 5: operational");
        assert!(d(0x085, &[0x11, 0x86, 0x20, 0, 0, 0, 0, 0]).starts_with("EMCY node 5: 8611h"));
        assert_eq!(d(0x185, &[0x37, 0x02]), "TPDO1 node 5: 37 02");
        assert_eq!(d(0x305, &[0x0F, 0x00]), "RPDO2 node 5: 0F 00");
        assert_eq!(d(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), "SDO master → node 5: read 1000h:00");
        assert_eq!(
            d(0x585, &[0x43, 0x00, 0x10, 0, 0x92, 0x01, 0x02, 0x00]),
            "SDO node 5 → master: 1000h:00 = 131474 (0x00020192)"
        );
        assert_eq!(
            d(0x605, &[0x2B, 0x17, 0x10, 0, 0x64, 0x00, 0, 0]),
            "SDO master → node 5: write 1017h:00 = 64 00"
        );
        assert!(
            d(0x585, &[0x80, 0x00, 0x20, 0, 0x00, 0x00, 0x02, 0x06])
                .contains("abort 2000h:00 code 0x06020000 Object does not exist")
        );
        // Short or odd frames never panic.
        for id in [0x000u16, 0x080, 0x085, 0x185, 0x585, 0x605, 0x705, 0x7E4, 0x7E5, 0x123] {
            for len in 0..=8 {
                let _ = d(id, &[0xFF; 8][..len]);
            }
        }
    }

    #[test]
    fn object_names_come_from_the_eds() {
        let eds = drivebus_personality::Profile::Akd.parse_eds().eds;
        let s = decode(&Frame::new(0x601, &[0x40, 0x41, 0x60, 0, 0, 0, 0, 0]), Some(&eds));
        assert!(s.starts_with("SDO master → node 1: read 6041h:00 ("), "{s}");
    }
}
