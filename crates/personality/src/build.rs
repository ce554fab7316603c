//! Building a running drive from a personality: the framework.
//!
//! [`build`] turns a [`Profile`] into a `NodeDevice<Personality>` — a CiA
//! 301 [`Node`] whose dictionary comes from the profile's EDS, and as its
//! application a [`Personality`]: a CiA 402 [`Drive`] installed on the node
//! with the profile's default PDOs as factory defaults, and the
//! personality's [`Behaviour`] in front of the drive. It is a
//! `drivebus_can::Device`, so any host runs it (the virtual bus, the
//! real-time host on a real bus):
//!
//! ```
//! use drivebus_bus::{Bus, BusConfig};
//! use drivebus_can::Duration;
//! use drivebus_node::NodeDevice;
//! use drivebus_personality::{Personality, Profile};
//!
//! let mut bus = Bus::new(BusConfig::zero_time());
//! let id = bus.attach(Profile::Generic.build(3).unwrap());
//! bus.run_for(Duration::from_millis(1));
//! let d = bus.node::<NodeDevice<Personality>>(id).unwrap();
//! assert_eq!(d.app.drive.statusword() & 0x4F, 0x40); // switch on disabled
//! assert_eq!(d.node.od().get_u32(0x1000, 0), Some(0x0002_0192));
//! ```
//!
//! # Order of construction (what [`build`] does)
//!
//! 1. dictionary: `drivebus_eds::to_od(profile EDS, node_id)`;
//! 2. [`node_config`] from [`ProfileInfo`] (identity, PDO counts and
//!    granularity, block SDO, TIME, NMT commands, error control, EMCY
//!    history, LSS, 1015h), then [`Behaviour::adjust_node_config`], then
//!    [`BuildOptions`] (1021h/1022h);
//! 3. `Node::with_dictionary(cfg, od, storage)`;
//! 4. [`drive_config`] + mode handlers from [`ProfileInfo::modes`] and a
//!    homing registry of [`ProfileInfo::homing_methods`] (standard codes from
//!    `drivebus_cia402`, manufacturer codes from
//!    [`Behaviour::homing_methods`]), `Drive::install_with`;
//! 5. 6502h and 60E3h set to what the profile reports;
//! 6. the profile's PDO defaults written as value *and* default (1011h
//!    restore brings them back);
//! 7. the objects named by [`Behaviour::hooked_objects`] reach the
//!    behaviour: it owns the plain ones and watches (may veto) those a
//!    CiA 301 service or the drive owns; their reads reach it too.
//!
//! # How a behaviour is composed with the drive
//!
//! The node hands the [`Personality`] the writes of the objects it owns
//! (the drive's, the behaviour's) and watches, once each on the write path
//! (`DEVELOPERS.md`): the behaviour decides *first* ([`Verdict`]), then the
//! drive's entry checks; after the store the drive applies, then
//! [`Behaviour::after_write`]. The 6060h check (manufacturer modes
//! included, [`Behaviour::manufacturer_mode`] →
//! `DriveConfig::manufacturer_modes`) is the drive's. Received frames pass
//! [`Behaviour::filter_rx`] before the node sees them. After every drive
//! step the behaviour may patch live values ([`Behaviour::after_step`]:
//! statusword bits 8/9/14/15). Fault codes the drive raises are turned into
//! EMCY frames by [`Behaviour::emcy`]. What a behaviour wants from the node
//! (EMCY, a TPDO, a local NMT command, …) it queues as a
//! [`drivebus_node::Request`] ([`Context::request`]), the one way requests
//! reach the node. [`Personality::behaviour_mut`] reaches the behaviour's
//! concrete type at run time ([`Behaviour::as_any_mut`]).

use crate::{PdoDefault, Profile, ProfileInfo};
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_can::{Frame, Instant};
use drivebus_cia402::drive::{Drive, DriveConfig, ModeHandler, op};
use drivebus_cia402::homing::{HomingMethod, HomingMode, HomingRegistry, StandardMethod};
use drivebus_cia402::interp::{CspMode, CstMode, CsvMode, IpMode};
use drivebus_nmt::{CommandSet, NmtCommand};
use drivebus_node::{Identity, MemoryStorage, Node, NodeConfig, NodeDevice, NodeEvent, Request, Storage};
use drivebus_od::{ObjectDictionary, Owner, SdoAbort, Value};
use drivebus_pdo::{DEFAULT_DUMMY_TYPES, Granularity, PdoDefaults, PdoKind, set_defaults};

