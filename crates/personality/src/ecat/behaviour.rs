//! [`EcatBehaviour`]: the profile's behaviour with the CoE object rules
//! and the EtherCAT error reporting in front of it.

use super::rules;
use super::sync::sub;
use super::{EMCY_COMMUNICATION, EcatFacts};
use crate::Profile;
use crate::build::{Behaviour, Context, EmcyFrame, FilterOutcome, Verdict};
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_can::Frame;
use drivebus_cia402::drive::DriveConfig;
use drivebus_cia402::homing::HomingMethod;
use drivebus_cia402::interp::IpMode;
use drivebus_coe::AlState;
use drivebus_node::{Node, NodeConfig, NodeEvent, Request};
use drivebus_od::{ObjectDictionary, SdoAbort};
use drivebus_pdo::PdoConfig;

extern crate alloc;

/// AL status codes that mean the master's communication was lost, not a
/// refused request (ETG.1000.6 Table 11): synchronization error,
/// sync manager watchdog, fatal sync error, no sync error.
fn communication_error(al_code: u16) -> bool {
    matches!(al_code, 0x001A | 0x001B | 0x002C | 0x002D)
}

/// The EMCY code of a refused ESM transition: A0xxh with the AL status
/// code's low byte (iPOS Table 3.1.3 gives "A0xx ESM transition error"
/// and no table of xx; docs/personalities.md).
pub fn transition_error_code(al_code: u16) -> u16 {
    0xA000 | (al_code & 0xFF)
}

/// A profile's behaviour on EtherCAT: the rules of [`rules`] first, then
/// the profile's own behaviour, for every write; the EtherCAT error
/// reporting the profile's [`EcatFacts`] call for.
pub struct EcatBehaviour {
    inner: Box<dyn Behaviour>,
    facts: &'static EcatFacts,
    pdo: PdoConfig,
    esm: AlState,
    /// A communication error (watchdog, lost SYNC0) is being reported.
    comm_error: bool,
    /// Controlword as last written (fault reset = bit 7 rising).
    controlword: u16,
}

impl core::fmt::Debug for EcatBehaviour {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("EcatBehaviour")
            .field("profile", &self.inner.profile())
            .field("esm", &self.esm)
            .field("comm_error", &self.comm_error)
            .finish()
    }
}

impl EcatBehaviour {
    /// `inner` on EtherCAT with `facts` and the PDO limits `pdo`.
    pub fn new(inner: Box<dyn Behaviour>, facts: &'static EcatFacts, pdo: PdoConfig) -> Self {
        EcatBehaviour { inner, facts, pdo, esm: AlState::Init, comm_error: false, controlword: 0 }
    }

    /// The ESM state the rules run in.
    pub fn esm(&self) -> AlState {
        self.esm
    }

    /// Whether a communication error is being reported (2000h bit 0 on
    /// the iPOS; EMCY 8100h active).
    pub fn communication_error(&self) -> bool {
        self.comm_error
    }

    /// The profile's own behaviour as its concrete type.
    pub fn inner_mut<T: core::any::Any>(&mut self) -> Option<&mut T> {
        self.inner.as_any_mut()?.downcast_mut::<T>()
    }

    /// The PDO limits mappings are checked against.
    pub fn pdo_config(&self) -> &PdoConfig {
        &self.pdo
    }

    pub(crate) fn set_esm(&mut self, esm: AlState) {
        self.esm = esm;
    }

    /// The AL error indication changed: a communication error starts the
    /// 8100h reporting, any other error is a refused transition (A0xxh);
    /// an acknowledge ends the communication error.
    pub(crate) fn al_error(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, code: Option<u16>) {
        match code {
            Some(c) if communication_error(c) => self.set_comm_error(cx, od, true),
            Some(c) if self.facts.esm_emcy => {
                cx.request(self.inner.emcy(transition_error_code(c)).raw());
            }
            Some(_) => {}
            None => self.set_comm_error(cx, od, false),
        }
    }

