//! The objects of a hosted slave for a local tool (the page of
//! `drivebus ethercat serve --http`): one entry read or written through
//! the slave's own read and write path, the path its CoE server takes for
//! an SDO upload or download, so access rights, limits, hooks and the
//! EtherCAT rules apply and a refusal is the abort a master would get;
//! and [`Watch`], entries sampled after every frame that carried a
//! slave's process data. The external master keeps the mailbox: nothing
//! here goes through it.
//!
//! Positions are line positions from 1, as [`crate::SlaveState`] gives them.

use crate::described::DescribedSlave;
use crate::drive::DriveSlave;
use crate::host::{BoxDevice, Host};
use drivebus_can::Instant;
use drivebus_coe::ObjectAccess;
use drivebus_esc::segment::Segment;
use drivebus_od::{ObjectDictionary, SdoAbort};
use drivebus_personality::ecat::rules;

/// Why an object of a hosted slave could not be read or written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObjectError {
    /// No slave at this position.
    NoSlave {
        /// The position asked for.
        position: usize,
        /// Slaves on the line.
        count: usize,
    },
    /// The slave has no CoE dictionary (an I/O terminal from its EEPROM
    /// image, a device whose description announces no CoE).
    NoDictionary {
        /// The position asked for.
        position: usize,
    },
    /// The slave is powered off (a fault of the line).
    PoweredOff {
        /// The position asked for.
        position: usize,
    },
    /// The slave refused: the SDO abort a master would get.
    Abort(SdoAbort),
}

impl std::fmt::Display for ObjectError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            ObjectError::NoSlave { position, count } => {
                write!(f, "no slave at position {position}: the line has {count} (positions 1..{count})")
            }
            ObjectError::NoDictionary { position } => write!(
                f,
                "slave {position} has no CoE object dictionary (an I/O device without a mailbox): only its process data exists"
            ),
            ObjectError::PoweredOff { position } => {
                write!(f, "slave {position} is powered off: power it on first")
            }
            ObjectError::Abort(a) => {
                write!(
                    f,
                    "{} (SDO abort {:08X}h)",
                    a.description().unwrap_or("manufacturer-specific abort"),
                    a.0
                )
            }
        }
    }
}

impl std::error::Error for ObjectError {}

/// `f` on a device's objects at `now`; `None` for a device without a
/// CoE dictionary.
fn access<R>(dev: &mut BoxDevice, now: Instant, f: impl FnOnce(&mut dyn ObjectAccess) -> R) -> Option<R> {
    let any = dev.as_any_mut()?;
    if any.is::<DriveSlave>() {
        return any.downcast_mut::<DriveSlave>().map(|d| d.app_mut().with_objects(now, f));
    }
    any.downcast_mut::<DescribedSlave>()?.app_mut().with_objects(f)
}

/// Runs `f` on the objects of the slave at `position` (from 1), now.
pub fn with_objects<R>(
    host: &Host,
    position: usize,
    f: impl FnOnce(&mut dyn ObjectAccess) -> R,
) -> Result<R, ObjectError> {
    // Deadlines due first: the drive is where it would be for a master.
    host.poll();
    let now = host.clock().now();
    host.with_segment(|seg| {
        let count = seg.devices().len();
        let i =
            position.checked_sub(1).filter(|i| *i < count).ok_or(ObjectError::NoSlave { position, count })?;
        if !seg.is_powered(i) {
            return Err(ObjectError::PoweredOff { position });
        }
        let dev = seg.device_mut(i).ok_or(ObjectError::NoSlave { position, count })?;
        access(dev, now, f).ok_or(ObjectError::NoDictionary { position })
    })
}

/// Reads `index:sub` of the slave at `position` as a CoE SDO upload would.
pub fn read(host: &Host, position: usize, index: u16, sub: u8) -> Result<Vec<u8>, ObjectError> {
    with_objects(host, position, |a| a.read(index, sub).map(<[u8]>::to_vec))?.map_err(ObjectError::Abort)
}

