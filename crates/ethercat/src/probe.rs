//! An ethercrab master scenario for digital I/O lines: discovery, INIT →
//! PRE-OP → SAFE-OP → OP (optionally with DC SYNC0), then cyclic process
//! data with a check of the working counter and of every slave's inputs on
//! every cycle. The in-process tests, the veth test and the
//! `drivebus-ecat-probe` binary all run this one scenario.
//!
//! Data check: the master writes a new pattern to every slave's outputs
//! each cycle; a [`crate::dio`] slave answers `outputs ^ mask`. The inputs
//! read in cycle k must show the outputs of cycle k − 1 (they are latched
//! after the master's previous read, or at the SYNC0 between the frames in
//! DC mode). Inputs one cycle older still are counted as `late` (a real-
//! time scheduler let the frame overtake the SYNC0 pulse); anything else is
//! `bad`.

use crate::dio::VENDOR_ID;
use drivebus_can::Duration;
use ethercrab::error::Error;
use ethercrab::subdevice_group::DcConfiguration;
use ethercrab::{DcSync, MainDevice, RegisterAddress};
use std::future::Future;

/// Most slaves the scenario handles.
pub const MAX_SUBDEVICES: usize = 64;
/// Largest process image.
pub const MAX_PDI: usize = 512;

/// What to run.
#[derive(Debug, Clone)]
pub struct ScenarioConfig {
    /// Input XOR mask of every slave, in line order (the slave count).
    pub masks: Vec<u32>,
    /// Cycles of process data.
    pub cycles: u32,
    /// Cycle time when not in DC mode.
    pub cycle: Duration,
    /// DC with this SYNC0 period (and a SYNC0 shift of half a period).
    pub dc: Option<Duration>,
    /// Process-data watchdog to program (0x0420, 100 µs units), so a stall
    /// of the host does not trip it.
    pub watchdog_units: u16,
}

/// Identity of a discovered slave.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Found {
    /// ethercrab's name (SII General "order" string).
    pub name: String,
    /// Vendor ID.
    pub vendor_id: u32,
    /// Product code.
    pub product_id: u32,
    /// Serial number.
    pub serial: u32,
    /// Configured station address.
    pub address: u16,
    /// Propagation delay ethercrab computed, ns.
    pub propagation_delay: u32,
    /// Input bytes.
    pub inputs: usize,
    /// Output bytes.
    pub outputs: usize,
}

/// What happened.
#[derive(Debug, Clone, Default)]
pub struct ScenarioReport {
    /// Slaves found, in line order.
    pub found: Vec<Found>,
    /// Cycles run.
    pub cycles: u32,
    /// Cycles whose LRW working counter was not 3 per slave.
    pub bad_wkc: u32,
    /// Slave-cycles with inputs that match neither of the last two outputs.
    pub bad_data: u32,
    /// Slave-cycles with inputs one cycle later than expected.
    pub late_data: u32,
    /// The working counter expected on every cycle.
    pub expected_wkc: u16,
    /// DC: largest |cycle start offset − shift| seen, ns.
    pub max_dc_offset_error: u64,
}

impl ScenarioReport {
    /// One line for logs.
    pub fn summary(&self) -> String {
        format!(
            "slaves={} cycles={} expected_wkc={} bad_wkc={} bad_data={} late_data={} max_dc_offset_error_ns={}",
            self.found.len(),
            self.cycles,
            self.expected_wkc,
            self.bad_wkc,
            self.bad_data,
            self.late_data,
            self.max_dc_offset_error
        )
    }
}

fn pattern(cycle: u32, slave: usize) -> u32 {
    cycle.wrapping_mul(0x9E37_79B9).rotate_left(slave as u32 * 7) ^ slave as u32
}

fn to_u32(b: &[u8]) -> u32 {
    let mut x = [0u8; 4];
    let n = b.len().min(4);
    x[..n].copy_from_slice(&b[..n]);
    u32::from_le_bytes(x)
}

fn mask_to(v: u32, bytes: usize) -> u32 {
    if bytes >= 4 { v } else { v & ((1u32 << (bytes * 8)) - 1) }
}

