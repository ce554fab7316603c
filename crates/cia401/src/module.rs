//! [`IoModule`]: the CiA 401 objects of a node's dictionary brought to
//! life (the table of what is implemented is in the crate docs).

use alloc::vec::Vec;
use drivebus_can::LinkState;
use drivebus_node::{AppContext, Application, NmtState, Node, NodeEvent, Request};
use drivebus_od::{EntryRef, ObjectDictionary, Owner, SdoAbort, Target, le_i64};

/// The objects an [`IoModule`] owns, by application tag (`Owner::app(k)`
/// with `k` the position here).
const OWNED: [u16; 21] = [
    0x6002, 0x6005, 0x6006, 0x6007, 0x6008, 0x6200, 0x6202, 0x6206, 0x6207, 0x6208, 0x6411, 0x6421, 0x6422,
    0x6423, 0x6424, 0x6425, 0x6426, 0x6427, 0x6428, 0x6443, 0x6444,
];

/// The tag of `index` among [`OWNED`].
fn tag(index: u16) -> Option<u8> {
    OWNED.iter().position(|&i| i == index).map(|k| k as u8)
}

/// CiA 401 analog input volts to the 16-bit raw value: ±10 V full scale
/// (±32767), saturating beyond (a choice: CiA 401 leaves the scaling to
/// the device).
pub fn volts_to_raw(volts: f64) -> i16 {
    let r = volts * 3276.7;
    if r.is_nan() {
        0
    } else if r >= 32767.0 {
        32767
    } else if r <= -32767.0 {
        -32767
    } else {
        // Round half away from zero without libm.
        (if r < 0.0 { r - 0.5 } else { r + 0.5 }) as i16
    }
}

/// Handles of sub `k` (1-based) of an ARRAY, `None` where the file has no
/// such sub-index.
fn subs(od: &ObjectDictionary, index: u16, n: usize) -> Vec<Option<EntryRef>> {
    (1..=n).map(|k| u8::try_from(k).ok().and_then(|k| od.find(index, k).ok())).collect()
}

/// The channels of an ARRAY: sub 1 up to the highest sub-index it has.
fn channels(od: &ObjectDictionary, index: u16) -> usize {
    od.object(index).and_then(|o| o.subs().last()).map_or(0, |s| usize::from(s.sub))
}

/// One 8-bit group of digital inputs.
#[derive(Debug, Clone, Copy)]
struct DiGroup {
    value: EntryRef,
    polarity: Option<EntryRef>,
    any: Option<EntryRef>,
    rise: Option<EntryRef>,
    fall: Option<EntryRef>,
}

/// One 8-bit group of digital outputs.
#[derive(Debug, Clone, Copy)]
struct DoGroup {
    value: EntryRef,
    polarity: Option<EntryRef>,
    err_mode: Option<EntryRef>,
    err_value: Option<EntryRef>,
    filter: Option<EntryRef>,
}

/// One analog input channel.
#[derive(Debug, Clone, Copy)]
struct AiChan {
    value: EntryRef,
    trigger: Option<EntryRef>,
    upper: Option<EntryRef>,
    lower: Option<EntryRef>,
    delta: Option<EntryRef>,
    fall: Option<EntryRef>,
    rise: Option<EntryRef>,
}

/// One analog output channel.
#[derive(Debug, Clone, Copy)]
struct AoChan {
    value: EntryRef,
    err_mode: Option<EntryRef>,
    err_value: Option<EntryRef>,
}

/// A CiA 401 generic I/O module on a node (see the crate docs).
#[derive(Debug, Clone)]
pub struct IoModule {
    di: Vec<DiGroup>,
    dout: Vec<DoGroup>,
    ai: Vec<AiChan>,
    ao: Vec<AoChan>,
    di_enable: Option<EntryRef>,
    ai_enable: Option<EntryRef>,
    /// Input levels the outside sets, per group (before wiring, polarity).
    lines: Vec<u8>,
    /// Analog inputs the outside sets.
    analog: Vec<i16>,
    /// Physical outputs.
    outputs: Vec<u8>,
    analog_out: Vec<i32>,
    /// Output line `k + 1` drives input line `wiring[k]` (0: none).
    wiring: Vec<u16>,
    /// Analog value at each channel's last interrupt.
    ai_last: Vec<i16>,
    /// Channels that caused an interrupt since 6422h was last read.
    ai_irq: u32,
    /// Per digital group / analog channel: the TPDOs (0-based) mapping it.
    di_tpdos: Vec<Vec<u16>>,
    ai_tpdos: Vec<Vec<u16>>,
    error: bool,
    operational: bool,
    /// Inputs changed outside a callback: applied at the next poll.
    pending: bool,
}

