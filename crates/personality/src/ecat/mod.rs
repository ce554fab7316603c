//! The personalities on EtherCAT (CoE, ETG.1000.6): the same node, the
//! same CiA 402 drive and the same behaviour as on CAN, with the
//! dictionary a CoE device has and the CoE object rules.
//!
//! [`build`] builds the CAN personality, then makes its dictionary the
//! EtherCAT one:
//!
//! * the CAN communication objects the profile's CoE object list does not
//!   have are taken out ([`EcatFacts::can_only`]): a CoE device has no
//!   COB-IDs, SDO server parameters, heartbeat or guarding; the node's CAN
//!   services stay, inert (no frame ever reaches them);
//! * the sync manager objects are there ([`sync_objects`]): 1C00h, 1C12h
//!   and 1C13h (from the EDS where the manual lists them), 1C32h/1C33h
//!   (ETG.1020 synchronisation parameters);
//! * the PDO mapping objects, 1C12h/1C13h and 1C32h/1C33h belong to the
//!   [`EcatBehaviour`] wrapped around the profile's behaviour, which checks
//!   every write by the rules of [`rules`] (ETG.1000.6 and, for the iPOS,
//!   §2.3.10/§2.3.11, §2.4, §1.6.3.1) before the profile's own behaviour.
//!
//! The EtherCAT layer tells the personality its ESM state and AL errors
//! with [`esm_event`]: the state maps onto the node's NMT state (INIT,
//! PRE-OP and BOOT pre-operational; SAFE-OP and OP operational), leaving
//! OP executes the drive's abort connection option 6007h with error code
//! 8100h, and the profile's EtherCAT error reporting runs
//! ([`EcatFacts::esm_emcy`]: the iPOS's EMCY 8100h / A0xxh and 2000h bit 0).

mod behaviour;
pub mod rules;
mod sync;

pub use behaviour::EcatBehaviour;
pub use sync::sub as sync_sub;
pub use sync::{SYNC_MODES_SUPPORTED, sync_objects};

use crate::build::{BuildError, BuildOptions, Context, PersonalityDevice, build_full};
use crate::{Personality, Profile};
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_can::{Instant, TxSink};
use drivebus_coe::{AlState, FileHandler, NoFiles};
use drivebus_node::{NmtState, Storage};
use drivebus_od::ObjectDictionary;
use drivebus_pdo::{Granularity, PdoConfig};

extern crate alloc;

/// EMCY 8100h "EtherCAT communication error" (iPOS Table 3.1.3; CiA 301
/// "communication, generic").
pub const EMCY_COMMUNICATION: u16 = 0x8100;

/// What a profile is on EtherCAT besides its CAN dictionary.
#[derive(Debug)]
pub struct EcatFacts {
    /// CAN communication objects its CoE object list does not have.
    pub can_only: fn(u16) -> bool,
    /// 1C12h default: the RxPDOs assigned to SM2.
    pub rx_assigned: &'static [u16],
    /// 1C13h default: the TxPDOs assigned to SM3.
    pub tx_assigned: &'static [u16],
    /// Shortest SYNC0 cycle (1C32h:05) \[ns\].
    pub min_cycle_ns: u32,
    /// The SYNC0 cycle must be a multiple of this \[ns\] (the control loop).
    pub cycle_step_ns: u32,
    /// Bits one PDO carries at most.
    pub max_pdo_bits: u32,
    /// ESM errors are reported as the iPOS does: EMCY 8100h and 2000h bit 0
    /// for a communication error (watchdog, lost SYNC0), EMCY A0xxh for a
    /// refused transition (iPOS Table 3.1.3, §3.1, 2000h).
    pub esm_emcy: bool,
}

/// The generic servo on EtherCAT: every CAN-only service object goes
/// (SYNC/TIME COB-IDs and windows, guarding, heartbeat, SDO server and
/// PDO communication parameters, 1029h); 1003h, 1010h/1011h and the EDS
/// objects stay, they mean the same over CoE.
fn generic_can_only(index: u16) -> bool {
    matches!(
        index,
        0x1005..=0x1007 | 0x100C | 0x100D | 0x1012..=0x1017 | 0x1019 | 0x1029 | 0x1200..=0x12FF
            | 0x1400..=0x15FF | 0x1800..=0x19FF
    )
}

