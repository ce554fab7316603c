//! Who owns a sub-object, and the write path through its owner.
//!
//! Every sub-object carries an [`Owner`] tag, resolved once when the
//! dictionary is built (like CANopenNode's OD extensions): the frame path
//! finds the owner of a written entry with one load, never by searching or
//! by asking a chain of handlers. The dictionary drives the checks and
//! calls the owner through [`ObjectHooks`]:
//!
//! 1. **find** `(index, sub)` → [`EntryRef`] (`0602 0000`, `0609 0011`);
//! 2. **access**: an SDO write needs a writable access type (`0601 0002`);
//!    RPDO and local writes skip this step;
//! 3. **type, length, limits** ([`SubObject::validate`]);
//! 4. no owner and not watched → **store**, done (the fast path);
//! 5. **owner check** ([`ObjectHooks::check_write`]): a watched entry's
//!    veto comes first inside it (the application refusing, say, a 1010h
//!    store while the drive is enabled), then the owner's own check; an
//!    abort stops the write, [`WriteOutcome::Handled`] means the owner
//!    applied it itself;
//! 6. **store** the bytes;
//! 7. **owner apply** ([`ObjectHooks::apply_write`]), once: the owner takes
//!    the new value (a service reconfigures, a drive copies a parameter).
//!
//! A read checks access, then, for a [`SubObject::live`] entry, lets its
//! owner refresh the value ([`ObjectHooks::on_read`]).

use crate::{EntryRef, ObjectDictionary, SdoAbort};

/// The owner of a sub-object: who checks and applies writes to it (and,
/// for a live entry, refreshes it before reads).
///
/// `0` is no owner (a plain value the dictionary stores itself), `1`
/// ([`Owner::HOOKED`]) an entry installed with [`SubObject::hooked`] whose
/// concrete owner is not resolved yet, `2..=0x3F` the owners a device
/// (`drivebus-node`) assigns to its services, `0x40..=0xFF` the
/// application's own tags ([`Owner::app`]).
///
/// [`SubObject::hooked`]: crate::SubObject::hooked
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Owner(pub u8);

impl Owner {
    /// No owner: writes are stored as they are.
    pub const NONE: Owner = Owner(0);
    /// Owned by whoever dispatches this dictionary's writes; a device
    /// resolves it to a concrete owner when it takes the dictionary.
    pub const HOOKED: Owner = Owner(1);
    /// The first application tag: [`Owner::app`]`(0)`.
    pub const APP: Owner = Owner(0x40);

    /// Application tag `k` (`0..=0xBF`; larger values saturate).
    pub const fn app(k: u8) -> Owner {
        Owner(if k > 0xBF { 0xFF } else { 0x40 + k })
    }
    /// The tag belongs to the application.
    #[inline]
    pub const fn is_app(self) -> bool {
        self.0 >= 0x40
    }
    /// The application tag number (`app(k)` → `Some(k)`).
    #[inline]
    pub const fn app_tag(self) -> Option<u8> {
        if self.is_app() { Some(self.0 - 0x40) } else { None }
    }
}

/// The entry a hook is called for: where it is, who owns it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Target {
    /// The resolved handle (read or update the value without a search).
    pub r: EntryRef,
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// The owner tag of the entry.
    pub owner: Owner,
    /// The application watches the entry (its veto runs before the owner's check).
    pub watched: bool,
}

/// What an owner's check decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WriteOutcome {
    /// Store the written bytes, then apply them.
    Store,
    /// The owner has applied the write itself (possibly storing other
    /// values): nothing is stored and nothing applied.
    Handled,
}

/// The owners of a dictionary's entries, as the dictionary calls them on
/// the write path (see the module docs for the order). Implemented by a
/// device's dispatcher (`drivebus-node` routes by [`Owner`] tag to its
/// services and to the application); [`NoHooks`] for a dictionary of plain
/// values.
///
/// Hooks live outside the dictionary and get it passed in, so an owner may
/// read or update other entries (1003h sub 0 clearing the history).
pub trait ObjectHooks {
    /// Before a live entry is read (SDO upload, PDO sampling, export): may
    /// refresh the stored value with [`ObjectDictionary::set_raw`], or refuse.
    fn on_read(&mut self, od: &mut ObjectDictionary, at: &Target) -> Result<(), SdoAbort> {
        let _ = (od, at);
        Ok(())
    }
    /// Step 5: veto (watched entries) and the owner's check of `data`,
    /// after type, length and limits passed. Nothing is stored yet.
    fn check_write(
        &mut self,
        od: &mut ObjectDictionary,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        let _ = (od, at, data);
        Ok(WriteOutcome::Store)
    }
    /// Step 7: the value [`check_write`](Self::check_write) accepted with
    /// `Store` is stored; the owner takes it. Called once per write.
    fn apply_write(&mut self, od: &mut ObjectDictionary, at: &Target) {
        let _ = (od, at);
    }
}

/// Hooks that do nothing: a dictionary of plain values.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoHooks;
impl ObjectHooks for NoHooks {}