/// Writes `data` to `index:sub` of the slave at `position` as a CoE SDO
/// download would.
pub fn write(host: &Host, position: usize, index: u16, sub: u8, data: &[u8]) -> Result<(), ObjectError> {
    with_objects(host, position, |a| a.write(index, sub, data))?.map_err(ObjectError::Abort)
}

/// A copy of the slave's dictionary (names, types, access, limits,
/// defaults; values as they are now).
pub fn dictionary(host: &Host, position: usize) -> Result<ObjectDictionary, ObjectError> {
    with_objects(host, position, |a| a.dictionary().clone())
}

/// Whether `index:sub` is mapped in a PDO that 1C12h or 1C13h assigns in
/// `od` now (ETG.1000.6 §5.6.7.4): it moves with the process data.
pub fn in_process_data(od: &ObjectDictionary, index: u16, sub: u8) -> bool {
    let key = (u32::from(index) << 16) | (u32::from(sub) << 8);
    [0x1C12, 0x1C13].into_iter().flat_map(|a| rules::assigned(od, a)).any(|pdo| {
        // A mapping entry is index, sub-index, bit length.
        rules::entries(od, pdo).iter().any(|e| e & 0xFFFF_FF00 == key)
    })
}

/// A device's process-data count (input updates plus output updates)
/// and its dictionary; `None` without a CoE dictionary.
fn cycles_and_dictionary(dev: &mut BoxDevice) -> Option<(u64, &ObjectDictionary)> {
    let any = dev.as_any_mut()?;
    if any.is::<DriveSlave>() {
        let app = any.downcast_mut::<DriveSlave>()?.app();
        let s = app.stats();
        return Some((s.inputs_sampled + s.outputs_applied, app.device().node.od()));
    }
    let app = any.downcast_mut::<DescribedSlave>()?.app();
    let s = app.stats();
    Some((s.inputs_produced + s.outputs_applied, app.dictionary()?))
}

/// Entries of hosted slaves sampled once per process-data cycle: after a
/// frame in which a slave's inputs were latched or its outputs applied,
/// the values that cycle exchanged (the TxPDO entries were refreshed
/// through the read path for the frame, the RxPDO entries written by
/// it). Run it from a [`Host::observe_frames`] observer.
#[derive(Debug, Clone)]
pub struct Watch {
    entries: Vec<(usize, u16, u8)>,
    /// Per entry, the slave's process-data count at the last look.
    last: Vec<Option<u64>>,
}

impl Watch {
    /// Watches `(position, index, sub)` entries.
    pub fn new(entries: Vec<(usize, u16, u8)>) -> Watch {
        let last = vec![None; entries.len()];
        Watch { entries, last }
    }

