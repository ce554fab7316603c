//! Serving a [`Host`] on a real network interface through an AF_PACKET raw
//! socket (Linux, needs root or CAP_NET_RAW), so any master on the wire —
//! ethercrab, SOEM/pysoem, TwinCAT — sees the segment.
//!
//! The socket is bound to EtherType 0x88A4 on one interface and put in
//! promiscuous mode (masters send to the broadcast address from arbitrary
//! source MACs, which we never filter). The loop blocks in `ppoll` until a
//! frame arrives or the segment's next deadline (SYNC0, watchdog) is due —
//! it never busy-polls — processes each frame and sends the reply out of
//! the same interface. It returns when the stop flag is set (checked at
//! least every 50 ms).

#![allow(unsafe_code)] // AF_PACKET sockets need libc calls; each is wrapped below.

use crate::host::Host;
use drivebus_can::Duration;
use drivebus_esc::frame;
use std::ffi::CString;
use std::io;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::sync::atomic::{AtomicBool, Ordering};

const ETH_P_ECAT: u16 = 0x88A4;
/// Longest wait between stop-flag checks.
const MAX_WAIT: Duration = Duration::from_millis(50);

/// An AF_PACKET socket bound to EtherType 0x88A4 on one interface.
#[derive(Debug)]
pub struct RawSocket {
    fd: OwnedFd,
    ifindex: i32,
}

fn check(r: libc::c_int) -> io::Result<libc::c_int> {
    if r < 0 { Err(io::Error::last_os_error()) } else { Ok(r) }
}

impl RawSocket {
    /// Opens and binds the socket, and enables promiscuous mode.
    pub fn open(interface: &str) -> io::Result<RawSocket> {
        let name = CString::new(interface).map_err(|_| io::Error::from(io::ErrorKind::InvalidInput))?;
        // SAFETY: `name` is a valid NUL-terminated string.
        let ifindex = unsafe { libc::if_nametoindex(name.as_ptr()) } as i32;
        if ifindex == 0 {
            return Err(io::Error::last_os_error());
        }
        let proto = ETH_P_ECAT.to_be();
        // SAFETY: plain syscall; the result is checked before use.
        let raw = check(unsafe {
            libc::socket(libc::AF_PACKET, libc::SOCK_RAW | libc::SOCK_CLOEXEC, i32::from(proto))
        })?;
        // SAFETY: `raw` is a fresh descriptor we own from here on.
        let fd = unsafe { OwnedFd::from_raw_fd(raw) };
        // SAFETY: sockaddr_ll is plain data; zeroed is a valid value.
        let mut sll: libc::sockaddr_ll = unsafe { std::mem::zeroed() };
        sll.sll_family = libc::AF_PACKET as u16;
        sll.sll_protocol = proto;
        sll.sll_ifindex = ifindex;
        // SAFETY: we pass a pointer to a live sockaddr_ll and its size.
        check(unsafe {
            libc::bind(
                fd.as_raw_fd(),
                (&sll as *const libc::sockaddr_ll).cast(),
                std::mem::size_of::<libc::sockaddr_ll>() as libc::socklen_t,
            )
        })?;
        // SAFETY: packet_mreq is plain data; zeroed is a valid value.
        let mut mreq: libc::packet_mreq = unsafe { std::mem::zeroed() };
        mreq.mr_ifindex = ifindex;
        mreq.mr_type = libc::PACKET_MR_PROMISC as u16;
        // SAFETY: pointer to a live packet_mreq and its size.
        check(unsafe {
            libc::setsockopt(
                fd.as_raw_fd(),
                libc::SOL_PACKET,
                libc::PACKET_ADD_MEMBERSHIP,
                (&mreq as *const libc::packet_mreq).cast(),
                std::mem::size_of::<libc::packet_mreq>() as libc::socklen_t,
            )
        })?;
        Ok(RawSocket { fd, ifindex })
    }

