//! Handles of the objects the iPOS reads or patches every control period,
//! resolved once instead of searched by index each step (a step runs 8
//! times per 1 ms cycle and after every checked write).

use drivebus_od::{EntryRef, ObjectDictionary, le_i64, le_u64};

/// `None` where the dictionary lacks the object (what `get_u32` would
/// answer `None` for).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Refs {
    /// Number of objects when resolved: inserting or removing an object
    /// moves handles, so a different count resolves again.
    objects: usize,
    resolved: bool,
    pub(super) master_source: Option<EntryRef>,
    pub(super) mode_display: Option<EntryRef>,
    pub(super) statusword: Option<EntryRef>,
    pub(super) limit_config: Option<EntryRef>,
    pub(super) motion_errors: Option<EntryRef>,
    pub(super) detailed_errors: Option<EntryRef>,
    pub(super) aux_settings: Option<EntryRef>,
    pub(super) sub_mode: Option<EntryRef>,
    pub(super) ip_status: Option<EntryRef>,
    pub(super) outputs_status: Option<EntryRef>,
    /// 208Fh:01 / :02.
    pub(super) inputs8: [Option<EntryRef>; 2],
    pub(super) error_code: Option<EntryRef>,
    pub(super) demand_internal: Option<EntryRef>,
    pub(super) velocity_sensor: Option<EntryRef>,
    pub(super) velocity_actual: Option<EntryRef>,
    pub(super) position_actual: Option<EntryRef>,
    /// 2075h:01..04.
    pub(super) triggers: [Option<EntryRef>; 4],
    pub(super) triggered_outputs: Option<EntryRef>,
    pub(super) inputs: Option<EntryRef>,
    pub(super) brake: Option<EntryRef>,
    pub(super) aux_encoder: Option<EntryRef>,
    pub(super) max_slippage: Option<EntryRef>,
    pub(super) slippage_time: Option<EntryRef>,
    pub(super) velocity_demand: Option<EntryRef>,
    /// 2046h reference, 2047h feedback analogue inputs.
    pub(super) analog: [Option<EntryRef>; 2],
    pub(super) tml_priority: Option<EntryRef>,
}

impl Refs {
    fn resolve(od: &ObjectDictionary) -> Refs {
        let f = |i: u16| od.find(i, 0).ok();
        Refs {
            objects: od.objects().len(),
            resolved: true,
            master_source: f(0x201D),
            mode_display: f(0x6061),
            statusword: f(0x6041),
            limit_config: f(0x60B8),
            motion_errors: f(0x2000),
            detailed_errors: f(0x2002),
            aux_settings: f(0x208E),
            sub_mode: f(0x60C0),
            ip_status: f(0x2072),
            outputs_status: f(0x2045),
            inputs8: [od.find(0x208F, 1).ok(), od.find(0x208F, 2).ok()],
            error_code: f(0x603F),
            demand_internal: f(0x60FC),
            velocity_sensor: f(0x6069),
            velocity_actual: f(0x606C),
            position_actual: f(0x6064),
            triggers: [1, 2, 3, 4].map(|s| od.find(0x2075, s).ok()),
            triggered_outputs: f(0x2085),
            inputs: f(0x60FD),
            brake: f(0x2102),
            aux_encoder: f(0x208D),
            max_slippage: f(0x60F8),
            slippage_time: f(0x2005),
            velocity_demand: f(0x606B),
            analog: [f(0x2046), f(0x2047)],
            tml_priority: f(0x2112),
        }
    }

    /// The handles, resolved again when the dictionary's structure changed.
    #[inline]
    pub(super) fn fresh(&mut self, od: &ObjectDictionary) -> Refs {
        if !self.resolved || self.objects != od.objects().len() {
            *self = Refs::resolve(od);
        }
        *self
    }
}

/// `ObjectDictionary::get_u32` through a handle.
#[inline]
pub(super) fn u32_at(od: &ObjectDictionary, r: Option<EntryRef>) -> Option<u32> {
    r.map(|r| le_u64(od.bytes(r)) as u32)
}

/// `ObjectDictionary::get_i64` through a handle.
#[inline]
pub(super) fn i64_at(od: &ObjectDictionary, r: Option<EntryRef>) -> Option<i64> {
    r.map(|r| le_i64(od.bytes(r)))
}