extern crate alloc;

mod conform;
mod eds_od;
mod node_od;
mod personality;

pub(crate) use personality::BEHAVIOUR;
pub use personality::Personality;

/// A running personality: the node and its [`Personality`].
pub type PersonalityDevice = NodeDevice<Personality>;

/// What [`Behaviour::filter_rx`] does with a received frame (the node's
/// [`drivebus_node::FrameFilter`]).
pub type FilterOutcome = drivebus_node::FrameFilter;

/// Why a personality could not be built.
#[derive(Debug, Clone, PartialEq)]
pub enum BuildError {
    /// Node-ID outside 1..=127.
    NodeId(u8),
    /// The profile's EDS did not convert to a dictionary.
    Eds(alloc::string::String),
    /// The drive model or configuration was refused.
    Drive(drivebus_cia402::model::ParamError),
    /// A default PDO of the profile could not be applied (RPDO/TPDO, 0-based
    /// number, abort).
    Pdo(PdoKind, u16, SdoAbort),
    /// The machine around the drive does not make sense.
    Machine(crate::machine::MachineError),
}

impl core::fmt::Display for BuildError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            BuildError::NodeId(id) => write!(f, "node-ID {id} outside 1..=127"),
            BuildError::Eds(e) => write!(f, "EDS: {e}"),
            BuildError::Drive(e) => write!(f, "drive: {e:?}"),
            BuildError::Pdo(k, n, a) => write!(f, "default {k:?} {}: abort {:08X}", n + 1, a.0),
            BuildError::Machine(e) => write!(f, "machine: {e}"),
        }
    }
}

impl std::error::Error for BuildError {}

/// What the behaviour decides about a write, before the drive sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Not the behaviour's business: the drive (and then the CiA 301
    /// service owning the object) checks and stores it.
    Pass,
    /// Store the written bytes as they are, without asking the drive (the
    /// CiA 301 service still checks communication objects).
    Store,
    /// The behaviour applied the write itself (possibly storing other
    /// values, possibly nothing: a dummy object that ignores its data).
    Handled,
}

/// One EMCY frame as a personality sends it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EmcyFrame {
    /// Error code (bytes 0–1).
    pub code: u16,
    /// Error register bits of this error (byte 2, also 1001h); `None` =
    /// CiA 301's bookkeeping (generic bit 0 plus the class bit). With
    /// `Some`, the framework keeps the error bookkeeping itself and the
    /// register is exactly the OR of the active errors' bits, without a
    /// forced generic bit (KC1/AKD examples 11/12: 08h for 4310h).
    pub register: Option<u8>,
    /// Manufacturer-specific bytes 3–7.
    pub bytes: [u8; 5],
}

impl EmcyFrame {
    /// Raise this error (1001h, 1003h, EMCY).
    pub fn raise(self) -> Request {
        Request::RaiseEmcy { code: self.code, register: self.register, manufacturer: self.bytes }
    }
    /// Send this frame outside the error bookkeeping.
    pub fn raw(self) -> Request {
        Request::RawEmcy { code: self.code, register: self.register.unwrap_or(0), bytes: self.bytes }
    }
}

/// The context a [`Behaviour`] gets: the drive (to forward a translated
/// write, read its state, inject a fault) and the node's request queue.
pub struct Context<'a> {
    /// The CiA 402 drive this behaviour sits in front of.
    pub drive: &'a mut Drive,
    /// Requests for the node, carried out after the current call.
    pub requests: &'a mut Vec<Request>,
    /// The node-ID.
    pub node_id: u8,
    /// Simulated time of the call.
    pub now: Instant,
}

impl Context<'_> {
    /// Queue a request for the node (EMCY, TPDO, local NMT, …).
    pub fn request(&mut self, r: Request) {
        self.requests.push(r);
    }
}

/// What makes a drive a KC1 rather than a generic servo: the quirks of a
/// personality, as hooks around the CiA 402 drive. Every method has a
/// do-nothing default, so a personality implements only what its manual
/// documents ("faithful by default").
pub trait Behaviour: Send {
    /// The personality this behaviour belongs to.
    fn profile(&self) -> Profile;

    /// Change the node configuration derived from [`ProfileInfo`] (e.g. RTR
    /// on TPDOs, 1021h EDS object, SDO buffer size).
    fn adjust_node_config(&self, cfg: &mut NodeConfig) {
        let _ = cfg;
    }

