//! The personality of a drive this process does not host (`ui --bus URL`,
//! a real drive): picked from its identity 1018h when exactly one of ours
//! has that vendor-ID and product code (and revision, to tell apart two
//! that share them), so its EMCYs get the manual's texts, as a hosted
//! drive's do. Its dictionary stays what `--eds` gives (a real drive's
//! firmware may differ from our EDS). Vendor-ID 0 (none assigned, the
//! generic personality's) identifies nothing.

use std::collections::HashSet;
use std::sync::Arc;
use std::time::Duration;

use drivebus_master::MasterEvent;
use drivebus_personality::Profile;
use tokio::sync::broadcast::error::RecvError;

use super::Web;

/// What 1018h says about which of our personalities a device is.
#[derive(Debug, PartialEq, Eq)]
pub enum IdentityMatch {
    /// Exactly one.
    One(Profile),
    /// None has this vendor-ID and product code.
    None,
    /// Several have the same identity (the KC1 and the AKD share
    /// Kollmorgen's example "M006"): none is picked.
    Several(Vec<Profile>),
}

/// Our personality with this vendor-ID, product code and (where given on
/// both sides) revision.
pub fn personality_of(vendor_id: u32, product_code: u32, revision: Option<u32>) -> IdentityMatch {
    let same = |p: &&Profile| {
        let i = p.info();
        vendor_id != 0 && i.vendor_id == Some(vendor_id) && i.product_code == Some(product_code)
    };
    let mut found: Vec<Profile> = Profile::all().iter().filter(same).copied().collect();
    if found.len() > 1
        && let Some(r) = revision
    {
        found.retain(|p| p.info().revision.is_none_or(|x| x == r));
    }
    match found.len() {
        0 => IdentityMatch::None,
        1 => IdentityMatch::One(found[0]),
        _ => IdentityMatch::Several(found),
    }
}

/// Reads 1018h of `node` and, when it is one of ours, registers the
/// personality: its EMCY texts with the master, and the profile for the
/// API's `detail`.
async fn identify(web: &Web, node: u8) {
    let sdo = web.master.sdo(node);
    let (Ok(vendor), Ok(product)) = (sdo.read::<u32>(0x1018, 1).await, sdo.read::<u32>(0x1018, 2).await)
    else {
        return;
    };
    let revision = sdo.read::<u32>(0x1018, 3).await.ok();
    match personality_of(vendor, product, revision) {
        IdentityMatch::One(p) => {
            tracing::info!(
                node,
                personality = p.name(),
                "web: identified by 1018h; the manual's EMCY texts apply"
            );
            web.master.add_emcy_texts(node, p.info().emcy.iter().map(|e| (e.code, e.text)));
            web.identified.lock().unwrap_or_else(|e| e.into_inner()).insert(node, p);
        }
        IdentityMatch::Several(ps) => {
            let names: Vec<&str> = ps.iter().map(|p| p.name()).collect();
            tracing::info!(node, candidates = ?names, "web: 1018h fits several personalities; CiA texts apply");
        }
        IdentityMatch::None => {}
    }
}

/// Identifies every node the master hears that this process does not
/// host, once, and again after its boot-up (a node-ID can change hands).
pub async fn keep_identifying(web: Arc<Web>) {
    let mut events = web.master.subscribe_events();
    let mut done: HashSet<u8> = web.profiles.keys().copied().collect();
    loop {
        for node in web.master.seen_nodes() {
            if done.insert(node) {
                identify(&web, node).await;
            }
        }
        tokio::select! {
            e = events.recv() => match e {
                Ok(MasterEvent::Bootup { node }) if !web.profiles.contains_key(&node) => {
                    done.remove(&node);
                }
                Err(RecvError::Closed) => return,
                _ => {}
            },
            _ = tokio::time::sleep(Duration::from_secs(1)) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_identity_of_ours_picks_its_personality() {
        let p = |n| Profile::from_name(n).unwrap();
        let dds6 = p("dds6").info();
        assert_eq!(personality_of(0x30C, 0x0062_4400, None), IdentityMatch::One(p("dds6")), "{dds6:?}");
        assert_eq!(personality_of(0x1A3, 28_002_021, Some(0x4130_3047)), IdentityMatch::One(p("ipos")));
        assert_eq!(personality_of(0x30C, 0x0062_4401, None), IdentityMatch::None);
        // Vendor-ID 0 is nobody's: not the generic personality.
        assert_eq!(personality_of(0, 0x402, Some(0x0001_0000)), IdentityMatch::None);
        // AKD and KC1 share vendor, product and revision: neither is picked.
        match personality_of(0x6A, 0x4D30_3036, Some(0x0014_0000)) {
            IdentityMatch::Several(ps) => {
                assert!(ps.contains(&p("akd")) && ps.contains(&p("kc1")), "{ps:?}");
            }
            other => panic!("{other:?}"),
        }
    }
}
