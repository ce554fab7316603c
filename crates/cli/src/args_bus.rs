//! Arguments of the bus-level commands that produce or measure traffic:
//! `produce` (SYNC, heartbeat, TIME), `gen` (cangen) and `stats`.

use clap::Args;

use crate::args::node_id;

/// How `dump` stamps its lines (candump's `-t`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimestampMode {
    /// Seconds since the first frame shown (candump -t z).
    #[value(alias = "z")]
    Zero,
    /// Seconds since the previous frame shown (candump -t d).
    #[value(alias = "d")]
    Delta,
    /// Unix time (candump -t a).
    #[value(alias = "a")]
    Absolute,
}

/// Examples of `drivebus produce`.
pub const PRODUCE_EXAMPLES: &str = "\
Examples:
  drivebus --bus socketcand://127.0.0.1:29536/can0 produce --sync 1                 SYNC every 1 ms
  drivebus --bus socketcand://127.0.0.1:29536/can0 produce --sync 10 --sync-counter 8
  drivebus --bus socketcand://127.0.0.1:29536/can0 produce --heartbeat 100 --heartbeat-id 100
  drivebus --bus socketcand://127.0.0.1:29536/can0 produce --time 1000 --seconds 10

The master's producers (CiA 301): SYNC (080h, counter 1..N with --sync-counter N, 1006h/1019h),
the tool's own heartbeat as node --heartbeat-id (700h + node, state operational, 1017h) and
TIME stamps (100h) from this computer's clock. Late SYNCs are skipped, never bunched. Runs until
--seconds or Ctrl-C, then prints what it sent.";

/// `drivebus produce`.
#[derive(Args, Debug)]
pub struct ProduceArgs {
    /// SYNC every MS milliseconds (fractions allowed: 0.5).
    #[arg(long, value_name = "MS")]
    pub sync: Option<f64>,
    /// SYNC counter overflow value 2..240 (1019h); 0 sends SYNC without a counter.
    #[arg(long, value_name = "N", default_value_t = 0, requires = "sync")]
    pub sync_counter: u8,
    /// The tool's heartbeat every MS milliseconds, as node --heartbeat-id.
    #[arg(long, value_name = "MS", requires = "heartbeat_id")]
    pub heartbeat: Option<u16>,
    /// Node-ID the tool's heartbeat goes out as (1..127).
    #[arg(long, value_name = "NODE", value_parser = node_id, requires = "heartbeat")]
    pub heartbeat_id: Option<u8>,
    /// TIME stamp every MS milliseconds, from this computer's clock.
    #[arg(long, value_name = "MS")]
    pub time: Option<u64>,
    /// Stop after this many seconds (default: until Ctrl-C).
    #[arg(long)]
    pub seconds: Option<f64>,
}

/// Examples of `drivebus gen`.
pub const GEN_EXAMPLES: &str = "\
Examples:
  drivebus --bus socketcand://127.0.0.1:29536/can0 gen                        random frames every 200 ms
  drivebus --bus socketcand://127.0.0.1:29536/can0 gen -g 1 -I 42A -L 8 -D i  42Ah, 8 counting bytes, every ms
  drivebus --bus socketcand://127.0.0.1:29536/can0 gen -g 0 --count 10000     10000 frames back to back
  drivebus --bus virtual gen -I i -L 2 -D 1122 --count 5 -v

Like cangen: -I/-L/-D take a fixed value, `r` (random) or `i` (incrementing); the random sequence
is the same for the same --seed. Stops after --count frames, --seconds or Ctrl-C, and prints the count.";

/// `drivebus gen`.
#[derive(Args, Debug)]
pub struct GenArgs {
    /// Milliseconds between frames; 0 sends back to back (cangen -g).
    #[arg(short = 'g', long, value_name = "MS", default_value_t = 200.0)]
    pub gap: f64,
    /// CAN-ID: hex, `r` random or `i` incrementing (cangen -I).
    #[arg(short = 'I', long = "id", value_name = "ID|r|i", default_value = "r")]
    pub id: String,
    /// Data length 0..8, `r` random or `i` incrementing (cangen -L).
    #[arg(short = 'L', long = "len", value_name = "N|r|i", default_value = "r")]
    pub len: String,
    /// Data: hex bytes (e.g. 1122AABB), `r` random or `i` incrementing (cangen -D).
    #[arg(short = 'D', long = "data", value_name = "HEX|r|i", default_value = "r")]
    pub data: String,
    /// 29-bit identifiers (cangen -e).
    #[arg(short = 'e', long)]
    pub extended: bool,
    /// Remote (RTR) frames (cangen -R).
    #[arg(short = 'R', long)]
    pub rtr: bool,
    /// Stop after this many frames (cangen's -n; -n is --node here).
    #[arg(long, value_name = "N")]
    pub count: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Seed of the random values.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print every frame sent, candump style (cangen -v).
    #[arg(short = 'v', long)]
    pub verbose: bool,
}

/// Examples of `drivebus stats`.
pub const STATS_EXAMPLES: &str = "\
Examples:
  drivebus --bus socketcand://127.0.0.1:29536/can0 stats --bitrate 1000000
  drivebus --bus 'slcan:///dev/ttyUSB0?bitrate=500000' stats --interval 5     (bit rate from the URL)
  drivebus --bus socketcan://can0 stats --bitrate 500000 --seconds 10 --top 20
  drivebus --bus socketcand://127.0.0.1:29536/can0 --json stats --seconds 3   (JSON lines)

Every --interval: frames per second, bits per second (exact stuffed frame lengths plus
intermission), the load as a share of --bitrate, the busiest COB-IDs with their frames per second,
and the error frames and error counters where the transport reports them (SocketCAN).";

/// `drivebus stats`.
#[derive(Args, Debug)]
pub struct StatsArgs {
    /// The bus's bit rate, for the load [default: the bitrate of an slcan URL].
    #[arg(long, value_name = "BPS")]
    pub bitrate: Option<u32>,
    /// Seconds between reports.
    #[arg(long, default_value_t = 1.0)]
    pub interval: f64,
    /// Stop after this many seconds (default: until Ctrl-C).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// How many COB-IDs to list, busiest first.
    #[arg(long, default_value_t = 10)]
    pub top: usize,
}
