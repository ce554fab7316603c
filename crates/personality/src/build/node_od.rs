//! The node's dictionary before the drive is installed (the EDS's objects
//! with the CiA 301 services merged in), without building the services'
//! dictionary twice at every build.
//!
//! `Node::with_dictionary` builds the services' own dictionary for the
//! node-ID and once more for a neighbouring node-ID (to find the
//! node-relative defaults), then merges it into the EDS's. For a profile's
//! usual configuration that result is made once per process for node-ID 1
//! ([`NodeTemplate`]) and each build moves it to its node-ID
//! ([`NodeTemplate::moved_to`]). Checked once against the direct result
//! for node-ID 127 (configuration and dictionary equal); a profile that
//! does not pass, or a build whose configuration differs from the usual
//! one in more than the node-ID (another behaviour, `BuildOptions`), takes
//! the direct path.

use super::eds_od;
use crate::Profile;
use drivebus_node::{NodeConfig, NodeTemplate};
use std::sync::OnceLock;

/// The template's node-ID and the one it is checked at.
const LOW: u8 = 1;
const HIGH: u8 = 127;

/// `cfg` with its node-IDs (own, NMT, PDO where in step) set to `to`.
fn with_node_id(mut cfg: NodeConfig, to: u8) -> NodeConfig {
    if cfg.pdo.node_id == cfg.node_id {
        cfg.pdo.node_id = to;
    }
    cfg.node_id = to;
    cfg.nmt.node_id = to;
    cfg
}

/// `NodeTemplate::with_dictionary(cfg, EDS dictionary)` for `cfg`'s node-ID.
fn direct(profile: Profile, cfg: NodeConfig) -> Option<NodeTemplate> {
    let eds = eds_od::eds_dictionary(profile, cfg.node_id).ok()?;
    Some(NodeTemplate::with_dictionary(cfg, eds.od))
}

fn template(profile: Profile, usual: impl FnOnce() -> NodeConfig) -> Option<&'static NodeTemplate> {
    static TEMPLATES: [OnceLock<Option<NodeTemplate>>; 6] = [const { OnceLock::new() }; 6];
    TEMPLATES[profile as usize]
        .get_or_init(|| {
            let cfg = with_node_id(usual(), LOW);
            let low = direct(profile, cfg.clone())?;
            let high = direct(profile, with_node_id(cfg, HIGH))?;
            let moved = low.moved_to(HIGH)?;
            (moved.config() == high.config() && moved.od() == high.od()).then_some(low)
        })
        .as_ref()
}

/// The template for the build of `profile` with configuration `cfg`, when
/// `cfg` is the profile's usual one (`usual`, for any node-ID) and the
/// profile's file allows it (see the module docs).
pub(super) fn node_template(
    profile: Profile,
    cfg: &NodeConfig,
    usual: impl FnOnce() -> NodeConfig,
) -> Option<NodeTemplate> {
    let node_id = cfg.node_id;
    if !(LOW..=HIGH).contains(&node_id) {
        return None;
    }
    let t = template(profile, usual)?;
    // Only the node-ID may differ from the template's configuration.
    if with_node_id(cfg.clone(), LOW) != *t.config() {
        return None;
    }
    t.moved_to(node_id)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::{BuildOptions, full_node_config};

    #[test]
    fn every_profile_has_a_template_equal_to_the_direct_build() {
        for &p in Profile::all() {
            let usual = |id| full_node_config(p, id, &*p.behaviour(), BuildOptions::default());
            for id in [1, 2, 5, 64, 126, 127] {
                let cfg = usual(id);
                let t = node_template(p, &cfg, || usual(id)).unwrap_or_else(|| panic!("{p}: no template"));
                let d = direct(p, cfg).unwrap();
                assert!(t.od() == d.od(), "{p} node {id}");
                assert!(t.config() == d.config(), "{p} node {id}");
            }
            // Another configuration than the usual one takes the direct path.
            let other = full_node_config(p, 5, &*p.behaviour(), BuildOptions { eds_object: true });
            if other != usual(5) {
                assert!(node_template(p, &other, || usual(5)).is_none(), "{p}");
            }
        }
    }
}