impl IoModule {
    /// Brings the CiA 401 objects of `node`'s dictionary to life: takes
    /// the writes of those it owns, watches the TPDO mappings (1A00h..) to
    /// know which TPDOs an input change sends. Objects the dictionary
    /// lacks are features the module lacks.
    pub fn install(node: &mut Node) -> IoModule {
        let od = node.od_mut();
        for &index in &OWNED {
            let subs: Vec<u8> =
                od.object(index).map(|o| o.subs().iter().map(|s| s.sub).collect()).unwrap_or_default();
            for s in subs {
                if let Some(e) = od.get_mut(index, s)
                    && e.owner == Owner::NONE
                {
                    e.owner = Owner::app(tag(index).unwrap_or(0));
                    e.live = index == 0x6422;
                }
            }
        }
        let mut n = 0u16;
        while od.object(0x1A00 + n).is_some() && n < 512 {
            let subs: Vec<u8> =
                od.object(0x1A00 + n).map(|o| o.subs().iter().map(|s| s.sub).collect()).unwrap_or_default();
            for s in subs {
                if let Some(e) = od.get_mut(0x1A00 + n, s) {
                    e.watched = true;
                }
            }
            n += 1;
        }
        let od: &ObjectDictionary = od;
        // Only entries of the width CiA 401 gives them (a file's other
        // type would not take the module's values).
        let sized =
            |r: Option<EntryRef>, n: usize| r.filter(|&r| od.entry(r).data_type.fixed_size() == Some(n));
        let ndi = channels(od, 0x6000);
        let ndo = channels(od, 0x6200);
        let nai = channels(od, 0x6401);
        let nao = channels(od, 0x6411);
        let di = subs(od, 0x6000, ndi)
            .into_iter()
            .enumerate()
            .filter_map(|(k, v)| {
                let at = |i| od.find(i, k as u8 + 1).ok();
                Some(DiGroup {
                    value: sized(v, 1)?,
                    polarity: at(0x6002),
                    any: at(0x6006),
                    rise: at(0x6007),
                    fall: at(0x6008),
                })
            })
            .collect::<Vec<_>>();
        let dout = subs(od, 0x6200, ndo)
            .into_iter()
            .enumerate()
            .filter_map(|(k, v)| {
                let at = |i| od.find(i, k as u8 + 1).ok();
                Some(DoGroup {
                    value: sized(v, 1)?,
                    polarity: at(0x6202),
                    err_mode: at(0x6206),
                    err_value: at(0x6207),
                    filter: at(0x6208),
                })
            })
            .collect::<Vec<_>>();
        let ai = subs(od, 0x6401, nai)
            .into_iter()
            .enumerate()
            .filter_map(|(k, v)| {
                let at = |i| od.find(i, k as u8 + 1).ok();
                Some(AiChan {
                    value: sized(v, 2)?,
                    trigger: at(0x6421),
                    upper: at(0x6424),
                    lower: at(0x6425),
                    delta: at(0x6426),
                    fall: at(0x6427),
                    rise: at(0x6428),
                })
            })
            .collect::<Vec<_>>();
        let ao = subs(od, 0x6411, nao)
            .into_iter()
            .enumerate()
            .filter_map(|(k, v)| {
                let at = |i| od.find(i, k as u8 + 1).ok();
                Some(AoChan { value: sized(v, 2)?, err_mode: at(0x6443), err_value: at(0x6444) })
            })
            .collect::<Vec<_>>();
        let (gi, go, ci, co) = (di.len(), dout.len(), ai.len(), ao.len());
        let mut m = IoModule {
            di,
            dout,
            ai,
            ao,
            di_enable: od.find(0x6005, 0).ok(),
            ai_enable: od.find(0x6423, 0).ok(),
            lines: alloc::vec![0; gi],
            analog: alloc::vec![0; ci],
            outputs: alloc::vec![0; go],
            analog_out: alloc::vec![0; co],
            wiring: Vec::new(),
            ai_last: alloc::vec![0; ci],
            ai_irq: 0,
            di_tpdos: alloc::vec![Vec::new(); gi],
            ai_tpdos: alloc::vec![Vec::new(); ci],
            error: false,
            operational: false,
            pending: true,
        };
        m.ai_last.clone_from(&m.analog);
        m
    }

