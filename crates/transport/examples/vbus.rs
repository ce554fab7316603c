//! A bus hub for trying third-party tools: a socketcand server on
//! 127.0.0.1, optionally an slcan pty on the same bus, and optionally a toy
//! responder that answers every frame 0x600+n with 0x580+n (same data).
//!
//! ```text
//! cargo run -p drivebus-transport --example vbus -- [--port N] [--channel NAME]
//!     [--pty] [--slcan-tcp] [--responder] [--bitrate N] [--seconds N]
//! ```
//! Prints `socketcand 127.0.0.1:PORT`, `slcan-pty PATH` and
//! `slcan-tcp 127.0.0.1:PORT` (pyserial `socket://`) lines, then runs
//! until killed or for `--seconds`.

use std::time::Duration;

use drivebus_transport::slcan::{SlcanPty, SlcanTcpServer};
use drivebus_transport::socketcand::{SocketcandConfig, SocketcandServer};
use drivebus_transport::{Frame, Hub, HubConfig};

#[tokio::main]
async fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (mut port, mut channel, mut pty, mut slcan_tcp, mut responder, mut bitrate, mut seconds) =
        (0u16, "can0".to_owned(), false, false, false, None, 3600u64);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--port" => port = args.next().ok_or("--port N")?.parse()?,
            "--channel" => channel = args.next().ok_or("--channel NAME")?,
            "--pty" => pty = true,
            "--slcan-tcp" => slcan_tcp = true,
            "--responder" => responder = true,
            "--bitrate" => bitrate = Some(args.next().ok_or("--bitrate N")?.parse()?),
            "--seconds" => seconds = args.next().ok_or("--seconds N")?.parse()?,
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    let hub = Hub::new(HubConfig { bitrate, ..HubConfig::default() });
    let (_srv, addr) =
        SocketcandServer::bind_with(("127.0.0.1", port), SocketcandConfig::new(&channel), hub.clone())
            .await?;
    println!("socketcand {addr}");
    let _pty = if pty {
        let p = SlcanPty::spawn(hub.attach())?;
        println!("slcan-pty {}", p.path().display());
        Some(p)
    } else {
        None
    };
    let _slcan_tcp = if slcan_tcp {
        let (s, a) = SlcanTcpServer::bind("127.0.0.1:0", hub.clone()).await?;
        println!("slcan-tcp {a}");
        Some(s)
    } else {
        None
    };
    if responder {
        let mut bus = hub.attach();
        tokio::spawn(async move {
            while let Ok(f) = bus.recv().await {
                if let Some(id @ 0x601..=0x67F) = f.std_id()
                    && !f.is_rtr()
                {
                    let _ = bus.send(Frame::new(id - 0x80, f.data())).await;
                }
            }
        });
    }
    tokio::time::sleep(Duration::from_secs(seconds)).await;
    Ok(())
}