    /// Waits up to `timeout` for a frame sent *to* this host (frames this
    /// socket itself sent are skipped). `Ok(None)` on timeout.
    pub fn recv(&self, buf: &mut [u8], timeout: Duration) -> io::Result<Option<usize>> {
        let mut pfd = libc::pollfd { fd: self.fd.as_raw_fd(), events: libc::POLLIN, revents: 0 };
        let ts = libc::timespec {
            tv_sec: timeout.as_secs() as libc::time_t,
            tv_nsec: libc::c_long::from(timeout.subsec_nanos() as i32),
        };
        // SAFETY: one live pollfd, a live timespec, no signal mask.
        let n = unsafe { libc::ppoll(&mut pfd, 1, &ts, std::ptr::null()) };
        if n < 0 {
            let e = io::Error::last_os_error();
            return if e.kind() == io::ErrorKind::Interrupted { Ok(None) } else { Err(e) };
        }
        if n == 0 || pfd.revents & libc::POLLIN == 0 {
            return Ok(None);
        }
        // SAFETY: sockaddr_ll is plain data; zeroed is a valid value.
        let mut from: libc::sockaddr_ll = unsafe { std::mem::zeroed() };
        let mut fromlen = std::mem::size_of::<libc::sockaddr_ll>() as libc::socklen_t;
        // SAFETY: `buf` and `from` are live and their lengths are passed.
        let r = unsafe {
            libc::recvfrom(
                self.fd.as_raw_fd(),
                buf.as_mut_ptr().cast(),
                buf.len(),
                libc::MSG_DONTWAIT,
                (&mut from as *mut libc::sockaddr_ll).cast(),
                &mut fromlen,
            )
        };
        if r < 0 {
            let e = io::Error::last_os_error();
            return if e.kind() == io::ErrorKind::WouldBlock { Ok(None) } else { Err(e) };
        }
        if from.sll_pkttype == libc::PACKET_OUTGOING {
            return Ok(None);
        }
        Ok(Some(r as usize))
    }

    /// Sends one frame out of the interface.
    pub fn send(&self, frame: &[u8]) -> io::Result<()> {
        // SAFETY: `frame` is live and its length is passed.
        let r = unsafe { libc::send(self.fd.as_raw_fd(), frame.as_ptr().cast(), frame.len(), 0) };
        if r < 0 {
            return Err(io::Error::last_os_error());
        }
        Ok(())
    }

    /// Interface index.
    pub fn ifindex(&self) -> i32 {
        self.ifindex
    }
}

/// What a server run did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ServerStats {
    /// EtherCAT frames answered.
    pub frames: u64,
    /// Non-EtherCAT frames seen and dropped.
    pub ignored: u64,
    /// EtherCAT frames a fault of the line lost (no reply sent).
    pub lost: u64,
}

/// Serves `host` on `interface` until `stop` is set.
pub fn serve(interface: &str, host: &Host, stop: &AtomicBool) -> io::Result<ServerStats> {
    let sock = RawSocket::open(interface)?;
    serve_socket(&sock, host, stop)
}

/// Serves `host` on an opened socket until `stop` is set.
pub fn serve_socket(sock: &RawSocket, host: &Host, stop: &AtomicBool) -> io::Result<ServerStats> {
    let mut stats = ServerStats::default();
    let mut buf = vec![0u8; 9216];
    while !stop.load(Ordering::Acquire) {
        let now = host.clock().now();
        let wait = host.poll().map_or(MAX_WAIT, |d| d.saturating_duration_since(now)).min(MAX_WAIT);
        let Some(n) = sock.recv(&mut buf, wait)? else { continue };
        if frame::ethercat_offset(&buf[..n]).is_none() {
            stats.ignored += 1;
            continue;
        }
        stats.frames += 1;
        // The reply leaves before the slaves' firmware reacts to the frame.
        let mut sent = Ok(());
        let r = host.process_frame_then(&mut buf[..n], |reply, lost| {
            if !lost {
                sent = sock.send(reply);
            }
        });
        stats.lost += u64::from(r.lost);
        sent?;
    }
    Ok(stats)
}