    /// Input line `line` (1-based: line `8(k−1)+b+1` is 6000h sub `k` bit
    /// `b`) is high; shows at the node's next poll. Lines beyond the
    /// module's are ignored.
    pub fn set_input_line(&mut self, line: u16, level: bool) {
        let Some(i) = line.checked_sub(1) else { return };
        if let Some(g) = self.lines.get_mut(usize::from(i / 8)) {
            let bit = 1u8 << (i % 8);
            *g = if level { *g | bit } else { *g & !bit };
            self.pending = true;
        }
    }

    /// Analog input `channel` (1-based, 6401h sub) reads `raw`; shows at
    /// the node's next poll.
    pub fn set_analog_input(&mut self, channel: u16, raw: i16) {
        if let Some(a) = channel.checked_sub(1).and_then(|c| self.analog.get_mut(usize::from(c))) {
            *a = raw;
            self.pending = true;
        }
    }

    /// Output line `k + 1` drives input line `wiring[k]` (1-based; 0: not
    /// wired): the input reads high while the output is (a machine's
    /// loop-back).
    pub fn set_wiring(&mut self, wiring: &[u16]) {
        self.wiring = wiring.to_vec();
        self.pending = true;
    }

    /// The physical output lines, 8 per group (6200h sub `k` is byte `k − 1`).
    pub fn output_lines(&self) -> &[u8] {
        &self.outputs
    }

    /// The physical analog outputs (6411h sub `k` is entry `k − 1`).
    pub fn analog_outputs(&self) -> &[i32] {
        &self.analog_out
    }

    /// Whether the outputs are in their error state.
    pub fn in_error_state(&self) -> bool {
        self.error
    }

    /// Whether the module has inputs set from outside still to show.
    pub fn has_pending_inputs(&self) -> bool {
        self.pending
    }

    fn flag(od: &ObjectDictionary, r: Option<EntryRef>, absent: bool) -> bool {
        r.map_or(absent, |r| od.word(r) != 0)
    }

    fn byte(od: &ObjectDictionary, r: Option<EntryRef>, absent: u8) -> u8 {
        r.map_or(absent, |r| od.word(r) as u8)
    }

    fn int(od: &ObjectDictionary, r: Option<EntryRef>) -> Option<i64> {
        r.map(|r| le_i64(od.bytes(r)))
    }

    /// The output lines from 6200h, 6202h, 6208h and the error state;
    /// the analog outputs from 6411h and the error state.
    fn refresh_outputs(&mut self, od: &ObjectDictionary) {
        for (k, g) in self.dout.iter().enumerate() {
            let written = od.word(g.value) as u8 ^ Self::byte(od, g.polarity, 0);
            let pass = Self::byte(od, g.filter, 0xFF);
            let mut out = (written & pass) | (self.outputs[k] & !pass);
            if self.error {
                let mode = Self::byte(od, g.err_mode, 0xFF);
                out = (out & !mode) | (Self::byte(od, g.err_value, 0) & mode);
            }
            self.outputs[k] = out;
        }
        for (k, c) in self.ao.iter().enumerate() {
            let mut v = le_i64(od.bytes(c.value)) as i32;
            if self.error && Self::byte(od, c.err_mode, 1) != 0 {
                v = Self::int(od, c.err_value).unwrap_or(0) as i32;
            }
            self.analog_out[k] = v;
        }
    }