    fn set_comm_error(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, on: bool) {
        if on == self.comm_error {
            return;
        }
        self.comm_error = on;
        if self.facts.esm_emcy {
            // iPOS 2000h bit 0 "EtherCAT communication error".
            if let Some(v) = od.get_u32(0x2000, 0)
                && let Ok(r) = od.find(0x2000, 0)
            {
                let v = if on { v | 1 } else { v & !1 } as u16;
                od.set_le(r, &v.to_le_bytes());
            }
        }
        if on {
            let e: EmcyFrame = self.inner.emcy(EMCY_COMMUNICATION);
            cx.request(e.raise());
        } else if cx.drive.state_machine().fault_code() != EMCY_COMMUNICATION {
            // A drive still faulted on it (6007h = 1) keeps the error
            // until its fault reset, which clears the EMCY itself.
            cx.request(Request::ClearEmcy(EMCY_COMMUNICATION));
        }
    }
}

impl Behaviour for EcatBehaviour {
    fn profile(&self) -> Profile {
        self.inner.profile()
    }
    fn adjust_node_config(&self, cfg: &mut NodeConfig) {
        self.inner.adjust_node_config(cfg);
    }
    fn adjust_drive_config(&self, cfg: &mut DriveConfig) {
        self.inner.adjust_drive_config(cfg);
    }
    fn homing_methods(&self) -> Vec<Box<dyn HomingMethod + Send>> {
        self.inner.homing_methods()
    }
    fn ip_mode(&self) -> IpMode {
        self.inner.ip_mode()
    }
    fn manufacturer_mode(&self, mode: i8) -> Option<i8> {
        self.inner.manufacturer_mode(mode)
    }
    fn hooked_objects(&self) -> &'static [u16] {
        self.inner.hooked_objects()
    }
    fn finish(&mut self, node: &mut Node) {
        self.inner.finish(node);
    }
    fn filter_rx(&mut self, od: &ObjectDictionary, node_id: u8, frame: &Frame) -> FilterOutcome {
        self.inner.filter_rx(od, node_id, frame)
    }

    fn on_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<Verdict, SdoAbort> {
        rules::check(self.esm, &self.pdo, od, index, sub, data)?;
        let v = self.inner.on_write(cx, od, index, sub, data)?;
        if v == Verdict::Pass && rules::is_mapping(index) && sub == 0 {
            let n = data.first().copied().unwrap_or(0);
            rules::check_length(od, index, n, self.facts.max_pdo_bits)?;
        }
        Ok(v)
    }

    fn after_write(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, index: u16, s: u8) {
        self.inner.after_write(cx, od, index, s);
        match (index, s) {
            (0x6040, 0) => {
                let cw = od.get_u32(0x6040, 0).unwrap_or(0) as u16;
                // A fault reset (bit 7 rising) clears the communication
                // error (iPOS 2000h bit 0: "reset by a Reset Fault command").
                if cw & 0x80 != 0 && self.controlword & 0x80 == 0 {
                    self.set_comm_error(cx, od, false);
                }
                self.controlword = cw;
            }
            (0x1C32 | 0x1C33, sub::GET_CYCLE) if od.get_u32(index, s) == Some(2) => {
                // ETG.1020: 2 resets the error counters.
                for (k, z) in [
                    (sub::SM_EVENT_MISSED, &[0u8, 0][..]),
                    (sub::CYCLE_TOO_SMALL, &[0, 0]),
                    (sub::SYNC_ERROR, &[0]),
                ] {
                    if let Ok(r) = od.find(index, k) {
                        od.set_le(r, z);
                    }
                }
            }
            _ => {}
        }
    }

    fn on_read(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
    ) -> Result<(), SdoAbort> {
        self.inner.on_read(cx, od, index, sub)
    }
    fn on_boot(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        self.inner.on_boot(cx, od);
    }
    fn on_event(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, event: &NodeEvent) {
        self.inner.on_event(cx, od, event);
        // A reset the drive made itself (iPOS 2080h, §4.9.8: "it does not
        // reset the ECAT interface"): the node follows the ESM again.
        if let NodeEvent::NmtState { to: drivebus_node::NmtState::PreOperational, .. } = event
            && super::nmt_state(self.esm) == drivebus_node::NmtState::Operational
        {
            cx.request(Request::Nmt(drivebus_nmt::NmtCommand::Start));
        }
    }
    fn after_step(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        self.inner.after_step(cx, od);
    }
    fn emcy(&self, code: u16) -> EmcyFrame {
        self.inner.emcy(code)
    }
    fn as_any_mut(&mut self) -> Option<&mut dyn core::any::Any> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes() {
        assert_eq!(transition_error_code(0x001D), 0xA01D);
        assert!(communication_error(0x001B) && !communication_error(0x0011));
    }
}