/// The generic servo's EtherCAT facts. Its PDO mapping objects keep their
/// CAN defaults; SM2/SM3 get the CiA 402 position set (1602h controlword +
/// target position, 1A02h statusword + position actual value), the
/// process data a csp master needs.
pub static GENERIC: EcatFacts = EcatFacts {
    can_only: generic_can_only,
    rx_assigned: &[0x1602],
    tx_assigned: &[0x1A02],
    min_cycle_ns: 125_000,
    cycle_step_ns: 125_000,
    max_pdo_bits: 64,
    esm_emcy: false,
};

/// The EtherCAT facts of `profile`, `None` for a CAN-only drive.
pub fn facts(profile: Profile) -> Option<&'static EcatFacts> {
    match profile {
        Profile::Ipos => Some(&crate::ipos::ecat::FACTS),
        Profile::Generic => Some(&GENERIC),
        _ => None,
    }
}

/// The PDO limits of `profile` on EtherCAT (validation of mappings).
pub fn pdo_config(profile: Profile) -> PdoConfig {
    let info = profile.info();
    let mut c = crate::build::node_config(info, 1).pdo;
    let bits = facts(profile).map_or(64, |f| f.max_pdo_bits);
    c.max_len = (bits / 8) as usize;
    c.granularity = if info.granularity == 8 { Granularity::Byte } else { Granularity::Bit };
    c
}

/// Builds `profile` as an EtherCAT slave's drive: the CAN personality,
/// then its EtherCAT dictionary (see the module docs). A profile without
/// [`facts`] is refused.
pub fn build(profile: Profile, storage: Box<dyn Storage + Send>) -> Result<PersonalityDevice, BuildError> {
    let facts = facts(profile)
        .ok_or_else(|| BuildError::Eds(alloc::format!("{profile} has no EtherCAT (CoE) dictionary")))?;
    let inner = profile.behaviour();
    let wrapper = EcatBehaviour::new(inner, facts, pdo_config(profile));
    let mut dev = build_full(profile, 1, storage, Box::new(wrapper), |_| {}, BuildOptions::default())?;
    let od = dev.node.od_mut();
    let gone: Vec<u16> = od.objects().iter().map(|o| o.index).filter(|i| (facts.can_only)(*i)).collect();
    for index in gone {
        od.remove(index);
    }
    sync_objects(od, facts);
    // The objects the EtherCAT rules own: mapping objects, assignment and
    // synchronisation parameters (the CAN PDO service has no PDO left).
    let owned: Vec<(u16, u8)> = od
        .objects()
        .iter()
        .filter(|o| rules::is_ecat_object(o.index))
        .flat_map(|o| o.subs().iter().map(move |s| (o.index, s.sub)))
        .collect();
    for (index, sub) in owned {
        if let Some(s) = od.get_mut(index, sub) {
            s.owner = crate::build::BEHAVIOUR;
            s.watched = false;
        }
    }
    // Re-resolve every service's handles after the edits.
    if let Some(o) = dev.node.od().object(0x1000).cloned() {
        dev.node.insert_object(o);
    }
    Ok(dev)
}

/// A drive's FoE files: the CoE layer's [`FileHandler`] plus what the
/// drive's dictionary says about them.
pub trait DriveFiles: FileHandler + Send {
    /// Re-reads the objects the policy depends on (iPOS 210Ch) before a
    /// request is handled.
    fn refresh(&mut self, od: &ObjectDictionary) {
        let _ = od;
    }
    /// The handler as [`Any`](core::any::Any), to reach its concrete type.
    fn as_any_mut(&mut self) -> &mut dyn core::any::Any;
}

// A drive without FoE is CoE's own `NoFiles`.
impl DriveFiles for NoFiles {
    fn as_any_mut(&mut self) -> &mut dyn core::any::Any {
        self
    }
}

