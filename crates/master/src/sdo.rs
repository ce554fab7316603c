//! Async SDO access: [`SdoHandle`] queues transfers in the master core,
//! which runs them with the sans-IO `drivebus_sdo::client::SdoClient`.
//!
//! One transfer per server at a time (an SDO server runs one): transfers to
//! the same node queue in order; transfers to different nodes run in
//! parallel. Dropping the future aborts the transfer (abort 0800 0000h on
//! the bus, so the server is free at once).

use std::fmt;
use std::sync::Arc;
use std::time::Duration;

use drivebus_od::{DataType, SdoAbort, Value};
use drivebus_sdo::client::{ClientError, Completed, Protocol, SdoClientConfig};
use tokio::sync::oneshot;

pub use crate::core::sdo::Progress;
use crate::core::sdo::{Outcome, Request};
use crate::master::Master;

/// Why an SDO transfer failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SdoError {
    /// The server aborted the transfer.
    Abort {
        /// Abort code (CiA 301 table 22).
        code: SdoAbort,
        /// Its standard text, when the code is a standard one.
        text: Option<&'static str>,
    },
    /// The server did not answer in time (after every retry).
    Timeout,
    /// The server broke the protocol; the master sent it this abort code.
    Protocol(SdoAbort),
    /// The master aborted for a local reason (upload too large).
    LocalAbort(SdoAbort),
    /// The bus failed.
    Transport(String),
    /// The request cannot be sent as asked (protocol/size, unknown type).
    InvalidRequest(String),
    /// The data does not decode as the requested type.
    Decode(String),
    /// The transfer failed while another SDO client was talking to the
    /// same node (its requests or its answers were on the bus); it was
    /// started again where that is safe.
    OtherClient {
        /// How the last attempt failed.
        cause: Box<SdoError>,
        /// Times the transfer was started again.
        retries: u8,
        /// The object the other client's last answer named, if one was seen.
        their_object: Option<(u16, u8)>,
    },
}

impl SdoError {
    /// The abort code of a server abort.
    pub fn abort_code(&self) -> Option<SdoAbort> {
        match self {
            SdoError::Abort { code, .. } => Some(*code),
            SdoError::OtherClient { cause, .. } => cause.abort_code(),
            _ => None,
        }
    }

    fn from_client(e: ClientError) -> SdoError {
        match e {
            ClientError::ServerAbort(code) => SdoError::Abort { code, text: code.description() },
            ClientError::Timeout => SdoError::Timeout,
            ClientError::ProtocolViolation(a) => SdoError::Protocol(a),
            ClientError::LocalAbort(a) => SdoError::LocalAbort(a),
            e @ (ClientError::Busy | ClientError::InvalidRequest) => SdoError::InvalidRequest(e.to_string()),
        }
    }
}

impl fmt::Display for SdoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SdoError::Abort { code, text } => {
                write!(f, "SDO abort {:08X}h: {}", code.0, text.unwrap_or("manufacturer-specific code"))
            }
            SdoError::Timeout => f.write_str("SDO timeout: no response from the node"),
            SdoError::Protocol(a) => {
                write!(f, "SDO protocol violation by the node (sent abort {:08X}h)", a.0)
            }
            SdoError::LocalAbort(a) => write!(f, "SDO transfer aborted locally: {a}"),
            SdoError::Transport(s) => write!(f, "bus error: {s}"),
            SdoError::InvalidRequest(s) => write!(f, "invalid SDO request: {s}"),
            SdoError::Decode(s) => write!(f, "cannot decode SDO data: {s}"),
            SdoError::OtherClient { cause, retries, their_object } => {
                write!(f, "another SDO client is talking to the node")?;
                if let Some((i, s)) = their_object {
                    write!(f, " (answers for its {i:04X}h:{s:02X} came in between)")?;
                }
                write!(f, "; {cause}")?;
                if *retries > 0 {
                    write!(f, " (after {retries} retries)")?;
                }
                f.write_str(
                    "; stop the other client (a monitor, a second tool) or give it another SDO channel",
                )
            }
        }
    }
}

impl std::error::Error for SdoError {}

