//! Motion on a [`RemoteDrive`]: profile position moves, homing that waits for a
//! fresh "homing attained", velocity and torque targets, SYNC-aligned
//! streaming, stopping what was started (halt, else quick stop), and the
//! objects that limit a motion (read from the drive, to explain a wait).

use std::time::Duration;

use tokio::sync::broadcast;

use super::outcome::pp_at_rest;
use super::{DriveError, DriveState, MotionProgress, MotionReport, MoveProfile, RemoteDrive, cw, mode, sw};

/// How a motion was stopped by [`RemoteDrive::stop_motion`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopAction {
    /// The drive was not in operation enabled: nothing to stop.
    NotMoving,
    /// Halt (controlword bit 8): the axis decelerated to standstill.
    Halted,
    /// Halt did not bring the axis to rest in time: quick stop
    /// (controlword 02h), then the drive left operation enabled.
    QuickStopped,
}

/// What [`RemoteDrive::stop_motion`] did and where the axis is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StopReport {
    /// The action that took effect.
    pub action: StopAction,
    /// Position actual value 6064h afterwards, when readable.
    pub position: Option<i32>,
    /// Statusword afterwards.
    pub statusword: u16,
}

/// The objects that bound a motion, as the drive has them (`None`: the
/// drive does not have the object or refused the read).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MotionLimits {
    /// 6081h profile velocity.
    pub profile_velocity: Option<u32>,
    /// 6083h profile acceleration.
    pub profile_acceleration: Option<u32>,
    /// 6084h profile deceleration.
    pub profile_deceleration: Option<u32>,
    /// 607Fh max profile velocity (caps 6081h).
    pub max_profile_velocity: Option<u32>,
    /// 6080h max motor speed.
    pub max_motor_speed: Option<u32>,
    /// 607Dh software position limits (min, max).
    pub software_limits: Option<(i32, i32)>,
    /// 6099h homing speeds (search for switch, search for zero).
    pub homing_speeds: Option<(u32, u32)>,
    /// 609Ah homing acceleration.
    pub homing_acceleration: Option<u32>,
}

impl MotionLimits {
    /// The velocity a profile move runs at: 6081h capped by 607Fh.
    pub fn effective_velocity(&self) -> Option<u32> {
        let v = self.profile_velocity?;
        Some(match self.max_profile_velocity {
            Some(m) if m > 0 => v.min(m),
            _ => v,
        })
    }

    /// Seconds a profile move over `distance` units takes at least, on a
    /// trapezoid with the drive's velocity, acceleration and deceleration.
    /// `None` when the velocity is missing or 0 (drives differ on what 0
    /// means, some "no limit"); an acceleration of 0 or missing leaves the
    /// ramps out (the time at the velocity alone, a lower bound).
    pub fn move_seconds(&self, distance: f64) -> Option<f64> {
        let v = f64::from(self.effective_velocity().filter(|&v| v > 0)?);
        let s = distance.abs();
        let (a, d) = match (self.profile_acceleration, self.profile_deceleration) {
            (Some(a), d) if a > 0 => (f64::from(a), f64::from(d.filter(|&d| d > 0).unwrap_or(a))),
            _ => return Some(s / v),
        };
        if s == 0.0 {
            return Some(0.0);
        }
        // Reaching v takes v/a; if the distance is too short, a triangle.
        let ramps = v * v / (2.0 * a) + v * v / (2.0 * d);
        Some(if ramps >= s {
            let peak = (2.0 * s * a * d / (a + d)).sqrt();
            peak / a + peak / d
        } else {
            v / a + v / d + (s - ramps) / v
        })
    }

