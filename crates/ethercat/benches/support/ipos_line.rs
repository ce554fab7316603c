//! A line of emulated iPOS drives run by ethercrab 0.7.1 the way a real
//! application runs it: discovery, DC with SYNC0 at 1 ms (shift 0.5 ms),
//! cyclic synchronous position (6060h = 8) written in PRE-OP, SAFE-OP → OP,
//! then `tx_rx_dc` every cycle while each drive is brought to Operation
//! enabled and holds its position. Shared by the `drive_line` bench (over
//! the in-process link, simulated time) and the `veth_rtt` example (over
//! a veth pair, real time).

use ethercrab::error::Error;
use ethercrab::subdevice_group::DcConfiguration;
use ethercrab::{DcSync, MainDevice, RegisterAddress};
use std::future::Future;
use std::time::Duration;

/// Most drives on the line.
pub const MAX_SLAVES: usize = 64;
/// Process image: the iPOS default mapping has 6 output and 16 input bytes
/// per drive (§2.3).
pub const MAX_PDI: usize = MAX_SLAVES * 22;

/// What the cycles saw.
#[derive(Debug, Default)]
pub struct Cycles {
    /// Drives found.
    pub slaves: usize,
    /// Wall-clock time of every `tx_rx_dc` once all drives were in OP.
    pub round_trips: Vec<Duration>,
    /// Cycles in OP whose working counter was not 3 per drive.
    pub bad_wkc: u32,
    /// Drives in Operation enabled after the last cycle.
    pub enabled: usize,
}

/// The controlword that moves a drive one step towards Operation enabled
/// (CiA 402 device control), from its statusword.
fn controlword(sw: u16, cycle: u32) -> u16 {
    if sw & 0x08 != 0 {
        // Fault reset on a rising edge of bit 7.
        return if cycle.is_multiple_of(2) { 0x00 } else { 0x80 };
    }
    match sw & 0x6F {
        0x21 => 0x07,
        0x23 | 0x27 => 0x0F,
        _ => 0x06,
    }
}

/// Runs the line for `cycles` cycles in OP (after the cycles it takes to
/// get there). `hook(k)` runs before the `k`th cycle in OP; `sleep` waits
/// until the next cycle (really, or in simulated time).
pub async fn run<S, F>(
    md: &MainDevice<'_>,
    now: impl Fn() -> u64 + Copy,
    cycles: u32,
    mut sleep: S,
    mut hook: impl FnMut(u32),
) -> Result<Cycles, Error>
where
    S: FnMut(Duration) -> F,
    F: Future<Output = ()>,
{
    let mut group = md.init_single_group::<MAX_SLAVES, MAX_PDI>(now).await?;
    for mut sd in group.iter_mut(md) {
        sd.set_dc_sync(DcSync::Sync0);
        // 100 ms process-data watchdog (100 µs units).
        sd.register_write(RegisterAddress::SyncManagerWatchdog, 1000u16).await?;
    }
    for sd in group.iter(md) {
        sd.sdo_write(0x6060, 0, 8i8).await?;
    }
    let mut out = Cycles { slaves: group.len(), ..Cycles::default() };
    let expected = 3 * group.len() as u16;
    let group = group.into_pre_op_pdi(md).await?;
    let period = Duration::from_millis(1);
    let cfg = DcConfiguration {
        start_delay: Duration::from_millis(100),
        sync0_period: period,
        sync0_shift: period / 2,
    };
    let group = group.configure_dc_sync(md, cfg).await?;
    let group = group.into_safe_op(md).await?.request_into_op(md).await?;
    let (mut k, mut tick) = (0u32, 0u32);
    let mut in_op = false;
    while k < cycles {
        for sd in group.iter(md) {
            let mut io = sd.io_raw_mut();
            let i = io.inputs();
            let sw = u16::from_le_bytes([i[0], i[1]]);
            let pos = [i[2], i[3], i[4], i[5]];
            let o = io.outputs();
            o[..2].copy_from_slice(&controlword(sw, tick).to_le_bytes());
            // csp: the target is where the drive is (hold position).
            o[2..6].copy_from_slice(&pos);
        }
        if in_op {
            hook(k);
        }
        let t = std::time::Instant::now();
        let r = group.tx_rx_dc(md).await?;
        let rtt = t.elapsed();
        tick += 1;
        if in_op {
            out.round_trips.push(rtt);
            if r.working_counter != expected {
                out.bad_wkc += 1;
            }
            k += 1;
        } else {
            in_op = r.all_op();
        }
        sleep(r.extra.next_cycle_wait).await;
    }
    out.enabled = group
        .iter(md)
        .filter(|sd| {
            let io = sd.io_raw();
            let i = io.inputs();
            u16::from_le_bytes([i[0], i[1]]) & 0x6F == 0x27
        })
        .count();
    Ok(out)
}
