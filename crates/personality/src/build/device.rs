//! A device from any EDS or DCF (`drivebus serve --device FILE:NODE`):
//! the CiA 301 node the file describes ([`Node::from_eds`]) and, when
//! 1000h says it is a CiA 401 generic I/O module, a
//! [`drivebus_cia401::IoModule`] as its application, its inputs driven by
//! the machine around it ([`Machine::io`](crate::machine::Machine::io) and
//! the `[[node.inputs]]` schedule, `docs/machine.md`).
//!
//! ```
//! use drivebus_node::{EdsOptions, MemoryStorage};
//! use drivebus_personality::build::{DeviceApp, build_device};
//! let text = "[1000]\nParameterName=Device type\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x00030191\n\
//!             [6000]\nParameterName=Read input 8-bit\nObjectType=0x8\nSubNumber=2\n\
//!             [6000sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n\
//!             [6000sub1]\nParameterName=Input 1-8\nDataType=0x0005\nAccessType=ro\nPDOMapping=1\n";
//! let eds = drivebus_eds::parse(text).unwrap().eds;
//! let (dev, _warnings) =
//!     build_device(&eds, text, 9, Box::new(MemoryStorage::new()), EdsOptions::default(), None).unwrap();
//! assert!(matches!(dev.app, DeviceApp::Io(_)));
//! ```

use crate::machine::{Change, FaultSchedule, Input, Machine, MachineError};
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_can::Instant;
use drivebus_cia401::{IoModule, volts_to_raw};
use drivebus_cia402::drive::Injection;
use drivebus_cia402::model::ModelInjection as Plant;
use drivebus_eds::{Diagnostic, Eds, EdsError};
use drivebus_node::{AppContext, Application, EdsOptions, FrameFilter, Node, NodeDevice, NodeEvent, Storage};
use drivebus_od::{ObjectDictionary, SdoAbort, Target, WriteOutcome};

extern crate alloc;

/// A CiA 401 module and the machine's input schedule that drives it.
pub struct IoNode {
    /// The module (its outputs, the inputs it shows).
    pub module: IoModule,
    schedule: FaultSchedule,
}

impl IoNode {
    /// The module on `machine`: its digital inputs (lines 1–16), analog
    /// inputs (channels 1–4, volts as [`volts_to_raw`]), outputs wired back
    /// to inputs, and the input changes it schedules.
    pub fn new(mut module: IoModule, machine: &Machine) -> IoNode {
        for line in 1..=16u16 {
            module.set_input_line(line, machine.io.digital_inputs & (1 << (line - 1)) != 0);
        }
        for (k, &v) in machine.io.analog_inputs.iter().enumerate() {
            module.set_analog_input(k as u16 + 1, volts_to_raw(v));
        }
        let wiring: Vec<u16> = machine.io.wiring.iter().map(|&l| u16::from(l)).collect();
        if wiring.iter().any(|&l| l != 0) {
            module.set_wiring(&wiring);
        }
        IoNode { module, schedule: machine.fault_schedule() }
    }

    /// Changes a digital or analog input at `now` for `duration` seconds
    /// through the machine's schedule, as a `[[node.inputs]]` entry due
    /// now (`Personality::change_machine` for a drive); a module has no
    /// other input and no machine faults.
    pub fn change_machine(
        &mut self,
        now: Instant,
        change: Change,
        duration: Option<f64>,
    ) -> Result<(), MachineError> {
        match change {
            Change::Input(Input::Digital { .. } | Input::Analog { .. }) => {
                self.schedule.change(now, change, duration)
            }
            Change::Input(_) => Err(MachineError {
                key: "input".into(),
                reason: "a device from an EDS/DCF has only digital and analog inputs".into(),
                other: None,
            }),
            Change::Fault(_) | Change::ClearFaults => Err(MachineError {
                key: "kind".into(),
                reason: "a device from an EDS/DCF has no machine faults".into(),
                other: None,
            }),
        }
    }

    fn inject(module: &mut IoModule, i: Injection) {
        match i {
            Injection::Model(Plant::DigitalInput { line, level }) => {
                module.set_input_line(line.into(), level)
            }
            Injection::Model(Plant::AnalogInput { channel, volts }) => {
                module.set_analog_input(channel.into(), volts_to_raw(volts))
            }
            // `io_machine_for` admits no other input; the model's others
            // have nothing to act on here.
            _ => {}
        }
    }
}

impl IoNode {
    /// The input changes in force at `now`.
    pub fn in_force(&self, now: Instant) -> Vec<crate::machine::InForce> {
        self.schedule.in_force(now)
    }
}

/// The application of a device built from a file.
pub enum DeviceApp {
    /// A CiA 301 device: the dictionary is all there is.
    Plain,
    /// A CiA 401 generic I/O module.
    Io(Box<IoNode>),
}

