//! An ethercrab master scenario for lines of CoE drives: discovery and
//! identity (SII and 1018h over CoE), the PDO mapping read over CoE,
//! optionally the manual's remapping in PRE-OP (iPOS E10/E11, §2.5/§2.6),
//! INIT → PRE-OP → SAFE-OP → OP (free run or DC SYNC0), then cyclic
//! process data: every drive is enabled through its controlword and
//! follows a cyclic synchronous position (csp) sine, the working counter
//! and the following error checked on every cycle. The in-process tests,
//! the veth test and the `drivebus-ecat-drive-probe` binary run this one
//! scenario.

use drivebus_can::Duration;
use drivebus_cia402::codes::EnableStep;
use ethercrab::error::Error;
use ethercrab::subdevice_group::DcConfiguration;
use ethercrab::{DcSync, MainDevice, RegisterAddress, SubDeviceRef};
use std::future::Future;
use std::ops::Deref;

/// Most slaves the scenario handles.
pub const MAX_SUBDEVICES: usize = 16;
/// Largest process image.
pub const MAX_PDI: usize = 1024;
/// Technosoft's vendor ID (iPOS §4.8.6).
pub const TECHNOSOFT: u32 = 0x1A3;

/// What to run.
#[derive(Debug, Clone)]
pub struct DriveScenario {
    /// Cycles of process data once every drive is in OP.
    pub cycles: u32,
    /// Cycle time when not in DC mode.
    pub cycle: Duration,
    /// DC with this SYNC0 period (and a SYNC0 shift of half a period).
    pub dc: Option<Duration>,
    /// Remap in PRE-OP as the iPOS manual's E10 (RxPDO3 = controlword +
    /// modes of operation, assigned third) and E11 (TxPDO4 = position
    /// actual value + digital inputs, assigned fourth) do.
    pub remap: bool,
    /// Sine amplitude of the csp trajectory \[position units\].
    pub amplitude: f64,
    /// Sine period in cycles.
    pub period_cycles: u32,
    /// Process-data watchdog to program (0x0420, 100 µs units).
    pub watchdog_units: u16,
}

impl Default for DriveScenario {
    fn default() -> Self {
        DriveScenario {
            cycles: 5_000,
            cycle: Duration::from_millis(1),
            dc: None,
            remap: false,
            amplitude: 4000.0,
            period_cycles: 2000,
            watchdog_units: 1000,
        }
    }
}

/// One PDO as read over CoE: the master's type.
pub use crate::master::PdoMapping;

/// A discovered drive.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FoundDrive {
    /// ethercrab's name (SII General "order" string).
    pub name: String,
    /// Identity from the SII: vendor, product, revision, serial.
    pub sii_identity: [u32; 4],
    /// 1018h:01–04 read over CoE.
    pub coe_identity: [u32; 4],
    /// Configured station address.
    pub address: u16,
    /// RxPDOs as 1C12h assigns them, read over CoE after any remapping.
    pub rx: Vec<PdoMapping>,
    /// TxPDOs as 1C13h assigns them.
    pub tx: Vec<PdoMapping>,
    /// Output bytes ethercrab sized.
    pub outputs: usize,
    /// Input bytes ethercrab sized.
    pub inputs: usize,
    /// 6065h following error window.
    pub window: u32,
}

/// What happened on one drive.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AxisReport {
    /// The cycle it reached Operation enabled.
    pub enabled_at: Option<u32>,
    /// Cycles it spent in Operation enabled.
    pub enabled_cycles: u32,
    /// Cycles with the fault bit (statusword bit 3) once it had been
    /// enabled.
    pub fault_cycles: u32,
    /// Largest |demand of the previous cycle − position actual value|.
    pub max_following: f64,
    /// Largest |position actual value − start|: the drive really moved.
    pub travel: f64,
}

/// What happened.
#[derive(Debug, Clone, Default)]
pub struct DriveReport {
    /// Drives found, in line order.
    pub found: Vec<FoundDrive>,
    /// Cycles run in OP.
    pub cycles: u32,
    /// Cycles whose LRW working counter was not 3 per drive.
    pub bad_wkc: u32,
    /// The working counter expected on every cycle.
    pub expected_wkc: u16,
    /// Per drive.
    pub axes: Vec<AxisReport>,
    /// DC: largest |cycle start offset − shift| seen, ns.
    pub max_dc_offset_error: u64,
    /// The trajectory's amplitude.
    pub amplitude: f64,
}

