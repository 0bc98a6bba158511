//! Rigid tapping geared to the measured spindle angle ([`OpKind::RigidTap`], cycles 207 and
//! 209): the tool axis is a function of the spindle angle, not of time.
//!
//! With `ψ` the measured angle in the thread's direction of rotation (degrees, counted
//! from where the spindle stood still when the tap began) and `p` the pitch, the tool
//! stands at `s = p·ψ/360` mm along the hole's axis, every servo cycle, whatever the
//! spindle does: it starts from rest together with the spindle, slows down with it before
//! each stroke's end, and follows it through the reversal. The angle is predicted one cycle
//! ahead with the measured speed, as for thread passes (the setpoint acts a cycle later).
//!
//! The spindle is what the run steers. Each stroke has a target angle (its depth over the
//! pitch); the spindle is commanded towards it at the programmed speed (on retracting
//! strokes the speed times the retraction factor, within the machine's maximum), slowing
//! where the remaining angle needs it: the speed is the least of the stroke's speed, the
//! speed from which half the spindle's ramp rate stops it in the remaining angle
//! (`√(2·α·r)`), and the remaining angle over [`SETTLE_TIME`] (a proportional position loop
//! for the last degrees). A stroke has ended when the remaining angle is within
//! [`end_window`]; the next stroke then reverses the spindle, with the tool on it. After the
//! last stroke the spindle returns to the speed it had before the tap and the run waits for
//! it to reach that speed.
//!
//! Before anything moves, [`TapProfile::new`] refuses a tap the axes cannot follow: an axis
//! share of the tool's speed at the fastest stroke above its `max_velocity`, or of the
//! acceleration the spindle's ramp gives the tool above its `max_acceleration`. Feed
//! override and feed hold do not act inside a tap; a stop requested during it takes effect
//! when it has ended.

use super::sync::{GearedStart, path_length};
use super::{Run, RunError};
use crate::config::{MachineConfig, SpindleBackendConfig};
use klar_interp::op::SpindleDir;
use klar_interp::{Op, OpKind, Pose, SourceLoc};

/// Time constant of the spindle's approach to a stroke's end over its last degrees, s.
pub(crate) const SETTLE_TIME: f64 = 0.01;

/// The measured speed below which the spindle counts as at rest before a tap, rpm.
const STILL_RPM: f64 = 1.0;

/// Share of the spindle's ramp rate the approach to a stroke's end plans with.
const RAMP_SHARE: f64 = 0.5;

/// The angle window (degrees) within which a stroke of pitch `pitch` has ended: 1 µm of
/// tool travel, between 0.1° and 0.5°.
pub(crate) fn end_window(pitch: f64) -> f64 {
    (0.001 / pitch * 360.0).clamp(0.1, 0.5)
}

/// The ramp rate of the machine's spindle, rpm/s, as its machine file gives it (a
/// simulated or CiA 402 spindle's `acceleration`); `None` when the file does not say.
pub(crate) fn spindle_ramp(config: &MachineConfig) -> Option<f64> {
    match &config.spindle.as_ref()?.backend {
        SpindleBackendConfig::Sim(s) => Some(s.acceleration),
        SpindleBackendConfig::Modbus(m) => m.simulate.as_ref().map(|s| s.acceleration),
        SpindleBackendConfig::Canopen(c) => Some(c.drive.acceleration),
    }
}

/// The geometry and speeds of one rigid tap.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TapProfile {
    /// Start on the hole's axis.
    pub from: Pose,
    /// Unit direction into the hole, per pose component.
    pub dir: [f64; 9],
    /// Pitch, mm per revolution.
    pub pitch: f64,
    /// 1 when the thread is entered turning M3, -1 for M4.
    pub hand: f64,
    /// Spindle speed of the strokes into the hole and out of it, rpm (magnitudes).
    pub rpm_in: f64,
    /// Retracting speed, rpm.
    pub rpm_out: f64,
    /// Angular deceleration the approach to a stroke's end plans with, °/s².
    pub brake: f64,
}