    /// 6000h and 6401h from the inputs, the wiring and 6002h; the TPDOs
    /// an edge or an analog trigger sends.
    fn refresh_inputs(&mut self, cx: &mut AppContext<'_>) {
        self.pending = false;
        let od: &mut ObjectDictionary = cx.od;
        let mut requests: Vec<u16> = Vec::new();
        let enabled = Self::flag(od, self.di_enable, true);
        for (k, g) in self.di.iter().enumerate() {
            let mut level = self.lines[k];
            for (out, &to) in self.wiring.iter().enumerate() {
                let on = self.outputs.get(out / 8).is_some_and(|b| b & (1 << (out % 8)) != 0);
                if on && usize::from(to.wrapping_sub(1)) / 8 == k && to != 0 {
                    level |= 1 << ((to - 1) % 8);
                }
            }
            let new = level ^ Self::byte(od, g.polarity, 0);
            let old = od.word(g.value) as u8;
            if new == old {
                continue;
            }
            od.set_raw(g.value, &[new]);
            // Edges 6006h does not already report through change tracking.
            let edge = ((new & !old & Self::byte(od, g.rise, 0)) | (old & !new & Self::byte(od, g.fall, 0)))
                & !Self::byte(od, g.any, 0xFF);
            if enabled && edge != 0 {
                requests.extend_from_slice(&self.di_tpdos[k]);
            }
        }
        let ai_on = self.ai_enable.map(|r| od.word(r) != 0);
        for (k, c) in self.ai.iter().enumerate() {
            let v = self.analog[k];
            let bytes = v.to_le_bytes();
            if od.bytes(c.value) == bytes {
                continue;
            }
            od.set_raw(c.value, &bytes);
            if ai_on != Some(true) || c.trigger.is_none() {
                continue;
            }
            let trig = Self::byte(od, c.trigger, 0x07);
            let (v64, last) = (i64::from(v), i64::from(self.ai_last[k]));
            let beyond =
                |r: Option<EntryRef>, dir: i64| Self::int(od, r).is_some_and(|l| (v64 - l) * dir > 0);
            let moved = |r: Option<EntryRef>, d: i64| {
                let step = Self::int(od, r).unwrap_or(0);
                d > 0 && d >= step
            };
            let fire = (trig & 1 != 0 && beyond(c.upper, 1))
                || (trig & 2 != 0 && beyond(c.lower, -1))
                || (trig & 4 != 0 && moved(c.delta, (v64 - last).abs()))
                || (trig & 8 != 0 && moved(c.fall, last - v64))
                || (trig & 16 != 0 && moved(c.rise, v64 - last));
            if fire {
                self.ai_last[k] = v;
                self.ai_irq |= 1u32.checked_shl(k as u32).unwrap_or(0);
                requests.extend_from_slice(&self.ai_tpdos[k]);
            }
        }
        requests.sort_unstable();
        requests.dedup();
        for n in requests {
            cx.request(Request::RequestTpdo(n));
        }
    }

