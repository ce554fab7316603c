//! The dictionary of a profile's EDS for one node-ID, without reading and
//! converting the file at every build.
//!
//! The file is read once per process ([`Profile::eds`]) and converted once
//! for node-ID 1, names borrowed from the read file. A build clones that
//! template and moves the defaults that follow the node-ID (`$NODEID+…`,
//! CiA 306 §4.6.3) to its own node-ID. That is exact only where every
//! `$NODEID` expression is the node-ID plus a constant in a default: the
//! template is checked against the conversion for node-ID 127 once, and a
//! profile whose file does not pass is converted at every build as before.

use crate::Profile;
use alloc::borrow::Cow;
use alloc::vec::Vec;
use drivebus_od::{Object, ObjectDictionary, le_u64};
use std::sync::OnceLock;

extern crate alloc;

/// The EDS dictionary converted for node-ID 1, and the entries whose
/// default and value move with the node-ID.
pub(super) struct Template {
    od: ObjectDictionary,
    relative: Vec<(u16, u8)>,
}

/// The template's node-ID and the other end of the range it is checked at.
const LOW: u8 = 1;
const HIGH: u8 = 127;

/// `bytes + d` in the width of `bytes` (two's complement wraps like the type).
fn shifted(bytes: &[u8], d: u64) -> Vec<u8> {
    let n = bytes.len().min(8);
    le_u64(bytes).wrapping_add(d).to_le_bytes()[..n].to_vec()
}

/// Moves the `relative` entries of `od` (converted for node-ID [`LOW`]) to
/// node-ID `LOW + d`: default and value.
fn rebase(od: &mut ObjectDictionary, relative: &[(u16, u8)], d: u64) {
    for &(index, sub) in relative {
        let Ok(r) = od.find(index, sub) else { continue };
        let value = shifted(od.bytes(r), d);
        od.set_raw(r, &value);
        if let Some(s) = od.get_mut(index, sub) {
            s.default = shifted(&s.default, d);
        }
    }
}

fn template(profile: Profile) -> Option<&'static Template> {
    static TEMPLATES: [OnceLock<Option<Template>>; 6] = [const { OnceLock::new() }; 6];
    TEMPLATES[profile as usize]
        .get_or_init(|| {
            let eds = &profile.eds().eds;
            let od = drivebus_eds::to_od_static(eds, LOW).ok()?;
            let relative: Vec<(u16, u8)> = od
                .objects()
                .iter()
                .flat_map(|o| o.subs().iter().filter(|s| s.node_id_relative).map(|s| (o.index, s.sub)))
                .collect();
            // The check: moved to the other end of the range, the template
            // is exactly what converting for that node-ID gives.
            let mut high = od.clone();
            rebase(&mut high, &relative, u64::from(HIGH - LOW));
            let fits = relative
                .iter()
                .all(|&(i, s)| od.get(i, s).is_some_and(|x| x.default.len() <= 8 && x.bytes().len() <= 8));
            (fits && drivebus_eds::to_od_static(eds, HIGH).ok()? == high).then_some(Template { od, relative })
        })
        .as_ref()
}

/// What the profile's EDS describes for one node-ID: the dictionary the
/// node starts from, and the description `conform` brings it back to.
pub(super) struct EdsDictionary {
    /// `drivebus_eds::to_od(profile's EDS, node_id)`: the node's to own.
    pub od: ObjectDictionary,
    /// The same dictionary, read-only, for `conform`.
    pub described: Described,
}

/// The EDS dictionary `conform` compares with: the shared template (no
/// copy per build), its node-relative entries moved when an object is
/// taken over whole; or, for a file without a template, a copy.
pub(super) enum Described {
    /// The template and the node-ID difference from it.
    Template(&'static Template, u64),
    /// The dictionary converted for this build.
    Own(ObjectDictionary),
}

impl Described {
    /// The object at `index` as converted for the build's node-ID.
    pub fn object(&self, index: u16) -> Option<Cow<'_, Object>> {
        match self {
            Described::Own(od) => od.object(index).map(Cow::Borrowed),
            Described::Template(t, d) => {
                let o = t.od.object(index)?;
                if *d == 0 || !o.subs().iter().any(|s| s.node_id_relative) {
                    return Some(Cow::Borrowed(o));
                }
                let mut one = ObjectDictionary::new();
                one.insert(o.clone());
                let relative: Vec<(u16, u8)> =
                    o.subs().iter().filter(|s| s.node_id_relative).map(|s| (index, s.sub)).collect();
                rebase(&mut one, &relative, *d);
                one.remove(index).map(Cow::Owned)
            }
        }
    }
}

/// `drivebus_eds::to_od(profile's EDS, node_id)`, from the template when
/// the profile's file allows it (see the module docs).
pub(super) fn eds_dictionary(profile: Profile, node_id: u8) -> Result<EdsDictionary, drivebus_eds::EdsError> {
    let Some(t) = template(profile).filter(|_| (LOW..=HIGH).contains(&node_id)) else {
        let od = drivebus_eds::to_od_static(&profile.eds().eds, node_id)?;
        return Ok(EdsDictionary { described: Described::Own(od.clone()), od });
    };
    let d = u64::from(node_id - LOW);
    let mut od = t.od.clone();
    rebase(&mut od, &t.relative, d);
    Ok(EdsDictionary { od, described: Described::Template(t, d) })
}

/// What `conform` compares a build for `node_id` with, without a copy of
/// the dictionary: `None` for a profile without a template.
pub(super) fn described(profile: Profile, node_id: u8) -> Option<Described> {
    let t = template(profile).filter(|_| (LOW..=HIGH).contains(&node_id))?;
    Some(Described::Template(t, u64::from(node_id - LOW)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_profile_has_a_template_equal_to_converting_its_file() {
        for &p in Profile::all() {
            assert!(template(p).is_some(), "{p}: no template");
            let eds = drivebus_eds::parse(p.eds_text()).unwrap().eds;
            for id in [1, 2, 5, 64, 126, 127] {
                let direct = drivebus_eds::to_od(&eds, id).unwrap();
                let built = eds_dictionary(p, id).unwrap();
                assert!(built.od == direct, "{p} node {id}");
                for o in direct.objects() {
                    assert_eq!(built.described.object(o.index).as_deref(), Some(o), "{p} node {id}");
                }
            }
        }
    }

    #[test]
    fn relative_defaults_move_in_their_width() {
        assert_eq!(shifted(&[0xFC, 0xFF], 126), [0x7A, 0x00]); // -4 + 126 as INTEGER16
        assert_eq!(shifted(&[0x81, 0x01, 0, 0], 4), [0x85, 0x01, 0, 0]);
    }
}
