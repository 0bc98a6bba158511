//! Moves geared to the spindle (thread passes, [`OpKind::SpindleSync`]): electronic gearing
//! in the servo loop.
//!
//! The path position is a function of the spindle angle, not of time. With `φ` the angle
//! the spindle has turned since the pass was triggered (degrees, in its direction of
//! rotation) and `g` the path travel per degree (the pitch over 360°, over the share of the
//! path the pitch measures), the path position `s(φ)` is:
//!
//! - run-in (length `B`): `s = g·φ²/(2·Φ_in)` with `Φ_in = 2B/g`: the slide accelerates
//!   with the spindle from rest and reaches `g` mm/° at `s = B`;
//! - thread: `s = B + g·(φ − Φ_in)`;
//! - run-out (length `P`): the mirror of the run-in, ending at rest on the end point.
//!
//! Every servo cycle the run reads the measured angle, predicts it one cycle ahead with the
//! measured speed (the setpoint acts a cycle later), and commands `s` of that angle: the
//! lead follows the spindle however its speed changes under the cut. The pass is triggered
//! at the angle that puts the spindle at the programmed start angle when the run-in ends, so
//! every pass with the same start angle cuts the same groove. Feed override and feed hold do
//! not act inside a pass; a stop requested during it takes effect when it has ended.
//!
//! Before anything moves, [`SyncProfile::new`] refuses a pass the axes cannot follow at the
//! commanded spindle speed: an axis's share of the synchronous speed above its
//! `max_velocity`, or a run-in or run-out shorter than its `max_acceleration` needs. Without
//! a programmed run-in or run-out the shortest length the axes allow is used, with a
//! quarter of margin for the speed changes of the spindle.

use super::{Run, RunError};
use crate::config::MachineConfig;
use klar_interp::op::ThreadLead;
use klar_interp::{AxisLetter, Op, OpKind, Pose};
use klar_motion::Sample;

/// Margin on the shortest run-in and run-out: their acceleration stays at 80 % of the limit.
const RUN_MARGIN: f64 = 1.25;

/// The geometry and timing of one geared pass at a given spindle speed.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SyncProfile {
    /// Start and end of the path.
    pub from: Pose,
    /// End point.
    pub to: Pose,
    /// Path length, mm.
    pub length: f64,
    /// Path travel per degree of spindle, mm/°.
    pub per_degree: f64,
    /// Run-in and run-out along the path, mm.
    pub run_in: f64,
    /// Run-out, mm.
    pub run_out: f64,
    /// Spindle angle at the end of the run-in, degrees.
    pub start_angle: f64,
    /// Chip cross-section under cut, mm².
    pub section: f64,
}

impl SyncProfile {
    /// The profile of a [`OpKind::SpindleSync`] op at `rpm` (its magnitude), or why the axes
    /// of `config` cannot follow it. `None` for any other op.
    pub(crate) fn new(
        kind: &OpKind,
        rpm: f64,
        config: &MachineConfig,
    ) -> Option<Result<SyncProfile, String>> {
        let OpKind::SpindleSync {
            from,
            to,
            pitch,
            lead,
            start_angle,
            run_in,
            run_out,
            section,
        } = kind
        else {
            return None;
        };
        Some(Self::build(
            *from,
            *to,
            *pitch,
            *lead,
            *start_angle,
            (*run_in, *run_out),
            *section,
            rpm,
            config,
        ))
    }

