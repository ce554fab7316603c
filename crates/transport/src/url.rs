//! Bus URL grammar.

use crate::error::TransportError;

/// Default TCP port of socketcand.
pub const SOCKETCAND_PORT: u16 = 29536;
/// Default serial line speed for slcan adapters (USB CDC adapters ignore it).
pub const SLCAN_BAUD: u32 = 115_200;

/// Where an slcan adapter is reached.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SlcanPort {
    /// A serial device path (`/dev/ttyACM0`, `COM3`, a pty slave).
    Serial(String),
    /// A TCP byte stream carrying slcan (pyserial `socket://` style).
    Tcp {
        /// Host name or address.
        host: String,
        /// TCP port.
        port: u16,
    },
}

/// A parsed bus URL.
///
/// ```text
/// socketcand://HOST[:PORT]/CHANNEL          PORT defaults to 29536; [v6]:PORT accepted
/// slcan://PATH[?bitrate=N][&baud=N]         PATH absolute (slcan:///dev/ttyUSB0) or a name (slcan://COM3)
/// slcan://tcp:HOST:PORT[?bitrate=N]         slcan over TCP
/// socketcan://IFACE                         e.g. socketcan://can0
/// virtual | virtual:// | virtual://NAME     in-process hub; NAME defaults to "default"
/// ```
///
/// `bitrate` is the CAN bit rate (10000, 20000, 50000, 100000, 125000,
/// 250000, 500000, 750000/800000, 1000000 or 83300); without it the
/// adapter keeps its configured rate. `baud` is the serial line speed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BusUrl {
    /// A socketcand server.
    Socketcand {
        /// Host name or address.
        host: String,
        /// TCP port.
        port: u16,
        /// Bus name sent in `< open CHANNEL >`.
        channel: String,
    },
    /// An slcan adapter.
    Slcan {
        /// Where it is.
        port: SlcanPort,
        /// CAN bit rate to configure (`S<n>`), `None` to keep the adapter's.
        bitrate: Option<u32>,
        /// Serial line speed.
        baud: u32,
    },
    /// A Linux SocketCAN interface.
    SocketCan {
        /// Interface name.
        interface: String,
    },
    /// An in-process virtual bus.
    Virtual {
        /// Bus name; handles opened on the same name share the bus.
        name: String,
    },
}

impl BusUrl {
    /// Parses `url`; the error says what is wrong and shows the expected form.
    pub fn parse(url: &str) -> Result<BusUrl, TransportError> {
        let bad = |why: &str| TransportError::bad_url(url, why);
        let s = url.trim();
        if s == "virtual" {
            return Ok(BusUrl::Virtual { name: "default".into() });
        }
        let Some((scheme, rest)) = s.split_once("://") else {
            return Err(bad(
                "expected SCHEME://…, one of socketcand://HOST:PORT/CHANNEL, slcan:///dev/ttyUSB0?bitrate=N, \
                 slcan://tcp:HOST:PORT, socketcan://IFACE, virtual://NAME",
            ));
        };
        match scheme.to_ascii_lowercase().as_str() {
            "virtual" => {
                let name = rest.trim_end_matches('/');
                if name.contains(['/', '?', ' ']) {
                    return Err(bad("virtual bus name must not contain '/', '?' or spaces"));
                }
                let name = if name.is_empty() { "default" } else { name };
                Ok(BusUrl::Virtual { name: name.into() })
            }
            "socketcand" => {
                let Some((hostport, channel)) = rest.split_once('/') else {
                    return Err(bad("missing channel: expected socketcand://HOST:PORT/CHANNEL"));
                };
                let channel = channel.trim_end_matches('/');
                if channel.is_empty() || channel.contains(['/', ' ', '<', '>', '?']) {
                    return Err(bad("bad channel name: expected socketcand://HOST:PORT/CHANNEL, e.g. /can0"));
                }
                let (host, port) = host_port(hostport, Some(SOCKETCAND_PORT)).map_err(|e| bad(&e))?;
                Ok(BusUrl::Socketcand { host, port, channel: channel.into() })
            }
            "slcan" => {
                let (target, query) = match rest.split_once('?') {
                    Some((t, q)) => (t, Some(q)),
                    None => (rest, None),
                };
                let mut bitrate = None;
                let mut baud = SLCAN_BAUD;
                for pair in query.unwrap_or("").split('&').filter(|p| !p.is_empty()) {
                    let (k, v) = pair.split_once('=').ok_or_else(|| bad("query must be KEY=VALUE"))?;
                    let n: u32 = v.parse().map_err(|_| bad(&format!("{k}={v}: not a number")))?;
                    match k {
                        "bitrate" => {
                            if crate::slcan::bitrate_command(n).is_none() {
                                return Err(bad(&format!(
                                    "bitrate={n} has no slcan S command; use 10000, 20000, 50000, 100000, \
                                     125000, 250000, 500000, 750000, 800000, 1000000 or 83300"
                                )));
                            }
                            bitrate = Some(n);
                        }
                        "baud" if n > 0 => baud = n,
                        _ => {
                            return Err(bad(&format!(
                                "unknown or bad parameter `{pair}` (known: bitrate, baud)"
                            )));
                        }
                    }
                }
                if let Some(hp) = target.strip_prefix("tcp:") {
                    let (host, port) = host_port(hp, None).map_err(|e| bad(&e))?;
                    return Ok(BusUrl::Slcan { port: SlcanPort::Tcp { host, port }, bitrate, baud });
                }
                if target.is_empty() {
                    return Err(bad(
                        "missing device: expected slcan:///dev/ttyUSB0 or slcan://tcp:HOST:PORT",
                    ));
                }
                Ok(BusUrl::Slcan { port: SlcanPort::Serial(target.into()), bitrate, baud })
            }
            "socketcan" => {
                let iface = rest.trim_end_matches('/');
                // Linux interface names are at most 15 bytes (IFNAMSIZ - 1).
                if iface.is_empty() || iface.len() > 15 || iface.contains(['/', ' ', '?']) {
                    return Err(bad("bad interface name: expected socketcan://IFACE, e.g. socketcan://can0"));
                }
                Ok(BusUrl::SocketCan { interface: iface.into() })
            }
            other => {
                Err(bad(&format!("unknown scheme `{other}` (known: socketcand, slcan, socketcan, virtual)")))
            }
        }
    }
}

