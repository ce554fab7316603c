//! The owners of a node's dictionary entries and the dispatch of the write
//! path to them (see `drivebus_od::owner` for the order of checks).
//!
//! Each communication object gets its service's tag once, when the node
//! takes the dictionary ([`resolve`]); a write then reaches its owner by
//! one `match` on that tag, and the owner marks what changed for the next
//! poll ([`Services::dirty`]).

use crate::app::{AppContext, Application, Request};
use crate::storage::{Slot, Storage, encode_image};
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_can::Instant;
use drivebus_emcy::{Emcy, EmcyConsumer};
use drivebus_nmt::Nmt;
use drivebus_od::{
    ObjectDictionary, ObjectHooks, Owner, PersistGroup, SdoAbort, Target, WriteOutcome, le_u64,
};
use drivebus_pdo::Pdo;
use drivebus_sync::{SyncService, TimeService};

/// "save" as an UNSIGNED32 (CiA 301 §7.5.2.13).
pub const SAVE_SIGNATURE: u32 = 0x6576_6173;
/// "load" as an UNSIGNED32 (CiA 301 §7.5.2.14).
pub const LOAD_SIGNATURE: u32 = 0x6461_6F6C;

/// The owner tags a node gives its services' objects (`drivebus_od::Owner`
/// values 2..=0x3F; applications use [`Owner::app`]).
pub mod tag {
    use drivebus_od::Owner;
    /// 1010h store, 1011h restore.
    pub const STORE: Owner = Owner(2);
    /// 1001h, 1003h, 1014h, 1015h: the EMCY producer.
    pub const EMCY: Owner = Owner(3);
    /// 1028h: the EMCY consumer.
    pub const EMCY_CONSUMER: Owner = Owner(4);
    /// 1005h–1007h, 1019h: SYNC.
    pub const SYNC: Owner = Owner(5);
    /// 1012h: TIME.
    pub const TIME: Owner = Owner(6);
    /// 100Ch, 100Dh, 1016h, 1017h, 1029h: NMT and error control.
    pub const NMT: Owner = Owner(7);
    /// 1200h–127Fh: SDO server parameters.
    pub const SDO: Owner = Owner(8);
    /// 1400h–1BFFh: PDO communication and mapping parameters.
    pub const PDO: Owner = Owner(9);
    /// 1021h: the EDS, generated on read.
    pub const EDS: Owner = Owner(10);
    /// A hooked communication object no service owns: stored as written.
    pub const COMM: Owner = Owner(11);
}

/// Services whose inputs changed since they were last polled.
pub(crate) mod dirty {
    pub const NMT: u8 = 1;
    pub const SYNC: u8 = 2;
    pub const PDO: u8 = 4;
    pub const SDO: u8 = 8;
    pub const EMCY: u8 = 16;
    pub const APP: u8 = 32;
    /// The identifier → service table must be rebuilt.
    pub const ROUTES: u8 = 64;
    /// The PDO configuration changed: re-mark the entries event-driven
    /// TPDOs map.
    pub const PDO_MAP: u8 = 128;
    /// Every service (a state change, a reset).
    pub const ALL: u8 = NMT | SYNC | PDO | SDO | EMCY | APP;
}

/// The owner tag of a communication-area entry installed with `hooked()`.
fn service_tag(index: u16) -> Owner {
    match index {
        0x1010 | 0x1011 => tag::STORE,
        0x1001 | 0x1003 | 0x1014 | 0x1015 => tag::EMCY,
        0x1028 => tag::EMCY_CONSUMER,
        0x1005..=0x1007 | 0x1019 => tag::SYNC,
        0x1012 => tag::TIME,
        0x100C | 0x100D | 0x1016 | 0x1017 | 0x1029 => tag::NMT,
        0x1200..=0x127F => tag::SDO,
        0x1400..=0x1BFF => tag::PDO,
        0x1021 => tag::EDS,
        _ => tag::COMM,
    }
}

/// Gives every entry still tagged [`Owner::HOOKED`] its concrete owner:
/// its service in the communication area (live only where the service
/// refreshes reads: 1003h, 1021h), the application elsewhere.
pub(crate) fn resolve(od: &mut ObjectDictionary) {
    // One pass in place: a build resolves after every batch of inserts.
    od.for_each_sub_mut(|index, s| {
        if s.owner != Owner::HOOKED {
            return;
        }
        if (0x1000..=0x1FFF).contains(&index) {
            s.owner = service_tag(index);
            s.live = matches!(index, 0x1003 | 0x1021);
        } else {
            s.owner = Owner::APP;
        }
    });
}