    /// Change the drive configuration derived from [`ProfileInfo`] (units,
    /// motor, I/O, option codes).
    fn adjust_drive_config(&self, cfg: &mut DriveConfig) {
        let _ = cfg;
    }

    /// Manufacturer homing methods (negative 6098h codes) this drive offers.
    /// Standard codes of [`ProfileInfo::homing_methods`] are built by the
    /// framework.
    fn homing_methods(&self) -> Vec<Box<dyn HomingMethod + Send>> {
        Vec::new()
    }

    /// The interpolated position handler (60C4h buffer depth and
    /// organisation), for profiles with ip: a 16-record FIFO unless the
    /// drive documents otherwise.
    fn ip_mode(&self) -> IpMode {
        IpMode::new(16)
    }

    /// The standard mode (1..=10) a manufacturer mode (negative 6060h) runs
    /// on inside the drive; `None` refuses the mode. 6061h shows the
    /// manufacturer code while the drive runs the stand-in mode.
    fn manufacturer_mode(&self, mode: i8) -> Option<i8> {
        let _ = mode;
        None
    }

    /// Objects whose reads and writes this behaviour must see (all their
    /// sub-indices are hooked after the drive is installed).
    fn hooked_objects(&self) -> &'static [u16] {
        &[]
    }

    /// Called once the dictionary is complete (after the drive and the PDO
    /// defaults): last adjustments of values and defaults.
    fn finish(&mut self, node: &mut Node) {
        let _ = node;
    }

    /// A received frame before the node handles it: pass it, replace it
    /// (e.g. an SDO download whose size field is corrected to the object's
    /// size) or drop it (see [`FilterOutcome`]). The personality's
    /// [`drivebus_node::Application::filter_frame`].
    fn filter_rx(&mut self, od: &ObjectDictionary, node_id: u8, frame: &Frame) -> FilterOutcome {
        let _ = (od, node_id, frame);
        FilterOutcome::Pass
    }

    /// A write to a hooked object, before the drive sees it.
    fn on_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<Verdict, SdoAbort> {
        let _ = (cx, od, index, sub, data);
        Ok(Verdict::Pass)
    }

    /// A write to an object the personality owns or watches was stored
    /// and applied by its owner (the drive, a CiA 301 service).
    fn after_write(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, index: u16, sub: u8) {
        let _ = (cx, od, index, sub);
    }

    /// A read of a hooked object (SDO upload, TPDO sampling): may refresh
    /// the value or refuse.
    fn on_read(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
    ) -> Result<(), SdoAbort> {
        let _ = (cx, od, index, sub);
        Ok(())
    }

    /// After the boot-up message: extra frames the drive sends at power-on
    /// (queued as requests; sent by the poll that follows).
    fn on_boot(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let _ = (cx, od);
    }

    /// A node event (NMT state, guarding, SYNC loss …), after the drive saw it.
    fn on_event(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, event: &NodeEvent) {
        let _ = (cx, od, event);
    }

    /// After the drive stepped and published: patch live values (statusword
    /// bits 8, 9, 14, 15; 6061h of a manufacturer mode).
    fn after_step(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let _ = (cx, od);
    }

    /// The EMCY frame for a fault code the drive raises (603Fh code).
    fn emcy(&self, code: u16) -> EmcyFrame {
        EmcyFrame { code, register: None, bytes: [0; 5] }
    }

    /// The behaviour as [`Any`](core::any::Any), so its owner can reach the
    /// concrete type at run time ([`Personality::behaviour_mut`]: the
    /// SSD 630's enable input, a test's switches). `None`: not reachable.
    fn as_any_mut(&mut self) -> Option<&mut dyn core::any::Any> {
        None
    }
}

/// A behaviour with no quirks: the drive as CiA 301/402 describe it (a
/// variant of a personality without its quirks, tests).
#[derive(Debug, Clone, Copy)]
pub struct Plain(pub Profile);

impl Behaviour for Plain {
    fn profile(&self) -> Profile {
        self.0
    }
}