/// SDO access to one node; built by [`Master::sdo`], configured with the
/// builder methods, cheap to clone.
#[derive(Clone)]
pub struct SdoHandle {
    master: Master,
    node: u8,
    cfg: SdoClientConfig,
    protocol: Protocol,
    progress: Option<Progress>,
}

impl fmt::Debug for SdoHandle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SdoHandle").field("node", &self.node).field("cfg", &self.cfg).finish_non_exhaustive()
    }
}

impl Master {
    /// SDO access to `node`'s default server (600h/580h + node) with the
    /// master's default timeout and retries.
    pub fn sdo(&self, node: u8) -> SdoHandle {
        let mut cfg = SdoClientConfig::for_node(node);
        cfg.timeout = self.config().sdo_timeout;
        cfg.retries = self.config().sdo_retries;
        SdoHandle { master: self.clone(), node, cfg, protocol: Protocol::Auto, progress: None }
    }
}

impl SdoHandle {
    /// Protocol for transfers (default `Auto`: expedited ≤ 4 bytes, else segmented).
    pub fn protocol(mut self, p: Protocol) -> Self {
        self.protocol = p;
        self
    }
    /// Response timeout.
    pub fn timeout(mut self, t: Duration) -> Self {
        self.cfg.timeout = t;
        self
    }
    /// Retries after a timeout.
    pub fn retries(mut self, n: u8) -> Self {
        self.cfg.retries = n;
        self
    }
    /// Block size asked for in block uploads (1..=127).
    pub fn block_size(mut self, n: u8) -> Self {
        self.cfg.block_size = n.clamp(1, drivebus_sdo::client::MAX_BLOCK_SIZE);
        self
    }
    /// `Auto` downloads of at least `bytes` use block transfer.
    pub fn block_threshold(mut self, bytes: Option<usize>) -> Self {
        self.cfg.block_threshold = bytes;
        self
    }
    /// Offer CRC in block transfers.
    pub fn crc(mut self, on: bool) -> Self {
        self.cfg.crc = on;
        self
    }
    /// Full client configuration (custom COB-IDs for extra SDO servers).
    pub fn client_config(mut self, cfg: SdoClientConfig) -> Self {
        self.cfg = cfg;
        self
    }
    /// Called with (bytes done, total) whenever a transfer makes progress.
    pub fn on_progress(mut self, f: impl Fn(usize, Option<usize>) + Send + Sync + 'static) -> Self {
        self.progress = Some(Arc::new(f));
        self
    }
    /// The node addressed.
    pub fn node(&self) -> u8 {
        self.node
    }

    /// Reads `index`/`sub`.
    pub async fn upload(&self, index: u16, sub: u8) -> Result<Vec<u8>, SdoError> {
        self.transfer(index, sub, None).await.map(Completed::into_data)
    }