    #[allow(clippy::too_many_arguments)]
    fn build(
        from: Pose,
        to: Pose,
        pitch: f64,
        lead: ThreadLead,
        start_angle: f64,
        (run_in, run_out): (Option<f64>, Option<f64>),
        section: f64,
        rpm: f64,
        config: &MachineConfig,
    ) -> Result<SyncProfile, String> {
        let length = path_length(from, to);
        let measured = match lead {
            ThreadLead::Z => (to[AxisLetter::Z] - from[AxisLetter::Z]).abs(),
            ThreadLead::X => (to[AxisLetter::X] - from[AxisLetter::X]).abs(),
            ThreadLead::Path => length,
        };
        if !(length > 1e-9 && measured > 1e-9 && pitch > 0.0 && pitch.is_finite()) {
            return Err("the thread pass does not move along its pitch".into());
        }
        let rpm = rpm.abs();
        if !(rpm > 0.0 && rpm.is_finite()) {
            return Err("a thread pass needs the spindle turning (M3 or M4 with a speed)".into());
        }
        let per_degree = pitch * length / measured / 360.0;
        // Path speed at the commanded spindle speed, mm/s (rpm · 6 = °/s).
        let v = per_degree * rpm * 6.0;
        // The shortest run length the acceleration of every moving axis allows.
        let mut shortest: f64 = 0.0;
        for a in &config.axes {
            let share = (to[a.letter] - from[a.letter]).abs() / length;
            if share <= 1e-12 {
                continue;
            }
            let axis_v = v * share;
            if axis_v > a.max_velocity {
                return Err(format!(
                    "axis {} would need {:.0} mm/min for pitch {pitch} mm at {rpm} rpm, above \
                     its {:.0} mm/min: lower the spindle speed below {:.0} rpm",
                    a.letter,
                    axis_v * 60.0,
                    a.max_velocity * 60.0,
                    rpm * a.max_velocity / axis_v
                ));
            }
            shortest = shortest.max(v * v * share / (2.0 * a.max_acceleration));
        }
        let mut lengths = [0.0; 2];
        for (k, (given, what)) in [(run_in, "run-in B"), (run_out, "run-out P")]
            .into_iter()
            .enumerate()
        {
            lengths[k] = match given {
                Some(b) if b + 1e-9 < shortest => {
                    return Err(format!(
                        "{what}{b} is too short for pitch {pitch} mm at {rpm} rpm: the axes \
                         need {shortest:.3} mm to reach the thread's speed"
                    ));
                }
                Some(b) if b > 0.0 => b,
                _ => (shortest * RUN_MARGIN).max(1e-6),
            };
        }
        if lengths[0] + lengths[1] > length + 1e-9 {
            return Err(format!(
                "the pass of {length:.3} mm is shorter than its run-in {:.3} mm and run-out \
                 {:.3} mm at {rpm} rpm",
                lengths[0], lengths[1]
            ));
        }
        Ok(SyncProfile {
            from,
            to,
            length,
            per_degree,
            run_in: lengths[0],
            run_out: lengths[1],
            start_angle,
            section,
        })
    }

    /// Spindle degrees of the run-in.
    pub(crate) fn run_in_degrees(&self) -> f64 {
        2.0 * self.run_in / self.per_degree
    }

    /// Spindle degrees of the whole pass.
    pub(crate) fn total_degrees(&self) -> f64 {
        let thread = self.length - self.run_in - self.run_out;
        self.run_in_degrees() + thread / self.per_degree + 2.0 * self.run_out / self.per_degree
    }

    /// Path position (mm) and its rate (mm per spindle degree) `phi` degrees after the
    /// trigger.
    pub(crate) fn at(&self, phi: f64) -> (f64, f64) {
        let g = self.per_degree;
        let phi_in = self.run_in_degrees();
        let total = self.total_degrees();
        if phi <= 0.0 {
            return (0.0, 0.0);
        }
        if phi >= total {
            return (self.length, 0.0);
        }
        if phi < phi_in {
            return (g * phi * phi / (2.0 * phi_in), g * phi / phi_in);
        }
        let phi_out = 2.0 * self.run_out / g;
        let left = total - phi;
        if left < phi_out {
            return (
                self.length - g * left * left / (2.0 * phi_out),
                g * left / phi_out,
            );
        }
        (self.run_in + g * (phi - phi_in), g)
    }

    /// The pose at path position `s`.
    pub(crate) fn pose(&self, s: f64) -> Pose {
        let mut p = self.from;
        let k = s / self.length;
        for i in 0..9 {
            p.0[i] = self.from.0[i] + (self.to.0[i] - self.from.0[i]) * k;
        }
        p
    }