impl DriveReport {
    /// One line for logs.
    pub fn summary(&self) -> String {
        let following: Vec<String> = self.axes.iter().map(|a| format!("{:.0}", a.max_following)).collect();
        format!(
            "drives={} cycles={} expected_wkc={} bad_wkc={} enabled={} faults={} max_following=[{}] \
             max_dc_offset_error_ns={}",
            self.found.len(),
            self.cycles,
            self.expected_wkc,
            self.bad_wkc,
            self.axes.iter().filter(|a| a.enabled_at.is_some()).count(),
            self.axes.iter().map(|a| a.fault_cycles).sum::<u32>(),
            following.join(","),
            self.max_dc_offset_error
        )
    }

    /// Every drive enabled, followed within its window, moved (more than
    /// half the amplitude), never faulted, and every cycle had the
    /// expected working counter.
    pub fn all_followed(&self) -> bool {
        self.bad_wkc == 0
            && self.axes.len() == self.found.len()
            && self.axes.iter().zip(&self.found).all(|(a, f)| {
                a.enabled_at.is_some()
                    && a.fault_cycles == 0
                    && a.max_following <= f64::from(f.window)
                    && a.travel > 0.5 * self.amplitude
            })
    }
}

async fn mapping<S: Deref<Target = ethercrab::SubDevice>>(
    sd: &SubDeviceRef<'_, S>,
    assign: u16,
) -> Result<Vec<PdoMapping>, Error> {
    let n: u8 = sd.sdo_read(assign, 0).await?;
    let mut out = Vec::new();
    for s in 1..=n {
        let pdo: u16 = sd.sdo_read(assign, s).await?;
        let m: u8 = sd.sdo_read(pdo, 0).await?;
        let mut entries = Vec::new();
        for e in 1..=m {
            entries.push(sd.sdo_read::<u32>(pdo, e).await?);
        }
        out.push((pdo, entries));
    }
    Ok(out)
}

/// iPOS §2.5 (E10) and §2.6 (E11), as SDO downloads in PRE-OP, on an
/// iPOS: RxPDO3 1602h := controlword + modes of operation, assigned
/// third; TxPDO4 1A03h := position actual value + digital inputs,
/// assigned fourth. The examples leave 1C12h:02 and 1C13h:03 as they are;
/// with the counts 3 and 4 those must already name a PDO (E10/E11 analyst
/// notes), so every slot below is assigned as E09 step 6 says. A generic
/// servo gets the same E09 procedure on its free PDOs (its 1602h/1A02h
/// carry the position set): 1603h := controlword + modes of operation
/// after 1602h, 1A03h as on the iPOS after 1A02h.
async fn remap<S: Deref<Target = ethercrab::SubDevice>>(
    sd: &SubDeviceRef<'_, S>,
    ipos: bool,
) -> Result<(), Error> {
    let (rx_pdo, rx, tx): (u16, &[u16], &[u16]) = if ipos {
        (0x1602, &[0x1600, 0x1601, 0x1602], &[0x1A00, 0x1A01, 0x1A02, 0x1A03])
    } else {
        (0x1603, &[0x1602, 0x1603], &[0x1A02, 0x1A03])
    };
    sd.sdo_write(0x1C12, 0, 0u8).await?;
    sd.sdo_write(rx_pdo, 0, 0u8).await?;
    sd.sdo_write(rx_pdo, 1, 0x6040_0010u32).await?;
    sd.sdo_write(rx_pdo, 2, 0x6060_0008u32).await?;
    sd.sdo_write(rx_pdo, 0, 2u8).await?;
    for (i, p) in rx.iter().enumerate() {
        sd.sdo_write(0x1C12, i as u8 + 1, *p).await?;
    }
    sd.sdo_write(0x1C12, 0, rx.len() as u8).await?;
    sd.sdo_write(0x1C13, 0, 0u8).await?;
    sd.sdo_write(0x1A03, 0, 0u8).await?;
    sd.sdo_write(0x1A03, 1, 0x6064_0020u32).await?;
    sd.sdo_write(0x1A03, 2, 0x60FD_0020u32).await?;
    sd.sdo_write(0x1A03, 0, 2u8).await?;
    for (i, p) in tx.iter().enumerate() {
        sd.sdo_write(0x1C13, i as u8 + 1, *p).await?;
    }
    sd.sdo_write(0x1C13, 0, tx.len() as u8).await?;
    Ok(())
}