    /// Which TPDOs map which input, and the change masks that leave the
    /// inputs' interrupt masks to the module (CiA 401: 6005h/6006h for
    /// digital inputs; 6423h for analog ones).
    fn configure_tpdos(&mut self, cx: &mut AppContext<'_>) {
        let od: &ObjectDictionary = cx.od;
        let enabled = Self::flag(od, self.di_enable, true);
        let ai_on = self.ai_enable.map(|r| od.word(r) != 0);
        for v in self.di_tpdos.iter_mut().chain(self.ai_tpdos.iter_mut()) {
            v.clear();
        }
        let mut masks: Vec<(u16, Option<[u8; 8]>)> = Vec::new();
        let mut n = 0u16;
        while n < 512 && od.object(0x1A00 + n).is_some() {
            let map = 0x1A00 + n;
            let count = od.get_u32(map, 0).unwrap_or(0).min(64) as u8;
            let mut mask = [0xFFu8; 8];
            let mut bit = 0u32;
            let mut ours = false;
            for s in 1..=count {
                let e = od.get_u32(map, s).unwrap_or(0);
                let (index, sub, len) = ((e >> 16) as u16, (e >> 8) as u8, e & 0xFF);
                let k = usize::from(sub).wrapping_sub(1);
                let keep: Option<u8> = match index {
                    0x6000 if k < self.di.len() => {
                        self.di_tpdos[k].push(n);
                        Some(if enabled { Self::byte(od, self.di[k].any, 0xFF) } else { 0 })
                    }
                    0x6401 if k < self.ai.len() => {
                        self.ai_tpdos[k].push(n);
                        // Without 6423h the channel is any mapped value.
                        Some(if ai_on.is_none() || (ai_on == Some(true) && self.ai[k].trigger.is_none()) {
                            0xFF
                        } else {
                            0
                        })
                    }
                    _ => None,
                };
                if let Some(m) = keep {
                    ours = true;
                    for b in 0..len {
                        let at = bit + b;
                        let on = if len == 8 { m & (1 << b) != 0 } else { m != 0 };
                        if !on && at < 64 {
                            mask[(at / 8) as usize] &= !(1 << (at % 8));
                        }
                    }
                }
                bit += len;
            }
            masks.push((n, ours.then_some(mask)));
            n += 1;
        }
        for (tpdo, mask) in masks {
            cx.request(Request::TpdoChangeMask { tpdo, mask });
        }
    }

    fn set_error(&mut self, cx: &mut AppContext<'_>, on: bool) {
        if self.error != on {
            self.error = on;
            self.refresh_outputs(cx.od);
            self.refresh_inputs(cx);
        }
    }
}

/// Every value CiA 401 allows is taken (the file's types and limits are
/// checked before): the module only applies.
impl Application for IoModule {
    fn apply_write(&mut self, cx: &mut AppContext<'_>, at: &Target) {
        match at.index {
            0x6200 | 0x6202 | 0x6206 | 0x6207 | 0x6208 | 0x6411 | 0x6443 | 0x6444 => {
                self.refresh_outputs(cx.od);
                if !self.wiring.is_empty() {
                    self.refresh_inputs(cx);
                }
            }
            0x6002 => self.refresh_inputs(cx),
            0x6005 | 0x6006 | 0x6423 | 0x6421 | 0x1A00..=0x1BFF => self.configure_tpdos(cx),
            _ => {}
        }
    }

    fn on_read(&mut self, cx: &mut AppContext<'_>, at: &Target) -> Result<(), SdoAbort> {
        if at.index == 0x6422 && at.sub >= 1 {
            // 32 channels per sub-index; the bits read are reset.
            let shift = 32 * u32::from(at.sub - 1);
            let bits = self.ai_irq.checked_shr(shift).unwrap_or(0);
            cx.od.set_raw(at.r, &bits.to_le_bytes());
            self.ai_irq &= !bits.checked_shl(shift).unwrap_or(0);
        }
        Ok(())
    }

    fn on_start(&mut self, cx: &mut AppContext<'_>) {
        self.refresh_outputs(cx.od);
        self.refresh_inputs(cx);
        self.configure_tpdos(cx);
    }

    fn on_event(&mut self, cx: &mut AppContext<'_>, event: NodeEvent) {
        match event {
            NodeEvent::NmtState { to, .. } => {
                self.operational = to == NmtState::Operational;
                match to {
                    NmtState::Stopped => self.set_error(cx, true),
                    NmtState::Operational => self.set_error(cx, false),
                    _ => {}
                }
            }
            NodeEvent::HeartbeatTimeout { .. }
            | NodeEvent::LifeGuardingLost
            | NodeEvent::RpdoTimeout { .. }
            | NodeEvent::Link(LinkState::BusOff { .. }) => self.set_error(cx, true),
            NodeEvent::HeartbeatRecovered { .. }
            | NodeEvent::LifeGuardingResolved
            | NodeEvent::Link(LinkState::Active)
                if self.operational =>
            {
                self.set_error(cx, false)
            }
            NodeEvent::ResetApplication | NodeEvent::ResetCommunication => {
                // The node set the parameters to their power-on values.
                self.error = false;
                self.ai_irq = 0;
                self.refresh_outputs(cx.od);
                self.refresh_inputs(cx);
                self.configure_tpdos(cx);
            }
            _ => {}
        }
    }