impl TapProfile {
    /// The profile of an [`OpKind::RigidTap`] op at `rpm` (the programmed speed, its
    /// magnitude counts), or why the machine of `config` cannot tap it. `None` for any
    /// other op.
    pub(crate) fn new(
        kind: &OpKind,
        rpm: f64,
        config: &MachineConfig,
    ) -> Option<Result<TapProfile, String>> {
        let OpKind::RigidTap {
            from,
            to,
            pitch,
            hand,
            strokes,
            retract_factor,
        } = kind
        else {
            return None;
        };
        Some(Self::build(
            *from,
            *to,
            *pitch,
            *hand,
            strokes,
            *retract_factor,
            rpm,
            config,
        ))
    }

    #[allow(clippy::too_many_arguments)]
    fn build(
        from: Pose,
        to: Pose,
        pitch: f64,
        hand: SpindleDir,
        strokes: &[f64],
        retract_factor: f64,
        rpm: f64,
        config: &MachineConfig,
    ) -> Result<TapProfile, String> {
        let length = path_length(from, to);
        if !(length > 1e-9 && length.is_finite() && pitch > 0.0 && pitch.is_finite()) {
            return Err("the rigid tap does not move along its pitch".into());
        }
        if strokes.is_empty()
            || strokes
                .iter()
                .any(|d| !(d.is_finite() && *d >= -1e-9 && *d <= length + 1e-9))
        {
            return Err("the rigid tap's strokes leave the hole".into());
        }
        let hand = match hand {
            SpindleDir::Cw => 1.0,
            SpindleDir::Ccw => -1.0,
            SpindleDir::Off => return Err("the rigid tap has no hand of thread".into()),
        };
        let rpm_in = rpm.abs();
        if !(rpm_in > 0.0 && rpm_in.is_finite()) {
            return Err("rigid tapping needs the spindle turning (M3 or M4 with a speed)".into());
        }
        let Some(spindle) = config.spindle.as_ref() else {
            return Err("this machine has no spindle: it cannot tap".into());
        };
        let factor = if retract_factor.is_finite() && retract_factor > 0.0 {
            retract_factor
        } else {
            1.0
        };
        // The retraction is limited to the spindle's top speed.
        let rpm_out = (rpm_in * factor).min(spindle.max_rpm);
        let Some(ramp) = spindle_ramp(config).filter(|r| r.is_finite() && *r > 0.0) else {
            return Err(
                "the machine file gives no ramp rate for this spindle: rigid \
                        tapping needs it"
                    .into(),
            );
        };
        let fastest = rpm_in.max(rpm_out);
        let mut dir = [0.0; 9];
        for (i, d) in dir.iter_mut().enumerate() {
            *d = (to.0[i] - from.0[i]) / length;
        }
        for a in &config.axes {
            let share = dir[a.letter.index()].abs();
            if share <= 1e-12 {
                continue;
            }
            let v = share * pitch * fastest / 60.0;
            if v > a.max_velocity {
                return Err(format!(
                    "axis {} would need {:.0} mm/min for pitch {pitch} mm at {fastest:.0} \
                     rpm, above its {:.0} mm/min: lower the spindle speed below {:.0} rpm",
                    a.letter,
                    v * 60.0,
                    a.max_velocity * 60.0,
                    fastest * a.max_velocity / v
                ));
            }
            let acc = share * pitch * ramp / 60.0;
            if acc > a.max_acceleration {
                return Err(format!(
                    "axis {} would need {acc:.0} mm/s² to follow the spindle's ramp of \
                     {ramp:.0} rpm/s at pitch {pitch} mm, above its {:.0} mm/s²",
                    a.letter, a.max_acceleration
                ));
            }
        }
        Ok(TapProfile {
            from,
            dir,
            pitch,
            hand,
            rpm_in,
            rpm_out,
            brake: RAMP_SHARE * ramp * 6.0,
        })
    }

