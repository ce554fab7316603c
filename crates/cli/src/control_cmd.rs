//! `drivebus control --connect ADDR …`: one request to a running
//! `drivebus serve --control ADDR` or `drivebus ethercat serve --control
//! ADDR` (docs/control.md).

use anyhow::bail;
use clap::{Args, Subcommand};

use crate::args::Global;
use crate::control::{Addr, ControlRequest, request};

/// `drivebus control`.
#[derive(Args, Debug)]
pub struct ControlArgs {
    /// The server's control address: 127.0.0.1:PORT or a Unix socket path (serve --control or
    /// ethercat serve --control).
    #[arg(long, value_name = "ADDR")]
    pub connect: String,
    /// What to do.
    #[command(subcommand)]
    pub cmd: ControlCmd,
}

/// A control request.
#[derive(Subcommand, Debug)]
pub enum ControlCmd {
    /// Set a machine input of a drive: digital LINE on|off, analog CHANNEL VOLTS, master_velocity,
    /// master_position, motor_temperature VALUE, brake on|off (docs/machine.md).
    Input {
        /// Node-ID of the drive.
        #[arg(value_name = "NODE")]
        drive: u8,
        /// digital, analog, master_velocity, master_position, motor_temperature or brake.
        input: String,
        /// [LINE] VALUE: a line for digital (1..16) and analog (1..4), then the value (on/off,
        /// 1/0, volts, counts, °C).
        #[arg(num_args = 1..=2, required = true, allow_negative_numbers = true)]
        args: Vec<String>,
        /// Only this long (seconds), then back to the machine's value.
        #[arg(long = "for", value_name = "SECONDS")]
        duration: Option<f64>,
    },
    /// Trigger a machine fault of a drive (encoder, over_current, over_temperature, over_voltage,
    /// under_voltage, trip SWITCH, wire_break SWITCH) or `clear` them.
    Fault {
        /// Node-ID of the drive.
        #[arg(value_name = "NODE")]
        drive: u8,
        /// The kind, or `clear`.
        kind: String,
        /// For trip and wire_break: negative_limit, positive_limit or home_switch.
        switch: Option<String>,
        /// Only this long (seconds), then it clears.
        #[arg(long = "for", value_name = "SECONDS")]
        duration: Option<f64>,
    },
    /// Drop or corrupt frames on the server's bus, clear the rules, or put a drive bus-off
    /// (`bus off NODE`) and back (`bus on NODE`); on an EtherCAT line (`ethercat serve`): break
    /// the link after a slave, lose or corrupt frames, skew a slave's working counter.
    Bus {
        /// drop, corrupt, clear, rule (then --rule in `serve --fault` syntax), off or on; EtherCAT:
        /// break, lose, corrupt (without --id), wkc, drift, jitter, clear.
        action: String,
        /// off, on: the drive's node-ID.
        #[arg(value_name = "NODE")]
        drive: Option<u8>,
        /// The CAN-ID, or a range LOW-HIGH (hex with 0x or decimal).
        #[arg(long, value_name = "IDS")]
        id: Option<String>,
        /// Hit at most this many frames.
        #[arg(long, value_name = "N")]
        count: Option<u32>,
        /// corrupt: hex digits XORed onto the data.
        #[arg(long, value_name = "HEX")]
        mask: Option<String>,
        /// rule: a whole `--fault` rule, e.g. drop:0x180-0x1FF,every=2.
        #[arg(long, value_name = "RULE")]
        rule: Option<String>,
        /// off: the controller recovers by itself after 128 × 11 bit times (at serve's --bitrate,
        /// 125 kbit/s when unpaced) and the node sends EMCY 8140h; without it, `bus on NODE`.
        #[arg(long)]
        recover: bool,
        /// EtherCAT line faults.
        #[command(flatten)]
        line: LineOpts,
    },
    /// Switch a drive's power off or on (it boots from its stored parameters).
    Power {
        /// Node-ID of the drive.
        #[arg(value_name = "NODE")]
        drive: u8,
        /// on or off.
        state: String,
    },
}