/// Byte offsets of every occurrence of `(index, sub)` in a direction's image.
pub fn offsets(pdos: &[PdoMapping], index: u16, sub: u8) -> Vec<usize> {
    crate::master::image_layout(pdos)
        .filter(|m| m.is(index, sub) && m.bit_offset.is_multiple_of(8))
        .map(|m| m.bit_offset / 8)
        .collect()
}

/// One drive's process data and csp state.
#[derive(Debug, Clone, Default)]
struct Axis {
    cw: Vec<usize>,
    target: Vec<usize>,
    mode: Vec<usize>,
    sw: Option<usize>,
    pos: Option<usize>,
    start: f64,
    k: u32,
    previous: Option<f64>,
    report: AxisReport,
}

fn get(b: &[u8], off: Option<usize>, n: usize) -> i64 {
    let Some(o) = off else { return 0 };
    let mut x = [0u8; 8];
    if let Some(s) = b.get(o..o + n) {
        x[..n].copy_from_slice(s);
    }
    match n {
        2 => i64::from(u16::from_le_bytes([x[0], x[1]])),
        _ => i64::from(i32::from_le_bytes([x[0], x[1], x[2], x[3]])),
    }
}

fn put(b: &mut [u8], offs: &[usize], v: &[u8]) {
    for &o in offs {
        if let Some(s) = b.get_mut(o..o + v.len()) {
            s.copy_from_slice(v);
        }
    }
}

impl Axis {
    /// One cycle: the statusword and position read, the controlword and
    /// target to write (CiA 402-2 §6.2.1 device control, csp §6.7).
    fn step(&mut self, inputs: &[u8], outputs: &mut [u8], cycle: u32, s: &DriveScenario) {
        let sw = get(inputs, self.sw, 2) as u16;
        let pos = get(inputs, self.pos, 4) as f64;
        let step = EnableStep::from_statusword(sw);
        let (cw, target): (u16, f64) = if step == EnableStep::Done {
            self.report.enabled_at.get_or_insert(cycle);
            self.report.enabled_cycles += 1;
            if let Some(p) = self.previous {
                self.report.max_following = self.report.max_following.max((p - pos).abs());
            }
            self.report.travel = self.report.travel.max((pos - self.start).abs());
            self.k += 1;
            let phase = 2.0 * std::f64::consts::PI * f64::from(self.k) / f64::from(s.period_cycles.max(1));
            (step.cyclic_controlword(false), self.start + s.amplitude * phase.sin())
        } else {
            // A fault from before (a previous master left OP: 6007h) is
            // reset; one after the drive was enabled here is a failure.
            if step == EnableStep::FaultReset && self.report.enabled_at.is_some() {
                self.report.fault_cycles += 1;
            }
            self.start = pos;
            self.previous = None;
            (step.cyclic_controlword(!cycle.is_multiple_of(2)), pos)
        };
        let t = target.round() as i32;
        put(outputs, &self.cw, &cw.to_le_bytes());
        put(outputs, &self.target, &t.to_le_bytes());
        put(outputs, &self.mode, &[8]);
        self.previous = (step == EnableStep::Done).then_some(f64::from(t));
    }
}

