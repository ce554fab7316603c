//! The node's write path and SYNC for another protocol's process data
//! (EtherCAT SM2/SM3): what the PDO service does with a CAN frame, without
//! the frame.
//!
//! A CoE device keeps its dictionary, its application and every rule on
//! the node; only the transport differs. Its RxPDO data goes through
//! [`Node::process_data`] exactly as a received RPDO does (write path
//! without the access check, `ObjectDictionary::write_local`), its TxPDO
//! data is sampled the same way (live entries refreshed through
//! `read_ref`), and its SYNC0 pulse reaches the application as a SYNC
//! would ([`Node::foreign_sync`]).

use crate::owners::Dispatch;
use crate::{AppContext, Application, Node};
use drivebus_can::{Instant, TxSink};
use drivebus_od::{ObjectDictionary, ObjectHooks};

impl Node {
    /// Runs `f` with the dictionary and the node's write-path hooks (the
    /// owner dispatch the SDO and PDO services use), then the node's
    /// follow-ups: reconfigured services, NMT events, the application's
    /// requests (an EMCY it raised goes to `out`). For process data of
    /// another protocol: `f` writes mapped values with
    /// `ObjectDictionary::write_local` and samples them with `read_ref`.
    pub fn process_data<A: Application + ?Sized, R>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
        f: impl FnOnce(&mut ObjectDictionary, &mut dyn ObjectHooks) -> R,
    ) -> R {
        self.s.link.now = now;
        let r = {
            let mut d = Dispatch { s: &mut self.s, app: &mut *app };
            f(&mut self.od, &mut d)
        };
        self.after_write(now, app, out);
        if self.run_requests(now, app, out) {
            self.poll_services(now, app, out);
        }
        r
    }

    /// A SYNC that did not come as a CAN frame (an EtherCAT SYNC0 pulse or
    /// SM event): the application's `on_sync` (cyclic set-points latch)
    /// and its requests. The CAN PDO service is not involved: its PDOs run
    /// on CAN SYNC frames only.
    pub fn foreign_sync<A: Application + ?Sized>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        self.s.link.now = now;
        app.on_sync(&mut self.s.cx(&mut self.od), None);
        if self.run_requests(now, app, out) {
            self.poll_services(now, app, out);
        }
    }

    /// An event of another protocol for the application (an EtherCAT state
    /// change or AL error): `f` gets the application and its context, and
    /// the requests it queues (an EMCY) are carried out as after any
    /// callback.
    pub fn with_app<A: Application + ?Sized, R>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
        f: impl FnOnce(&mut A, &mut AppContext<'_>) -> R,
    ) -> R {
        self.s.link.now = now;
        let r = f(&mut *app, &mut self.s.cx(&mut self.od));
        if self.run_requests(now, app, out) {
            self.poll_services(now, app, out);
        }
        r
    }
}