/// The options of the EtherCAT line's faults (`bus break|lose|corrupt|wkc`).
#[derive(Args, Debug, Default, Clone, PartialEq)]
pub struct LineOpts {
    /// break: the link behind this slave (position from 1) breaks.
    #[arg(long, value_name = "N")]
    pub after: Option<u8>,
    /// lose, corrupt: only every N-th frame.
    #[arg(long, value_name = "N")]
    pub every: Option<u32>,
    /// lose, corrupt: each frame with this probability (0..1).
    #[arg(long, value_name = "P")]
    pub probability: Option<f64>,
    /// lose, corrupt: seed of the probability's generator (a run replays).
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// corrupt: damaged in front of this slave (default 1); wkc: the slave that miscounts.
    #[arg(long, value_name = "N")]
    pub slave: Option<u8>,
    /// wkc: added to each working counter the slave counts in (e.g. 1 or -1).
    #[arg(long, value_name = "D", allow_negative_numbers = true)]
    pub skew: Option<i16>,
    /// drift: the slave's clock runs this many parts per million fast (negative: slow).
    #[arg(long, value_name = "PPM", allow_negative_numbers = true)]
    pub ppm: Option<f64>,
    /// jitter: the largest deviation of the slave's time stamps, ns (--seed picks the sequence).
    #[arg(long, value_name = "NS")]
    pub amplitude: Option<u32>,
}

/// The rule of an EtherCAT line fault (docs/control.md), `None` when the
/// action is not one.
fn line_rule(
    action: &str,
    can_options: bool,
    count: Option<u32>,
    o: &LineOpts,
) -> anyhow::Result<Option<String>> {
    let mut opts = String::new();
    for (k, v) in [
        ("every", o.every.map(|v| v.to_string())),
        ("times", count.map(|v| v.to_string())),
        ("probability", o.probability.map(|v| v.to_string())),
        ("seed", o.seed.map(|v| v.to_string())),
    ] {
        if let Some(v) = v {
            opts.push_str(&format!(",{k}={v}"));
        }
    }
    Ok(Some(match action {
        "break" => match o.after {
            Some(n) => format!("break:{n}"),
            None => bail!("bus break needs --after N: the link behind slave N breaks"),
        },
        "lose" => format!("lose{opts}"),
        "corrupt" if !can_options => match o.slave {
            Some(n) => format!("corrupt:{n}{opts}"),
            None => format!("corrupt{opts}"),
        },
        "wkc" => match (o.slave, o.skew) {
            (Some(n), Some(d)) => format!("wkc:{n}:{d}"),
            _ => bail!("bus wkc needs --slave N --skew D, e.g. --slave 2 --skew 1"),
        },
        "drift" => match (o.slave, o.ppm) {
            (Some(n), Some(p)) => format!("drift:{n}:{p}"),
            _ => bail!("bus drift needs --slave N --ppm X, e.g. --slave 2 --ppm 800"),
        },
        "jitter" => match (o.slave, o.amplitude) {
            (Some(n), Some(a)) => {
                format!("jitter:{n}:{a}{}", o.seed.map_or_else(String::new, |s| format!(",seed={s}")))
            }
            _ => bail!("bus jitter needs --slave N --amplitude NS, e.g. --slave 2 --amplitude 5000"),
        },
        _ => return Ok(None),
    }))
}

/// Examples of `drivebus control`.
pub const CONTROL_EXAMPLES: &str = "\
Examples:
  drivebus control --connect 127.0.0.1:29537 input 5 digital 3 on
  drivebus control --connect 127.0.0.1:29537 input 5 analog 1 2.5 --for 0.5
  drivebus control --connect 127.0.0.1:29537 fault 5 encoder
  drivebus control --connect 127.0.0.1:29537 fault 5 clear
  drivebus control --connect 127.0.0.1:29537 bus drop --id 0x185 --count 5
  drivebus control --connect 127.0.0.1:29537 bus off 5
  drivebus control --connect 127.0.0.1:29537 power 5 off
  drivebus control --connect /tmp/ecat.sock bus break --after 1
  drivebus control --connect /tmp/ecat.sock bus lose --probability 0.01 --seed 7
  drivebus control --connect /tmp/ecat.sock bus wkc --slave 2 --skew 1
  drivebus control --connect /tmp/ecat.sock bus drift --slave 2 --ppm 800
  drivebus control --connect /tmp/ecat.sock bus jitter --slave 2 --amplitude 5000 --seed 7
  drivebus control --connect /tmp/ecat.sock power 2 off";

