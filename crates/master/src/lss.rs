//! LSS master (CiA 305) on the async bus.
//!
//! Operations are serialised on one lock (LSS has a single COB-ID pair, so
//! two concurrent operations could take each other's answers). Each runs
//! in the master core as an operation that sends its request and takes the
//! 7E4h answer with the expected command specifier.

use std::fmt;
use std::time::Duration;

use drivebus_can::Frame;
use drivebus_lss::codec::{LssField, LssResponse, err};
use drivebus_lss::{FastScan, FastScanOutcome, Identity, LssAddressRange, LssMode, master};

use crate::core::ops::{Exchange, FastScanOp, Matcher};
use crate::master::Master;

/// Why an LSS operation failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LssError {
    /// No answer in time (no slave in configuration / with that address).
    Timeout,
    /// The slave refused: `error` per CiA 305 (1: not supported / out of
    /// range, 2: storage access error, FFh: see `spec_error`).
    Refused {
        /// Error code.
        error: u8,
        /// Implementation-specific error (when `error` is FFh).
        spec_error: u8,
    },
    /// The bus failed.
    Transport(String),
    /// A node-ID or bit timing outside the allowed range.
    InvalidArgument(String),
}

impl fmt::Display for LssError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LssError::Timeout => f.write_str("LSS: no answer"),
            LssError::Refused { error, spec_error } => {
                write!(f, "LSS: slave refused (error {error}, specific error {spec_error})")
            }
            LssError::Transport(s) => write!(f, "LSS: bus error: {s}"),
            LssError::InvalidArgument(s) => write!(f, "LSS: {s}"),
        }
    }
}

impl std::error::Error for LssError {}

/// What [`LssMaster::configure_only_slave`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OnlySlave {
    /// The one non-configured slave, now with the node-ID (and stored if asked).
    Configured(Identity),
    /// No non-configured slave answered.
    NoneFound,
    /// More than one non-configured slave is on the bus: nothing was
    /// configured (the first one found is given, for a selective switch).
    Several(Identity),
}

/// The LSS master; from [`Master::lss`].
#[derive(Clone, Debug)]
pub struct LssMaster {
    master: Master,
    timeout: Duration,
}

impl Master {
    /// The LSS master with a 100 ms answer timeout.
    pub fn lss(&self) -> LssMaster {
        LssMaster { master: self.clone(), timeout: Duration::from_millis(100) }
    }
}

fn check(error: u8, spec_error: u8) -> Result<(), LssError> {
    if error == err::OK { Ok(()) } else { Err(LssError::Refused { error, spec_error }) }
}

impl LssMaster {
    /// Timeout for each answer.
    pub fn timeout(mut self, t: Duration) -> Self {
        self.timeout = t;
        self
    }

    async fn send(&self, f: Frame) -> Result<(), LssError> {
        self.master.send(f).await.map_err(|e| LssError::Transport(e.to_string()))
    }

    /// Sends `frames` and collects the LSS answers `accept` takes: the
    /// first one (`first_only`) or all within the timeout.
    async fn exchange(
        &self,
        frames: &[Frame],
        accept: impl Fn(LssResponse) -> bool + Send + 'static,
        first_only: bool,
    ) -> Result<Vec<LssResponse>, LssError> {
        let matcher: Matcher = Box::new(move |f: &Frame| {
            f.std_id() == Some(drivebus_lss::SLAVE_TO_MASTER)
                && master::parse_response(f).is_some_and(&accept)
        });
        let (op, rx) = Exchange::new(frames.to_vec(), matcher, first_only, self.timeout);
        let id = self.master.inner.with_core(|c| c.start_op(Box::new(op)));
        let guard = OpGuard { master: &self.master, id };
        let got = rx.await.map_err(|_| {
            LssError::Transport(self.master.bus_lost().unwrap_or_else(|| "the master's bus is closed".into()))
        })?;
        drop(guard);
        Ok(got.iter().filter_map(master::parse_response).collect())
    }