/// The services whose objects live in the communication area, and what
/// the dispatch leaves for the node to do after a write.
pub(crate) struct Services {
    pub nmt: Nmt,
    pub pdo: Pdo,
    pub emcy: Emcy,
    pub emcy_consumer: Option<EmcyConsumer>,
    pub sync: SyncService,
    pub time: Option<TimeService>,
    pub storage: Box<dyn Storage + Send>,
    /// What the application's callbacks need (and what they mark dirty).
    pub link: Link,
    /// 1200h..127Fh changed while a server was borrowed: rebuild after.
    pub sdo_params_dirty: bool,
    /// An NMT event produced while reconfiguring inside a hook.
    pub pending_nmt: Option<drivebus_nmt::NmtEvent>,
    /// What the EDS served at 1021h says besides the dictionary: LSS
    /// slave or not, and the device's own `[DeviceInfo]` and `[FileInfo]`.
    #[cfg(feature = "std")]
    pub eds_info: crate::eds_object::Given,
}

/// The node's side of an application callback, borrowed apart from the
/// services (the PDO service runs while its hooks call the application).
pub(crate) struct Link {
    /// What changed since the services were last polled ([`dirty`]).
    pub dirty: u8,
    /// What the application asked for during the current call.
    pub requests: Vec<Request>,
    pub node_id: u8,
    pub now: Instant,
}

impl Link {
    /// The context for an application callback (which marks the
    /// application dirty: it is polled after).
    #[inline]
    pub(crate) fn cx<'a>(&'a mut self, od: &'a mut ObjectDictionary) -> AppContext<'a> {
        self.dirty |= dirty::APP;
        AppContext::new(od, self.now, self.node_id, &mut self.requests)
    }
}

impl Services {
    /// The context for an application callback.
    #[inline]
    pub(crate) fn cx<'a>(&'a mut self, od: &'a mut ObjectDictionary) -> AppContext<'a> {
        self.link.cx(od)
    }

    /// The PDO service, and the application's side of the dispatch for
    /// what it maps (PDOs map application objects; a communication object
    /// mapped into a PDO is stored as sent, as the services never map one).
    #[inline]
    pub(crate) fn pdo_and_app<'a, A: ?Sized>(&'a mut self, app: &'a mut A) -> (&'a mut Pdo, AppHooks<'a, A>) {
        (&mut self.pdo, AppHooks { app, link: &mut self.link })
    }
}

/// The application's side of the dispatch: entries it owns or watches.
pub(crate) struct AppHooks<'a, A: ?Sized> {
    pub app: &'a mut A,
    pub link: &'a mut Link,
}

impl<A: ?Sized> AppHooks<'_, A> {
    /// The application and a context for calling it.
    #[inline]
    fn split<'a>(&'a mut self, od: &'a mut ObjectDictionary) -> (&'a mut A, AppContext<'a>) {
        (&mut *self.app, self.link.cx(od))
    }
}

impl<A: Application + ?Sized> ObjectHooks for AppHooks<'_, A> {
    #[inline]
    fn on_read(&mut self, od: &mut ObjectDictionary, at: &Target) -> Result<(), SdoAbort> {
        if at.owner.is_app() || at.watched {
            let (app, mut cx) = self.split(od);
            return app.on_read(&mut cx, at);
        }
        Ok(())
    }
    #[inline]
    fn check_write(
        &mut self,
        od: &mut ObjectDictionary,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        if at.owner.is_app() || at.watched {
            let (app, mut cx) = self.split(od);
            return app.check_write(&mut cx, at, data);
        }
        Ok(WriteOutcome::Store)
    }
    #[inline]
    fn apply_write(&mut self, od: &mut ObjectDictionary, at: &Target) {
        if at.owner.is_app() || at.watched {
            let (app, mut cx) = self.split(od);
            app.apply_write(&mut cx, at);
        }
    }
}

/// The write path's dispatcher: one owner per entry, by tag.
pub(crate) struct Dispatch<'a, A: ?Sized> {
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

/// 1010h store / 1011h restore: the signature, then the storage.
pub(crate) fn store_restore(
    storage: &mut (dyn Storage + Send),
    od: &ObjectDictionary,
    at: &Target,
    data: &[u8],
) -> Result<WriteOutcome, SdoAbort> {
    let value = le_u64(data) as u32;
    let (signature, save) = if at.index == 0x1010 { (SAVE_SIGNATURE, true) } else { (LOAD_SIGNATURE, false) };
    // CiA 301: a wrong signature is refused with 0800 002xh.
    if value != signature {
        return Err(SdoAbort::CANNOT_STORE);
    }
    commit_groups(storage, od, at.sub, save).map_err(|_| SdoAbort::HARDWARE_ERROR)?;
    // The object keeps reading its capability (1: on command), not the signature.
    Ok(WriteOutcome::Handled)
}