fn level(s: &str) -> Option<f64> {
    match s {
        "on" | "high" => Some(1.0),
        "off" | "low" => Some(0.0),
        _ => s.parse().ok(),
    }
}

/// The request `cmd` makes.
pub fn to_request(cmd: &ControlCmd) -> anyhow::Result<ControlRequest> {
    Ok(match cmd {
        ControlCmd::Input { drive: node, input, args, duration } => {
            let (line, value) = match args.as_slice() {
                [v] => (None, v),
                [l, v] => match l.parse::<u8>() {
                    Ok(l) => (Some(l), v),
                    Err(_) => bail!("bad line `{l}`: expected a number, e.g. `input {node} digital 3 on`"),
                },
                _ => bail!("expected [LINE] VALUE after the input, e.g. `input {node} digital 3 on`"),
            };
            let Some(value) = level(value) else {
                bail!("bad value `{value}`: expected on, off or a number");
            };
            ControlRequest::Input { node: *node, input: input.clone(), line, value, duration: *duration }
        }
        ControlCmd::Fault { drive: node, kind, switch, duration } => ControlRequest::Fault {
            node: *node,
            kind: kind.clone(),
            switch: switch.clone(),
            duration: *duration,
        },
        ControlCmd::Bus {
            action,
            drive: Some(node),
            id: None,
            count: None,
            mask: None,
            rule: None,
            recover,
            ..
        } if action == "off" || (action == "on" && !recover) => {
            ControlRequest::Link { node: *node, bus_off: action == "off", recover: *recover }
        }
        ControlCmd::Bus { recover: true, .. } => {
            bail!("--recover goes with `bus off NODE`: the controller recovers by itself")
        }
        ControlCmd::Bus { action, drive: None, id, count, mask, rule, line, recover: false } => {
            if let Some(rule) = line_rule(action, id.is_some() || mask.is_some(), *count, line)? {
                return Ok(ControlRequest::Bus { rule });
            }
            let times = count.map_or_else(String::new, |n| format!(",times={n}"));
            let rule = match (action.as_str(), id, mask, rule) {
                ("clear", None, None, None) => "clear".to_owned(),
                ("rule", None, None, Some(r)) if count.is_none() => r.clone(),
                ("drop", Some(id), None, None) => format!("drop:{id}{times}"),
                ("corrupt", Some(id), Some(m), None) => format!("corrupt:{id}:{m}{times}"),
                ("drop" | "corrupt", None, _, _) => bail!("bus {action} needs --id, e.g. --id 0x185"),
                ("corrupt", _, None, _) => bail!("bus corrupt needs --mask, e.g. --mask FF"),
                ("rule", _, _, None) => bail!("bus rule needs --rule, e.g. --rule drop:0x185,times=3"),
                _ => bail!(
                    "bad bus request `{action}`: use drop --id IDS [--count N], corrupt --id IDS --mask HEX \
                     [--count N], rule --rule RULE, clear, off NODE or on NODE"
                ),
            };
            ControlRequest::Bus { rule }
        }
        ControlCmd::Bus { action, .. } => {
            bail!("bad bus request `{action}` with a node-ID: use `bus off NODE` or `bus on NODE`")
        }
        ControlCmd::Power { drive: node, state } => match state.as_str() {
            "on" => ControlRequest::Power { node: *node, on: true },
            "off" => ControlRequest::Power { node: *node, on: false },
            s => bail!("bad power state `{s}`: expected on or off"),
        },
    })
}

