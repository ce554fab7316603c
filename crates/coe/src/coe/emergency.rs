//! CoE emergency (ETG.1000.6 §5.6, emergency service): the CiA 301 EMCY message carried in
//! a mailbox of its own, and the bounded queue it waits in.

use alloc::vec::Vec;

/// One emergency: error code, error register (1001h) and five bytes of
/// manufacturer-specific data, as in a CAN EMCY frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Emergency {
    /// Error code (e.g. 0x8210 PDO length error, 0x0000 error reset).
    pub code: u16,
    /// Error register (object 1001h).
    pub register: u8,
    /// Manufacturer-specific data.
    pub data: [u8; 5],
}

impl Emergency {
    /// The CoE service data: CoE header (service 1, emergency), then the
    /// 8 bytes of the CANopen EMCY.
    pub fn body(&self) -> [u8; 10] {
        let c = self.code.to_le_bytes();
        let d = self.data;
        [0x00, 0x10, c[0], c[1], self.register, d[0], d[1], d[2], d[3], d[4]]
    }

    /// Decode the service data of a CoE emergency mailbox (`None` if it is
    /// not one).
    pub fn from_body(body: &[u8]) -> Option<Emergency> {
        let b: &[u8; 10] = body.first_chunk()?;
        (b[1] >> 4 == super::service::EMERGENCY).then(|| Emergency {
            code: u16::from_le_bytes([b[2], b[3]]),
            register: b[4],
            data: [b[5], b[6], b[7], b[8], b[9]],
        })
    }
}

/// The emergency queue is full (or emergencies are disabled): the
/// emergency was not queued.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmergencyQueueFull;

impl core::fmt::Display for EmergencyQueueFull {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("CoE emergency queue full")
    }
}

#[cfg(feature = "std")]
impl std::error::Error for EmergencyQueueFull {}

/// A fixed-capacity FIFO. When full, new emergencies are refused and the
/// queued ones kept: the first error of a burst is usually the cause.
#[derive(Clone, Debug)]
pub(crate) struct EmergencyQueue {
    ring: Vec<Emergency>,
    cap: usize,
    head: usize,
    len: usize,
}

impl EmergencyQueue {
    pub(crate) fn new(cap: usize) -> Self {
        EmergencyQueue { ring: Vec::with_capacity(cap), cap, head: 0, len: 0 }
    }

    pub(crate) fn len(&self) -> usize {
        self.len
    }

    pub(crate) fn push(&mut self, e: Emergency) -> Result<(), EmergencyQueueFull> {
        if self.len >= self.cap {
            return Err(EmergencyQueueFull);
        }
        let at = (self.head + self.len) % self.cap;
        if at < self.ring.len() {
            self.ring[at] = e;
        } else {
            // Fills the capacity reserved in `new`, never beyond it.
            self.ring.push(e);
        }
        self.len += 1;
        Ok(())
    }

    pub(crate) fn pop(&mut self) -> Option<Emergency> {
        if self.len == 0 {
            return None;
        }
        let e = self.ring[self.head];
        self.head = (self.head + 1) % self.cap;
        self.len -= 1;
        Some(e)
    }

    pub(crate) fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn body_is_coe_header_then_canopen_emcy() {
        let e = Emergency { code: 0x8210, register: 0x11, data: [1, 2, 3, 4, 5] };
        assert_eq!(e.body(), [0x00, 0x10, 0x10, 0x82, 0x11, 1, 2, 3, 4, 5]);
        assert_eq!(Emergency::from_body(&e.body()), Some(e));
        assert_eq!(Emergency::from_body(&[0x00, 0x30, 0, 0, 0, 0, 0, 0, 0, 0]), None);
    }

    #[test]
    fn queue_is_fifo_and_refuses_when_full() {
        let mut q = EmergencyQueue::new(2);
        let e = |c| Emergency { code: c, register: 0, data: [0; 5] };
        q.push(e(1)).unwrap();
        q.push(e(2)).unwrap();
        assert_eq!(q.push(e(3)), Err(EmergencyQueueFull));
        assert_eq!(q.pop().map(|x| x.code), Some(1));
        q.push(e(4)).unwrap();
        assert_eq!((q.pop().map(|x| x.code), q.pop().map(|x| x.code), q.pop()), (Some(2), Some(4), None));
        let mut off = EmergencyQueue::new(0);
        assert_eq!(off.push(e(1)), Err(EmergencyQueueFull));
        assert_eq!(off.pop(), None);
    }
}
