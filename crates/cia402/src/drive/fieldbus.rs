//! What a fieldbus with its own cycle asks of the drive (EtherCAT DC,
//! ETG.6010): the control step phase-locked to the bus's SYNC0, and the
//! abort-connection reaction with the bus's own error code.

use super::Drive;
use drivebus_can::Instant;

impl Drive {
    /// Puts the next control step at `at` (a SYNC0 pulse), so the control
    /// periods from then on start on the bus's cycle, as a drive that
    /// synchronises its loop to SYNC0 does (Technosoft iPOS §3.2: SYNC0's
    /// edge starts the control loop). Nothing changes when the next step
    /// is already at `at`, when the drive has not started its clock, or
    /// when the next step is a whole period or more away from `at` (then
    /// the caller has not stepped the drive up to the pulse). The one
    /// period that moves is a one-time shift of less than a control period,
    /// like a PLL locking. Call before stepping the drive to `at`. Returns
    /// whether it moved.
    pub fn align_steps(&mut self, at: Instant) -> bool {
        match self.next {
            Some(next) if next != at && next + self.period > at && next < at + self.period => {
                self.next = Some(at);
                true
            }
            _ => false,
        }
    }

    /// The connection to the master is lost (CiA 402-2 6007h): in
    /// Operation enabled the drive executes its abort connection option;
    /// a fault takes `code` (e.g. 8100h on EtherCAT, where CAN uses 8130h).
    pub fn abort_connection(&mut self, code: u16) {
        self.connection_lost(code);
    }
}