    /// Writes `data` to `index`/`sub`.
    pub async fn download(&self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoError> {
        self.transfer(index, sub, Some(data)).await.map(|_| ())
    }

    /// Reads a typed value (`u8`..`u64`, `i8`..`i64`, `f32`, `f64`, `bool`, `String`, `Vec<u8>`).
    pub async fn read<T: SdoValue>(&self, index: u16, sub: u8) -> Result<T, SdoError> {
        let data = self.upload(index, sub).await?;
        T::from_sdo(&data).ok_or_else(|| {
            SdoError::Decode(format!("{index:04X}h:{sub} gave {} bytes, not a {}", data.len(), T::NAME))
        })
    }

    /// Writes a typed value.
    pub async fn write<T: SdoValue>(&self, index: u16, sub: u8, value: T) -> Result<(), SdoError> {
        self.download(index, sub, &value.to_sdo()).await
    }

    /// The data type of `index`/`sub`: from the dictionary registered
    /// with [`Master::set_eds`], else from the CiA 301/402 standard
    /// objects (`drivebus_objects`).
    pub fn data_type(&self, index: u16, sub: u8) -> Option<DataType> {
        self.master
            .eds(self.node)
            .and_then(|od| od.get(index, sub).map(|s| s.data_type))
            .or_else(|| drivebus_objects::entry(index, sub).map(|e| e.data_type))
    }

    fn resolve_type(&self, index: u16, sub: u8, dt: Option<DataType>) -> Result<DataType, SdoError> {
        dt.or_else(|| self.data_type(index, sub)).ok_or_else(|| {
            SdoError::InvalidRequest(format!(
                "data type of {index:04X}h:{sub} unknown (no EDS entry, not a CiA 301/402 standard object)"
            ))
        })
    }

    /// Reads and decodes `index`/`sub` as `dt`, or as the type the node's
    /// EDS dictionary or the standard objects give when `dt` is `None`.
    pub async fn read_value(&self, index: u16, sub: u8, dt: Option<DataType>) -> Result<Value, SdoError> {
        let dt = self.resolve_type(index, sub, dt)?;
        let data = self.upload(index, sub).await?;
        Value::decode(dt, &data).map_err(|a| SdoError::Decode(format!("{index:04X}h:{sub} as {dt:?}: {a}")))
    }

    /// Encodes `value` as `dt` (or the EDS type) and writes it.
    pub async fn write_value(
        &self,
        index: u16,
        sub: u8,
        value: &Value,
        dt: Option<DataType>,
    ) -> Result<(), SdoError> {
        let dt = self.resolve_type(index, sub, dt)?;
        let data =
            value.encode(dt).map_err(|a| SdoError::InvalidRequest(format!("{value:?} as {dt:?}: {a}")))?;
        self.download(index, sub, &data).await
    }

    async fn transfer(&self, index: u16, sub: u8, download: Option<&[u8]>) -> Result<Completed, SdoError> {
        let shared = &self.master.inner;
        let (done, rx) = oneshot::channel();
        let req = Request {
            cfg: self.cfg,
            index,
            sub,
            data: download.map(<[u8]>::to_vec),
            protocol: self.protocol,
            progress: self.progress.clone(),
            done,
        };
        let id = shared.with_core_and_send(|c| {
            if let Some(why) = &c.closed {
                return Err(SdoError::Transport(why.clone()));
            }
            let id = c.id();
            let now = c.now();
            let mut out = Vec::new();
            c.sdo.start(id, req, now, &mut out);
            for f in out {
                c.send(f);
            }
            Ok(id)
        })?;
        // Dropping this future aborts the transfer on the bus.
        let mut guard = CancelGuard { master: &self.master, id: Some(id) };
        let r = rx.await;
        guard.id = None;
        match r {
            Ok(Outcome { result, other }) => result.map_err(|e| {
                let cause = SdoError::from_client(e);
                match other {
                    Some(o) => SdoError::OtherClient {
                        cause: Box::new(cause),
                        retries: o.retries,
                        their_object: o.last,
                    },
                    None => cause,
                }
            }),
            Err(_) => Err(SdoError::Transport(
                shared.core().closed.clone().unwrap_or_else(|| "the master's bus is closed".into()),
            )),
        }
    }
}

/// Aborts a transfer whose future is dropped before it finished.
struct CancelGuard<'a> {
    master: &'a Master,
    id: Option<u64>,
}

impl Drop for CancelGuard<'_> {
    fn drop(&mut self) {
        if let Some(id) = self.id {
            self.master.inner.with_core(|c| {
                let now = c.now();
                let mut out = Vec::new();
                c.sdo.cancel(id, now, &mut out);
                for f in out {
                    c.send(f);
                }
            });
        }
    }
}

/// A Rust type with a CiA 301 little-endian encoding.
pub trait SdoValue: Sized {
    /// Type name for error messages.
    const NAME: &'static str;
    /// Decodes SDO data. Integers accept their exact width, or up to 4
    /// bytes for narrower types (an expedited upload without size indicated
    /// carries 4 bytes).
    fn from_sdo(data: &[u8]) -> Option<Self>;
    /// Encodes for a download.
    fn to_sdo(&self) -> Vec<u8>;
}

macro_rules! sdo_num {
    ($($t:ty),*) => {$(
        impl SdoValue for $t {
            const NAME: &'static str = stringify!($t);
            fn from_sdo(data: &[u8]) -> Option<Self> {
                const N: usize = std::mem::size_of::<$t>();
                if data.len() == N || (N < 4 && data.len() > N && data.len() <= 4) {
                    let mut b = [0u8; N];
                    b.copy_from_slice(&data[..N]);
                    Some(<$t>::from_le_bytes(b))
                } else {
                    None
                }
            }
            fn to_sdo(&self) -> Vec<u8> {
                self.to_le_bytes().to_vec()
            }
        }
    )*};
}