    /// One line per object that shapes a move from `position` to
    /// `target` (or a homing), for messages.
    pub fn describe(&self, position: Option<i32>, target: Option<i32>, homing: bool) -> Vec<String> {
        let mut v = Vec::new();
        if homing {
            if let Some((s, z)) = self.homing_speeds {
                v.push(format!(
                    "6099h homing speeds: {s} (search for switch), {z} (search for zero) units/s"
                ));
            }
            if let Some(a) = self.homing_acceleration {
                v.push(format!("609Ah homing acceleration: {a} units/s²"));
            }
        } else {
            if let Some(p) = self.profile_velocity {
                v.push(format!("6081h profile velocity: {p} units/s"));
            }
            if let Some(m) = self.max_profile_velocity {
                v.push(format!("607Fh max profile velocity: {m} units/s (caps 6081h)"));
            }
            if let Some(a) = self.profile_acceleration {
                v.push(format!("6083h profile acceleration: {a} units/s²"));
            }
            if let Some(d) = self.profile_deceleration {
                v.push(format!("6084h profile deceleration: {d} units/s²"));
            }
        }
        if let Some(m) = self.max_motor_speed {
            v.push(format!("6080h max motor speed: {m}"));
        }
        if let Some((lo, hi)) = self.software_limits {
            let outside = target.is_some_and(|t| lo < hi && (t < lo || t > hi));
            v.push(format!(
                "607Dh software position limits: {lo} .. {hi}{}",
                if outside { " (the target is outside them)" } else { "" }
            ));
        }
        if let (Some(p), Some(t)) = (position, target)
            && let Some(secs) = self.move_seconds(f64::from(t) - f64::from(p))
        {
            v.push(format!(
                "at these values the remaining {} units take at least {}",
                (i64::from(t) - i64::from(p)).abs(),
                human_secs(secs)
            ));
        }
        v
    }
}

/// `2.5 h`, `12 min`, `3.2 s`.
pub fn human_secs(s: f64) -> String {
    if s >= 7200.0 {
        format!("{:.1} h", s / 3600.0)
    } else if s >= 120.0 {
        format!("{:.0} min", s / 60.0)
    } else {
        format!("{s:.1} s")
    }
}

impl RemoteDrive {
    pub(super) async fn read_i32(&self, index: u16, sub: u8) -> Option<i32> {
        let v = self.read_raw(index, sub).await.ok()?;
        (v.len() >= 4).then(|| i32::from_le_bytes([v[0], v[1], v[2], v[3]]))
    }

    async fn read_u32(&self, index: u16, sub: u8) -> Option<u32> {
        self.read_i32(index, sub).await.map(|v| v as u32)
    }

    /// Position actual value 6064h.
    pub async fn position(&self) -> Option<i32> {
        self.read_i32(0x6064, 0).await
    }

    /// Velocity actual value 606Ch.
    pub async fn actual_velocity(&self) -> Option<i32> {
        self.read_i32(0x606C, 0).await
    }

    /// Reads the objects that bound a motion.
    pub async fn motion_limits(&self) -> MotionLimits {
        let pair = |a: Option<u32>, b: Option<u32>| a.zip(b);
        MotionLimits {
            profile_velocity: self.read_u32(0x6081, 0).await,
            profile_acceleration: self.read_u32(0x6083, 0).await,
            profile_deceleration: self.read_u32(0x6084, 0).await,
            max_profile_velocity: self.read_u32(0x607F, 0).await,
            max_motor_speed: self.read_u32(0x6080, 0).await,
            software_limits: self.read_i32(0x607D, 1).await.zip(self.read_i32(0x607D, 2).await),
            homing_speeds: pair(self.read_u32(0x6099, 1).await, self.read_u32(0x6099, 2).await),
            homing_acceleration: self.read_u32(0x609A, 0).await,
        }
    }

    /// A target starts a motion only in Operation enabled: then 6061h
    /// must show the mode first; before it [`RemoteDrive::enable`] waits for it.
    async fn confirm_mode_if_enabled(&self) -> Result<(), DriveError> {
        let pending = self.mode_pending.lock().unwrap_or_else(|e| e.into_inner()).is_some();
        if pending && self.state().await? == DriveState::OperationEnabled {
            self.confirm_mode().await?;
        }
        Ok(())
    }

    /// Reports progress now (see [`RemoteDrive::on_progress`]), whatever the
    /// interval.
    pub(super) async fn report(&self, waiting_for: &'static str, statusword: u16) {
        let Some(cb) = &self.progress else { return };
        let p = MotionProgress {
            waiting_for,
            statusword,
            state: DriveState::from_statusword(statusword),
            position: self.position().await,
            velocity: self.actual_velocity().await,
        };
        cb(&p);
    }

