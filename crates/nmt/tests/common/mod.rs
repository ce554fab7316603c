//! A device under test: one `Nmt` over its dictionary, frames collected.
#![allow(dead_code)]

use drivebus_can::{Frame, Instant};
use drivebus_nmt::{Nmt, NmtConfig, NmtEvent, install, install_error_behaviour};
use drivebus_od::{NoHooks, ObjectDictionary, SdoAbort};

pub const NODE: u8 = 5;

pub fn ms(n: u64) -> Instant {
    Instant::from_millis(n)
}

pub struct Dev {
    pub nmt: Nmt,
    pub od: ObjectDictionary,
    pub out: Vec<Frame>,
    /// Events returned by `reconfigure` (the node would act on them).
    pub reconfigure_events: Vec<NmtEvent>,
}

impl Dev {
    /// Installed, not booted (Initialisation / reset application).
    pub fn new(config: NmtConfig, n_consumer: u8, n_classes: u8) -> Dev {
        let mut od = ObjectDictionary::new();
        install(&mut od, &config, n_consumer);
        if n_classes > 0 {
            install_error_behaviour(&mut od, n_classes);
        }
        Dev { nmt: Nmt::new(config), od, out: Vec::new(), reconfigure_events: Vec::new() }
    }

    /// Every feature on, node 5, booted at 0 ms, boot-up frame consumed.
    pub fn booted() -> Dev {
        let mut d = Dev::new(NmtConfig::new(NODE), 4, 2);
        d.boot(ms(0));
        assert_eq!(d.take(), [Frame::new(0x705, &[0])]);
        d
    }

    pub fn boot(&mut self, t: Instant) -> Option<NmtEvent> {
        self.nmt.boot(&self.od, t, &mut self.out)
    }

    pub fn rx(&mut self, f: Frame, t: Instant) -> Option<NmtEvent> {
        self.nmt.handle_frame(&f, t, &mut self.out)
    }

    pub fn cmd(&mut self, cs: u8, node: u8, t: Instant) -> Option<NmtEvent> {
        self.rx(Frame::new(0x000, &[cs, node]), t)
    }

    pub fn poll(&mut self, t: Instant) -> Option<Instant> {
        self.nmt.poll(t, &mut self.out)
    }

    /// An SDO-style write as the node wires it: check, store, reconfigure.
    pub fn write(&mut self, index: u16, sub: u8, data: &[u8], t: Instant) -> Result<(), SdoAbort> {
        self.nmt.check_write(&self.od, index, sub, data)?;
        self.od.write(&mut NoHooks, index, sub, data)?;
        if let Some(ev) = self.nmt.reconfigure(&self.od, index, sub, t) {
            self.reconfigure_events.push(ev);
        }
        Ok(())
    }

    pub fn take(&mut self) -> Vec<Frame> {
        core::mem::take(&mut self.out)
    }

    pub fn events(&mut self) -> Vec<NmtEvent> {
        core::iter::from_fn(|| self.nmt.pop_event()).collect()
    }

    /// Poll at every millisecond in `from..=to`, collecting frames with the
    /// time they were sent.
    pub fn run(&mut self, from: u64, to: u64) -> Vec<(u64, Frame)> {
        let mut got = Vec::new();
        for t in from..=to {
            self.poll(ms(t));
            for f in self.take() {
                got.push((t, f));
            }
        }
        got
    }
}
