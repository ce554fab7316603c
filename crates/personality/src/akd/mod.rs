//! Kollmorgen AKD (seed001, *AKD CAN-BUS Kommunikation*, edition R 09/2016).
//!
//! Everything of [`Kollmorgen`] (the AKD manual repeats the KC1's CiA 301
//! chapters: §5.4.1 NMT, §5.4.3 TIME, §5.4.5 SDO, §6.3 PDO, §7.2.2.1 2100h),
//! plus:
//!
//! - manufacturer modes (§6.4.2.4 / 6060h table): −1 analog current, −2
//!   analog velocity, −3 electronic gearing, with their set-points from the
//!   machine's analog input 1 and master encoder (`modes.rs`): −1 runs as
//!   torque mode, −2 and −3 as profile velocity. While one of them is
//!   active, 6071h/60FFh writes are stored but do not move the motor (the
//!   set-point comes from the input, not the bus). 6061h shows the
//!   negative code.
//! - manufacturer homing methods (§6.10.2.2 table, edition R): −7/−6 to the
//!   reference switch negative/positive then the next feedback zero
//!   (CiA 402 methods 5/3 behave so), −5 set reference here (as 37), −4/−3
//!   reference switch without index, positive/negative (as 19/21).

mod emcy;
mod facts;
mod modes;

pub use facts::INFO;

/// The EDS file (`crates/personality/eds/akd.eds`).
pub const EDS: &str = include_str!("../../eds/akd.eds");

use crate::Profile;
use crate::build::{Behaviour, Context, EmcyFrame, FilterOutcome, Verdict};
use crate::kc1::Kollmorgen;
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_can::Frame;
use drivebus_cia402::drive::{DriveConfig, op};
use drivebus_cia402::homing::{HomingContext, HomingMethod, MethodStep, StandardMethod};
use drivebus_node::{Node, NodeConfig, NodeEvent};
use drivebus_od::{ObjectDictionary, SdoAbort, le_u64};

extern crate alloc;

/// A manufacturer homing code running a CiA 402 method's motion.
pub struct Alias {
    code: i8,
    inner: StandardMethod,
}

impl Alias {
    /// `code` behaving as standard method `standard`.
    pub fn new(code: i8, standard: i8) -> Option<Self> {
        Some(Alias { code, inner: StandardMethod::new(standard)? })
    }
}

impl HomingMethod for Alias {
    fn code(&self) -> i8 {
        self.code
    }
    fn begin(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        self.inner.begin(ctx)
    }
    fn update(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        self.inner.update(ctx)
    }
}

/// AKD manufacturer homing methods and the standard method each runs as.
pub const HOMING_ALIASES: [(i8, i8); 5] = [(-7, 5), (-6, 3), (-5, 37), (-4, 19), (-3, 21)];

/// The AKD: the Kollmorgen behaviour and the input-driven modes.
#[derive(Debug, Clone)]
pub struct Akd(Kollmorgen, modes::InputModes);

impl Akd {
    /// The AKD behaviour.
    pub fn new() -> Self {
        Akd(Kollmorgen::new(Profile::Akd), modes::InputModes::default())
    }

    /// With the DC bus charged before *Switch on* (statusword 0231h; see
    /// [`Kollmorgen::dc_bus_before_switch_on`]).
    pub fn with_dc_bus_before_switch_on(self, on: bool) -> Self {
        Akd(self.0.with_dc_bus_before_switch_on(on), self.1)
    }
}

impl Default for Akd {
    fn default() -> Self {
        Self::new()
    }
}

/// The KC1's hooked objects plus 6071h/60FFh (the set-points modes
/// −1..−3 take from their inputs).
const HOOKED: [u16; Kollmorgen::HOOKED.len() + 2] = {
    let k = Kollmorgen::HOOKED;
    let mut all = [0x6071; Kollmorgen::HOOKED.len() + 2];
    let mut i = 0;
    while i < k.len() {
        all[i] = k[i];
        i += 1;
    }
    all[k.len() + 1] = 0x60FF;
    all
};