    /// Per-axis velocity for the path rate `rate` (mm/°) at `deg_per_s`.
    pub(crate) fn velocity(&self, rate: f64, deg_per_s: f64) -> [f64; 9] {
        let mut v = [0.0; 9];
        for (i, out) in v.iter_mut().enumerate() {
            *out = (self.to.0[i] - self.from.0[i]) / self.length * rate * deg_per_s;
        }
        v
    }
}

/// The straight-line length of the path from `from` to `to` over all nine pose components.
pub(super) fn path_length(from: Pose, to: Pose) -> f64 {
    (0..9)
        .map(|i| (to.0[i] - from.0[i]).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// What every move geared to the spindle starts from: its profile at the commanded speed
/// and the spindle it follows.
pub(super) struct GearedStart<P> {
    /// The op's profile at the commanded spindle speed.
    pub profile: P,
    /// The spindle in words.
    pub name: String,
    /// The signed spindle speed commanded before the op, rpm.
    pub commanded: f64,
    /// The spindle's at-speed timeout, s.
    pub timeout: f64,
}

/// A geared pass under way: one servo cycle of it per [`Run::step`].
pub(super) struct SyncPass {
    profile: SyncProfile,
    /// Direction of rotation: 1 (M3) or -1 (M4).
    dir: f64,
    /// The trigger, as an angle in the direction of rotation, degrees.
    trigger: f64,
    /// Machine time the wait for the trigger began.
    waited_from: f64,
    /// The tool is past the run-in (the spindle carries the cut's load).
    cutting: bool,
    /// The spindle in words, and how long the trigger may take.
    name: String,
    timeout: f64,
    loc: klar_interp::SourceLoc,
}

impl Run<'_, '_> {
    /// Starts a [`OpKind::SpindleSync`] op: checks the spindle and the axes, and fixes the
    /// trigger angle; [`Run::sync_step`] then runs it cycle by cycle.
    pub(super) fn spindle_sync(&mut self, op: &Op) -> Result<(), RunError> {
        let loc = op.loc;
        let Some(GearedStart {
            profile,
            name,
            commanded,
            timeout,
        }) = self.geared_start(
            op,
            "a thread pass needs a spindle",
            "cut threads",
            SyncProfile::new,
        )?
        else {
            return Ok(());
        };
        let dir = commanded.signum();
        let period = self.config.servo_period;
        // The trigger, as an angle in the direction of rotation: the next one at least a
        // cycle's travel ahead that puts the spindle on the start angle when the run-in ends.
        let (psi_now, w_now) = self.spindle_angle(dir);
        let trigger_mod = (dir * profile.start_angle - profile.run_in_degrees()).rem_euclid(360.0);
        let ahead = psi_now + w_now * period;
        let mut trigger = ahead - ahead.rem_euclid(360.0) + trigger_mod;
        if trigger < ahead {
            trigger += 360.0;
        }
        self.sync = Some(SyncPass {
            profile,
            dir,
            trigger,
            waited_from: self.t,
            cutting: false,
            name,
            timeout,
            loc,
        });
        Ok(())
    }

    /// One servo cycle of the pass under way: waiting for the trigger angle, or commanding
    /// the path position of the predicted spindle angle. The pass ends on its end point.
    pub(super) fn sync_step(&mut self) -> Result<(), RunError> {
        let Some(pass) = self.sync.take() else {
            return Ok(());
        };
        let period = self.config.servo_period;
        let (psi, w) = self.spindle_angle(pass.dir);
        let phi = psi + w * period - pass.trigger;
        let loc = pass.loc;
        if phi < 0.0 {
            if self.t - pass.waited_from > pass.timeout {
                return Err(RunError::Spindle {
                    message: format!(
                        "{}: the thread pass did not reach its start angle within {} s",
                        pass.name, pass.timeout
                    ),
                    line: loc.line,
                });
            }
            self.sync = Some(pass);
            return self.hold_cycle();
        }
        let mut pass = pass;
        if !pass.cutting && phi >= pass.profile.run_in_degrees() {
            pass.cutting = true;
            if let Some(s) = self.io.spindle_mut() {
                s.set_load(pass.profile.section);
            }
        }
        let done = phi >= pass.profile.total_degrees();
        let (s, rate) = pass.profile.at(phi);
        let (pose, velocity) = if done {
            (pass.profile.to, [0.0; 9])
        } else {
            (pass.profile.pose(s), pass.profile.velocity(rate, w))
        };
        if done {
            if let Some(s) = self.io.spindle_mut() {
                s.set_load(0.0);
            }
        } else {
            self.sync = Some(pass);
        }
        self.geared_cycle(pose, velocity, loc)?;
        if let Some(sp) = self.io.spindle_mut()
            && let Some(fault) = sp.feedback().fault.clone()
        {
            // The axes are geared to a spindle that no longer follows: the pass ends here.
            let message = sp.describe_fault(&fault);
            self.sync = None;
            return Err(RunError::Spindle {
                message,
                line: loc.line,
            });
        }
        Ok(())
    }

    /// The measured spindle angle in the direction of rotation `dir` (degrees) and the
    /// measured speed in that direction (°/s).
    fn spindle_angle(&mut self, dir: f64) -> (f64, f64) {
        self.io.spindle_mut().map_or((0.0, 0.0), |s| {
            let f = s.feedback();
            (
                dir * f.position.unwrap_or(0.0),
                (dir * f.rpm * 6.0).max(0.0),
            )
        })
    }

    /// Checks what a move geared to the spindle needs before it starts: the axes at rest, a
    /// spindle (`no_spindle` says what lacks one), a measured spindle angle (without one it
    /// cannot `what`), and a profile `profile` accepts at the commanded speed. `None` when
    /// `profile` does not take the op.
    pub(super) fn geared_start<P>(
        &mut self,
        op: &Op,
        no_spindle: &str,
        what: &str,
        profile: impl FnOnce(&OpKind, f64, &MachineConfig) -> Option<Result<P, String>>,
    ) -> Result<Option<GearedStart<P>>, RunError> {
        let loc = op.loc;
        self.settle_all()?;
        let Some(spindle) = self.io.spindle_mut() else {
            return Err(self.diagnostic(loc, no_spindle.into()));
        };
        let name = spindle.name().to_string();
        let commanded = spindle.commanded();
        let timeout = spindle.at_speed_timeout;
        if spindle.feedback().position.is_none() {
            return Err(self.diagnostic(
                loc,
                format!("the {name} measures no spindle angle: it cannot {what}"),
            ));
        }
        match profile(&op.kind, commanded, self.config) {
            Some(Ok(profile)) => Ok(Some(GearedStart {
                profile,
                name,
                commanded,
                timeout,
            })),
            Some(Err(message)) => Err(self.diagnostic(loc, message)),
            None => Ok(None),
        }
    }

    /// One servo cycle commanding `pose` with the velocity feed-forward `velocity`; planner
    /// time stands still (like a hold cycle).
    pub(super) fn geared_cycle(
        &mut self,
        pose: Pose,
        velocity: [f64; 9],
        loc: klar_interp::SourceLoc,
    ) -> Result<(), RunError> {
        let period = self.config.servo_period;
        self.shift += period;
        let t = self.t + period;
        let sample = Sample {
            t: t - self.shift,
            pose,
            velocity,
            acceleration: [0.0; 9],
            loc,
        };
        self.line = loc.line;
        let positions =
            self.command
                .positions(&sample, t)
                .map_err(|violation| RunError::Setpoint {
                    diagnostic: super::command::refused_in_run(self.path, loc, &violation),
                    violation,
                })?;
        for (c, &x) in self.commanded.iter_mut().zip(positions) {
            *c = x;
        }
        self.command
            .setpoints(&sample, &self.commanded, self.io.setpoints_mut());
        self.last_loc = Some(loc);
        self.servo_cycle(t)
    }
}
