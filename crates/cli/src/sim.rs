//! A synchronous master on the simulated bus (`drivebus_bus::Bus`): what
//! the demo uses. Time is simulated, so the demo is exact and repeatable;
//! every value it reports came over the bus in frames.

use drivebus_bus::{Bus, BusConfig, ProbeId};
use drivebus_can::{Duration, Frame, Instant};
use drivebus_sdo::client::{Protocol, SdoClient, SdoClientConfig};

use crate::link::SdoFailure;
use crate::vdrive::{DriveSpec, build};

/// The master's station and the drives on a simulated bus.
pub struct SimMaster {
    /// The bus.
    pub bus: Bus,
    probe: ProbeId,
    /// Frames received but not consumed by an SDO transfer.
    pub backlog: Vec<(Instant, Frame)>,
    /// SDO transfers done.
    pub sdo_count: u64,
}

impl SimMaster {
    /// A bus at `bitrate` with `specs` attached (not yet booted: they boot
    /// at the first step).
    pub fn new(bitrate: u32, specs: &[DriveSpec]) -> anyhow::Result<SimMaster> {
        let mut bus = Bus::new(BusConfig { log: false, ..BusConfig::with_bitrate(bitrate) });
        let probe = bus.attach_probe();
        for s in specs {
            bus.attach(build(*s, None, Default::default())?);
        }
        Ok(SimMaster { bus, probe, backlog: Vec::new(), sdo_count: 0 })
    }

    /// Simulated time now.
    pub fn now(&self) -> Instant {
        self.bus.now()
    }

    /// Queues a frame from the master.
    pub fn send(&mut self, f: Frame) {
        self.bus.send_from(self.probe, f);
    }

    /// Advances `d`; received frames go to the backlog.
    pub fn run_for(&mut self, d: Duration) {
        let until = self.bus.now() + d;
        self.bus.run_until(until);
        let got = self.bus.take_received_timed(self.probe);
        self.backlog.extend(got);
    }

    /// Takes the backlog.
    pub fn take(&mut self) -> Vec<(Instant, Frame)> {
        std::mem::take(&mut self.backlog)
    }

    fn transfer(&mut self, node: u8, index: u16, sub: u8, data: Option<&[u8]>) -> anyhow::Result<Vec<u8>> {
        let cfg = SdoClientConfig { retries: 0, ..SdoClientConfig::for_node(node) };
        let mut c = SdoClient::new(cfg);
        let mut out: Vec<Frame> = Vec::new();
        let now = self.now();
        let write = data.is_some();
        let fail =
            |error| SdoFailure { node, index, sub, write, error, timeout: std::time::Duration::from_secs(1) };
        match data {
            Some(d) => c.start_download(index, sub, d, Protocol::Auto, now, &mut out),
            None => c.start_upload(index, sub, Protocol::Auto, now, &mut out),
        }
        .map_err(|e| anyhow::Error::new(fail(e)))?;
        self.sdo_count += 1;
        loop {
            for f in out.drain(..) {
                self.send(f);
            }
            if let Some(r) = c.take_result() {
                return r.map(|x| x.into_data()).map_err(|e| anyhow::Error::new(fail(e)));
            }
            let until = self.bus.now() + Duration::from_micros(100);
            self.bus.run_until(until);
            for (t, f) in self.bus.take_received_timed(self.probe) {
                if f.id() == cfg.rx_id {
                    c.handle_frame(&f, t, &mut out);
                } else {
                    self.backlog.push((t, f));
                }
            }
            let now = self.now();
            c.poll(now, &mut out);
        }
    }

    /// SDO read.
    pub fn read(&mut self, node: u8, index: u16, sub: u8) -> anyhow::Result<Vec<u8>> {
        self.transfer(node, index, sub, None)
    }

    /// SDO read of an integer (sign-extended for 1, 2, 4 bytes when `signed`).
    pub fn read_int(&mut self, node: u8, index: u16, sub: u8, signed: bool) -> anyhow::Result<i64> {
        let d = self.read(node, index, sub)?;
        let mut b = [0u8; 8];
        let n = d.len().min(8);
        b[..n].copy_from_slice(&d[..n]);
        let u = u64::from_le_bytes(b);
        Ok(if signed && (1..8).contains(&n) {
            let sh = 64 - 8 * n as u32;
            ((u << sh) as i64) >> sh
        } else {
            u as i64
        })
    }

    /// SDO write.
    pub fn write(&mut self, node: u8, index: u16, sub: u8, data: &[u8]) -> anyhow::Result<()> {
        self.transfer(node, index, sub, Some(data)).map(|_| ())
    }

    /// Maps `entries` into PDO `n` (0-based) of `node`, CiA 301 §7.2.2
    /// order: invalidate, clear, map, count, type, validate.
    pub fn map_pdo(
        &mut self,
        node: u8,
        tpdo: bool,
        n: u16,
        entries: &[u32],
        transmission: u8,
    ) -> anyhow::Result<u32> {
        let (comm, map) = if tpdo { (0x1800 + n, 0x1A00 + n) } else { (0x1400 + n, 0x1600 + n) };
        let cob = self.read_int(node, comm, 1, false)? as u32;
        self.write(node, comm, 1, &(cob | 0x8000_0000).to_le_bytes())?;
        self.write(node, map, 0, &[0])?;
        for (k, e) in entries.iter().enumerate() {
            self.write(node, map, k as u8 + 1, &e.to_le_bytes())?;
        }
        self.write(node, map, 0, &[entries.len() as u8])?;
        self.write(node, comm, 2, &[transmission])?;
        let cob = cob & 0x7FF;
        self.write(node, comm, 1, &cob.to_le_bytes())?;
        Ok(cob)
    }

    /// Switches TPDO `n` (0-based) of `node` off (COB-ID bit 31); a PDO
    /// the device does not have is fine.
    pub fn disable_tpdo(&mut self, node: u8, n: u16) -> anyhow::Result<()> {
        match self.read_int(node, 0x1800 + n, 1, false) {
            Ok(cob) => self.write(node, 0x1800 + n, 1, &((cob as u32) | 0x8000_0000).to_le_bytes()),
            Err(_) => Ok(()),
        }
    }
}