    /// Profile position move (mode must be PP): optional profile
    /// (6081h/6083h/6084h), target 607Ah, new set-point (bit 4, change
    /// immediately bit 5, relative bit 6), waits for the acknowledge (bit
    /// 12), clears bit 4, then waits within `timeout` for the end of the
    /// motion: bit 10 (target reached, or standing at a limit), bit 13
    /// (following error) or the drive leaving operation enabled.
    ///
    /// `Ok` with the report when the target was reached;
    /// [`DriveError::Stopped`] with where and why when a limit switch, a
    /// software limit, a following error, a fault, a quick stop or a halt
    /// ended it. The motion is not stopped on a timeout: see
    /// [`stop_motion`](Self::stop_motion).
    pub async fn move_to(
        &self,
        target: i32,
        relative: bool,
        profile: Option<MoveProfile>,
        timeout: Duration,
    ) -> Result<MotionReport, DriveError> {
        let started = self.master.now();
        // No set-point before 6061h shows the mode (set_mode outside
        // Operation enabled left it to be seen).
        self.confirm_mode().await?;
        if let Some(p) = profile {
            self.sdo.write(0x6081, 0, p.velocity).await?;
            self.sdo.write(0x6083, 0, p.acceleration).await?;
            self.sdo.write(0x6084, 0, p.deceleration).await?;
        }
        let absolute =
            if relative { self.position().await.map(|p| p.saturating_add(target)) } else { Some(target) };
        self.write_raw(0x607A, 0, &target.to_le_bytes()).await?;
        let base = cw::ENABLE_OPERATION | cw::CHANGE_IMMEDIATELY | if relative { cw::RELATIVE } else { 0 };
        self.controlword(base).await?;
        self.controlword(base | cw::NEW_SET_POINT).await?;
        let sw = self
            .wait_sw("set-point acknowledge", true, |sw| {
                sw & sw::MODE_12 != 0 || RemoteDrive::ended_abnormally(sw, false)
            })
            .await?;
        if RemoteDrive::ended_abnormally(sw, false) {
            return RemoteDrive::settle(self.classify(sw, absolute, None, started).await);
        }
        self.controlword(base).await?;
        let sw = self
            .wait_sw_for("target reached", true, timeout, |sw| {
                pp_at_rest(sw) || RemoteDrive::ended_abnormally(sw, false)
            })
            .await?;
        RemoteDrive::settle(self.classify(sw, absolute, None, started).await)
    }

    /// Target velocity 60FFh (profile velocity / CSV).
    pub async fn velocity(&self, v: i32) -> Result<(), DriveError> {
        self.confirm_mode_if_enabled().await?;
        self.write_raw(0x60FF, 0, &v.to_le_bytes()).await
    }

    /// Target torque 6071h (profile torque / CST).
    pub async fn torque(&self, t: i16) -> Result<(), DriveError> {
        self.confirm_mode_if_enabled().await?;
        self.write_raw(0x6071, 0, &t.to_le_bytes()).await
    }