/// Saves (or, `save` false, forgets) the groups 1010h/1011h sub-index
/// `sub` covers, in one commit: a crash in the middle of "save all" must
/// not leave a mix of old and new groups.
pub(crate) fn commit_groups(
    storage: &mut (dyn Storage + Send),
    od: &ObjectDictionary,
    sub: u8,
    save: bool,
) -> Result<(), crate::storage::StorageError> {
    let images: Vec<(Slot, Option<Vec<u8>>)> = slots(sub)
        .iter()
        // Restored defaults take effect at the next reset (§7.5.2.14).
        .map(|&slot| (slot, save.then(|| encode_image(od, group(slot)))))
        .collect();
    let changes: Vec<(Slot, Option<&[u8]>)> =
        images.iter().map(|(slot, image)| (*slot, image.as_deref())).collect();
    storage.commit(&changes)
}

impl<A: Application + ?Sized> ObjectHooks for Dispatch<'_, A> {
    fn on_read(&mut self, od: &mut ObjectDictionary, at: &Target) -> Result<(), SdoAbort> {
        if at.owner.is_app() || at.watched {
            self.app.on_read(&mut self.s.cx(od), at)?;
        }
        match at.owner {
            tag::EMCY => self.s.emcy.check_read(at.index, at.sub),
            #[cfg(feature = "std")]
            tag::EDS => {
                let text = crate::eds_object::generate(
                    od,
                    self.s.nmt.node_id(),
                    self.s.pdo.config(),
                    &self.s.eds_info,
                );
                od.set_raw(at.r, text.as_bytes());
                Ok(())
            }
            _ => Ok(()),
        }
    }

    fn check_write(
        &mut self,
        od: &mut ObjectDictionary,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        if at.owner.is_app() {
            return self.app.check_write(&mut self.s.cx(od), at, data);
        }
        // A watcher's veto comes before the owner's check.
        if at.watched && self.app.check_write(&mut self.s.cx(od), at, data)? == WriteOutcome::Handled {
            return Ok(WriteOutcome::Handled);
        }
        let s = &mut *self.s;
        let (index, sub) = (at.index, at.sub);
        match at.owner {
            tag::STORE => return store_restore(&mut *s.storage, od, at, data),
            tag::EMCY => s.emcy.check_write(od, index, sub, data)?,
            tag::EMCY_CONSUMER => {
                if let Some(c) = &s.emcy_consumer {
                    c.check_write(od, index, sub, data)?;
                }
            }
            tag::SYNC => s.sync.check_write(od, index, sub, data)?,
            tag::TIME => {
                if let Some(t) = &s.time {
                    t.check_write(od, index, sub, data)?;
                }
            }
            tag::NMT => s.nmt.check_write(od, index, sub, data)?,
            tag::SDO => drivebus_sdo::server::check_write(od, index, sub, data)?,
            tag::PDO => s.pdo.check_write(od, index, sub, data)?,
            _ => {}
        }
        Ok(WriteOutcome::Store)
    }

    fn apply_write(&mut self, od: &mut ObjectDictionary, at: &Target) {
        if at.owner.is_app() {
            self.app.apply_write(&mut self.s.cx(od), at);
            return;
        }
        let s = &mut *self.s;
        let (index, sub) = (at.index, at.sub);
        match at.owner {
            tag::EMCY => {
                s.emcy.reconfigure(od, index, sub);
                s.link.dirty |= dirty::EMCY;
            }
            tag::EMCY_CONSUMER => {
                if let Some(c) = &mut s.emcy_consumer {
                    c.reconfigure(od, index, sub);
                }
                s.link.dirty |= dirty::ROUTES;
            }
            tag::SYNC => {
                s.sync.apply_value(index, sub, od.word(at.r) as u32);
                s.link.dirty |= match index {
                    // The window only bounds synchronous PDOs: no deadline moves.
                    0x1007 => 0,
                    0x1005 => dirty::SYNC | dirty::ROUTES,
                    _ => dirty::SYNC,
                };
            }
            tag::TIME => {
                if let Some(t) = &mut s.time {
                    t.reconfigure(od, index, sub);
                }
                s.link.dirty |= dirty::ROUTES;
            }
            tag::NMT => {
                if let Some(ev) = s.nmt.reconfigure(od, index, sub, s.link.now) {
                    s.pending_nmt = Some(ev);
                }
                s.link.dirty |= dirty::NMT;
            }
            tag::SDO => s.sdo_params_dirty = true,
            tag::PDO => {
                s.pdo.reconfigure(od, index, sub);
                s.link.dirty |= dirty::PDO | dirty::PDO_MAP;
                if matches!(index, 0x1400..=0x15FF | 0x1800..=0x19FF) {
                    s.link.dirty |= dirty::ROUTES;
                }
            }
            _ => {}
        }
        if at.watched {
            self.app.apply_write(&mut self.s.cx(od), at);
        }
    }
}