/// Sends the request and reports the answer.
pub async fn run(g: &Global, a: &ControlArgs) -> anyhow::Result<()> {
    let addr = Addr::parse(&a.connect)?;
    let req = to_request(&a.cmd)?;
    let resp = request(&addr, &req).await?;
    if let Some(e) = resp.error {
        bail!("{e}");
    }
    crate::output::emit(g.json, serde_json::json!({ "ok": true, "request": req }), || "ok".to_owned());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_make_the_documented_requests() {
        let input = ControlCmd::Input {
            drive: 5,
            input: "digital".into(),
            args: vec!["3".into(), "on".into()],
            duration: None,
        };
        assert_eq!(
            to_request(&input).unwrap(),
            ControlRequest::Input {
                node: 5,
                input: "digital".into(),
                line: Some(3),
                value: 1.0,
                duration: None
            }
        );
        let off = ControlCmd::Bus {
            action: "off".into(),
            drive: Some(5),
            id: None,
            count: None,
            mask: None,
            rule: None,
            recover: false,
            line: LineOpts::default(),
        };
        assert_eq!(
            to_request(&off).unwrap(),
            ControlRequest::Link { node: 5, bus_off: true, recover: false }
        );
        let link = |action: &str, recover| ControlCmd::Bus {
            action: action.into(),
            drive: Some(5),
            id: None,
            count: None,
            mask: None,
            rule: None,
            recover,
            line: LineOpts::default(),
        };
        let auto = ControlRequest::Link { node: 5, bus_off: true, recover: true };
        assert_eq!(to_request(&link("off", true)).unwrap(), auto);
        let e = to_request(&link("on", true)).unwrap_err().to_string();
        assert!(e.contains("--recover goes with `bus off NODE`"), "{e}");
        let bus = ControlCmd::Bus {
            action: "drop".into(),
            drive: None,
            id: Some("0x181".into()),
            count: Some(5),
            mask: None,
            rule: None,
            recover: false,
            line: LineOpts::default(),
        };
        assert_eq!(to_request(&bus).unwrap(), ControlRequest::Bus { rule: "drop:0x181,times=5".into() });
        let bad = ControlCmd::Bus {
            action: "drop".into(),
            drive: None,
            id: None,
            count: None,
            mask: None,
            rule: None,
            recover: false,
            line: LineOpts::default(),
        };
        assert!(to_request(&bad).unwrap_err().to_string().contains("needs --id"));
        let ecat = |action: &str, line: LineOpts| ControlCmd::Bus {
            action: action.into(),
            drive: None,
            id: None,
            count: None,
            mask: None,
            rule: None,
            recover: false,
            line,
        };
        let rule = |c| match to_request(&c).unwrap() {
            ControlRequest::Bus { rule } => rule,
            r => panic!("{r:?}"),
        };
        assert_eq!(rule(ecat("break", LineOpts { after: Some(2), ..LineOpts::default() })), "break:2");
        let lose = LineOpts { probability: Some(0.25), seed: Some(7), ..LineOpts::default() };
        assert_eq!(rule(ecat("lose", lose)), "lose,probability=0.25,seed=7");
        assert_eq!(
            rule(ecat("corrupt", LineOpts { every: Some(4), ..LineOpts::default() })),
            "corrupt,every=4"
        );
        let wkc = LineOpts { slave: Some(2), skew: Some(-1), ..LineOpts::default() };
        assert_eq!(rule(ecat("wkc", wkc)), "wkc:2:-1");
        let drift = LineOpts { slave: Some(1), ppm: Some(800.0), ..LineOpts::default() };
        assert_eq!(rule(ecat("drift", drift)), "drift:1:800");
        let jitter = LineOpts { slave: Some(2), amplitude: Some(5000), seed: Some(7), ..LineOpts::default() };
        assert_eq!(rule(ecat("jitter", jitter)), "jitter:2:5000,seed=7");
        assert!(to_request(&ecat("break", LineOpts::default())).unwrap_err().to_string().contains("--after"));
        let p = ControlCmd::Power { drive: 5, state: "of".into() };
        assert!(to_request(&p).is_err());
    }
}