    /// After a frame: `sample(i, bytes)` for every entry `i` whose slave
    /// exchanged process data since the last look (the first look only
    /// notes where each slave is). Entries of absent slaves, slaves
    /// without a dictionary, or objects they lack give nothing.
    pub fn after_frame(&mut self, seg: &mut Segment<BoxDevice>, mut sample: impl FnMut(usize, &[u8])) {
        for (i, &(position, index, sub)) in self.entries.iter().enumerate() {
            let Some(dev) = position.checked_sub(1).and_then(|p| seg.device_mut(p)) else { continue };
            let Some((cycles, od)) = cycles_and_dictionary(dev) else { continue };
            let was = self.last[i].replace(cycles);
            if was.is_some_and(|w| w != cycles)
                && let Some(e) = od.get(index, sub)
            {
                sample(i, e.bytes());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Clock;
    use crate::described::{self, Member};
    use drivebus_esc::frame::{DatagramCommand, FrameBuilder, position_address};

    fn line() -> Host {
        let members = vec![
            Member::Drive(crate::drive::profile("ipos").unwrap()),
            Member::Drive(crate::drive::profile("generic").unwrap()),
        ];
        Host::line(described::devices(&members, None).unwrap(), Clock::simulated(Instant::ZERO))
    }

    /// Reads and writes take the drive's write path: 6060h written reads
    /// back, a read-only 6041h refuses with 0601 0002h and keeps its
    /// value, an absent object is 0602 0000h; positions count from 1.
    #[test]
    fn read_and_write_through_the_write_path() {
        let host = line();
        let sw = read(&host, 1, 0x6041, 0).unwrap();
        assert_eq!(sw.len(), 2);
        let mode1 = read(&host, 1, 0x6060, 0).unwrap();
        write(&host, 2, 0x6060, 0, &[3]).unwrap();
        assert_eq!(read(&host, 2, 0x6060, 0).unwrap(), [3]);
        assert_eq!(read(&host, 1, 0x6060, 0).unwrap(), mode1, "the other drive keeps its mode");
        assert_eq!(write(&host, 1, 0x6041, 0, &[0, 0]), Err(ObjectError::Abort(SdoAbort::WRITE_READ_ONLY)));
        assert_eq!(read(&host, 1, 0x6041, 0).unwrap(), sw);
        assert_eq!(read(&host, 1, 0x5FFF, 0), Err(ObjectError::Abort(SdoAbort::NO_OBJECT)));
        assert_eq!(read(&host, 3, 0x6041, 0), Err(ObjectError::NoSlave { position: 3, count: 2 }));
        assert_eq!(read(&host, 0, 0x6041, 0), Err(ObjectError::NoSlave { position: 0, count: 2 }));
        assert!(
            ObjectError::Abort(SdoAbort::WRITE_READ_ONLY).to_string().contains("read only"),
            "{}",
            ObjectError::Abort(SdoAbort::WRITE_READ_ONLY)
        );
        host.with_segment(|s| s.power_off(0));
        assert_eq!(read(&host, 1, 0x6041, 0), Err(ObjectError::PoweredOff { position: 1 }));
    }

    /// The dictionary names the objects; the iPOS's default TxPDO maps
    /// 6064h, 6040h is in an RxPDO, 1018h:01 in neither.
    #[test]
    fn dictionary_and_process_data_entries() {
        let host = line();
        let od = dictionary(&host, 1).unwrap();
        assert!(od.get(0x6064, 0).is_some_and(|e| !e.name.is_empty()));
        assert!(in_process_data(&od, 0x6064, 0));
        assert!(in_process_data(&od, 0x6040, 0));
        assert!(!in_process_data(&od, 0x1018, 1));
    }

    /// A device without CoE has no dictionary to reach.
    #[test]
    fn a_device_without_coe_has_no_objects() {
        let d = crate::dio::slave(&crate::dio::DioConfig::default());
        let host = Host::line(vec![Box::new(d)], Clock::simulated(Instant::ZERO));
        assert_eq!(read(&host, 1, 0x1000, 0), Err(ObjectError::NoDictionary { position: 1 }));
    }

    /// The watch samples only after frames that exchanged process data:
    /// a frame without (an AL status read) gives nothing.
    #[test]
    fn the_watch_samples_per_process_data_cycle() {
        let host = line();
        let mut w = Watch::new(vec![(1, 0x6041, 0), (3, 0x6041, 0)]);
        let mut got = Vec::new();
        let frame = || {
            let mut buf = [0u8; 64];
            let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
            b.push(DatagramCommand::Aprd, 1, position_address(0, 0x0130), &[0, 0]).unwrap();
            let n = b.finish();
            host.process_frame(&mut buf[..n]);
        };
        frame();
        host.with_segment(|s| w.after_frame(s, |i, b| got.push((i, b.to_vec()))));
        frame();
        host.with_segment(|s| w.after_frame(s, |i, b| got.push((i, b.to_vec()))));
        assert!(got.is_empty(), "{got:?}");
        // A process-data cycle of slave 1 (its inputs latched).
        crate::drive::with_drive(&host, 0, |d| {
            let mut data = vec![0u8; 64];
            drivebus_esc::slave::SlaveApp::inputs(d.app_mut(), &mut data, Instant::ZERO);
        });
        host.with_segment(|s| w.after_frame(s, |i, b| got.push((i, b.to_vec()))));
        assert_eq!(got.len(), 1);
        assert_eq!((got[0].0, got[0].1.len()), (0, 2));
    }
}
