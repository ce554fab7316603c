//! What a device is: identity, which services it has, and their sizes.

use alloc::string::String;
use drivebus_can::Identity;
use drivebus_nmt::NmtConfig;
use drivebus_pdo::PdoConfig;
use drivebus_sdo::server::ServerConfig;

/// Everything fixed when a device is built.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeConfig {
    /// Node-ID 1..=127, or 0xFF for an unconfigured LSS node.
    pub node_id: u8,
    /// 1000h device type (e.g. 0x0002_0192 for a CiA 402 servo drive).
    pub device_type: u32,
    /// 1018h.
    pub identity: Identity,
    /// 1008h manufacturer device name (`None`: object absent).
    pub device_name: Option<String>,
    /// 1009h manufacturer hardware version.
    pub hardware_version: Option<String>,
    /// 100Ah manufacturer software version.
    pub software_version: Option<String>,
    /// NMT and error-control switches (the node-ID in it is kept in step).
    pub nmt: NmtConfig,
    /// PDO counts, granularity, limits.
    pub pdo: PdoConfig,
    /// SDO server behaviour (timeout, block support, size limits).
    pub sdo: ServerConfig,
    /// Additional server SDOs (1201h..).
    pub extra_sdo_servers: u8,
    /// 1200h, the default SDO server's parameter (optional in CiA 301:
    /// its identifiers are the pre-defined 600h/580h + node-ID). Without
    /// it the default server runs all the same.
    pub sdo_server_param: bool,
    /// 1016h entries (0: no heartbeat consumer).
    pub heartbeat_consumers: u8,
    /// 1003h history depth (0: no 1003h).
    pub emcy_history: u8,
    /// 1028h entries (0: no EMCY consumer).
    pub emcy_consumers: u8,
    /// 1029h error classes (0: no 1029h).
    pub error_classes: u8,
    /// 1015h inhibit time EMCY. Without it (a device whose manual does not
    /// list the object) EMCY frames go out with no inhibit time.
    pub emcy_inhibit: bool,
    /// The EMCY of a heartbeat or life-guarding loss (8130h) with a
    /// device-defined error register and manufacturer bytes (as the
    /// application's `Request::RaiseEmcy` with `Some` register), for a
    /// device that sends it in the form of its other errors; `None`: CiA
    /// 301 bookkeeping.
    pub comm_error_emcy: Option<(u8, [u8; 5])>,
    /// 1007h synchronous window length. Without it there is no window:
    /// synchronous PDOs are processed whenever a SYNC came.
    pub sync_window: bool,
    /// 1019h synchronous counter overflow value. Without it SYNC has no
    /// counter (DLC 0).
    pub sync_counter: bool,
    /// TIME object 1012h and its service.
    pub time: bool,
    /// LSS slave (CiA 305).
    pub lss: bool,
    /// 1010h/1011h store and restore.
    pub store_restore: bool,
    /// 1021h "store EDS" (generated from the running dictionary on read)
    /// and 1022h storage format (0: ASCII). Needs the `std` feature.
    pub eds_object: bool,
    /// `[DeviceInfo]` of the EDS served at 1021h: what only the device's
    /// own description knows (vendor and product names, order code, bit
    /// rates). What the running node knows (1018h, PDO counts and
    /// granularity, LSS) is taken from it. `None`: no names, every CiA
    /// 301 bit rate.
    #[cfg(feature = "std")]
    pub eds_device_info: Option<drivebus_eds::DeviceInfo>,
    /// `[FileInfo]` of the EDS served at 1021h: the device's own
    /// description's (file name, versions, dates, authors), so the served
    /// file identifies itself as the shipped one does. `None`: drivebus's
    /// generated header.
    #[cfg(feature = "std")]
    pub eds_file_info: Option<Vec<(String, String)>>,
    /// The file served at 1021h as it is (a device built from its EDS or
    /// DCF, [`crate::Node::from_eds`]) instead of one generated from the
    /// running dictionary.
    #[cfg(feature = "std")]
    pub eds_text: Option<std::sync::Arc<str>>,
}

impl NodeConfig {
    /// A generic CiA 301 device with every service: 4+4 PDOs, heartbeat and
    /// guarding, 8-deep error history, SYNC, TIME, LSS, store/restore.
    pub fn new(node_id: u8) -> NodeConfig {
        let pdo_id = if (1..=127).contains(&node_id) { node_id } else { 1 };
        NodeConfig {
            node_id,
            device_type: 0,
            identity: Identity::default(),
            device_name: None,
            hardware_version: None,
            software_version: None,
            nmt: NmtConfig::new(node_id),
            pdo: PdoConfig::new(pdo_id),
            sdo: ServerConfig::default(),
            extra_sdo_servers: 0,
            sdo_server_param: true,
            heartbeat_consumers: 4,
            emcy_history: 8,
            emcy_consumers: 0,
            error_classes: 1,
            emcy_inhibit: true,
            comm_error_emcy: None,
            sync_window: true,
            sync_counter: true,
            time: true,
            lss: true,
            store_restore: true,
            eds_object: false,
            #[cfg(feature = "std")]
            eds_device_info: None,
            #[cfg(feature = "std")]
            eds_file_info: None,
            #[cfg(feature = "std")]
            eds_text: None,
        }
    }
}