/// Runs the scenario on `md`. `now` is the master's clock for DC offsets;
/// `sleep` waits (really or in simulated time).
pub async fn run<S, F>(
    md: &MainDevice<'_>,
    now: impl Fn() -> u64 + Copy,
    s: &DriveScenario,
    mut sleep: S,
) -> Result<DriveReport, Error>
where
    S: FnMut(Duration) -> F,
    F: Future<Output = ()>,
{
    let mut group = md.init_single_group::<MAX_SUBDEVICES, MAX_PDI>(now).await?;
    for mut sd in group.iter_mut(md) {
        if s.dc.is_some() {
            sd.set_dc_sync(DcSync::Sync0);
        }
        sd.register_write(RegisterAddress::SyncManagerWatchdog, s.watchdog_units).await?;
    }
    let mut report = DriveReport { amplitude: s.amplitude, ..DriveReport::default() };
    for sd in group.iter(md) {
        if s.remap {
            remap(&sd, sd.identity().vendor_id == TECHNOSOFT).await?;
        }
        // What TwinCAT's startup list writes after every reset (iPOS
        // §1.6.1): cyclic synchronous position.
        sd.sdo_write(0x6060, 0, 8i8).await?;
        let id = sd.identity();
        let mut coe = [0u32; 4];
        for (i, c) in coe.iter_mut().enumerate() {
            *c = sd.sdo_read(0x1018, i as u8 + 1).await?;
        }
        report.found.push(FoundDrive {
            name: sd.name().to_owned(),
            sii_identity: [id.vendor_id, id.product_id, id.revision, id.serial],
            coe_identity: coe,
            address: sd.configured_address(),
            rx: mapping(&sd, 0x1C12).await?,
            tx: mapping(&sd, 0x1C13).await?,
            outputs: 0,
            inputs: 0,
            window: sd.sdo_read(0x6065, 0).await?,
        });
    }
    let group = group.into_pre_op_pdi(md).await?;
    let mut axes = Vec::new();
    for (sd, f) in group.iter(md).zip(report.found.iter_mut()) {
        let io = sd.io_raw();
        (f.inputs, f.outputs) = (io.inputs().len(), io.outputs().len());
        axes.push(Axis {
            cw: offsets(&f.rx, 0x6040, 0),
            target: offsets(&f.rx, 0x607A, 0),
            mode: offsets(&f.rx, 0x6060, 0),
            sw: offsets(&f.tx, 0x6041, 0).first().copied(),
            pos: offsets(&f.tx, 0x6064, 0).first().copied(),
            ..Axis::default()
        });
    }
    let n = report.found.len();
    report.expected_wkc = 3 * n as u16;
    let mut k = 0u32;
    if let Some(period) = s.dc {
        let cfg = DcConfiguration {
            start_delay: Duration::from_millis(100),
            sync0_period: period,
            sync0_shift: period / 2,
        };
        let group = group.configure_dc_sync(md, cfg).await?;
        let group = group.into_safe_op(md).await?.request_into_op(md).await?;
        let mut in_op = false;
        while k < s.cycles {
            for (sd, a) in group.iter(md).zip(axes.iter_mut()) {
                let mut io = sd.io_raw_mut();
                let inputs = io.inputs().to_vec();
                a.step(&inputs, io.outputs(), k, s);
            }
            let r = group.tx_rx_dc(md).await?;
            if !in_op {
                in_op = r.all_op();
                sleep(r.extra.next_cycle_wait).await;
                continue;
            }
            if r.working_counter != report.expected_wkc {
                report.bad_wkc += 1;
            }
            let off = r.extra.cycle_start_offset.as_nanos() as i64 - (period / 2).as_nanos() as i64;
            report.max_dc_offset_error = report.max_dc_offset_error.max(off.unsigned_abs());
            k += 1;
            sleep(r.extra.next_cycle_wait).await;
        }
        group.into_safe_op(md).await?;
    } else {
        let group = group.into_safe_op(md).await?.into_op(md).await?;
        while k < s.cycles {
            for (sd, a) in group.iter(md).zip(axes.iter_mut()) {
                let mut io = sd.io_raw_mut();
                let inputs = io.inputs().to_vec();
                a.step(&inputs, io.outputs(), k, s);
            }
            let r = group.tx_rx(md).await?;
            if r.working_counter != report.expected_wkc {
                report.bad_wkc += 1;
            }
            k += 1;
            sleep(s.cycle).await;
        }
        group.into_safe_op(md).await?;
    }
    report.cycles = k;
    report.axes = axes.into_iter().map(|a| a.report).collect();
    Ok(report)
}