sdo_num!(u8, u16, u32, u64, i8, i16, i32, i64, f32, f64);

impl SdoValue for bool {
    const NAME: &'static str = "bool";
    fn from_sdo(data: &[u8]) -> Option<Self> {
        u8::from_sdo(data).map(|b| b != 0)
    }
    fn to_sdo(&self) -> Vec<u8> {
        vec![u8::from(*self)]
    }
}

impl SdoValue for String {
    const NAME: &'static str = "String";
    /// VISIBLE_STRING; trailing NULs (padding some devices send) are dropped.
    fn from_sdo(data: &[u8]) -> Option<Self> {
        let end = data.iter().rposition(|&b| b != 0).map_or(0, |p| p + 1);
        Some(String::from_utf8_lossy(&data[..end]).into_owned())
    }
    fn to_sdo(&self) -> Vec<u8> {
        self.as_bytes().to_vec()
    }
}

impl SdoValue for Vec<u8> {
    const NAME: &'static str = "bytes";
    fn from_sdo(data: &[u8]) -> Option<Self> {
        Some(data.to_vec())
    }
    fn to_sdo(&self) -> Vec<u8> {
        self.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typed_decoding() {
        assert_eq!(u16::from_sdo(&[0x34, 0x12]), Some(0x1234));
        // Expedited without size indicated: 4 bytes for a narrower type.
        assert_eq!(u8::from_sdo(&[7, 0, 0, 0]), Some(7));
        assert_eq!(u32::from_sdo(&[1, 2]), None);
        assert_eq!(u64::from_sdo(&[0; 5]), None);
        assert_eq!(i16::from_sdo(&(-2i16).to_le_bytes()), Some(-2));
        assert_eq!(f32::from_sdo(&1.5f32.to_le_bytes()), Some(1.5));
        assert_eq!(String::from_sdo(b"abc\0\0"), Some("abc".to_string()));
        assert_eq!(bool::from_sdo(&[1]), Some(true));
        assert_eq!((-1i32).to_sdo(), vec![0xFF; 4]);
    }

    #[test]
    fn abort_text_in_display() {
        let e = SdoError::from_client(ClientError::ServerAbort(SdoAbort::NO_OBJECT));
        assert_eq!(e.abort_code(), Some(SdoAbort::NO_OBJECT));
        assert!(e.to_string().starts_with("SDO abort 06020000h: Object does not exist"), "{e}");
        let e = SdoError::from_client(ClientError::ServerAbort(SdoAbort(0x0F00_0001)));
        assert!(e.to_string().contains("manufacturer-specific"), "{e}");
    }
}

/// An SDO transfer that failed, with everything needed to explain it.
#[derive(Debug)]
pub struct SdoFailure {
    /// Node-ID.
    pub node: u8,
    /// Object.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Read or write.
    pub write: bool,
    /// The failure.
    pub error: SdoError,
    /// The timeout in force.
    pub timeout: Duration,
}

impl SdoFailure {
    /// The abort code, if the server sent one.
    pub fn abort(&self) -> Option<SdoAbort> {
        self.error.abort_code()
    }
}

impl fmt::Display for SdoFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = if self.write { "write" } else { "read" };
        write!(f, "node {}: SDO {what} {:04X}h:{:02X} ", self.node, self.index, self.sub)?;
        match &self.error {
            SdoError::Abort { code, text } => write!(
                f,
                "aborted by the device with code 0x{:08X}: {}",
                code.0,
                text.unwrap_or("unknown abort code")
            ),
            SdoError::Timeout => write!(
                f,
                "timed out: no response within {} ms (is node {} on the bus and in pre-operational or operational?)",
                self.timeout.as_millis(),
                self.node
            ),
            SdoError::Transport(why) => write!(f, "failed: the bus was lost: {why}"),
            e => write!(f, "failed: {e}"),
        }
    }
}

impl std::error::Error for SdoFailure {}
