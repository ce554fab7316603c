//! Raw CAN frames on the stream (`{"frames": {...}}`): every frame the
//! master receives whose identifier passes the client's filter, through
//! the client's bounded queue.

use std::ops::RangeInclusive;
use std::sync::Arc;
use std::sync::atomic::Ordering;

use drivebus_master::Frame;
use serde_json::{Value as Json_, json};
use tokio::sync::broadcast;

use super::Web;
use super::stream::Queue;
use super::values;

/// The CiA 301 pre-defined connection set by function: the names a filter
/// may give in `functions` and the identifiers each stands for.
const FUNCTIONS: &[(&str, &[RangeInclusive<u32>])] = &[
    ("nmt", &[0x000..=0x000]),
    ("sync", &[0x080..=0x080]),
    ("emcy", &[0x081..=0x0FF]),
    ("time", &[0x100..=0x100]),
    ("tpdo", &[0x181..=0x1FF, 0x281..=0x2FF, 0x381..=0x3FF, 0x481..=0x4FF]),
    ("rpdo", &[0x201..=0x27F, 0x301..=0x37F, 0x401..=0x47F, 0x501..=0x57F]),
    ("tpdo1", &[0x181..=0x1FF]),
    ("tpdo2", &[0x281..=0x2FF]),
    ("tpdo3", &[0x381..=0x3FF]),
    ("tpdo4", &[0x481..=0x4FF]),
    ("rpdo1", &[0x201..=0x27F]),
    ("rpdo2", &[0x301..=0x37F]),
    ("rpdo3", &[0x401..=0x47F]),
    ("rpdo4", &[0x501..=0x57F]),
    ("sdo", &[0x581..=0x5FF, 0x601..=0x67F]),
    ("sdo-tx", &[0x581..=0x5FF]),
    ("sdo-rx", &[0x601..=0x67F]),
    ("heartbeat", &[0x701..=0x77F]),
    ("lss", &[0x7E4..=0x7E5]),
];

/// Which frames a client wants: any identifier in `ids` (any frame
/// format) or in the standard identifiers of `functions`; both empty:
/// every frame.
#[derive(Debug, Default, PartialEq)]
pub struct FrameSelection {
    ids: Vec<RangeInclusive<u32>>,
    functions: Vec<RangeInclusive<u32>>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Request {
    #[serde(default)]
    ids: Vec<String>,
    #[serde(default)]
    functions: Vec<String>,
}

impl FrameSelection {
    /// The filter of a `frames` value: `{"ids": ["0x180-0x1FF", "080"],
    /// "functions": ["sync", "emcy"]}`.
    pub fn parse(v: &Json_) -> Result<FrameSelection, String> {
        let shape = r#"{"frames": {"ids": ["0x180-0x1FF", "080"], "functions": ["sync", "tpdo"]}}"#;
        let r: Request = serde_json::from_value(v.clone())
            .map_err(|e| format!("malformed frame filter: {e}; send {shape} ({{}} for every frame)"))?;
        let mut f = FrameSelection::default();
        for s in &r.ids {
            f.ids.push(crate::dump::id_range(s).map_err(|e| format!("{e:#}"))?);
        }
        for name in &r.functions {
            let lower = name.to_ascii_lowercase();
            let Some((_, ranges)) = FUNCTIONS.iter().find(|(n, _)| *n == lower) else {
                let known: Vec<&str> = FUNCTIONS.iter().map(|(n, _)| *n).collect();
                return Err(format!("`{name}` is not a CANopen function: use one of {}", known.join(", ")));
            };
            f.functions.extend(ranges.iter().cloned());
        }
        Ok(f)
    }

    /// True when `f` passes.
    pub fn passes(&self, f: &Frame) -> bool {
        if self.ids.is_empty() && self.functions.is_empty() {
            return true;
        }
        let raw = match f.id() {
            drivebus_can::CanId::Standard(v) => u32::from(v),
            drivebus_can::CanId::Extended(v) => v,
        };
        self.ids.iter().any(|r| r.contains(&raw))
            || f.std_id().is_some_and(|id| self.functions.iter().any(|r| r.contains(&u32::from(id))))
    }
}

/// A frame as the stream sends it; `t` is when the server got it.
pub fn frame_json(t: f64, f: &Frame) -> Json_ {
    let id = match f.id() {
        drivebus_can::CanId::Standard(v) => format!("{v:03X}"),
        drivebus_can::CanId::Extended(v) => format!("{v:08X}"),
    };
    json!({"type": "frame", "t": t, "id": id, "extended": f.std_id().is_none(), "rtr": f.is_rtr(),
        "len": f.len(), "data": values::hex(f.data())})
}

/// Puts every received frame that passes `filter` on `queue`; frames the
/// task could not keep up with count as dropped.
pub async fn forward(web: Arc<Web>, queue: Arc<Queue>, filter: FrameSelection) {
    let mut rx = web.master.subscribe_frames();
    loop {
        match rx.recv().await {
            Ok(f) if filter.passes(&f) => queue.push(&frame_json(web.t(), &f)),
            Ok(_) => {}
            Err(broadcast::error::RecvError::Lagged(n)) => {
                queue.dropped.fetch_add(n, Ordering::Relaxed);
            }
            Err(broadcast::error::RecvError::Closed) => return,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_and_functions_select_frames() {
        let f =
            FrameSelection::parse(&json!({"ids": ["0x180-0x1FF", "080"], "functions": ["emcy"]})).unwrap();
        for (id, pass) in
            [(0x181, true), (0x1FF, true), (0x080, true), (0x081, true), (0x200, false), (0x581, false)]
        {
            assert_eq!(f.passes(&Frame::new(id, &[1, 2])), pass, "{id:03X}");
        }
        let all = FrameSelection::parse(&json!({})).unwrap();
        assert!(all.passes(&Frame::new(0x7FF, &[])));
        let hb = FrameSelection::parse(&json!({"functions": ["Heartbeat"]})).unwrap();
        assert!(hb.passes(&Frame::new(0x701, &[5])) && !hb.passes(&Frame::new(0x700, &[5])));
    }

    #[test]
    fn a_bad_filter_names_its_fault() {
        let e = FrameSelection::parse(&json!({"ids": ["0x200-0x100"]})).unwrap_err();
        assert!(e.contains("200 is above 100"), "{e}");
        let e = FrameSelection::parse(&json!({"ids": ["zz"]})).unwrap_err();
        assert!(e.contains("CAN-IDs are hex"), "{e}");
        let e = FrameSelection::parse(&json!({"functions": ["pdo9"]})).unwrap_err();
        assert!(e.contains("not a CANopen function") && e.contains("tpdo1"), "{e}");
        let e = FrameSelection::parse(&json!({"id": ["181"]})).unwrap_err();
        assert!(e.contains("malformed frame filter"), "{e}");
    }

    #[test]
    fn a_frame_as_json() {
        let v = frame_json(1.5, &Frame::new(0x181, &[0x37, 0x02]));
        assert_eq!(
            v,
            json!({"type": "frame", "t": 1.5, "id": "181", "extended": false, "rtr": false, "len": 2, "data": "37 02"})
        );
    }
}