    /// Homing: writes 6098h, switches to homing mode, starts (bit 4 rising
    /// edge) and waits for a *fresh* homing completed (bit 12 with bit 10:
    /// attained and at rest), a homing error (bit 13) or the drive leaving
    /// operation enabled. Bit 12 left set by an earlier homing does not count:
    /// this run is only done once bit 12 was seen low after the start
    /// (homing in progress), or it was low before the start; for the
    /// methods homing on the current position (35, 37), which may finish
    /// before a low is visible, once 6064h equals the home offset 607Ch.
    ///
    /// `Ok` with the report when homing attained; [`DriveError::Stopped`]
    /// with the reason otherwise (a homing error names the method, the
    /// methods 60E3h offers and the active switch inputs).
    pub async fn home(&self, method: i8, timeout: Duration) -> Result<MotionReport, DriveError> {
        use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
        let started = self.master.now();
        self.sdo.write(0x6098, 0, method).await?;
        self.set_mode(mode::HM).await?;
        self.controlword(cw::ENABLE_OPERATION).await?;
        // A drive enabled just now shows homing in 6061h only then.
        self.confirm_mode().await?;
        let stale = self.statusword().await? & sw::MODE_12 != 0;
        let instant = matches!(method, 35 | 37);
        let offset = if instant && stale { self.read_i32(0x607C, 0).await } else { None };
        self.controlword(cw::ENABLE_OPERATION | cw::NEW_SET_POINT).await?;
        let deadline = self.master.now() + timeout;
        let seen_low = AtomicBool::new(!stale);
        let sw = loop {
            let left = deadline.saturating_duration_since(self.master.now());
            let sw = self
                .wait_sw_for("homing attained", true, left, |sw| {
                    if sw & sw::MODE_12 == 0 {
                        seen_low.store(true, Relaxed);
                    }
                    // CiA 402-2 homing: bit 12 with bit 10 is "completed"; bit 12
                    // alone is "attained, target not reached" (still moving).
                    sw & sw::MODE_13 != 0
                        || RemoteDrive::ended_abnormally(sw, true)
                        || (sw & sw::MODE_12 != 0
                            && sw & sw::TARGET_REACHED != 0
                            && (seen_low.load(Relaxed) || offset.is_some()))
                })
                .await?;
            if sw & sw::MODE_13 != 0 || RemoteDrive::ended_abnormally(sw, true) || seen_low.load(Relaxed) {
                break sw;
            }
            // An instant method with bit 12 still set from before: done once
            // the position took the home offset.
            if offset.is_some() && self.position().await == offset {
                break sw;
            }
            if self.master.now() >= deadline {
                return Err(DriveError::Timeout { waiting_for: "a fresh homing attained", statusword: sw });
            }
            self.master.sleep(self.poll).await;
        };
        if !RemoteDrive::ended_abnormally(sw, true) {
            self.controlword(cw::ENABLE_OPERATION).await?;
        }
        RemoteDrive::settle(self.classify(sw, None, Some(method), started).await)
    }

    /// Stops what a command started: halt (controlword bit 8, the drive
    /// decelerates by its halt option 605Dh) and waits up to `timeout` for
    /// standstill (bit 10 target reached and the velocity actual value
    /// inside the velocity window 606Dh, at least 10); if the axis is still
    /// moving, quick stop (controlword 02h). The halt bit stays set
    /// so nothing resumes; the next command writes its own controlword.
    pub async fn stop_motion(&self, timeout: Duration) -> Result<StopReport, DriveError> {
        let sw = self.statusword().await?;
        if DriveState::from_statusword(sw) != DriveState::OperationEnabled {
            return Ok(StopReport {
                action: StopAction::NotMoving,
                position: self.position().await,
                statusword: sw,
            });
        }
        self.controlword(cw::ENABLE_OPERATION | cw::HALT).await?;
        let deadline = self.master.now() + timeout;
        let halted =
            self.wait_sw_for("standstill after halt", true, timeout, |sw| sw & sw::TARGET_REACHED != 0).await;
        if let Err(e) = &halted
            && !matches!(e, DriveError::Timeout { .. })
        {
            return Err(halted.unwrap_err());
        }
        // Bit 10 follows the demand; the axis itself settles a little later.
        let window = self.read_u32(0x606D, 0).await.map_or(10, |w| w.max(10)) as i64;
        // Three readings in a row inside the window: not a zero crossing
        // of an axis still swinging.
        let mut still = 0;
        loop {
            let v = self.actual_velocity().await;
            still = if v.is_some_and(|v| i64::from(v).abs() <= window) { still + 1 } else { 0 };
            if still >= 3 {
                let statusword = self.statusword().await?;
                return Ok(StopReport {
                    action: StopAction::Halted,
                    position: self.position().await,
                    statusword,
                });
            }
            if self.master.now() >= deadline {
                break;
            }
            self.master.sleep(self.poll).await;
        }
        self.controlword(cw::QUICK_STOP).await?;
        let statusword = self
            .wait_sw_for("quick stop", true, timeout, |sw| {
                matches!(
                    DriveState::from_statusword(sw),
                    DriveState::QuickStopActive | DriveState::SwitchOnDisabled | DriveState::Fault
                )
            })
            .await?;
        Ok(StopReport { action: StopAction::QuickStopped, position: self.position().await, statusword })
    }