/// The CiA 301 configuration a profile's facts call for (before
/// [`Behaviour::adjust_node_config`]).
pub fn node_config(info: &ProfileInfo, node_id: u8) -> NodeConfig {
    let mut c = NodeConfig::new(node_id);
    c.device_type = info.device_type;
    c.identity = Identity {
        vendor_id: info.vendor_id.unwrap_or(0),
        product_code: info.product_code.unwrap_or(0),
        revision: info.revision.unwrap_or(0),
        serial: 0,
    };
    let mut cmds = CommandSet::ALL;
    if !info.nmt_enter_preoperational {
        cmds = cmds.without(NmtCommand::EnterPreOperational);
    }
    c.nmt.supported_commands = cmds;
    c.nmt.heartbeat_supported = info.heartbeat_producer;
    c.nmt.guarding_supported = info.node_guarding;
    c.nmt.life_guarding_honoured = info.life_guarding;
    c.pdo.rpdo_count = info.rpdo.len() as u16;
    c.pdo.tpdo_count = info.tpdo.len() as u16;
    c.pdo.granularity = if info.granularity == 8 { Granularity::Byte } else { Granularity::Bit };
    c.pdo.max_entries = info.max_mapped_entries;
    c.pdo.dummy_types = if info.dummy_mapping { DEFAULT_DUMMY_TYPES } else { 0 };
    c.sdo.block_transfer = info.sdo_block;
    c.heartbeat_consumers = info.heartbeat_consumers;
    c.emcy_history = info.error_history;
    c.error_classes = u8::from(info.error_behaviour);
    // 1015h only where the manual lists it (KC1 §8.1.2, AKD, iPOS lack it).
    c.emcy_inhibit = info.emcy_inhibit;
    c.time = info.time;
    c.lss = info.lss;
    c.store_restore = true;
    c.eds_object = false;
    c
}

/// The node configuration of a build: [`node_config`], the EDS's device
/// info for 1021h, the behaviour's adjustments, the options.
fn full_node_config(
    profile: Profile,
    node_id: u8,
    behaviour: &dyn Behaviour,
    options: BuildOptions,
) -> NodeConfig {
    let mut nc = node_config(profile.info(), node_id);
    // The EDS served at 1021h says what the shipped one says.
    nc.eds_device_info = Some(profile.eds().eds.device_info.clone());
    nc.eds_file_info = Some(profile.eds().eds.file_info.clone());
    behaviour.adjust_node_config(&mut nc);
    // An option adds to the personality; it never takes 1021h away.
    nc.eds_object |= options.eds_object;
    nc
}

/// The CiA 402 drive configuration a profile's facts call for (before
/// [`Behaviour::adjust_drive_config`]): the small servo model, the profile's
/// own modes among pp, vl, pv, tq, its first listed standard mode as the
/// power-on mode.
pub fn drive_config(info: &ProfileInfo) -> DriveConfig {
    let modes = [op::PP, op::VL, op::PV, op::TQ]
        .iter()
        .filter(|m| info.modes.contains(m))
        .fold(0, |acc, &m| acc | op::supported_bit(m));
    use drivebus_cia402::drive::{IoConfig, profile_type};
    let d = DriveConfig::default();
    DriveConfig {
        modes,
        initial_mode: 0,
        // The drive features a personality opts into in its
        // `Behaviour::adjust_drive_config`: 6086h = 3 (S-curve) with 60A4h,
        // 60D0h touch probe source. Off here, so each profile keeps the
        // objects of its EDS and its manual's 6086h range.
        motion_profile_types: profile_type::LINEAR | profile_type::SIN_SQUARED,
        profile_jerk_object: false,
        io: IoConfig { probe_source_object: false, ..d.io },
        ..d
    }
}

/// The mode handlers for the profile's hm, ip, csp, csv, cst.
fn handlers(info: &ProfileInfo, behaviour: &dyn Behaviour) -> Vec<Box<dyn ModeHandler + Send>> {
    let mut v: Vec<Box<dyn ModeHandler + Send>> = Vec::new();
    if info.modes.contains(&op::HM) {
        let mut reg = HomingRegistry::empty();
        for &code in info.homing_methods.iter().filter(|c| **c > 0) {
            if let Some(m) = StandardMethod::new(code) {
                reg.register(Box::new(m));
            }
        }
        for m in behaviour.homing_methods() {
            reg.register(m);
        }
        v.push(Box::new(HomingMode::new(reg)));
    }
    if info.modes.contains(&op::IP) {
        v.push(Box::new(behaviour.ip_mode()));
    }
    if info.modes.contains(&op::CSP) {
        v.push(Box::new(CspMode::new()));
    }
    if info.modes.contains(&op::CSV) {
        v.push(Box::new(CsvMode::new()));
    }
    if info.modes.contains(&op::CST) {
        v.push(Box::new(CstMode::new()));
    }
    v
}