impl Behaviour for Akd {
    fn profile(&self) -> Profile {
        Profile::Akd
    }
    fn adjust_node_config(&self, cfg: &mut NodeConfig) {
        self.0.adjust_node_config(cfg);
    }
    fn hooked_objects(&self) -> &'static [u16] {
        &HOOKED
    }
    fn adjust_drive_config(&self, cfg: &mut DriveConfig) {
        self.0.adjust_drive_config(cfg);
    }
    fn ip_mode(&self) -> drivebus_cia402::interp::IpMode {
        self.0.ip_mode()
    }
    fn finish(&mut self, node: &mut Node) {
        self.0.finish(node);
        let od = node.od_mut();
        // §6.10.2.3: 6099h:2 "50 % of 6099h:1" (the KC1's is 1/8).
        crate::build::set_default(od, 0x6099, 2, &drivebus_od::Value::U32(crate::kc1::UNITS_PER_REV / 2));
        // §6.9.2.3: 60C2h:1 default 2 (with 60C2h:2 = -3: 2 ms).
        crate::build::set_default(od, 0x60C2, 1, &drivebus_od::Value::U8(2));
    }
    fn homing_methods(&self) -> Vec<Box<dyn HomingMethod + Send>> {
        HOMING_ALIASES
            .iter()
            .filter_map(|&(c, s)| Alias::new(c, s))
            .map(|a| Box::new(a) as Box<dyn HomingMethod + Send>)
            .collect()
    }
    fn manufacturer_mode(&self, mode: i8) -> Option<i8> {
        match mode {
            -1 => Some(op::TQ),
            -2 | -3 => Some(op::PV),
            _ => None,
        }
    }
    fn filter_rx(&mut self, od: &ObjectDictionary, node_id: u8, frame: &Frame) -> FilterOutcome {
        self.0.filter_rx(od, node_id, frame)
    }
    fn on_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<Verdict, SdoAbort> {
        if matches!(index, 0x6071 | 0x60FF) {
            let m = od.get_i64(0x6060, 0).unwrap_or(0);
            if m < 0 {
                // The analog input / master encoder gives the set-point.
                return Ok(Verdict::Store);
            }
            return Ok(Verdict::Pass);
        }
        // §6.9.2.1: linear interpolation only (60C0h = 0).
        if index == 0x60C0 && le_u64(data) != 0 {
            return Err(SdoAbort::INVALID_VALUE);
        }
        // §7.1.5: 60C1h:2/3 are listed (the PVT mode's record, removed in
        // edition M): kept as values, the linear interpolation ignores them.
        if index == 0x60C1 && (2..=3).contains(&sub) {
            return Ok(Verdict::Store);
        }
        if index == 0x6060 && sub == 0 {
            let m = data.first().copied().unwrap_or(0) as i8;
            if m < 0 && self.manufacturer_mode(m).is_some() {
                // The set-point of the stand-in mode is the (absent) input: 0.
                let _ = cx.drive.on_write(od, 0x60FF, 0, &0i32.to_le_bytes());
                let _ = cx.drive.on_write(od, 0x6071, 0, &0i16.to_le_bytes());
            }
        }
        self.0.on_write(cx, od, index, sub, data)
    }
    fn after_write(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, index: u16, sub: u8) {
        self.0.after_write(cx, od, index, sub);
    }
    fn on_read(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
    ) -> Result<(), SdoAbort> {
        self.0.on_read(cx, od, index, sub)
    }
    fn on_event(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, event: &NodeEvent) {
        self.0.on_event(cx, od, event);
    }
    fn on_boot(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        self.0.on_boot(cx, od);
    }
    fn after_step(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        self.1.update(cx, od);
        self.0.after_step(cx, od);
    }
    fn emcy(&self, code: u16) -> EmcyFrame {
        self.0.emcy(code)
    }

    fn as_any_mut(&mut self) -> Option<&mut dyn core::any::Any> {
        Some(self)
    }
}