    fn poll(&mut self, cx: &mut AppContext<'_>) -> Option<drivebus_can::Instant> {
        if !self.pending {
            return None;
        }
        let seen = cx.od.generation();
        self.refresh_inputs(cx);
        // A changed mapped input goes out now: the node polls its TPDOs
        // again at this deadline (its own poll has passed them already).
        (cx.od.generation() != seen).then_some(cx.now)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::boxed::Box;
    use drivebus_can::{Device, Frame, Instant};
    use drivebus_node::{EdsOptions, MemoryStorage, NodeDevice};

    const EDS: &str = include_str!("../eds/io16.eds");

    /// The module of `eds/io16.eds` as node 1, booted and operational;
    /// the frames it sent so far are dropped.
    fn module() -> (NodeDevice<IoModule>, Vec<Frame>) {
        let eds = drivebus_eds::parse(EDS).unwrap().eds;
        let (mut node, w) =
            Node::from_eds(&eds, EDS, 1, Box::new(MemoryStorage::new()), EdsOptions::default()).unwrap();
        assert!(w.is_empty());
        let io = IoModule::install(&mut node);
        let mut dev = NodeDevice::new(node, io);
        let mut out = Vec::new();
        dev.start(Instant::ZERO, &mut out);
        dev.handle_frame(&Frame::new(0, &[1, 1]), Instant::ZERO, &mut out);
        dev.poll(Instant::ZERO, &mut out);
        (dev, Vec::new())
    }

    /// Lets the inputs set from outside show: the host polls the device,
    /// and again at the deadlines it returns for the same instant.
    fn settle(dev: &mut NodeDevice<IoModule>, out: &mut Vec<Frame>) {
        let now = Instant::from_nanos(1);
        dev.node.od_mut();
        for _ in 0..4 {
            if dev.poll(now, out).is_none_or(|d| d > now) {
                return;
            }
        }
        panic!("the device keeps asking to be polled at once");
    }

    fn write(dev: &mut NodeDevice<IoModule>, index: u16, sub: u8, data: &[u8], out: &mut Vec<Frame>) {
        let now = Instant::from_nanos(1);
        dev.write_object(index, sub, data, now, out).unwrap();
        dev.poll(now, out);
    }

    #[test]
    fn an_input_change_sends_tpdo1_with_the_polarity_applied() {
        let (mut dev, mut out) = module();
        dev.app.set_input_line(3, true);
        dev.app.set_input_line(9, true);
        settle(&mut dev, &mut out);
        assert_eq!(out, [Frame::new(0x181, &[0x04, 0x01])]);
        out.clear();
        write(&mut dev, 0x6002, 1, &[0x05], &mut out);
        assert_eq!(dev.node.od().get_u32(0x6000, 1), Some(0x01));
        assert_eq!(out, [Frame::new(0x181, &[0x01, 0x01])]);
    }

    #[test]
    fn interrupt_masks_choose_the_edges_that_send() {
        let (mut dev, mut out) = module();
        // Line 1: only its rising edge sends; line 2: every change.
        write(&mut dev, 0x6006, 1, &[0xFE], &mut out);
        write(&mut dev, 0x6007, 1, &[0x01], &mut out);
        out.clear();
        dev.app.set_input_line(1, true);
        settle(&mut dev, &mut out);
        assert_eq!(out, [Frame::new(0x181, &[0x01, 0x00])], "rising edge");
        out.clear();
        dev.app.set_input_line(1, false);
        settle(&mut dev, &mut out);
        assert!(out.is_empty(), "falling edge masked: {out:?}");
        assert_eq!(dev.node.od().get_u32(0x6000, 1), Some(0), "the value follows all the same");
        dev.app.set_input_line(2, true);
        settle(&mut dev, &mut out);
        assert_eq!(out, [Frame::new(0x181, &[0x02, 0x00])], "any change");
        out.clear();
        // 6005h FALSE: no input change sends.
        write(&mut dev, 0x6005, 0, &[0], &mut out);
        dev.app.set_input_line(2, false);
        settle(&mut dev, &mut out);
        assert!(out.is_empty(), "{out:?}");
    }

    #[test]
    fn outputs_follow_6200h_polarity_filter_and_the_error_state() {
        let (mut dev, mut out) = module();
        // RPDO1 (201h) writes 6200h:1/2.
        dev.handle_frame(&Frame::new(0x201, &[0x81, 0x02]), Instant::ZERO, &mut out);
        assert_eq!(dev.app.output_lines(), [0x81, 0x02]);
        write(&mut dev, 0x6202, 1, &[0x01], &mut out);
        assert_eq!(dev.app.output_lines(), [0x80, 0x02]);
        // 6208h: output 8 frozen.
        write(&mut dev, 0x6208, 1, &[0x7F], &mut out);
        write(&mut dev, 0x6200, 1, &[0x00], &mut out);
        assert_eq!(dev.app.output_lines(), [0x81, 0x02]);
        // Stopped: outputs with 6206h set take 6207h (output 2 of group 1 kept).
        write(&mut dev, 0x6206, 1, &[0xFD], &mut out);
        write(&mut dev, 0x6207, 1, &[0x10], &mut out);
        write(&mut dev, 0x6411, 1, &1234i16.to_le_bytes(), &mut out);
        write(&mut dev, 0x6444, 1, &(-5i32).to_le_bytes(), &mut out);
        assert_eq!(dev.app.analog_outputs(), [1234, 0]);
        dev.handle_frame(&Frame::new(0, &[2, 1]), Instant::ZERO, &mut out);
        assert!(dev.app.in_error_state());
        assert_eq!(dev.app.output_lines(), [0x10, 0x00]);
        assert_eq!(dev.app.analog_outputs(), [-5, 0]);
        dev.handle_frame(&Frame::new(0, &[1, 1]), Instant::ZERO, &mut out);
        assert!(!dev.app.in_error_state());
        // Back to 6200h, but output 8, frozen by 6208h, stays as the error
        // state left it.
        assert_eq!(dev.app.output_lines(), [0x01, 0x02]);
        assert_eq!(dev.app.analog_outputs(), [1234, 0]);
    }

    /// A communication error (here a heartbeat consumer timeout, as the
    /// node reports it) puts the outputs in their error state; the
    /// heartbeat coming back while operational takes them out.
    #[test]
    fn a_communication_error_sets_the_error_values() {
        let (mut dev, mut out) = module();
        write(&mut dev, 0x6200, 1, &[0x0F], &mut out);
        write(&mut dev, 0x6207, 1, &[0xF0], &mut out);
        let mut requests = Vec::new();
        let now = Instant::from_nanos(1);
        let mut cx = AppContext::new(dev.node.od_mut(), now, 1, &mut requests);
        dev.app.on_event(&mut cx, NodeEvent::HeartbeatTimeout { node: 9 });
        assert_eq!(dev.app.output_lines(), [0xF0, 0x00]);
        dev.app.on_event(&mut cx, NodeEvent::HeartbeatRecovered { node: 9 });
        assert_eq!(dev.app.output_lines(), [0x0F, 0x00]);
        // Bus-off likewise; and pre-operational alone changes nothing.
        dev.app.on_event(&mut cx, NodeEvent::Link(LinkState::BusOff { recover_at: None }));
        assert!(dev.app.in_error_state());
        let pre = NodeEvent::NmtState { from: NmtState::Operational, to: NmtState::PreOperational };
        dev.app.on_event(&mut cx, pre);
        assert!(dev.app.in_error_state());
    }

    #[test]
    fn a_wired_output_reads_back_at_its_input() {
        let (mut dev, mut out) = module();
        dev.app.set_wiring(&[5]);
        settle(&mut dev, &mut out);
        out.clear();
        write(&mut dev, 0x6200, 1, &[0x01], &mut out);
        assert_eq!(dev.node.od().get_u32(0x6000, 1), Some(0x10));
        assert_eq!(out, [Frame::new(0x181, &[0x10, 0x00])]);
    }

    #[test]
    fn analog_inputs_send_on_their_triggers_once_enabled() {
        let (mut dev, mut out) = module();
        dev.app.set_analog_input(1, 500);
        settle(&mut dev, &mut out);
        assert_eq!(dev.node.od().get_i64(0x6401, 1), Some(500));
        assert!(out.is_empty(), "6423h FALSE: no TPDO: {out:?}");
        write(&mut dev, 0x6423, 0, &[1], &mut out);
        write(&mut dev, 0x6421, 1, &[0x01], &mut out);
        write(&mut dev, 0x6424, 1, &1000i32.to_le_bytes(), &mut out);
        dev.app.set_analog_input(1, 900);
        settle(&mut dev, &mut out);
        assert!(out.is_empty(), "below the upper limit: {out:?}");
        dev.app.set_analog_input(1, 2000);
        settle(&mut dev, &mut out);
        assert_eq!(out, [Frame::new(0x281, &[0xD0, 0x07, 0, 0, 0, 0, 0, 0])]);
        let now = Instant::ZERO;
        assert_eq!(dev.read_object(0x6422, 1, now).unwrap(), 1u32.to_le_bytes());
        assert_eq!(dev.read_object(0x6422, 1, now).unwrap(), 0u32.to_le_bytes(), "reset when read");
    }

    /// The module's file broken in many ways (a window of lines left out,
    /// types and counts changed) gives a module or an error, never a
    /// panic: installed, booted, started, inputs set, outputs written.
    #[test]
    fn broken_files_never_panic() {
        let lines: Vec<&str> = EDS.lines().collect();
        let mut variants: Vec<String> = (0..lines.len())
            .step_by(7)
            .map(|at| {
                let mut l = lines.clone();
                l.drain(at..(at + 5).min(lines.len()));
                l.join("\n")
            })
            .collect();
        variants.push(EDS.replace("DataType=0x0005", "DataType=0x0007"));
        variants.push(
            EDS.replace("DataType=0x0003", "DataType=0x0005").replace("DefaultValue=0\n", "DefaultValue=1\n"),
        );
        variants.push(EDS.replace("DefaultValue=0x00000000", "DefaultValue=0x60000140"));
        let mut built = 0;
        for v in variants {
            let Ok(p) = drivebus_eds::parse(&v) else { continue };
            let Ok((mut node, _)) =
                Node::from_eds(&p.eds, &v, 1, Box::new(MemoryStorage::new()), EdsOptions::default())
            else {
                continue;
            };
            let io = IoModule::install(&mut node);
            let mut dev = NodeDevice::new(node, io);
            let mut out = Vec::new();
            let now = Instant::from_nanos(1);
            dev.start(Instant::ZERO, &mut out);
            dev.handle_frame(&Frame::new(0, &[1, 1]), now, &mut out);
            for line in [1, 8, 9, 16, 17, 200] {
                dev.app.set_input_line(line, true);
            }
            dev.app.set_analog_input(1, -3);
            dev.app.set_wiring(&[16, 1, 40]);
            dev.node.od_mut();
            dev.poll(now, &mut out);
            for (i, s) in [(0x6200, 1), (0x6411, 1), (0x6002, 2), (0x6423, 0), (0x1A00, 0), (0x6422, 1)] {
                let _ = dev.write_object(i, s, &[1], now, &mut out);
                let _ = dev.read_object(i, s, now);
            }
            dev.handle_frame(&Frame::new(0x201, &[0xFF, 0xFF]), now, &mut out);
            dev.handle_frame(&Frame::new(0, &[2, 1]), now, &mut out);
            dev.poll(now, &mut out);
            built += 1;
        }
        assert!(built > 50, "{built} variants built");
    }

    #[test]
    fn volts_scale_to_full_range_at_ten_volts() {
        assert_eq!(volts_to_raw(10.0), 32767);
        assert_eq!(volts_to_raw(-10.0), -32767);
        assert_eq!(volts_to_raw(2.5), 8192);
        assert_eq!(volts_to_raw(99.0), 32767);
        assert_eq!(volts_to_raw(f64::NAN), 0);
    }

    #[test]
    fn device_type_401_is_an_io_module() {
        assert!(crate::is_io_module(0x000F_0191));
        assert!(!crate::is_io_module(0x0002_0192));
    }
}