/// Sets value and default of one sub-object (if it exists).
pub fn set_default(od: &mut ObjectDictionary, index: u16, sub: u8, v: &Value) {
    if od.set_value(index, sub, v).is_ok()
        && let Ok(r) = od.find(index, sub)
    {
        let bytes = od.bytes(r).to_vec();
        if let Some(s) = od.get_mut(index, sub) {
            s.default = bytes;
        }
    }
}

/// Writes one profile PDO default into the dictionary (value and default).
fn apply_pdo(
    od: &mut ObjectDictionary,
    cfg: &drivebus_pdo::PdoConfig,
    kind: PdoKind,
    n: u16,
    d: &PdoDefault,
    node_id: u8,
) -> Result<(), SdoAbort> {
    let cob = d.cob_id.map(|c| {
        let base = c & 0x7FF;
        let id = if base & 0x7F == 0 { base + u32::from(node_id) } else { base };
        (c & 0xC000_0000) | id
    });
    let cob_id = match (d.enabled, cob) {
        // A valid pre-defined COB-ID stays node-relative (CiA 301 default).
        (true, _) => None,
        (false, Some(c)) => Some(c),
        // Not assigned on EtherCAT (no COB-ID given): on CAN the PDO is
        // there but invalid, the pre-defined COB-ID with bit 31 set (iPOS
        // §2.3.7/§2.3.8: "disabled … by setting Bit31 to 1").
        (false, None) => Some(drivebus_pdo::default_cob_id(cfg, kind, n) | drivebus_pdo::COB_INVALID),
    };
    let pd = PdoDefaults {
        entries: d.mapping,
        transmission_type: d.transmission_type.unwrap_or(0xFF),
        inhibit_time: 0,
        event_timer: d.event_timer_ms,
        cob_id,
    };
    set_defaults(od, cfg, kind, n, &pd)
}

/// Builds the personality `profile` as node `node_id` with parameters in
/// `storage`, with the profile's own [`Behaviour`]
/// ([`Profile::behaviour`]).
pub fn build(
    profile: Profile,
    node_id: u8,
    storage: Box<dyn Storage + Send>,
) -> Result<PersonalityDevice, BuildError> {
    build_with(profile, node_id, storage, profile.behaviour())
}

/// [`build`] with an explicit behaviour (tests, a personality variant).
pub fn build_with(
    profile: Profile,
    node_id: u8,
    storage: Box<dyn Storage + Send>,
    behaviour: Box<dyn Behaviour>,
) -> Result<PersonalityDevice, BuildError> {
    build_custom(profile, node_id, storage, behaviour, |_| {})
}

/// [`build`] on a given machine: `machine` adjusts the drive configuration
/// after the personality did — the plant the drive is attached to (home
/// and limit switches, end stops, load, motor), not the drive's behaviour.
pub fn build_on_machine(
    profile: Profile,
    node_id: u8,
    storage: Box<dyn Storage + Send>,
    machine: impl FnOnce(&mut DriveConfig),
) -> Result<PersonalityDevice, BuildError> {
    build_custom(profile, node_id, storage, profile.behaviour(), machine)
}

/// Options of a build beyond what the personality's manual describes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BuildOptions {
    /// Serve the device's own EDS at 1021h "store EDS" with 1022h "storage
    /// format" (CiA 301 §7.5.2.21/22), generated from the running
    /// dictionary, even where the manual does not list the objects (only
    /// `generic` has them by default): a tool can then read the emulated
    /// drive's dictionary off the bus (`drivebus serve --eds-object`).
    pub eds_object: bool,
}

/// [`build`] with [`BuildOptions`].
pub fn build_with_options(
    profile: Profile,
    node_id: u8,
    storage: Box<dyn Storage + Send>,
    options: BuildOptions,
) -> Result<PersonalityDevice, BuildError> {
    build_full(profile, node_id, storage, profile.behaviour(), |_| {}, options)
}

/// The general form of [`build`]: explicit behaviour and machine.
pub fn build_custom(
    profile: Profile,
    node_id: u8,
    storage: Box<dyn Storage + Send>,
    behaviour: Box<dyn Behaviour>,
    machine: impl FnOnce(&mut DriveConfig),
) -> Result<PersonalityDevice, BuildError> {
    build_full(profile, node_id, storage, behaviour, machine, BuildOptions::default())
}

