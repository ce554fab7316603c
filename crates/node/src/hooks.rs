//! Routing of object-dictionary hooks: communication objects go to the
//! service that owns them, everything else (and a veto on everything) to
//! the application.

use crate::app::Application;
use crate::storage::{Slot, Storage, encode_image};
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_can::Instant;
use drivebus_emcy::{Emcy, EmcyConsumer};
use drivebus_nmt::Nmt;
use drivebus_od::{ObjectDictionary, ObjectHooks, PersistGroup, SdoAbort, WriteOutcome, le_u64};
use drivebus_pdo::Pdo;
use drivebus_sync::{SyncService, TimeService};

/// "save" as an UNSIGNED32 (CiA 301 §7.5.2.13).
pub const SAVE_SIGNATURE: u32 = 0x6576_6173;
/// "load" as an UNSIGNED32 (CiA 301 §7.5.2.14).
pub const LOAD_SIGNATURE: u32 = 0x6461_6F6C;

/// The services whose objects live in the communication area.
pub(crate) struct Services {
    pub nmt: Nmt,
    pub pdo: Pdo,
    pub emcy: Emcy,
    pub emcy_consumer: Option<EmcyConsumer>,
    pub sync: SyncService,
    pub time: Option<TimeService>,
    pub storage: Box<dyn Storage + Send>,
    /// 1200h..127Fh changed while a server was borrowed: rebuild after.
    pub sdo_params_dirty: bool,
    /// A communication object changed: identifiers may have moved.
    pub comm_changed: bool,
    /// An NMT event produced while reconfiguring inside a hook.
    pub pending_nmt: Option<drivebus_nmt::NmtEvent>,
    pub now: Instant,
    /// What the EDS served at 1021h says besides the dictionary: LSS
    /// slave or not, and the device's own `[DeviceInfo]`.
    #[cfg(feature = "std")]
    pub eds_info: (bool, Option<drivebus_eds::DeviceInfo>),
}

/// Hooks seen by the SDO server and the PDO service of a node.
pub(crate) struct CommHooks<'a, A: ?Sized> {
    pub s: &'a mut Services,
    pub app: &'a mut A,
}

/// The 1010h/1011h sub-index → slots it covers.
fn slots(sub: u8) -> &'static [Slot] {
    match sub {
        1 => &[Slot::Communication, Slot::Application, Slot::Manufacturer],
        2 => &[Slot::Communication],
        3 => &[Slot::Application],
        4 => &[Slot::Manufacturer],
        _ => &[],
    }
}

fn group(slot: Slot) -> PersistGroup {
    match slot {
        Slot::Communication => PersistGroup::Communication,
        Slot::Application => PersistGroup::Application,
        Slot::Manufacturer | Slot::Lss => PersistGroup::Manufacturer,
    }
}

impl<A: Application + ?Sized> CommHooks<'_, A> {
    fn store_restore(
        &mut self,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        let value = le_u64(data) as u32;
        let (signature, save) =
            if index == 0x1010 { (SAVE_SIGNATURE, true) } else { (LOAD_SIGNATURE, false) };
        // CiA 301: a wrong signature is refused with 0800 002xh.
        if value != signature {
            return Err(SdoAbort::CANNOT_STORE);
        }
        // One commit for every group the sub-index covers: a crash in the
        // middle of "save all" must not leave a mix of old and new groups.
        let images: Vec<(Slot, Option<Vec<u8>>)> = slots(sub)
            .iter()
            // Restored defaults take effect at the next reset (§7.5.2.14).
            .map(|&slot| (slot, save.then(|| encode_image(od, group(slot)))))
            .collect();
        let changes: Vec<(Slot, Option<&[u8]>)> =
            images.iter().map(|(slot, image)| (*slot, image.as_deref())).collect();
        self.s.storage.commit(&changes).map_err(|_| SdoAbort::HARDWARE_ERROR)?;
        // The object keeps reading its capability (1: on command), not the signature.
        Ok(WriteOutcome::Handled)
    }
}

impl<A: Application + ?Sized> ObjectHooks for CommHooks<'_, A> {
    fn on_read(&mut self, od: &mut ObjectDictionary, index: u16, sub: u8) -> Result<(), SdoAbort> {
        if index == 0x1003 {
            self.s.emcy.check_read(index, sub)?;
        }
        self.app.on_read(od, index, sub)?;
        #[cfg(feature = "std")]
        if index == 0x1021 {
            let (lss, info) = &self.s.eds_info;
            let text = crate::eds_object::generate(
                od,
                self.s.nmt.node_id(),
                self.s.pdo.config(),
                *lss,
                info.as_ref(),
            );
            let r = od.find(index, sub)?;
            od.set_raw(r, text.as_bytes());
        }
        Ok(())
    }

    fn on_write(
        &mut self,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        // The application sees every write first: it may veto it (a drive
        // refusing to store while enabled) or take it over (quirks).
        if self.app.on_write(od, index, sub, data)? == WriteOutcome::Handled {
            return Ok(WriteOutcome::Handled);
        }
        if !(0x1000..=0x1FFF).contains(&index) {
            return Ok(WriteOutcome::Store);
        }
        let s = &mut *self.s;
        // Services check here and reconfigure in `after_write`, once the
        // dictionary has stored the value.
        match index {
            0x1010 | 0x1011 => return self.store_restore(od, index, sub, data),
            0x1001 | 0x1003 | 0x1014 | 0x1015 => s.emcy.check_write(od, index, sub, data)?,
            0x1028 => {
                if let Some(c) = &s.emcy_consumer {
                    c.check_write(od, index, sub, data)?;
                }
            }
            0x1005..=0x1007 | 0x1019 => s.sync.check_write(od, index, sub, data)?,
            0x1012 => {
                if let Some(t) = &s.time {
                    t.check_write(od, index, sub, data)?;
                }
            }
            0x100C | 0x100D | 0x1016 | 0x1017 | 0x1029 => s.nmt.check_write(od, index, sub, data)?,
            0x1200..=0x127F => drivebus_sdo::server::check_write(od, index, sub, data)?,
            0x1400..=0x1BFF => s.pdo.check_write(od, index, sub, data)?,
            _ => {}
        }
        Ok(WriteOutcome::Store)
    }

    fn after_write(&mut self, od: &mut ObjectDictionary, index: u16, sub: u8) {
        self.app.after_write(od, index, sub);
        let s = &mut *self.s;
        match index {
            0x1001 | 0x1003 | 0x1014 | 0x1015 => s.emcy.reconfigure(od, index, sub),
            0x1028 => {
                if let Some(c) = &mut s.emcy_consumer {
                    c.reconfigure(od, index, sub);
                }
            }
            0x1005..=0x1007 | 0x1019 => s.sync.reconfigure(od, index, sub),
            0x1012 => {
                if let Some(t) = &mut s.time {
                    t.reconfigure(od, index, sub);
                }
            }
            0x100C | 0x100D | 0x1016 | 0x1017 | 0x1029 => {
                if let Some(ev) = s.nmt.reconfigure(od, index, sub, s.now) {
                    s.pending_nmt = Some(ev);
                }
            }
            0x1200..=0x127F => s.sdo_params_dirty = true,
            0x1400..=0x1BFF => s.pdo.reconfigure(od, index, sub),
            _ => {}
        }
        if matches!(index, 0x1005 | 0x1012 | 0x1028 | 0x1400..=0x15FF | 0x1800..=0x19FF) {
            s.comm_changed = true;
        }
    }
}
