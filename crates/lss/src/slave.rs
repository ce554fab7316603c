//! The LSS slave (CiA 305 v3.0.0 §"LSS slave"), sans-IO.
//!
//! Figure numbers refer to CiA 305 v3.0.0. Which services each state accepts
//! follows the LSS slave FSA: switch state global in both states; switch
//! state selective and fastscan only in waiting; identify (non-configured)
//! remote slave in both; configure, activate, store and inquire only in
//! configuration. Anything else is silently ignored, as the standard says.

use drivebus_can::{Frame, Instant, TxSink};

use crate::codec::{FASTSCAN_CONFIRM, IdentifyStep, LssField, LssRequest, LssResponse, err};
use crate::{Identity, LssMode, STANDARD_TABLE, UNCONFIGURED, is_configurable_node_id, is_valid_node_id};

/// What the node must do after a frame was handled. The slave has already
/// sent whatever response the service needs (except for store, see
/// [`LssEvent::StoreRequested`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LssEvent {
    /// A new pending node-ID (1..=127, or FFh = unconfigured). It becomes
    /// active on the next NMT reset communication ([`LssSlave::reset_communication`]).
    NodeIdConfigured(u8),
    /// A new pending bit timing index (standard table); it becomes active on
    /// [`LssEvent::ActivateBitTiming`] or after a store and a power cycle.
    BitTimingConfigured(u8),
    /// Switch the CAN controller to [`LssSlave::pending_bit_timing`]: wait
    /// `delay_ms`, switch, then stay silent for another `delay_ms`
    /// (CiA 305 v3.0.0 Fig. 35). The slave already treats the pending bit
    /// timing as active.
    ActivateBitTiming {
        /// Switch delay in ms.
        delay_ms: u16,
    },
    /// Persist the pending node-ID and bit timing index, then report the
    /// outcome with [`LssSlave::complete_store`], which sends the response.
    StoreRequested {
        /// Pending node-ID to store (FFh stores "unconfigured").
        node_id: u8,
        /// Pending bit timing index to store.
        bit_timing: u8,
    },
    /// The slave entered LSS configuration.
    EnteredConfiguration,
    /// The slave entered LSS waiting.
    EnteredWaiting,
    /// The slave entered LSS waiting while its active node-ID is invalid and
    /// its pending one valid: the node must now perform NMT reset
    /// communication on its own and call [`LssSlave::reset_communication`]
    /// (the "unconfigured boot" contract in the crate docs).
    ResetCommunication {
        /// The node-ID that becomes active.
        node_id: u8,
    },
}

/// Outcome of a store configuration request, reported by the node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StoreStatus {
    /// The configuration was stored (error code 0).
    Stored,
    /// The device cannot store its LSS configuration (error code 1).
    NotSupported,
    /// Storage failed (error code 2).
    AccessError,
}

impl StoreStatus {
    const fn code(self) -> u8 {
        match self {
            StoreStatus::Stored => err::OK,
            StoreStatus::NotSupported => err::STORE_NOT_SUPPORTED,
            StoreStatus::AccessError => err::STORE_ACCESS_ERROR,
        }
    }
}

/// Bit timing indices a slave accepts by default: every defined rate of the
/// standard table (0..=4, 6..=8); reserved 5 and automatic detection 9 are off.
const DEFAULT_BIT_TIMINGS: u16 = 0b1_1101_1111;

/// The LSS slave of one CANopen device.
#[derive(Clone, Debug)]
pub struct LssSlave {
    identity: Identity,
    mode: LssMode,
    active_node_id: u8,
    pending_node_id: u8,
    active_bit_timing: u8,
    pending_bit_timing: u8,
    bit_timings: u16,
    store_supported: bool,
    store_pending: bool,
    /// Switch state selective frames matched so far, in order (0..=3).
    selective_matched: u8,
    /// Identify remote slave frames matched so far, in order (0..=5).
    identify_matched: u8,
    /// Fastscan LSSPos: the address part this slave checks next (0..=3).
    fastscan_pos: u8,
}