/// `HOST:PORT`, `[V6]:PORT`, or `HOST` when a default port is given.
fn host_port(s: &str, default_port: Option<u16>) -> Result<(String, u16), String> {
    let (host, port) = if let Some(v6) = s.strip_prefix('[') {
        let (h, after) = v6.split_once(']').ok_or("unclosed '[' in host")?;
        match after.strip_prefix(':') {
            Some(p) => (h, Some(p)),
            None if after.is_empty() => (h, None),
            None => return Err("expected ]:PORT after an IPv6 address".into()),
        }
    } else {
        match s.rsplit_once(':') {
            Some((h, p)) => (h, Some(p)),
            None => (s, None),
        }
    };
    if host.is_empty() {
        return Err("missing host".into());
    }
    let port = match (port, default_port) {
        (Some(p), _) => p.parse::<u16>().ok().filter(|&p| p != 0).ok_or(format!("bad port `{p}`"))?,
        (None, Some(d)) => d,
        (None, None) => return Err("missing port: expected HOST:PORT".into()),
    };
    Ok((host.into(), port))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grammar() {
        assert_eq!(
            BusUrl::parse("socketcand://127.0.0.1:29536/can0").unwrap(),
            BusUrl::Socketcand { host: "127.0.0.1".into(), port: 29536, channel: "can0".into() }
        );
        assert_eq!(
            BusUrl::parse("socketcand://[::1]/vbus0").unwrap(),
            BusUrl::Socketcand { host: "::1".into(), port: SOCKETCAND_PORT, channel: "vbus0".into() }
        );
        assert_eq!(
            BusUrl::parse("slcan:///dev/ttyUSB0?bitrate=1000000").unwrap(),
            BusUrl::Slcan {
                port: SlcanPort::Serial("/dev/ttyUSB0".into()),
                bitrate: Some(1_000_000),
                baud: SLCAN_BAUD
            }
        );
        assert_eq!(
            BusUrl::parse("slcan://tcp:localhost:4000?baud=9600").unwrap(),
            BusUrl::Slcan {
                port: SlcanPort::Tcp { host: "localhost".into(), port: 4000 },
                bitrate: None,
                baud: 9600
            }
        );
        assert_eq!(
            BusUrl::parse("socketcan://can0").unwrap(),
            BusUrl::SocketCan { interface: "can0".into() }
        );
        assert_eq!(BusUrl::parse("virtual").unwrap(), BusUrl::Virtual { name: "default".into() });
        assert_eq!(BusUrl::parse("virtual://a").unwrap(), BusUrl::Virtual { name: "a".into() });
    }

    #[test]
    fn errors_name_url_and_cause() {
        for (url, needle) in [
            ("can0", "expected SCHEME://"),
            ("foo://x", "unknown scheme `foo`"),
            ("socketcand://host:29536", "missing channel"),
            ("socketcand://host:99999/can0", "bad port `99999`"),
            ("socketcand://:1/can0", "missing host"),
            ("slcan:///dev/x?bitrate=123", "bitrate=123 has no slcan S command"),
            ("slcan:///dev/x?speed=1", "unknown or bad parameter `speed=1`"),
            ("slcan://tcp:host", "missing port"),
            ("slcan://", "missing device"),
            ("socketcan://", "bad interface name"),
            ("socketcan://averyveryverylongname", "bad interface name"),
        ] {
            let e = BusUrl::parse(url).unwrap_err().to_string();
            assert!(e.contains(url), "{e}");
            assert!(e.contains(needle), "{url}: {e}");
        }
    }
}
