//! The dictionary a personality answers with is the one its EDS describes
//! (CiA 306 §4.6: the EDS is the description of the device; the EDS files
//! are the manuals' object tables, `tools/tsv2eds.py`).
//!
//! The CiA 402 drive installs the full CiA 402-2 object set with the
//! standard's access, types and mappability, and the node adds every
//! CiA 301 sub-index its services know. A real drive has only what its
//! manual lists, as the manual lists it. So after the build:
//!
//! * an object the EDS lacks is taken out: the drive keeps working with
//!   the parameter ([`Drive::withdraw_object`]), a communication object's
//!   service runs on its power-on setting;
//! * a sub-index the EDS lacks is taken out of its object;
//! * where the EDS has a single value and the drive a structure (or the
//!   reverse: SSD 630 6080h is an ARRAY of two, §12), the EDS's object
//!   replaces the drive's, whose parameter is withdrawn; the behaviour
//!   translates (`src/ssd630/`);
//! * every other sub-object takes the EDS's name, data type, access, PDO
//!   mapping and limits; object code and name likewise.
//!
//! Values and defaults stay the drive's: `tests/eds_conformance.rs`
//! compares them with the EDS, so a wrong default is fixed on the side
//! the manual supports, not copied over.

use super::eds_od::Described;
use alloc::vec::Vec;
use drivebus_cia402::drive::Drive;
use drivebus_od::{Object, ObjectCode, ObjectDictionary, SubObject};

extern crate alloc;

/// Whether the index belongs to the CiA 402 drive (device profile area).
fn drive_object(index: u16) -> bool {
    (0x6000..=0x67FF).contains(&index)
}

fn single(code: ObjectCode) -> bool {
    matches!(code, ObjectCode::Var | ObjectCode::Domain | ObjectCode::DefType)
}

/// `o` with only the sub-indices `keep` allows, every kept sub-object as it
/// was (value, persistence group, owner). A sub 0 that held the highest
/// sub-index (CiA 301 §7.4.3) holds the new highest one.
fn without_subs(o: &Object, keep: impl Fn(u8) -> bool) -> Object {
    let highest = |subs: &[SubObject]| subs.last().map_or(0, |s| s.sub);
    let old_highest = highest(o.subs());
    let mut kept: Vec<SubObject> = o.subs().iter().filter(|s| keep(s.sub)).cloned().collect();
    let new_highest = highest(&kept);
    if let Some(s0) = kept.first_mut().filter(|s| s.sub == 0 && s.bytes() == [old_highest]) {
        s0.default = alloc::vec![new_highest];
        let mut fresh =
            SubObject::from_bytes(0, s0.name.clone(), s0.data_type, s0.access, s0.default.clone());
        fresh.persist = s0.persist;
        keep_owner(&mut fresh, s0);
        *s0 = fresh;
    }
    let mut n =
        kept.iter().cloned().fold(Object::with_code(o.index, o.code, o.name.clone()), Object::with_sub);
    n.flags = o.flags;
    for (dst, src) in n.subs_mut().iter_mut().zip(&kept) {
        *dst = src.clone();
    }
    n
}

/// `s` keeps `from`'s owner (its writes' path): owner, live, watched, marked.
fn keep_owner(s: &mut SubObject, from: &SubObject) {
    s.owner = from.owner;
    s.live = from.live;
    s.watched = from.watched;
    s.marked = from.marked;
}

/// Takes the EDS's description of one sub-object (see the module docs).
fn describe(s: &mut SubObject, e: &SubObject) {
    if s.data_type.fixed_size() != e.data_type.fixed_size() {
        // Another size: the EDS's value too (the drive reads through the
        // behaviour, which knows the manual's type).
        let was = s.clone();
        *s = e.clone();
        keep_owner(s, &was);
        return;
    }
    // `clone_from`: a limit the sub-object already has keeps its buffer.
    s.name.clone_from(&e.name);
    s.data_type = e.data_type;
    s.access = e.access;
    s.pdo_mappable = e.pdo_mappable;
    s.low_limit.clone_from(&e.low_limit);
    s.high_limit.clone_from(&e.high_limit);
}

/// Brings `od` (the node's dictionary, with `drive` installed) to the
/// objects and descriptions of `eds` (the EDS as converted for the same
/// node-ID), except the objects of `keep` (1021h/1022h, which
/// `BuildOptions::eds_object` adds to what the manual lists). The caller
/// re-resolves the node's services afterwards.
pub(super) fn conform(od: &mut ObjectDictionary, drive: &mut Drive, eds: &Described, keep: &[u16]) {
    let indices: Vec<u16> = od.objects().iter().map(|o| o.index).filter(|i| !keep.contains(i)).collect();
    for index in indices {
        let Some(e) = eds.object(index) else {
            if drive_object(index) {
                drive.withdraw_object(od, index);
            } else {
                od.remove(index);
            }
            continue;
        };
        let e = &*e;
        let Some(o) = od.object(index) else { continue };
        if single(o.code) != single(e.code) {
            if drive_object(index) {
                drive.withdraw_object(od, index);
            }
            od.insert(e.clone());
            continue;
        }
        // Sub-indices are kept sorted and unique: the same set is the
        // same sequence.
        let same_subs =
            o.subs().len() == e.subs().len() && o.subs().iter().zip(e.subs()).all(|(s, es)| s.sub == es.sub);
        if same_subs {
            // The usual case: describe in place, no copy of the object.
            if let Some(o) = od.object_mut(index) {
                o.code = e.code;
                o.name = e.name.clone();
                for (s, es) in o.subs_mut().iter_mut().zip(e.subs()) {
                    describe(s, es);
                }
            }
            continue;
        }
        let mut o = if o.subs().iter().any(|s| e.get(s.sub).is_none()) {
            without_subs(o, |sub| e.get(sub).is_some())
        } else {
            o.clone()
        };
        for es in e.subs() {
            if o.get(es.sub).is_none() {
                o = o.with_sub(es.clone());
            }
        }
        o.code = e.code;
        o.name = e.name.clone();
        for s in o.subs_mut() {
            if let Some(es) = e.get(s.sub) {
                describe(s, es);
            }
        }
        od.insert(o);
    }
}
