//! Carrying out the application's [`Request`]s: the one way an
//! application's wishes (EMCY, TPDO, local NMT, …) reach the node.

use crate::app::{Application, Request};
use crate::node::Node;
use crate::owners::dirty;
use drivebus_can::{Instant, TxSink};

/// Rounds of requests that produce requests (an NMT change the
/// application reacts to); bounded so an application cannot loop the node.
const ROUNDS: usize = 4;

impl Node {
    /// Carries out what the application queued; true if anything ran.
    pub(crate) fn run_requests<A: Application + ?Sized>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) -> bool {
        let mut any = false;
        for _ in 0..ROUNDS {
            if self.s.link.requests.is_empty() {
                break;
            }
            any = true;
            // Swap, so requests made while these run queue for the next round
            // and neither buffer is reallocated.
            core::mem::swap(&mut self.s.link.requests, &mut self.running);
            let mut i = 0;
            while let Some(&r) = self.running.get(i) {
                i += 1;
                self.run_request(r, now, app, out);
            }
            self.running.clear();
        }
        any
    }

    fn run_request<A: Application + ?Sized>(
        &mut self,
        r: Request,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        match r {
            Request::RaiseEmcy { code, register: None, manufacturer } => {
                self.raise_emcy(code, manufacturer, now);
            }
            Request::RaiseEmcy { code, register: Some(bits), manufacturer } => {
                self.raise_defined(code, bits, manufacturer, now);
            }
            Request::ClearEmcy(code) => {
                if !self.clear_defined(code, now) {
                    self.clear_emcy(code, now);
                }
            }
            Request::ClearAllEmcy => {
                while let Some(&(code, _)) = self.app_errors.first() {
                    self.clear_defined(code, now);
                }
                self.clear_all_emcy(now);
            }
            Request::RawEmcy { code, register, bytes } => self.send_raw_emcy(code, register, bytes, now),
            Request::RequestTpdo(n) => {
                self.request_tpdo(n);
            }
            Request::TpdoChangeMask { tpdo, mask } => {
                self.set_tpdo_change_mask(tpdo, mask);
            }
            Request::Nmt(cmd) => {
                // What is already queued goes first (a boot EMCY before the
                // PDOs of operational).
                self.poll_services(now, app, out);
                self.nmt_command(cmd, now, app, out);
            }
            Request::StoreParameters => {
                let _ = crate::owners::commit_groups(&mut *self.s.storage, &self.od, 1, true);
            }
            Request::Restore { index, sub, value, only_if } => {
                if let Ok(r) = self.od.find(index, sub)
                    && only_if.is_none_or(|v| self.od.get_u32(index, sub) == Some(v))
                {
                    let len = self.od.entry(r).data_type.fixed_size().unwrap_or(4).min(4);
                    self.od.set_raw(r, &value.to_le_bytes()[..len]);
                }
                self.s.pdo.reload(&self.od);
                self.s.link.dirty |= dirty::PDO | dirty::PDO_MAP;
                self.rebuild_routes();
            }
        }
    }

    /// An error with a device-defined register: 1001h is the OR of these
    /// errors' bits, 1003h gets `code | byte 0 << 16`, the EMCY is sent raw.
    pub(crate) fn raise_defined(&mut self, code: u16, bits: u8, bytes: [u8; 5], now: Instant) {
        if self.app_errors.iter().any(|(c, _)| *c == code) {
            return;
        }
        self.app_errors.push((code, bits));
        let reg = self.defined_register();
        self.send_raw_emcy(code, reg, bytes, now);
        if let Ok(r) = self.od.find(0x1001, 0) {
            self.od.set_raw(r, &[reg]);
        }
        // 1003h through the EMCY producer, so its reads agree (CiA 301
        // §7.5.2.5; KC1 §7.2.1.4: the code, with the manufacturer's first
        // byte as additional information).
        self.record_emcy_history(u32::from(code) | (u32::from(bytes[0]) << 16));
    }

    /// Clears an error raised by [`Self::raise_defined`]; the error-reset
    /// EMCY carries the bits of the errors still active.
    pub(crate) fn clear_defined(&mut self, code: u16, now: Instant) -> bool {
        let before = self.app_errors.len();
        self.app_errors.retain(|(c, _)| *c != code);
        if self.app_errors.len() == before {
            return false;
        }
        let reg = self.defined_register();
        self.send_raw_emcy(0, reg, [0; 5], now);
        if let Ok(r) = self.od.find(0x1001, 0) {
            self.od.set_raw(r, &[reg]);
        }
        true
    }

    fn defined_register(&self) -> u8 {
        self.app_errors.iter().fold(0, |a, (_, r)| a | r)
    }
}