/// [`build`] with [`BuildOptions`] on `machine`: the drive gets the
/// machine's axis, switches, stops, index and load
/// ([`Machine::apply`](crate::machine::Machine::apply)) and applies its
/// faults as time passes. What `drivebus serve` and the other CLI hosts
/// build, with [`Machine::default_for`](crate::machine::Machine::default_for)
/// the profile unless a machine file says otherwise.
pub fn build_on(
    profile: Profile,
    node_id: u8,
    storage: Box<dyn Storage + Send>,
    options: BuildOptions,
    machine: &crate::machine::Machine,
) -> Result<PersonalityDevice, BuildError> {
    machine.check().map_err(BuildError::Machine)?;
    let mut dev = build_full(profile, node_id, storage, profile.behaviour(), |c| machine.apply(c), options)?;
    dev.app.set_fault_schedule(machine.fault_schedule());
    Ok(dev)
}

/// [`build_custom`] with [`BuildOptions`]: every argument explicit.
pub fn build_full(
    profile: Profile,
    node_id: u8,
    storage: Box<dyn Storage + Send>,
    mut behaviour: Box<dyn Behaviour>,
    machine: impl FnOnce(&mut DriveConfig),
    options: BuildOptions,
) -> Result<PersonalityDevice, BuildError> {
    let info = profile.info();
    // Quirk `node-id-0-is-1` (KC1 §6.2): rotary switches at 0 mean node 1.
    let node_id =
        if node_id == 0 && info.quirks.iter().any(|q| q.id == "node-id-0-is-1") { 1 } else { node_id };
    if !(1..=127).contains(&node_id) {
        return Err(BuildError::NodeId(node_id));
    }
    let nc = full_node_config(profile, node_id, &*behaviour, options);
    let pdo_cfg = nc.pdo;
    // The EDS read and converted once per process (`eds_od`), the
    // services merged in once per process (`node_od`) for the profile's
    // usual configuration. What the drive must answer with, after the
    // build (`conform`): the EDS dictionary.
    let usual = || full_node_config(profile, node_id, &*profile.behaviour(), BuildOptions::default());
    let fast = node_od::node_template(profile, &nc, usual)
        .and_then(|t| Some((t, eds_od::described(profile, node_id)?)));
    let (mut node, described) = match fast {
        Some((t, described)) => (t.into_node(storage), described),
        None => {
            let eds_od::EdsDictionary { od, described } = eds_od::eds_dictionary(profile, node_id)
                .map_err(|e| BuildError::Eds(alloc::format!("{e:?}")))?;
            (Node::with_dictionary(nc, od, storage), described)
        }
    };

    let mut dc = drive_config(info);
    behaviour.adjust_drive_config(&mut dc);
    machine(&mut dc);
    // The manufacturer modes of 6060h the profile lists, on their stand-ins.
    dc.manufacturer_modes = info
        .modes
        .iter()
        .filter(|m| **m < 0)
        .filter_map(|&m| behaviour.manufacturer_mode(m).map(|s| (m, s)))
        .collect();
    let hs = handlers(info, &*behaviour);
    let mut drive = Drive::install_with(&mut node, dc, hs).map_err(BuildError::Drive)?;

    {
        let od = node.od_mut();
        // 6502h as the drive reports it (may differ from what 6060h takes).
        set_default(od, 0x6502, 0, &Value::U32(info.supported_drive_modes));
        // 60E3h: the profile's homing methods, manufacturer ones included.
        if od.object(0x60E3).is_some() {
            let n = info.homing_methods.len() as u8;
            let mut o = drivebus_od::Object::array(
                0x60E3,
                "Supported homing methods",
                drivebus_od::DataType::Integer8,
                drivebus_od::Access::Ro,
                n,
                Value::I8(0),
            );
            for (i, s) in o.subs_mut().iter_mut().skip(1).enumerate() {
                s.default = alloc::vec![info.homing_methods[i] as u8];
            }
            od.insert(o);
            for (i, &m) in info.homing_methods.iter().enumerate() {
                set_default(od, 0x60E3, i as u8 + 1, &Value::I8(m));
            }
        }
        for (n, d) in info.rpdo.iter().enumerate() {
            apply_pdo(od, &pdo_cfg, PdoKind::Rpdo, n as u16, d, node_id)
                .map_err(|a| BuildError::Pdo(PdoKind::Rpdo, n as u16, a))?;
        }
        for (n, d) in info.tpdo.iter().enumerate() {
            apply_pdo(od, &pdo_cfg, PdoKind::Tpdo, n as u16, d, node_id)
                .map_err(|a| BuildError::Pdo(PdoKind::Tpdo, n as u16, a))?;
        }
        for &index in behaviour.hooked_objects() {
            if let Some(o) = od.object(index) {
                let subs: Vec<u8> = o.subs().iter().map(|s| s.sub).collect();
                for s in subs {
                    if let Some(e) = od.get_mut(index, s) {
                        // A plain object becomes the behaviour's; one a
                        // service or the drive owns is watched (veto first).
                        if e.owner == Owner::NONE {
                            e.owner = BEHAVIOUR;
                        } else if !e.owner.is_app() {
                            e.watched = true;
                        }
                        e.live = true;
                    }
                }
            }
        }
    }
    behaviour.finish(&mut node);
    let keep: &[u16] = if node.config().eds_object { &[0x1021, 0x1022] } else { &[] };
    conform::conform(node.od_mut(), &mut drive, &described, keep);
    // Re-resolve every service's handles after the edits above.
    if let Some(o) = node.od().object(0x1000).cloned() {
        node.insert_object(o);
    }
    Ok(NodeDevice::new(node, Personality::new(drive, behaviour, profile)))
}