    /// Streams values of `index`/`sub`, one right after each SYNC the
    /// master produces (by a synchronous RPDO when one maps it, else any
    /// RPDO, else SDO, which cannot keep up with short cycles). Returns how
    /// many were sent.
    pub async fn stream_raw(
        &self,
        index: u16,
        sub: u8,
        values: impl IntoIterator<Item = Vec<u8>>,
    ) -> Result<usize, DriveError> {
        if !self.master.sync_running() {
            return Err(DriveError::NoSync);
        }
        self.confirm_mode().await?;
        let mut ticks = self.master.subscribe_sync();
        let mut n = 0;
        for v in values {
            loop {
                match self.master.timeout(Duration::from_secs(1), ticks.recv()).await {
                    Ok(Ok(_)) => {
                        // Behind by whole cycles: align to the latest SYNC
                        // rather than sending a burst for the old ones.
                        while !matches!(
                            ticks.try_recv(),
                            Err(broadcast::error::TryRecvError::Empty
                                | broadcast::error::TryRecvError::Closed)
                        ) {}
                        break;
                    }
                    // Behind by several cycles: send now, aligned to the latest.
                    Ok(Err(broadcast::error::RecvError::Lagged(_))) => {}
                    Ok(Err(broadcast::error::RecvError::Closed)) | Err(_) => return Err(DriveError::NoSync),
                }
            }
            self.write_via(index, sub, &v, true).await?;
            n += 1;
        }
        Ok(n)
    }

    /// Cyclic synchronous position: target positions 607Ah, one per SYNC.
    pub async fn stream_csp(&self, positions: impl IntoIterator<Item = i32>) -> Result<usize, DriveError> {
        self.stream_raw(0x607A, 0, positions.into_iter().map(|p| p.to_le_bytes().to_vec())).await
    }

    /// Cyclic synchronous velocity: target velocities 60FFh, one per SYNC.
    pub async fn stream_csv(&self, velocities: impl IntoIterator<Item = i32>) -> Result<usize, DriveError> {
        self.stream_raw(0x60FF, 0, velocities.into_iter().map(|p| p.to_le_bytes().to_vec())).await
    }

    /// Cyclic synchronous torque: target torques 6071h, one per SYNC.
    pub async fn stream_cst(&self, torques: impl IntoIterator<Item = i16>) -> Result<usize, DriveError> {
        self.stream_raw(0x6071, 0, torques.into_iter().map(|p| p.to_le_bytes().to_vec())).await
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn move_time_estimates() {
        let l = MotionLimits {
            profile_velocity: Some(10),
            profile_acceleration: Some(1000),
            profile_deceleration: Some(1000),
            ..Default::default()
        };
        // 90000 units at 10 units/s: 9000 s (plus tiny ramps): the AKD's default.
        let s = l.move_seconds(90_000.0).unwrap();
        assert!((s - 9000.01).abs() < 0.1, "{s}");
        assert_eq!(human_secs(s), "2.5 h");
        // Triangle: too short to reach the velocity.
        let fast = MotionLimits { profile_velocity: Some(1_000_000), ..l.clone() };
        let t = fast.move_seconds(100.0).unwrap();
        assert!((t - 0.632).abs() < 0.01, "{t}");
        // 607Fh caps 6081h.
        let capped = MotionLimits { max_profile_velocity: Some(5), ..l.clone() };
        assert_eq!(capped.effective_velocity(), Some(5));
        // 0 velocity: unknown (some drives read it as no limit); 0 acceleration: no ramps.
        let none = MotionLimits { profile_velocity: Some(0), ..l.clone() };
        assert_eq!(none.move_seconds(10.0), None);
        let flat = MotionLimits { profile_acceleration: Some(0), ..l };
        assert_eq!(flat.move_seconds(100.0), Some(10.0));
        let lines = flat.describe(Some(0), Some(100), false);
        assert!(lines.iter().any(|l| l.contains("6081h profile velocity: 10")), "{lines:?}");
        assert!(lines.iter().any(|l| l.contains("take at least 10.0 s")), "{lines:?}");
    }
}