    /// The pose `s` mm into the hole.
    pub(crate) fn pose(&self, s: f64) -> Pose {
        let mut p = self.from;
        for i in 0..9 {
            p.0[i] += self.dir[i] * s;
        }
        p
    }

    /// The spindle speed (rpm, in the thread's direction: positive enters) for `remaining`
    /// degrees to a stroke's end (positive: the end lies deeper).
    pub(crate) fn speed_for(&self, remaining: f64) -> f64 {
        let top = if remaining > 0.0 {
            self.rpm_in
        } else {
            self.rpm_out
        };
        let r = remaining.abs();
        let braking = (2.0 * self.brake * r).sqrt() / 6.0;
        let settling = r / SETTLE_TIME / 6.0;
        top.min(braking).min(settling).copysign(remaining)
    }
}

/// Where a tap under way stands.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    /// The spindle is brought to rest before the tool is geared to it.
    Stopping,
    /// Geared: stroke `k` under way.
    Stroke(usize),
}

/// A rigid tap under way: one servo cycle of it per [`Run::step`].
pub(super) struct TapPass {
    profile: TapProfile,
    /// Stroke depths, mm (kept from tap to tap: reused without allocating once grown).
    strokes: Vec<f64>,
    phase: Phase,
    /// Measured angle (in the thread's direction) where the tool stood at `from`.
    zero: f64,
    /// The signed spindle speed before the tap, rpm.
    before: f64,
    /// Machine time the present phase began, and how long it may take.
    since: f64,
    timeout: f64,
    /// The spindle's at-speed timeout: the time a phase may take beyond its own.
    grace: f64,
    loc: SourceLoc,
    active: bool,
}

impl TapPass {
    /// An idle tap with room for `strokes` strokes.
    pub(super) fn idle(strokes: usize) -> Self {
        TapPass {
            profile: TapProfile {
                from: Pose::ZERO,
                dir: [0.0; 9],
                pitch: 1.0,
                hand: 1.0,
                rpm_in: 0.0,
                rpm_out: 0.0,
                brake: 0.0,
            },
            strokes: Vec::with_capacity(strokes),
            phase: Phase::Stopping,
            zero: 0.0,
            before: 0.0,
            since: 0.0,
            timeout: 0.0,
            grace: 0.0,
            loc: SourceLoc::default(),
            active: false,
        }
    }

    /// True while a tap is under way.
    pub(super) fn active(&self) -> bool {
        self.active
    }
}

impl Run<'_, '_> {
    /// Starts an [`OpKind::RigidTap`] op: checks the spindle and the axes; [`Run::tap_step`]
    /// then runs it cycle by cycle.
    pub(super) fn rigid_tap(&mut self, op: &Op) -> Result<(), RunError> {
        let loc = op.loc;
        let Some(GearedStart {
            profile,
            commanded: before,
            timeout,
            ..
        }) = self.geared_start(
            op,
            "rigid tapping needs a spindle",
            "tap rigidly",
            TapProfile::new,
        )?
        else {
            return Ok(());
        };
        let OpKind::RigidTap { strokes, .. } = &op.kind else {
            return Ok(());
        };
        self.tap.strokes.clear();
        self.tap.strokes.extend_from_slice(strokes);
        self.tap.profile = profile;
        self.tap.phase = Phase::Stopping;
        self.tap.before = before;
        self.tap.since = self.t;
        self.tap.timeout = timeout;
        self.tap.grace = timeout;
        self.tap.loc = loc;
        self.tap.active = true;
        if let Some(s) = self.io.spindle_mut() {
            s.command(0.0)?;
        }
        Ok(())
    }

    /// How long stroke `k` may take: twice its time at its speed, and the spindle's
    /// at-speed timeout on top.
    fn stroke_time(&self, k: usize) -> f64 {
        let tap = &self.tap;
        let from = if k == 0 { 0.0 } else { tap.strokes[k - 1] };
        let depth = (tap.strokes[k] - from).abs();
        let rpm = tap.profile.rpm_in.min(tap.profile.rpm_out).max(1e-9);
        tap.grace + 2.0 * depth / tap.profile.pitch * 60.0 / rpm
    }