impl Profile {
    /// The personality's own [`Behaviour`], fresh (what [`build`] installs).
    pub fn behaviour(&self) -> Box<dyn Behaviour> {
        match self {
            Profile::Kc1 => Box::new(crate::kc1::kc1()),
            Profile::Akd => Box::new(crate::akd::Akd::new()),
            Profile::Generic => Box::new(crate::generic::Generic::new()),
            Profile::Ssd630 => Box::new(crate::ssd630::Ssd630::new()),
            Profile::Dds6 => Box::new(crate::dds6::Dds6::new()),
            Profile::Ipos => Box::new(crate::ipos::Ipos::new()),
        }
    }

    /// This personality as node `node_id`, parameters in memory: the
    /// one-liner for tests and the CLI (`serve --drive akd:5`).
    pub fn build(&self, node_id: u8) -> Result<PersonalityDevice, BuildError> {
        build(*self, node_id, Box::new(MemoryStorage::new()))
    }

    /// This personality with parameters in `storage` (e.g. a
    /// `drivebus_node::FileStorage`).
    pub fn build_with_storage(
        &self,
        node_id: u8,
        storage: Box<dyn Storage + Send>,
    ) -> Result<PersonalityDevice, BuildError> {
        build(*self, node_id, storage)
    }

    /// This personality as node `node_id` on its default machine
    /// ([`Machine::default_for`](crate::machine::Machine::default_for)),
    /// parameters in memory: the drive as `drivebus serve` hosts it.
    pub fn build_on_default_machine(&self, node_id: u8) -> Result<PersonalityDevice, BuildError> {
        let m = crate::machine::Machine::default_for(*self);
        build_on(*self, node_id, Box::new(MemoryStorage::new()), BuildOptions::default(), &m)
    }

    /// This personality on `machine`, parameters in memory.
    pub fn build_on(
        &self,
        node_id: u8,
        machine: &crate::machine::Machine,
    ) -> Result<PersonalityDevice, BuildError> {
        build_on(*self, node_id, Box::new(MemoryStorage::new()), BuildOptions::default(), machine)
    }

    /// This personality with parameters in `storage` and [`BuildOptions`]
    /// (e.g. the EDS at 1021h: `serve --eds-object`).
    pub fn build_with_options(
        &self,
        node_id: u8,
        storage: Box<dyn Storage + Send>,
        options: BuildOptions,
    ) -> Result<PersonalityDevice, BuildError> {
        build_with_options(*self, node_id, storage, options)
    }
}

/// Parses `PROFILE:NODE` (`akd:5`, `generic:0x10`) as the CLI takes it.
pub fn parse_drive_spec(spec: &str) -> Option<(Profile, u8)> {
    let (p, n) = spec.split_once(':')?;
    let profile = Profile::from_name(p.trim())?;
    let n = n.trim();
    let id = match n.strip_prefix("0x").or_else(|| n.strip_prefix("0X")) {
        Some(h) => u8::from_str_radix(h, 16).ok()?,
        None => n.parse().ok()?,
    };
    (1..=127).contains(&id).then_some((profile, id))
}