impl LssSlave {
    /// A slave in LSS waiting with its identity (1018h), its stored node-ID
    /// (`0xFF` = unconfigured: see the crate docs) and the index of its
    /// current bit timing in the standard table. An out-of-range node-ID
    /// (0, 128..=254) is treated as unconfigured.
    pub fn new(identity: Identity, node_id: u8, bit_timing_index: u8) -> LssSlave {
        let node_id = if is_valid_node_id(node_id) { node_id } else { UNCONFIGURED };
        LssSlave {
            identity,
            mode: LssMode::Waiting,
            active_node_id: node_id,
            pending_node_id: node_id,
            active_bit_timing: bit_timing_index,
            pending_bit_timing: bit_timing_index,
            bit_timings: DEFAULT_BIT_TIMINGS,
            store_supported: true,
            store_pending: false,
            selective_matched: 0,
            identify_matched: 0,
            fastscan_pos: 0,
        }
    }

    /// Restrict (or extend) the bit timing indices "configure bit timing"
    /// accepts: bit `i` of `mask` enables index `i` of the standard table.
    pub fn with_bit_timings(mut self, mask: u16) -> LssSlave {
        self.bit_timings = mask;
        self
    }

    /// Whether the device can store its LSS configuration. When `false`,
    /// store configuration is answered "not supported" without an event.
    pub fn with_store_supported(mut self, supported: bool) -> LssSlave {
        self.store_supported = supported;
        self
    }

    /// The LSS address.
    #[inline]
    pub fn identity(&self) -> &Identity {
        &self.identity
    }
    /// The LSS FSA state.
    #[inline]
    pub fn mode(&self) -> LssMode {
        self.mode
    }
    /// The node-ID in use (FFh while unconfigured).
    #[inline]
    pub fn active_node_id(&self) -> u8 {
        self.active_node_id
    }
    /// The node-ID that becomes active on the next reset communication.
    #[inline]
    pub fn pending_node_id(&self) -> u8 {
        self.pending_node_id
    }
    /// The bit timing index in use.
    #[inline]
    pub fn active_bit_timing(&self) -> u8 {
        self.active_bit_timing
    }
    /// The configured bit timing index (active after activate or a store and power cycle).
    #[inline]
    pub fn pending_bit_timing(&self) -> u8 {
        self.pending_bit_timing
    }
    /// True while the device has no valid active node-ID: the node must run
    /// LSS only (no boot-up, no other service), see the crate docs.
    #[inline]
    pub fn is_lss_only(&self) -> bool {
        self.active_node_id == UNCONFIGURED
    }
    /// True for a non-configured slave (CiA 305): neither an active nor a
    /// pending node-ID. Only such a slave takes part in fastscan and answers
    /// identify non-configured remote slave.
    #[inline]
    pub fn is_non_configured(&self) -> bool {
        self.active_node_id == UNCONFIGURED && self.pending_node_id == UNCONFIGURED
    }

    /// NMT reset communication: the pending node-ID becomes active. The node
    /// calls this in its reset-communication sequence (commanded, after
    /// [`LssEvent::ResetCommunication`], or at boot) and uses the returned
    /// node-ID; FFh (a master configured "unconfigured") means the node must
    /// go back to LSS-only operation. The LSS state is kept; selective and
    /// identify progress is dropped.
    pub fn reset_communication(&mut self) -> u8 {
        self.active_node_id = self.pending_node_id;
        self.selective_matched = 0;
        self.identify_matched = 0;
        self.active_node_id
    }

    /// Report the outcome of [`LssEvent::StoreRequested`]; sends the store
    /// configuration response (CiA 305 v3.0.0 Fig. 36). Returns false (and
    /// sends nothing) when no store was requested.
    pub fn complete_store(&mut self, status: StoreStatus, out: &mut impl TxSink) -> bool {
        if !core::mem::take(&mut self.store_pending) {
            return false;
        }
        out.send(LssResponse::StoreConfiguration { error: status.code(), spec_error: 0 }.to_frame());
        true
    }

