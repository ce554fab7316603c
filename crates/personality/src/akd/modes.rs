//! The set-points of the AKD's manufacturer modes (§6.4.2.4) from the
//! machine's inputs: −1 analog current (analog input 1 × AIN.ISCALE 5002h,
//! mA per V), −2 analog velocity (analog input 1 × AIN.VSCALE 3629h, rpm
//! per V, float scale 1000:1), both after AIN.OFFSET 5003h and
//! AIN.DEADBAND 5001h (mV); −3 electronic gearing (the master encoder's
//! speed × GEAR.OUT 50BEh / GEAR.IN 50BBh, motor increments per master
//! count, 0 read as 1). The modes run on tq / pv (`Akd::manufacturer_mode`),
//! the set-point handed to the drive as its 6071h / 60FFh.

use crate::build::Context;
use crate::kc1::UNITS_PER_REV;
use drivebus_od::{EntryRef, ObjectDictionary};

#[derive(Debug, Clone, Default)]
struct Refs {
    objects: usize,
    deadband: Option<EntryRef>,
    iscale: Option<EntryRef>,
    offset: Option<EntryRef>,
    vscale: Option<EntryRef>,
    gear_in: Option<EntryRef>,
    gear_out: Option<EntryRef>,
    icont: Option<EntryRef>,
}

/// The input-driven set-point of modes −1..−3.
#[derive(Debug, Clone, Default)]
pub struct InputModes {
    refs: Refs,
    /// The set-point last handed to the drive (mode, value).
    last: Option<(i8, i32)>,
}

fn word(od: &ObjectDictionary, r: Option<EntryRef>) -> u64 {
    r.map_or(0, |r| od.word(r))
}

impl InputModes {
    /// The analog input 1 after offset and deadband \[mV\].
    fn analog_mv(&self, cx: &Context<'_>, od: &ObjectDictionary) -> f64 {
        let mv =
            cx.drive.model().analog_input(1) * 1000.0 - f64::from(word(od, self.refs.offset) as u32 as i32);
        if mv.abs() < word(od, self.refs.deadband) as u32 as f64 { 0.0 } else { mv }
    }

    /// After every step: the set-point of the manufacturer mode in force.
    pub fn update(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let Some(mode) = cx.drive.manufacturer_mode() else {
            self.last = None;
            return;
        };
        if self.refs.objects != od.objects().len() {
            let f = |i: u16| od.find(i, 0).ok();
            self.refs = Refs {
                objects: od.objects().len(),
                deadband: f(0x5001),
                iscale: f(0x5002),
                offset: f(0x5003),
                vscale: f(0x3629),
                gear_in: f(0x50BB),
                gear_out: f(0x50BE),
                icont: f(0x358E),
            };
        }
        let (index, value) = match mode {
            -1 => {
                let ma = self.analog_mv(cx, od) / 1000.0 * word(od, self.refs.iscale) as u32 as f64;
                let rated = crate::kc1::status::rated_ma(cx.drive, word(od, self.refs.icont)) as f64;
                let per_mille = (ma * 1000.0 / rated).round().clamp(f64::from(i16::MIN), f64::from(i16::MAX));
                (0x6071, per_mille as i32)
            }
            -2 => {
                let rpm = self.analog_mv(cx, od) / 1000.0
                    * f64::from(word(od, self.refs.vscale) as u32 as i32)
                    / 1000.0;
                (0x60FF, (rpm * f64::from(UNITS_PER_REV) / 60.0).round() as i32)
            }
            -3 => {
                let ratio = |r: Option<EntryRef>| (word(od, r) as u32).max(1) as f64;
                let inc_per_s =
                    cx.drive.model().master_velocity() * ratio(self.refs.gear_out) / ratio(self.refs.gear_in);
                let per_rev = f64::from(cx.drive.config().params.encoder.counts_per_rev.max(1));
                let units = inc_per_s * f64::from(UNITS_PER_REV) / per_rev;
                (0x60FF, units.round().clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32)
            }
            _ => return,
        };
        if self.last == Some((mode, value)) {
            return;
        }
        self.last = Some((mode, value));
        // Within the objects' types (clamped above): the drive takes them.
        let _ = if index == 0x6071 {
            cx.drive.on_write(od, index, 0, &(value as i16).to_le_bytes())
        } else {
            cx.drive.on_write(od, index, 0, &value.to_le_bytes())
        };
    }
}
