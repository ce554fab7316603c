//! A drive and its CiA 301 node as one station of the virtual bus.

use super::{Drive, DriveConfig, EmcyRequest};
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_bus::{BusNode, LinkState, Outbox};
use drivebus_can::{Frame, Instant, TxSink, earliest};
use drivebus_node::{Application, Node, NodeConfig};
use drivebus_pdo::{PdoDefaults, PdoKind, map_entry, set_defaults};

/// A [`Node`] with its [`Drive`] on the virtual bus. Like
/// `drivebus_node::SimNode`, plus: the drive's EMCY requests go to
/// `Node::raise_emcy` / `Node::clear_emcy` after every call (and are sent
/// at once). Event-driven TPDOs (254/255, e.g. the statusword in TPDO 1)
/// go out on change of their data through the PDO service.
pub struct DriveNode {
    /// The CiA 301 device.
    pub node: Node,
    /// The drive application.
    pub drive: Drive,
    booted: bool,
}

impl DriveNode {
    /// Wraps a node whose dictionary already holds the drive's objects
    /// (see [`Drive::install`]). Boots at the first poll.
    pub fn new(node: Node, drive: Drive) -> Self {
        DriveNode { node, drive, booted: false }
    }

    /// Builds node and drive from their configurations.
    pub fn build(node_cfg: NodeConfig, cfg: DriveConfig) -> Result<Self, crate::model::ParamError> {
        let mut node = Node::new(node_cfg);
        let drive = Drive::install(&mut node, cfg)?;
        Ok(DriveNode::new(node, drive))
    }

    /// Applies the drive's EMCY requests to the node; returns whether any.
    fn drain(&mut self, now: Instant) -> bool {
        let mut any = false;
        for i in 0..self.drive.emcy.len() {
            any = true;
            match self.drive.emcy[i] {
                EmcyRequest::Raise(c) => {
                    self.node.raise_emcy(c, [0; 5], now);
                }
                EmcyRequest::Clear(c) => {
                    self.node.clear_emcy(c, now);
                }
            }
        }
        self.drive.emcy.clear();
        any
    }

    fn after(&mut self, now: Instant, out: &mut impl TxSink) -> Option<Instant> {
        if self.drain(now) {
            // Send what was raised/requested now (EMCY, TPDO).
            return self.node.poll(now, &mut self.drive, out);
        }
        None
    }
}

impl DriveNode {
    /// Handles a received frame, emitting into any [`TxSink`] (a real-time
    /// loop or a benchmark; the bus uses it through [`BusNode`]).
    pub fn handle_frame_into(&mut self, frame: &Frame, now: Instant, out: &mut impl TxSink) {
        if self.booted {
            self.node.handle_frame(frame, now, &mut self.drive, out);
            self.after(now, out);
        }
    }

    /// Boots at the first call, then does the node's timed work and steps
    /// the drive up to `now`; returns the next deadline.
    pub fn poll_into(&mut self, now: Instant, out: &mut impl TxSink) -> Option<Instant> {
        if !self.booted {
            self.booted = true;
            self.node.boot(now, &mut self.drive, out);
        }
        let next = self.node.poll(now, &mut self.drive, out);
        let d = self.drive.poll(self.node.od_mut(), now);
        let again = self.after(now, out);
        earliest(earliest(next, d), again)
    }
}

impl BusNode for DriveNode {
    fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut Outbox<'_>) {
        self.handle_frame_into(frame, now, out);
    }

    fn poll(&mut self, now: Instant, out: &mut Outbox<'_>) -> Option<Instant> {
        self.poll_into(now, out)
    }

    fn link_changed(&mut self, state: LinkState, now: Instant, out: &mut Outbox<'_>) {
        // CiA 402-2 6007h: bus-off aborts the connection.
        if state != LinkState::Active {
            self.drive.inject(super::Injection::ConnectionLost);
            self.after(now, out);
        }
    }
}

/// The CiA 402 pre-defined PDO set (CiA 402-3 style): RPDO1 6040h, RPDO2
/// 6040h+607Ah, RPDO3 6040h+60FFh, RPDO4 6040h+6071h; TPDO1 6041h
/// (event-driven), TPDO2 6041h+6064h, TPDO3 6041h+606Ch, TPDO4 6041h+6077h
/// (synchronous, every SYNC).
pub fn default_pdo_mapping(node: &mut Node) {
    let cfg = node.config().pdo;
    let cw = map_entry(0x6040, 0, 16);
    let sw = map_entry(0x6041, 0, 16);
    let rpdos: [Vec<u32>; 4] = [
        alloc::vec![cw],
        alloc::vec![cw, map_entry(0x607A, 0, 32)],
        alloc::vec![cw, map_entry(0x60FF, 0, 32)],
        alloc::vec![cw, map_entry(0x6071, 0, 16)],
    ];
    let tpdos: [Vec<u32>; 4] = [
        alloc::vec![sw],
        alloc::vec![sw, map_entry(0x6064, 0, 32)],
        alloc::vec![sw, map_entry(0x606C, 0, 32)],
        alloc::vec![sw, map_entry(0x6077, 0, 16)],
    ];
    let od = node.od_mut();
    for (n, e) in rpdos.iter().enumerate() {
        // A device with fewer PDOs simply lacks the later ones.
        let _ = set_defaults(od, &cfg, PdoKind::Rpdo, n as u16, &PdoDefaults::new(e));
    }
    for (n, e) in tpdos.iter().enumerate() {
        let tt = if n == 0 { 255 } else { 1 };
        let d = PdoDefaults { transmission_type: tt, ..PdoDefaults::new(e) };
        let _ = set_defaults(od, &cfg, PdoKind::Tpdo, n as u16, &d);
    }
    // Re-resolve the PDO service (insert_object reloads it).
    if let Some(o) = node.od().object(0x6502).cloned() {
        node.insert_object(o);
    }
}

/// A fully featured CiA 402 servo drive (pp, vl, pv, tq; small servo model,
/// 8 kHz, 0.001° position units) with the pre-defined PDO set, ready to
/// attach to a `drivebus_bus::Bus`.
pub fn generic_drive(node_id: u8) -> DriveNode {
    generic_drive_with(node_id, DriveConfig::default(), Vec::new())
}

/// [`generic_drive`] with a drive configuration and mode handlers.
pub fn generic_drive_with(
    node_id: u8,
    cfg: DriveConfig,
    handlers: Vec<Box<dyn super::ModeHandler + Send>>,
) -> DriveNode {
    let mut nc = NodeConfig::new(node_id);
    nc.device_type = 0x0002_0192; // CiA 402, servo drive
    nc.device_name = Some("drivebus virtual drive".into());
    let mut node = Node::new(nc);
    let drive = match Drive::install_with(&mut node, cfg, handlers) {
        Ok(d) => d,
        // The built-in presets always validate; a bad custom configuration
        // falls back to the default drive rather than failing the bus.
        Err(_) => Drive::install(&mut node, DriveConfig::default()).expect("default drive config is valid"),
    };
    default_pdo_mapping(&mut node);
    DriveNode::new(node, drive)
}