    /// Sends `frames` and returns the first answer `accept` maps to `Some`.
    async fn request<T: Send + 'static>(
        &self,
        frames: &[Frame],
        accept: impl Fn(LssResponse) -> Option<T> + Send + Sync + 'static,
    ) -> Result<T, LssError> {
        let _one = self.master.inner.lss_lock.lock().await;
        let accept = std::sync::Arc::new(accept);
        let a = accept.clone();
        let got = self.exchange(frames, move |r| a(r).is_some(), true).await?;
        got.into_iter().find_map(|r| accept(r)).ok_or(LssError::Timeout)
    }

    /// Switch state global: every slave enters `mode` (no answer).
    pub async fn switch_global(&self, mode: LssMode) -> Result<(), LssError> {
        let _one = self.master.inner.lss_lock.lock().await;
        self.send(master::switch_state_global(mode)).await
    }

    /// Switch state selective: the slave with `addr` enters configuration.
    pub async fn switch_selective(&self, addr: &Identity) -> Result<(), LssError> {
        let frames = master::switch_state_selective(addr);
        self.request(&frames, |r| (r == LssResponse::SwitchStateSelective).then_some(())).await
    }

    /// Inquires the LSS address of the slave in configuration.
    pub async fn inquire_identity(&self) -> Result<Identity, LssError> {
        let mut addr = Identity::default();
        for field in LssField::ALL {
            let v = self
                .request(&[master::inquire_identity(field)], move |r| match r {
                    LssResponse::Identity { field: f, value } if f == field => Some(value),
                    _ => None,
                })
                .await?;
            field.set(&mut addr, v);
        }
        Ok(addr)
    }

    /// Inquires the node-ID of the slave in configuration (FFh: unconfigured).
    pub async fn inquire_node_id(&self) -> Result<u8, LssError> {
        self.request(&[master::inquire_node_id()], |r| match r {
            LssResponse::NodeId(n) => Some(n),
            _ => None,
        })
        .await
    }

    /// Configures the pending node-ID (1..=127, or FFh to unconfigure).
    pub async fn configure_node_id(&self, node_id: u8) -> Result<(), LssError> {
        if !drivebus_lss::is_configurable_node_id(node_id) {
            return Err(LssError::InvalidArgument(format!("node-ID {node_id} is not 1..=127 or 255")));
        }
        let (e, s) = self
            .request(&[master::configure_node_id(node_id)], |r| match r {
                LssResponse::ConfigureNodeId { error, spec_error } => Some((error, spec_error)),
                _ => None,
            })
            .await?;
        check(e, s)
    }

    /// Configures the pending bit timing (index of the CiA standard table).
    pub async fn configure_bit_timing(&self, index: u8) -> Result<(), LssError> {
        let (e, s) = self
            .request(&[master::configure_bit_timing(index)], |r| match r {
                LssResponse::ConfigureBitTiming { error, spec_error } => Some((error, spec_error)),
                _ => None,
            })
            .await?;
        check(e, s)
    }

    /// Activates the pending bit timing after `delay_ms` (no answer).
    pub async fn activate_bit_timing(&self, delay_ms: u16) -> Result<(), LssError> {
        let _one = self.master.inner.lss_lock.lock().await;
        self.send(master::activate_bit_timing(delay_ms)).await
    }

    /// Stores the pending node-ID and bit timing.
    pub async fn store(&self) -> Result<(), LssError> {
        let (e, s) = self
            .request(&[master::store_configuration()], |r| match r {
                LssResponse::StoreConfiguration { error, spec_error } => Some((error, spec_error)),
                _ => None,
            })
            .await?;
        check(e, s)
    }

    /// Identify non-configured remote slaves: true if any answered.
    pub async fn identify_non_configured(&self) -> Result<bool, LssError> {
        match self
            .request(&[master::identify_non_configured()], |r| {
                (r == LssResponse::IdentifyNonConfiguredSlave).then_some(())
            })
            .await
        {
            Ok(()) => Ok(true),
            Err(LssError::Timeout) => Ok(false),
            Err(e) => Err(e),
        }
    }

    /// Identify remote slaves in `range`: true if any answered.
    pub async fn identify_remote(&self, range: &LssAddressRange) -> Result<bool, LssError> {
        let frames = master::identify_remote_slave(range);
        match self.request(&frames, |r| (r == LssResponse::IdentifySlave).then_some(())).await {
            Ok(()) => Ok(true),
            Err(LssError::Timeout) => Ok(false),
            Err(e) => Err(e),
        }
    }

    /// Fastscan (CiA 305): finds one non-configured slave in LSS waiting
    /// and leaves it alone in configuration. `Ok(None)` when none answers.
    /// Each of the up to 133 questions waits for this handle's timeout.
    /// A scan that loses its slave (an answer later than the timeout flips
    /// a bit) is repeated up to twice.
    pub async fn fastscan(&self) -> Result<Option<Identity>, LssError> {
        let mut tries = 0;
        loop {
            match self.fastscan_with(FastScan::new(self.timeout)).await {
                Err(LssError::Timeout) if tries < 2 => tries += 1,
                r => return r,
            }
        }
    }

    /// Fastscan with a prepared scanner (known parts, early advance).
    pub async fn fastscan_with(&self, scan: FastScan) -> Result<Option<Identity>, LssError> {
        let _one = self.master.inner.lss_lock.lock().await;
        let (op, rx) = FastScanOp::new(scan);
        let id = self.master.inner.with_core(|c| c.start_op(Box::new(op)));
        let guard = OpGuard { master: &self.master, id };
        let outcome = rx.await.map_err(|_| {
            LssError::Transport(self.master.bus_lost().unwrap_or_else(|| "the master's bus is closed".into()))
        })?;
        drop(guard);
        match outcome {
            FastScanOutcome::Found(a) => Ok(Some(a)),
            FastScanOutcome::NoneFound => Ok(None),
            FastScanOutcome::Lost(_) => Err(LssError::Timeout),
        }
    }

    /// Configures `node_id` on the non-configured slave, refusing when
    /// there is more than one (a global switch would give every slave the
    /// same node-ID): fastscan isolates one slave, which gets the node-ID;
    /// if another non-configured slave still answers "identify
    /// non-configured remote slave", the first is unconfigured again
    /// (node-ID FFh) and nothing changes. Otherwise the node-ID is stored
    /// when `store`, and the slave returns to waiting (it starts under the
    /// new node-ID, CiA 305).
    pub async fn configure_only_slave(&self, node_id: u8, store: bool) -> Result<OnlySlave, LssError> {
        self.configure_only_slave_with(FastScan::new(self.timeout), node_id, store).await
    }

    /// [`configure_only_slave`](Self::configure_only_slave) with a prepared scanner.
    pub async fn configure_only_slave_with(
        &self,
        scan: FastScan,
        node_id: u8,
        store: bool,
    ) -> Result<OnlySlave, LssError> {
        if !drivebus_lss::is_configurable_node_id(node_id) || node_id == 0xFF {
            return Err(LssError::InvalidArgument(format!("node-ID {node_id} is not 1..=127")));
        }
        let Some(addr) = self.fastscan_with(scan).await? else { return Ok(OnlySlave::NoneFound) };
        self.configure_node_id(node_id).await?;
        if self.identify_non_configured().await? {
            self.configure_node_id(0xFF).await?;
            self.switch_global(LssMode::Waiting).await?;
            return Ok(OnlySlave::Several(addr));
        }
        if store {
            self.store().await?;
        }
        self.switch_global(LssMode::Waiting).await?;
        Ok(OnlySlave::Configured(addr))
    }

    /// Finds the non-configured slave with the lowest LSS address (fastscan)
    /// and whether others are on the bus, leaving every slave as it was
    /// (the found one is given node-ID 1 for the check, then FFh again).
    pub async fn probe_unconfigured(&self) -> Result<Option<(Identity, bool)>, LssError> {
        let Some(addr) = self.fastscan().await? else { return Ok(None) };
        self.configure_node_id(1).await?;
        let more = self.identify_non_configured().await;
        self.configure_node_id(0xFF).await?;
        self.switch_global(LssMode::Waiting).await?;
        Ok(Some((addr, more?)))
    }

    /// Switch state selective on `addr`, configure `node_id`, store when
    /// asked, back to waiting. The node-ID of a slave that had one takes
    /// effect at its next NMT reset communication.
    pub async fn configure_selected(
        &self,
        addr: &Identity,
        node_id: u8,
        store: bool,
    ) -> Result<(), LssError> {
        self.switch_selective(addr).await?;
        let r = async {
            self.configure_node_id(node_id).await?;
            if store {
                self.store().await?;
            }
            Ok(())
        }
        .await;
        self.switch_global(LssMode::Waiting).await?;
        r
    }

    /// Fastscan, then configure `node_id` on the found slave, optionally
    /// store, and return it to waiting (it starts with the new node-ID
    /// after a reset communication / power cycle, CiA 305).
    pub async fn assign_node_id(&self, node_id: u8, store: bool) -> Result<Option<Identity>, LssError> {
        self.assign_node_id_with(FastScan::new(self.timeout), node_id, store).await
    }

    /// [`assign_node_id`](Self::assign_node_id) with a prepared scanner
    /// (known vendor/product make the scan 4× shorter).
    pub async fn assign_node_id_with(
        &self,
        scan: FastScan,
        node_id: u8,
        store: bool,
    ) -> Result<Option<Identity>, LssError> {
        let Some(addr) = self.fastscan_with(scan).await? else { return Ok(None) };
        self.configure_node_id(node_id).await?;
        if store {
            self.store().await?;
        }
        self.switch_global(LssMode::Waiting).await?;
        Ok(Some(addr))
    }
}

/// Removes an operation whose future went away.
struct OpGuard<'a> {
    master: &'a Master,
    id: u64,
}

impl Drop for OpGuard<'_> {
    fn drop(&mut self) {
        self.master.inner.with_core(|c| c.cancel_op(self.id));
    }
}