    /// Handle a received frame. Frames other than well-formed LSS requests
    /// on 7E5h are ignored, so the node may pass every frame. At most one
    /// response is sent into `out`.
    pub fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut impl TxSink) -> Option<LssEvent> {
        // The slave has no timers: activate bit timing delays belong to the node.
        let _ = now;
        let req = LssRequest::from_frame(frame)?;
        match req {
            LssRequest::SwitchStateGlobal(mode) => self.switch_global(mode),
            LssRequest::IdentifyRemoteSlave { step, value } => {
                self.identify_remote(step, value, out);
                None
            }
            LssRequest::IdentifyNonConfigured => {
                // Fig. 44: only slaves with neither an active nor a pending node-ID answer.
                if self.is_non_configured() {
                    out.send(LssResponse::IdentifyNonConfiguredSlave.to_frame());
                }
                None
            }
            _ => match self.mode {
                LssMode::Waiting => self.waiting(req, out),
                LssMode::Configuration => self.configuration(req, out),
            },
        }
    }

    /// Switch state global (Fig. 31).
    fn switch_global(&mut self, mode: LssMode) -> Option<LssEvent> {
        let previous = self.mode;
        self.mode = mode;
        self.selective_matched = 0;
        self.identify_matched = 0;
        match (previous, mode) {
            (LssMode::Waiting, LssMode::Configuration) => Some(LssEvent::EnteredConfiguration),
            (LssMode::Configuration, LssMode::Waiting) => {
                // An unconfigured device leaves LSS-only operation by itself
                // once it has a node-ID (CiA 305 v3.0.0 LSS slave FSA).
                if self.is_lss_only() && is_valid_node_id(self.pending_node_id) {
                    Some(LssEvent::ResetCommunication { node_id: self.pending_node_id })
                } else {
                    Some(LssEvent::EnteredWaiting)
                }
            }
            _ => None,
        }
    }

    fn waiting(&mut self, req: LssRequest, out: &mut impl TxSink) -> Option<LssEvent> {
        match req {
            LssRequest::SwitchStateSelective { field, value } => self.switch_selective(field, value, out),
            LssRequest::FastScan { id_number, bit_checked, sub, next } => {
                self.fastscan(id_number, bit_checked, sub, next, out)
            }
            _ => None,
        }
    }

    /// Switch state selective (Fig. 32): the four parts must arrive in order
    /// and all match; any mismatch or out-of-order frame restarts the sequence.
    fn switch_selective(&mut self, field: LssField, value: u32, out: &mut impl TxSink) -> Option<LssEvent> {
        let in_order = field == LssField::Vendor || field.index() == self.selective_matched;
        if !in_order || field.get(&self.identity) != value {
            self.selective_matched = 0;
            return None;
        }
        if field != LssField::Serial {
            self.selective_matched = field.index() + 1;
            return None;
        }
        self.selective_matched = 0;
        self.mode = LssMode::Configuration;
        out.send(LssResponse::SwitchStateSelective.to_frame());
        Some(LssEvent::EnteredConfiguration)
    }

    /// Identify remote slave (Fig. 42/43): vendor and product exact,
    /// revision and serial within the bounds; answered after the sixth frame.
    fn identify_remote(&mut self, step: IdentifyStep, value: u32, out: &mut impl TxSink) {
        let in_order = step == IdentifyStep::Vendor || step as u8 == self.identify_matched;
        let id = &self.identity;
        let matches = match step {
            IdentifyStep::Vendor => id.vendor_id == value,
            IdentifyStep::Product => id.product_code == value,
            IdentifyStep::RevisionLow => value <= id.revision,
            IdentifyStep::RevisionHigh => id.revision <= value,
            IdentifyStep::SerialLow => value <= id.serial,
            IdentifyStep::SerialHigh => id.serial <= value,
        };
        if !in_order || !matches {
            self.identify_matched = 0;
        } else if step == IdentifyStep::SerialHigh {
            self.identify_matched = 0;
            out.send(LssResponse::IdentifySlave.to_frame());
        } else {
            self.identify_matched = step as u8 + 1;
        }
    }

    /// Fastscan (Fig. 46). Only a non-configured slave in waiting takes part.
    /// BitChecked 80h resets LSSPos and confirms presence; otherwise, when
    /// LSSSub is this slave's LSSPos and bits 31..BitChecked of IDNumber match,
    /// it answers, moves LSSPos to LSSNext, and after a complete match
    /// (BitChecked 0) with LSSNext < LSSSub (the scan wrapped) it enters
    /// configuration.
    fn fastscan(
        &mut self,
        id_number: u32,
        bit_checked: u8,
        sub: u8,
        next: u8,
        out: &mut impl TxSink,
    ) -> Option<LssEvent> {
        if !self.is_non_configured() || next > 3 {
            return None;
        }
        if bit_checked == FASTSCAN_CONFIRM {
            self.fastscan_pos = 0;
            out.send(LssResponse::IdentifySlave.to_frame());
            return None;
        }
        let field = LssField::from_index(sub)?;
        if bit_checked > 31 || sub != self.fastscan_pos {
            return None;
        }
        let mask = u32::MAX << bit_checked;
        if (field.get(&self.identity) ^ id_number) & mask != 0 {
            return None;
        }
        self.fastscan_pos = next;
        out.send(LssResponse::IdentifySlave.to_frame());
        // Completion is "the scan wrapped" as in CANopenNode and Lely, which
        // lets a master skip trailing parts; CANopenNode PR #647 proposes the
        // stricter serial → vendor only.
        if bit_checked == 0 && next < sub {
            self.fastscan_pos = 0;
            self.mode = LssMode::Configuration;
            return Some(LssEvent::EnteredConfiguration);
        }
        None
    }

    fn configuration(&mut self, req: LssRequest, out: &mut impl TxSink) -> Option<LssEvent> {
        match req {
            // Fig. 33.
            LssRequest::ConfigureNodeId(id) => {
                if !is_configurable_node_id(id) {
                    out.send(
                        LssResponse::ConfigureNodeId { error: err::NODE_ID_OUT_OF_RANGE, spec_error: 0 }
                            .to_frame(),
                    );
                    return None;
                }
                self.pending_node_id = id;
                out.send(LssResponse::ConfigureNodeId { error: err::OK, spec_error: 0 }.to_frame());
                Some(LssEvent::NodeIdConfigured(id))
            }
            // Fig. 34.
            LssRequest::ConfigureBitTiming { table, index } => {
                // Indices 0..=9 exist in the standard table (9 = automatic
                // detection); the mask says which this device implements.
                let supported = table == STANDARD_TABLE && index <= 9 && self.bit_timings & (1 << index) != 0;
                if !supported {
                    out.send(
                        LssResponse::ConfigureBitTiming {
                            error: err::BIT_TIMING_NOT_SUPPORTED,
                            spec_error: 0,
                        }
                        .to_frame(),
                    );
                    return None;
                }
                self.pending_bit_timing = index;
                out.send(LssResponse::ConfigureBitTiming { error: err::OK, spec_error: 0 }.to_frame());
                Some(LssEvent::BitTimingConfigured(index))
            }
            // Fig. 35: no response.
            LssRequest::ActivateBitTiming { delay_ms } => {
                self.active_bit_timing = self.pending_bit_timing;
                Some(LssEvent::ActivateBitTiming { delay_ms })
            }
            // Fig. 36.
            LssRequest::StoreConfiguration => {
                if !self.store_supported {
                    out.send(
                        LssResponse::StoreConfiguration { error: err::STORE_NOT_SUPPORTED, spec_error: 0 }
                            .to_frame(),
                    );
                    return None;
                }
                self.store_pending = true;
                Some(LssEvent::StoreRequested {
                    node_id: self.pending_node_id,
                    bit_timing: self.pending_bit_timing,
                })
            }
            // Fig. 37..40.
            LssRequest::InquireIdentity(field) => {
                out.send(LssResponse::Identity { field, value: field.get(&self.identity) }.to_frame());
                None
            }
            // Fig. 41: the active node-ID; while LSS-only (still in NMT
            // initialisation) the pending one, so a master can read back what
            // it configured before the device starts.
            LssRequest::InquireNodeId => {
                let id = if self.is_lss_only() { self.pending_node_id } else { self.active_node_id };
                out.send(LssResponse::NodeId(id).to_frame());
                None
            }
            _ => None,
        }
    }
}
