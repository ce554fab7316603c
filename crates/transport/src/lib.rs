//! Async CAN transports for drivebus (tokio).
//!
//! Every transport yields the same handle, [`CanBus`]: `send(frame).await`
//! and `recv().await`, splittable into [`CanTx`] / [`CanRx`]. [`open`] picks
//! the transport from a URL (grammar in [`BusUrl`]):
//!
//! | URL | transport |
//! |---|---|
//! | `socketcand://HOST[:PORT]/CHANNEL` | socketcand client (TCP, ASCII, default port 29536) |
//! | `slcan:///dev/ttyUSB0?bitrate=1000000` | slcan (Lawicel) adapter on a serial device |
//! | `slcan://tcp:HOST:PORT?bitrate=…` | slcan over a TCP byte stream (pyserial `socket://` style) |
//! | `socketcan://can0` | Linux SocketCAN (Linux builds; needs AF_CAN at run time) |
//! | `virtual`, `virtual://NAME` | in-process [`Hub`] shared by every handle opened on NAME |
//!
//! Servers that let outside programs join a bus:
//! [`SocketcandServer`](socketcand::SocketcandServer) (a socketcand-compatible
//! TCP hub that python-can's `socketcand` interface talks to) and
//! [`SlcanPty`](slcan::SlcanPty) (an slcan adapter emulated on a
//! pseudo-terminal). Both relay through a [`Hub`]; in-process participants
//! (virtual drives) join the same hub with [`Hub::attach`].
//!
//! [`host`] runs any sans-IO `drivebus_can::Device` in real time on a
//! [`CanBus`] (and [`host::bridge`] puts a hub's devices on a real bus).

pub mod clock;
mod error;
mod handle;
pub mod host;
pub mod hub;
pub mod slcan;
#[cfg(target_os = "linux")]
pub mod socketcan;
pub mod socketcand;
pub mod stats;
mod url;

pub use drivebus_can::fault::{FaultAction, FaultRule};
pub use drivebus_can::{CanId, Frame};
pub use error::{Cause, TransportError};
pub use handle::{CanBus, CanRx, CanTx, TrySendError};
pub use hub::{FaultVerdict, Hub, HubConfig, UnsupportedFault};
pub use stats::{BusErrors, LoadMeter, LoadReport};
pub use url::{BusUrl, SlcanPort};

/// Opens the bus named by `url` (see [`BusUrl`] for the grammar).
///
/// Network and serial transports start a background task on the current
/// tokio runtime; the returned handle stops it when dropped.
pub async fn open(url: &str) -> Result<CanBus, TransportError> {
    let parsed = BusUrl::parse(url)?;
    open_parsed(url, &parsed).await
}

/// Opens an already parsed URL; `url` is only used in error messages.
pub async fn open_parsed(url: &str, parsed: &BusUrl) -> Result<CanBus, TransportError> {
    let io = |e: std::io::Error| TransportError::new(url, Cause::Io(e));
    match parsed {
        BusUrl::Virtual { name } => Ok(hub::virtual_hub(name).attach()),
        BusUrl::Socketcand { host, port, channel } => {
            socketcand::connect((host.as_str(), *port), channel).await.map_err(io)
        }
        BusUrl::Slcan { port, bitrate, baud } => match port {
            SlcanPort::Serial(path) => slcan::open_serial(path, *bitrate, *baud).await.map_err(io),
            SlcanPort::Tcp { host, port } => {
                slcan::connect_tcp((host.as_str(), *port), *bitrate).await.map_err(io)
            }
        },
        #[cfg(target_os = "linux")]
        BusUrl::SocketCan { interface } => socketcan::open(interface).map_err(io),
        #[cfg(not(target_os = "linux"))]
        BusUrl::SocketCan { .. } => {
            Err(TransportError::new(url, Cause::Unsupported("SocketCAN is Linux only".into())))
        }
    }
}
