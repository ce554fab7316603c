//! candump's filter syntax for `dump --filter` (SocketCAN `can_filter`
//! semantics, evaluated here so it works on every transport):
//!
//! - `ID:MASK` passes a frame when `frame_id & MASK == ID & MASK`;
//! - `ID~MASK` passes a frame when it does not (inverted);
//! - several filters, comma-separated or repeated, pass a frame that any of
//!   them passes; `j` (or `J`) among them joins them: every one must pass.
//!
//! IDs and masks are hex. The frame's identifier carries SocketCAN's flag
//! bits (`80000000` extended, `40000000` remote), so a mask can select
//! them; an 8-digit ID sets the extended flag, as candump does.

use anyhow::anyhow;
use drivebus_can::pcap::{CAN_EFF_FLAG, CAN_RTR_FLAG};
use drivebus_master::{CanId, Frame};

use crate::error::coded;

/// One `ID:MASK` or `ID~MASK`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Filter {
    id: u32,
    mask: u32,
    inverted: bool,
}

/// The filters of a `dump`, as given.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Filters {
    filters: Vec<Filter>,
    join: bool,
}

/// The frame's identifier as SocketCAN sees it: with its flag bits.
pub fn socketcan_id(f: &Frame) -> u32 {
    let mut id = match f.id() {
        CanId::Standard(v) => u32::from(v),
        CanId::Extended(v) => v | CAN_EFF_FLAG,
    };
    if f.is_rtr() {
        id |= CAN_RTR_FLAG;
    }
    id
}

impl Filters {
    /// Parses every `--filter` value (each may hold a comma-separated list).
    pub fn parse(args: &[String]) -> anyhow::Result<Filters> {
        let mut out = Filters::default();
        for item in args.iter().flat_map(|a| a.split(',')).map(str::trim).filter(|s| !s.is_empty()) {
            if item.eq_ignore_ascii_case("j") {
                out.join = true;
                continue;
            }
            let bad = || {
                coded(
                    "usage",
                    anyhow!(
                        "bad --filter `{item}`: write ID:MASK (181:7FF passes 181h), ID~MASK (inverted), \
                         hex, comma-separated; j joins them (every one must pass)"
                    ),
                )
            };
            let (id_text, mask_text, inverted) = match (item.split_once(':'), item.split_once('~')) {
                (Some((a, b)), None) => (a, b, false),
                (None, Some((a, b))) => (a, b, true),
                _ => return Err(bad()),
            };
            let hex = |t: &str| {
                let t = t.trim_start_matches("0x").trim_start_matches("0X");
                (!t.is_empty() && t.len() <= 8).then(|| u32::from_str_radix(t, 16).ok()).flatten()
            };
            let (Some(mut id), Some(mask)) = (hex(id_text), hex(mask_text)) else { return Err(bad()) };
            if id_text.trim_start_matches("0x").len() == 8 {
                id |= CAN_EFF_FLAG;
            }
            out.filters.push(Filter { id, mask, inverted });
        }
        Ok(out)
    }

    /// Whether `f` passes.
    pub fn pass(&self, f: &Frame) -> bool {
        if self.filters.is_empty() {
            return true;
        }
        let id = socketcan_id(f);
        let one = |x: &Filter| ((id & x.mask) == (x.id & x.mask)) != x.inverted;
        if self.join { self.filters.iter().all(one) } else { self.filters.iter().any(one) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(args: &[&str]) -> Filters {
        Filters::parse(&args.iter().map(|s| s.to_string()).collect::<Vec<_>>()).unwrap()
    }

    #[test]
    fn candump_filters() {
        let tpdo1 = Frame::new(0x181, &[1]);
        let tpdo1_n2 = Frame::new(0x182, &[1]);
        let sync = Frame::new(0x080, &[]);
        let one = f(&["181:7FF"]);
        assert!(one.pass(&tpdo1) && !one.pass(&tpdo1_n2) && !one.pass(&sync));
        // Every node's TPDO1: 180..1FF.
        let range = f(&["180:780"]);
        assert!(range.pass(&tpdo1) && range.pass(&tpdo1_n2) && !range.pass(&sync));
        // Inverted: everything but SYNC.
        let not_sync = f(&["080~7FF"]);
        assert!(not_sync.pass(&tpdo1) && !not_sync.pass(&sync));
        // Several: any passes.
        let two = f(&["181:7FF,080:7FF"]);
        assert!(two.pass(&tpdo1) && two.pass(&sync) && !two.pass(&tpdo1_n2));
        assert_eq!(f(&["181:7FF", "080:7FF"]), two);
        // Joined: all must pass (TPDO1s but not node 2's).
        let joined = f(&["180:780", "182~7FF", "j"]);
        assert!(joined.pass(&tpdo1) && !joined.pass(&tpdo1_n2));
        // Flags: remote frames only; 8 digits select extended frames.
        let rtr = f(&["40000000:40000000"]);
        assert!(rtr.pass(&Frame::remote(0x705, 1)) && !rtr.pass(&Frame::new(0x705, &[5])));
        let ext = f(&["18FF50E5:1FFFFFFF"]);
        assert!(ext.pass(&Frame::try_new(CanId::Extended(0x18FF_50E5), &[]).unwrap()));
        let only_ext = f(&["80000000:80000000"]);
        assert!(only_ext.pass(&Frame::try_new(CanId::Extended(0x0E5), &[]).unwrap()));
        assert!(!only_ext.pass(&Frame::new(0x0E5, &[])));
        assert!(f(&[]).pass(&sync));
        for bad in ["181", "181:", ":7FF", "181:7FF:1", "zz:7FF", "181~7FF~1", "123456789:7FF"] {
            let e = Filters::parse(&[bad.to_string()]).unwrap_err().to_string();
            assert!(e.contains("bad --filter"), "{bad}: {e}");
        }
    }
}