impl DeviceApp {
    /// The input changes in force at `now` (none on a plain device).
    pub fn machine_in_force(&self, now: Instant) -> Vec<crate::machine::InForce> {
        match self {
            DeviceApp::Io(n) => n.in_force(now),
            DeviceApp::Plain => Vec::new(),
        }
    }

    /// [`IoNode::change_machine`] on a CiA 401 module; a plain device has
    /// no inputs.
    pub fn change_machine(
        &mut self,
        now: Instant,
        change: Change,
        duration: Option<f64>,
    ) -> Result<(), MachineError> {
        match self {
            DeviceApp::Io(n) => n.change_machine(now, change, duration),
            DeviceApp::Plain => Err(MachineError {
                key: "input".into(),
                reason: "the device is not a CiA 401 I/O module (1000h): it has no inputs".into(),
                other: None,
            }),
        }
    }
}

/// A device built by [`build_device`].
pub type EdsDevice = NodeDevice<DeviceApp>;

/// Why a device could not be built from its file.
#[derive(Debug, Clone, PartialEq)]
pub enum DeviceError {
    /// Node-ID outside 1..=127.
    NodeId(u8),
    /// The file's values, each with its line.
    Eds(EdsError),
    /// The machine around it does not make sense.
    Machine(crate::machine::MachineError),
}

impl core::fmt::Display for DeviceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DeviceError::NodeId(id) => write!(f, "node-ID {id} outside 1..=127"),
            DeviceError::Eds(e) => write!(f, "{e}"),
            DeviceError::Machine(e) => write!(f, "machine: {e}"),
        }
    }
}

impl std::error::Error for DeviceError {}

/// The device `eds` (read from `text`) describes, as node `node_id` with
/// parameters in `storage`: a CiA 401 module on `machine` (its inputs; the
/// default: all low) when 1000h says so, else a plain CiA 301 device.
/// Returns the warnings about what the file has that the device leaves out.
pub fn build_device(
    eds: &Eds,
    text: &str,
    node_id: u8,
    storage: Box<dyn Storage + Send>,
    options: EdsOptions,
    machine: Option<&Machine>,
) -> Result<(EdsDevice, Vec<Diagnostic>), DeviceError> {
    if !(1..=127).contains(&node_id) {
        return Err(DeviceError::NodeId(node_id));
    }
    if let Some(m) = machine {
        m.check().map_err(DeviceError::Machine)?;
    }
    let (mut node, warnings) =
        Node::from_eds(eds, text, node_id, storage, options).map_err(DeviceError::Eds)?;
    let app = if drivebus_cia401::is_io_module(node.config().device_type) {
        let module = IoModule::install(&mut node);
        let default = Machine::default();
        DeviceApp::Io(Box::new(IoNode::new(module, machine.unwrap_or(&default))))
    } else {
        DeviceApp::Plain
    };
    Ok((NodeDevice::new(node, app), warnings))
}

impl Application for DeviceApp {
    fn check_write(
        &mut self,
        cx: &mut AppContext<'_>,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        match self {
            DeviceApp::Plain => Ok(WriteOutcome::Store),
            DeviceApp::Io(n) => n.module.check_write(cx, at, data),
        }
    }

    fn apply_write(&mut self, cx: &mut AppContext<'_>, at: &Target) {
        if let DeviceApp::Io(n) = self {
            n.module.apply_write(cx, at);
        }
    }

    fn on_read(&mut self, cx: &mut AppContext<'_>, at: &Target) -> Result<(), SdoAbort> {
        match self {
            DeviceApp::Plain => Ok(()),
            DeviceApp::Io(n) => n.module.on_read(cx, at),
        }
    }

    fn filter_frame(
        &mut self,
        _od: &ObjectDictionary,
        _node_id: u8,
        _frame: &drivebus_can::Frame,
    ) -> FrameFilter {
        FrameFilter::Pass
    }

    fn on_start(&mut self, cx: &mut AppContext<'_>) {
        if let DeviceApp::Io(n) = self {
            n.schedule.start(cx.now);
            n.module.on_start(cx);
        }
    }

    fn on_sync(&mut self, cx: &mut AppContext<'_>, counter: Option<u8>) {
        if let DeviceApp::Io(n) = self {
            n.module.on_sync(cx, counter);
        }
    }

    fn on_event(&mut self, cx: &mut AppContext<'_>, event: NodeEvent) {
        if let DeviceApp::Io(n) = self {
            n.module.on_event(cx, event);
        }
    }

    fn poll(&mut self, cx: &mut AppContext<'_>) -> Option<Instant> {
        let DeviceApp::Io(n) = self else { return None };
        let module = &mut n.module;
        let next = n.schedule.run_with(cx.now, |i| IoNode::inject(module, i));
        drivebus_can::earliest(next, n.module.poll(cx))
    }
}