/// Runs the scenario on `md`. `now` is the master's clock for DC offsets;
/// `sleep` waits (really or in simulated time).
pub async fn run<S, F>(
    md: &MainDevice<'_>,
    now: impl Fn() -> u64 + Copy,
    cfg: &ScenarioConfig,
    mut sleep: S,
) -> Result<ScenarioReport, Error>
where
    S: FnMut(Duration) -> F,
    F: Future<Output = ()>,
{
    let mut group = md.init_single_group::<MAX_SUBDEVICES, MAX_PDI>(now).await?;
    let mut report = ScenarioReport::default();
    for mut sd in group.iter_mut(md) {
        if cfg.dc.is_some() {
            sd.set_dc_sync(DcSync::Sync0);
        }
        sd.register_write(RegisterAddress::SyncManagerWatchdog, cfg.watchdog_units).await?;
    }
    let group = group.into_pre_op_pdi(md).await?;
    for sd in group.iter(md) {
        let id = sd.identity();
        let io = sd.io_raw();
        report.found.push(Found {
            name: sd.name().to_owned(),
            vendor_id: id.vendor_id,
            product_id: id.product_id,
            serial: id.serial,
            address: sd.configured_address(),
            propagation_delay: sd.propagation_delay(),
            inputs: io.inputs().len(),
            outputs: io.outputs().len(),
        });
    }
    let n = report.found.len();
    report.expected_wkc = 3 * n as u16;
    let sizes: Vec<usize> = report.found.iter().map(|f| f.inputs).collect();
    let masks: Vec<u32> = (0..n).map(|i| cfg.masks.get(i).copied().unwrap_or(0)).collect();
    let mut history: Vec<Vec<u32>> = vec![vec![0; n]; 3];

    let check = |report: &mut ScenarioReport, k: u32, inputs: &[u32], history: &[Vec<u32>]| {
        for i in 0..n {
            let bytes = sizes[i];
            let want1 = mask_to(history[(k as usize + 2) % 3][i] ^ masks[i], bytes);
            let want2 = mask_to(history[(k as usize + 1) % 3][i] ^ masks[i], bytes);
            if k < 2 {
                continue;
            }
            if inputs[i] == want1 {
            } else if inputs[i] == want2 {
                report.late_data += 1;
            } else {
                report.bad_data += 1;
            }
        }
    };

    let mut inputs = vec![0u32; n];
    if let Some(period) = cfg.dc {
        let group = group
            .configure_dc_sync(
                md,
                DcConfiguration {
                    start_delay: Duration::from_millis(100),
                    sync0_period: period,
                    sync0_shift: period / 2,
                },
            )
            .await?;
        let group = group.into_safe_op(md).await?.request_into_op(md).await?;
        // Cycle until everyone reached OP (the slaves wait for SYNC0).
        let mut k = 0u32;
        let mut in_op = false;
        while k < cfg.cycles {
            for (i, sd) in group.iter(md).enumerate() {
                let v = pattern(k, i);
                history[k as usize % 3][i] = v;
                let mut o = sd.outputs_raw_mut();
                let b = v.to_le_bytes();
                let l = o.len().min(4);
                o[..l].copy_from_slice(&b[..l]);
            }
            let r = group.tx_rx_dc(md).await?;
            if !in_op {
                in_op = r.all_op();
                sleep(r.extra.next_cycle_wait).await;
                continue; // the data check starts once all are in OP
            }
            if r.working_counter != report.expected_wkc {
                report.bad_wkc += 1;
            }
            for (i, sd) in group.iter(md).enumerate() {
                inputs[i] = to_u32(sd.io_raw().inputs());
            }
            check(&mut report, k, &inputs, &history);
            let off = r.extra.cycle_start_offset.as_nanos() as i64 - (period / 2).as_nanos() as i64;
            report.max_dc_offset_error = report.max_dc_offset_error.max(off.unsigned_abs());
            k += 1;
            report.cycles = k;
            sleep(r.extra.next_cycle_wait).await;
        }
        group.into_safe_op(md).await?;
    } else {
        let group = group.into_safe_op(md).await?.into_op(md).await?;
        for k in 0..cfg.cycles {
            for (i, sd) in group.iter(md).enumerate() {
                let v = pattern(k, i);
                history[k as usize % 3][i] = v;
                let mut o = sd.outputs_raw_mut();
                let b = v.to_le_bytes();
                let l = o.len().min(4);
                o[..l].copy_from_slice(&b[..l]);
            }
            let r = group.tx_rx(md).await?;
            if r.working_counter != report.expected_wkc {
                report.bad_wkc += 1;
            }
            for (i, sd) in group.iter(md).enumerate() {
                inputs[i] = to_u32(sd.io_raw().inputs());
            }
            check(&mut report, k, &inputs, &history);
            report.cycles = k + 1;
            sleep(cfg.cycle).await;
        }
        group.into_safe_op(md).await?;
    }
    Ok(report)
}

/// True if every slave is a drivebus device.
pub fn all_drivebus(report: &ScenarioReport) -> bool {
    report.found.iter().all(|f| f.vendor_id == VENDOR_ID)
}