    /// One servo cycle of the tap under way.
    pub(super) fn tap_step(&mut self) -> Result<(), RunError> {
        let loc = self.tap.loc;
        let period = self.config.servo_period;
        let hand = self.tap.profile.hand;
        let (angle, rpm, fault) = match self.io.spindle_mut() {
            Some(s) => {
                let f = s.feedback();
                let fault = f.fault.as_ref().map(|x| s.describe_fault(x));
                (f.position.unwrap_or(0.0), f.rpm, fault)
            }
            None => (0.0, 0.0, None),
        };
        if let Some(message) = fault {
            self.tap.active = false;
            return Err(RunError::Spindle {
                message,
                line: loc.line,
            });
        }
        let psi = hand * angle;
        let w = hand * rpm * 6.0;
        if self.t - self.tap.since > self.tap.timeout {
            self.tap.active = false;
            let what = match self.tap.phase {
                Phase::Stopping => "the spindle did not stop before the rigid tap",
                Phase::Stroke(_) => "a stroke of the rigid tap did not reach its end",
            };
            return Err(RunError::Spindle {
                message: format!("{what} within {} s", self.tap.timeout),
                line: loc.line,
            });
        }
        let k = match self.tap.phase {
            Phase::Stopping => {
                // At rest: measured below STILL_RPM and at its command of 0 as the spindle
                // reports it; from here the tool follows whatever the spindle does.
                let still = rpm.abs() <= STILL_RPM
                    && self.io.spindle_mut().is_some_and(|s| s.feedback().at_speed);
                if !still {
                    return self.hold_cycle();
                }
                self.tap.zero = psi;
                self.tap.phase = Phase::Stroke(0);
                self.tap.since = self.t;
                self.tap.timeout = self.stroke_time(0);
                0
            }
            Phase::Stroke(k) => k,
        };
        let profile = &self.tap.profile;
        let per_degree = profile.pitch / 360.0;
        let target = self.tap.zero + self.tap.strokes[k] / per_degree;
        let remaining = target - psi;
        let mut next = k;
        if remaining.abs() <= end_window(profile.pitch) {
            next = k + 1;
        }
        // The setpoint acts a cycle later: the angle then.
        let ahead = psi + w * period;
        let s = (ahead - self.tap.zero) * per_degree;
        let mut velocity = [0.0; 9];
        for (v, d) in velocity.iter_mut().zip(profile.dir) {
            *v = d * per_degree * w;
        }
        let pose = profile.pose(s);
        if next >= self.tap.strokes.len() {
            // The last stroke has ended: the tool on its end, the spindle back to its speed.
            let end = profile.pose(self.tap.strokes[k]);
            let before = self.tap.before;
            self.tap.active = false;
            if let Some(sp) = self.io.spindle_mut() {
                sp.command(0.0)?;
            }
            self.geared_cycle(end, [0.0; 9], loc)?;
            if before != 0.0 {
                if let Some(sp) = self.io.spindle_mut() {
                    sp.command(before)?;
                }
                let timeout = self.tap.grace;
                self.wait_at_speed(loc, timeout, |rpm| {
                    format!(
                        "did not reach {before} rpm within {timeout} s after the rigid tap \
                         (at {rpm:.0} rpm)"
                    )
                })?;
            }
            return Ok(());
        }
        if next != k {
            self.tap.phase = Phase::Stroke(next);
            self.tap.since = self.t;
            self.tap.timeout = self.stroke_time(next);
        }
        let goal = self.tap.zero + self.tap.strokes[next] / per_degree;
        let command = hand * profile.speed_for(goal - psi);
        if let Some(sp) = self.io.spindle_mut() {
            sp.command(command)?;
        }
        self.geared_cycle(pose, velocity, loc)
    }
}
