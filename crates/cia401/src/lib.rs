//! CiA 401 generic I/O modules: an [`IoModule`] is the application of a
//! CANopen node (`drivebus_node::NodeDevice<IoModule>`) whose dictionary
//! holds the CiA 401 objects — from the device's own EDS or DCF, with the
//! sub-indices, types and defaults the file gives them. Sans-IO: inputs
//! are set by the caller ([`IoModule::set_input_line`],
//! [`IoModule::set_analog_input`]) and take effect at the node's next
//! poll; outputs are what the master writes, seen as
//! [`IoModule::output_lines`] and [`IoModule::analog_outputs`] and, where
//! an output is wired back to an input ([`IoModule::set_wiring`]), at the
//! input.
//!
//! # What is implemented (CiA 401 v3.0 objects, as far as the file has them)
//!
//! | object | | behaviour |
//! |---|---|---|
//! | 6000h | read input 8-bit | the input lines (line `8(k−1)+b+1` is sub `k` bit `b`) after 6002h; an event-driven TPDO mapping it sends on a change through the node's change tracking |
//! | 6002h | polarity input 8-bit | a set bit inverts the line |
//! | 6005h | global interrupt enable digital | FALSE: input changes send no TPDO (SYNC and event timer still do) |
//! | 6006h | interrupt mask any change | a cleared bit: a change of that input sends no TPDO |
//! | 6007h / 6008h | interrupt mask low-to-high / high-to-low | a set bit sends the TPDOs mapping the input on that edge even where 6006h masks it |
//! | 6200h | write output 8-bit | the output lines, after 6202h, 6208h and the error state |
//! | 6202h | change polarity output 8-bit | a set bit inverts the output |
//! | 6206h / 6207h | error mode / error value output 8-bit | in the error state an output whose 6206h bit is set takes its 6207h bit; the others keep their value |
//! | 6208h | filter mask output 8-bit | a cleared bit freezes the output at its value (writes of 6200h do not reach it) |
//! | 6401h | read analogue input 16-bit | the analog inputs (INTEGER16 raw value: ±10 V is ±32767 in [`volts_to_raw`]) |
//! | 6411h | write analogue output 16-bit | the analog outputs, after the error state |
//! | 6421h | analogue input interrupt trigger selection | bit 0 above the upper limit (6424h), bit 1 below the lower limit (6425h), bit 2 changed by 6426h or more since the last interrupt, bit 3 fallen by 6427h, bit 4 risen by 6428h (a delta of 0: any change) |
//! | 6422h | analogue input interrupt source | bit `n−1`: channel `n` caused an interrupt; reset when read |
//! | 6423h | analogue input global interrupt enable | FALSE (CiA 401's default): analog changes send no TPDO; TRUE: the 6421h triggers send the TPDOs mapping the channel. A file without 6423h: every change counts, like any mapped value |
//! | 6443h / 6444h | analogue output error mode / error value | in the error state a channel whose 6443h is 1 takes 6444h |
//!
//! The **error state** (CiA 401: outputs on device failure) is entered on
//! NMT Stopped and on a communication error the node reports (heartbeat
//! consumer timeout, life guarding lost, RPDO timeout, bus-off); it is left
//! when the node enters Operational again, or when the error resolves
//! (heartbeat back, guarding resumed, link active) while it is
//! Operational. What the node does with its NMT state on such an error is
//! 1029h's (`drivebus-node`).
//!
//! Not implemented: 6003h filter constant (inputs are ideal: no bounce to
//! filter; the object is stored as written), the 1-, 16- and 32-bit
//! digital access objects (6020h–6120h, 6220h–6320h), the 8-/32-bit and
//! float analog objects (6400h, 6402h–6404h, 6410h, 6412h–6414h) and the
//! analog scaling objects (6431h–6434h, 6441h–6446h besides 6443h/6444h).
//! A file may list them: they are then plain values.

#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod module;

pub use module::{IoModule, volts_to_raw};

/// The device profile number CiA 401 devices give in 1000h bits 0–15.
pub const PROFILE: u16 = 401;

/// Whether 1000h `device_type` is a CiA 401 generic I/O module.
pub fn is_io_module(device_type: u32) -> bool {
    device_type & 0xFFFF == u32::from(PROFILE)
}