/// The FoE policy of `profile` (iPOS §17.4: [`IposFiles`]; the generic
/// servo has no FoE). Setup files go to `dir` when given.
///
/// [`IposFiles`]: crate::ipos::foe::IposFiles
pub fn files(profile: Profile, dir: Option<std::path::PathBuf>) -> Box<dyn DriveFiles> {
    match profile {
        Profile::Ipos => {
            let f = crate::ipos::foe::IposFiles::new();
            Box::new(match dir {
                Some(d) => f.with_dir(d),
                None => f,
            })
        }
        _ => Box::new(NoFiles),
    }
}

/// What the EtherCAT layer tells the personality.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EsmEvent {
    /// The slave went from one ESM state to another.
    Changed {
        /// Previous state.
        from: AlState,
        /// New state.
        to: AlState,
    },
    /// The AL status shows this error code (ETG.1000.6 Table 11).
    Error(u16),
    /// The master acknowledged the error (AL control bit 4).
    Acknowledged,
}

/// The NMT state the drive sees in an ESM state: SAFE-OP and OP are
/// operational (process data runs), the others pre-operational.
pub fn nmt_state(esm: AlState) -> NmtState {
    match esm {
        AlState::SafeOp | AlState::Op => NmtState::Operational,
        _ => NmtState::PreOperational,
    }
}

/// Carries an ESM event into the node, the drive and the behaviour (see
/// the module docs). Frames the node produces (EMCY) go to `out`.
pub fn esm_event(dev: &mut PersonalityDevice, ev: EsmEvent, now: Instant, out: &mut impl TxSink) {
    match ev {
        EsmEvent::Changed { from, to } => {
            if from == AlState::Op && to != AlState::Op {
                // ETG.6010 / CiA 402-2 6007h: outputs are no longer valid;
                // the drive's abort connection option, with the EtherCAT
                // code (CAN uses 8130h).
                with_behaviour(dev, now, out, |c, _, _| c.drive.abort_connection(EMCY_COMMUNICATION));
            }
            with_behaviour(dev, now, out, |_, w, _| w.set_esm(to));
            let nmt = nmt_state(to);
            if dev.node.nmt_state() != nmt {
                dev.node.set_nmt_state(nmt, now, &mut dev.app, out);
            }
        }
        EsmEvent::Error(code) => with_behaviour(dev, now, out, |c, w, od| w.al_error(c, od, Some(code))),
        EsmEvent::Acknowledged => with_behaviour(dev, now, out, |c, w, od| w.al_error(c, od, None)),
    }
}

/// The ESM state the personality's EtherCAT rules run in; `None` for a
/// personality not built by [`build`].
pub fn esm_state(dev: &mut PersonalityDevice) -> Option<AlState> {
    wrapper(&mut dev.app.behaviour).map(|w| w.esm())
}

fn wrapper(b: &mut Box<dyn crate::Behaviour>) -> Option<&mut EcatBehaviour> {
    b.as_any_mut()?.downcast_mut::<EcatBehaviour>()
}

/// Runs `f` with a behaviour context, the EtherCAT behaviour and the
/// dictionary, then hands the drive's EMCY requests to the node as the
/// personality does after every callback.
fn with_behaviour(
    dev: &mut PersonalityDevice,
    now: Instant,
    out: &mut impl TxSink,
    f: impl FnOnce(&mut Context<'_>, &mut EcatBehaviour, &mut ObjectDictionary),
) {
    dev.node.with_app(now, &mut dev.app, out, |p, cx| {
        let (now, node_id) = (cx.now, cx.node_id());
        {
            let (od, requests) = cx.parts();
            let Personality { drive, behaviour, .. } = p;
            let Some(w) = wrapper(behaviour) else { return };
            let mut c = Context { drive, requests, node_id, now };
            f(&mut c, w, od);
        }
        let b = &p.behaviour;
        p.drive.flush_emcy(cx, |code| b.emcy(code).raise());
    });
}
