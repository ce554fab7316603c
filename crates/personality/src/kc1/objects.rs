//! The writes of the Kollmorgen objects with an effect of their own
//! (KC1 §7.2, §7.7, §7.9, §7.11 and the §8.1.3 parameters; the AKD's
//! sections alike): the Telnet channels, the current set-point, the
//! software limits, the interpolation period and sub-mode, the parameters
//! forwarded to the drive, the latches, inputs, brake, save and motion
//! tasks. The CiA 301 quirks stay in `Kollmorgen::on_write`.

use super::{Kollmorgen, ascii, params, status, timing};
use crate::build::{Context, Verdict};
use drivebus_node::Request;
use drivebus_od::{ObjectDictionary, SdoAbort, le_u64};

impl Kollmorgen {
    /// The verdict on a write of one of these objects; `Ok(None)`: not one
    /// of them.
    pub(crate) fn object_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<Option<Verdict>, SdoAbort> {
        let verdict: Result<Verdict, SdoAbort> = match index {
            // §7.2.2.6 / example 10: Telnet commands, 4 characters per write,
            // executed at CR LF.
            0x2026 if sub == 1 => {
                if let Some(cmd) = self.telnet.receive(data) {
                    let text = self.command(cx, od, &cmd);
                    self.telnet.answer(&text);
                }
                Ok(Verdict::Handled)
            }
            // §7.2.1.18: the same channel one character at a time.
            0x1026 if sub == 1 => {
                if let Some(cmd) = self.prompt.receive(data) {
                    let text = self.command(cx, od, &cmd);
                    self.prompt.answer(&text);
                }
                Ok(Verdict::Handled)
            }
            // §7.7.2.1: the torque controller's input in mA, "alternatively
            // to 6071h": 6071h = mA × 1000 / the motor's rated current (mA;
            // 6075h is not in the object table).
            0x2071 => {
                let ma = le_u64(data) as u32 as i32;
                let peak = [0x5084u16, 0x358F]
                    .iter()
                    .filter_map(|&i| od.get_u32(i, 0))
                    .filter(|&p| p != 0)
                    .min()
                    .map_or(i64::MAX, i64::from);
                if i64::from(ma) > peak {
                    return Err(SdoAbort::VALUE_TOO_HIGH);
                }
                if -i64::from(ma) > peak {
                    return Err(SdoAbort::VALUE_TOO_LOW);
                }
                let rated = status::rated_ma(cx.drive, od.get_u64(0x358E, 0).unwrap_or(0));
                let t = (i64::from(ma) * 1000 / rated).clamp(i64::from(i16::MIN), i64::from(i16::MAX)) as i16;
                if let Ok(r) = od.find(0x6071, 0) {
                    od.set_raw(r, &t.to_le_bytes());
                }
                cx.drive.on_write(od, 0x6071, 0, &t.to_le_bytes())?;
                Ok(Verdict::Store)
            }
            // §7.11.2.2: "changed values must be saved and the drive must be
            // restarted": stored, the drive takes them when it reloads its
            // parameters (NMT reset node, power-on).
            0x607D if (1..=2).contains(&sub) => {
                let x = le_u64(data) as u32 as i32;
                let other = od.get_i64(0x607D, 3 - sub).unwrap_or(0) as i32;
                let (lo, hi) = if sub == 1 { (x, other) } else { (other, x) };
                if lo > hi {
                    return Err(SdoAbort::MAX_LESS_THAN_MIN);
                }
                Ok(Verdict::Store)
            }
            // §7.9.2.1: −1 is reserved (0 linear, −2 PVT).
            0x60C0 if le_u64(data) as u16 as i16 == -1 => Err(SdoAbort::INVALID_VALUE),
            // §7.9.2.3: the period changes when both subs are written, and
            // only to whole milliseconds.
            0x60C2 if (1..=2).contains(&sub) => match self.period.write(sub, le_u64(data) as u8)? {
                timing::PeriodWrite::Hold => Ok(Verdict::Store),
                timing::PeriodWrite::Complete(other, v) => {
                    cx.drive.on_write(od, 0x60C2, other, &[v])?;
                    Ok(Verdict::Pass)
                }
            },
            i if params::FORWARDED.contains(&i) => {
                self.forward(cx, od, index, sub, data)?;
                Ok(Verdict::Store)
            }
            // §7.2.2.11/12: the latches are the touch probes.
            0x20A4 => {
                self.latch_control(cx, od, le_u64(data) as u16)?;
                Ok(Verdict::Store)
            }
            0x20A5 => {
                self.latch_acknowledge(cx, od, le_u64(data) as u16)?;
                Ok(Verdict::Handled)
            }
            // §7.2.2.14: reset the change flags of DIN1–7 (60FDh bits 24–30).
            0x20B8 => {
                self.inputs.reset_changes(le_u64(data) as u16);
                Ok(Verdict::Store)
            }
            // §7.2.2.15: brake control by the fieldbus.
            0x345A if sub == 1 => {
                self.brake.command(le_u64(data) as u16);
                Ok(Verdict::Store)
            }
            0x3450 => {
                self.brake.manual(le_u64(data) as u8)?;
                Ok(Verdict::Store)
            }
            // DRV.NVSAVE (§8.1.3): save the parameters, as 1010h:1.
            0x35EB => {
                cx.request(Request::StoreParameters);
                Ok(Verdict::Handled)
            }
            // PL.ERRFTHRESH (§8.1.3 "max. following error") is 6065h.
            0x35C7 => {
                self.local_write(cx, od, 0x6065, 0, &(le_u64(data) as u32).to_le_bytes())?;
                Ok(Verdict::Store)
            }
            // MT.SET (§8.1.3): the pp set-point stored as motion task n.
            0x3431 => {
                let n = le_u64(data) as usize;
                let cntl = self.names.iter().find(|(m, _, _)| m == "MT.CNTL").map(|&(_, i, s)| (i, s));
                match self.tasks.get_mut(n) {
                    Some(t) => *t = ascii::current_task(od, cntl),
                    None => return Err(SdoAbort::VALUE_TOO_HIGH),
                }
                Ok(Verdict::Store)
            }
            _ => return Ok(None),
        };
        verdict.map(Some)
    }
}
