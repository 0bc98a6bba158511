//! The run's stop reactions: the quick stop when an axis can no longer follow the path, the
//! stop on the path (feed hold) when it can, the stop report, and the fault reset that reads
//! the position back from the drives.

use super::{Run, RunError};
use crate::monitor::{AxisStop, AxisStopFigures, StopCause, StopKind, StopReport};
use klar_interp::AxisLetter;
use klar_motion::{AxisFault, Setpoint};

/// A feed-hold stop on the path that has begun but not yet come to rest.
pub(super) struct PendingStop {
    pub(super) report: StopReport,
    pub(super) error: RunError,
}

/// Cycles the axes must stay still before a stop counts as at rest.
const REST_CYCLES: u32 = 20;
/// Band an axis must stay within (around where it last moved to) to count as still, mm or
/// degrees: a position control dithering by a few encoder counts around its target is at
/// rest; a creep out of the band restarts the count.
const REST_BAND: f64 = 1e-3;
/// Longest a stop may take before the run gives up waiting, s.
const STOP_TIMEOUT: f64 = 10.0;
/// Longest the run holds the axes after a stop on the path for them to settle, s.
const SETTLE_WAIT: f64 = 1.0;
/// Shortest time the run waits for faulted axes (whose feedback may be stale or noisy) to
/// show rest, s: their drives brake on their own. A drive with a configured quick-stop
/// deceleration is waited for as long as that deceleration needs from its speed.
const FAULTED_WAIT: f64 = 1.0;

impl Run<'_, '_> {
    /// Figures of every axis at the moment a fault is seen (rest positions filled later).
    pub(super) fn figures_now(&self) -> Vec<AxisStopFigures> {
        let setpoints = self.io.setpoints();
        self.letters
            .iter()
            .enumerate()
            .map(|(i, &axis)| {
                let sp = setpoints.get(i).copied().unwrap_or_default();
                AxisStopFigures {
                    axis,
                    velocity: sp.velocity,
                    acceleration: sp.acceleration,
                    position_at_fault: self.actual[i],
                    position_at_rest: self.actual[i],
                    following_error: (self.commanded[i] - self.actual[i]).abs(),
                }
            })
            .collect()
    }

    /// Starts a feed hold that ends the run with `error` once the path is at rest. A stop
    /// the operator or the caller asks for during a pass geared to the spindle waits like a
    /// feed hold (see `pass_hold`): a thread pass runs to its end and the retract after it
    /// runs before the run stops, out of the groove; a rigid tap ends out of the hole.
    pub(super) fn begin_path_stop(
        &mut self,
        cause: StopCause,
        axis: Option<AxisLetter>,
        error: RunError,
    ) {
        if matches!(cause, StopCause::Requested | StopCause::Operator) && self.in_geared_pass() {
            self.defer_hold();
        } else {
            self.planner.hold();
        }
        self.stopping = Some(PendingStop {
            report: StopReport {
                cause,
                axis,
                line: self.line,
                block: self.last_loc.and_then(|l| l.block),
                t_fault: self.t,
                t_rest: self.t,
                kind: StopKind::OnPath,
                axes: self.figures_now(),
            },
            error,
        });
    }

    /// Ends a path stop at rest: holds the axes until they are still, fills in the rest
    /// figures and returns its error.
    pub(super) fn end_path_stop(&mut self, pending: PendingStop) -> RunError {
        self.settle();
        let mut report = pending.report;
        report.t_rest = self.t;
        for (f, &x) in report.axes.iter_mut().zip(&self.actual) {
            f.position_at_rest = x;
        }
        self.report.stop = Some(report.clone());
        self.stop_report = Some(report);
        pending.error
    }

    /// Holds the commanded positions until every axis has been still for `REST_CYCLES`
    /// (at most `SETTLE_WAIT`): the drives are switched off at rest, and the trace ends at
    /// rest.
    fn settle(&mut self) {
        self.io.hold();
        let period = self.config.servo_period;
        let mut last = self.actual.clone();
        let mut still = 0;
        let cycles = (SETTLE_WAIT / period).ceil() as u64;
        for _ in 0..cycles {
            if still >= REST_CYCLES {
                break;
            }
            let t = self.t + period;
            self.wait_until(t);
            self.shift += period;
            if let Err(e) = self.io.cycle(t) {
                self.defer("stop on the path: the backend no longer answers", e.into());
                break;
            }
            if let Err(e) = self.record_cycle(t) {
                self.defer("stop on the path: trace", e);
            }
            let mut moved = false;
            for (a, b) in self.actual.iter().zip(last.iter_mut()) {
                if (a - *b).abs() > REST_BAND {
                    *b = *a;
                    moved = true;
                }
            }
            still = if moved { 0 } else { still + 1 };
        }
    }

    /// The reaction to a fault the axes cannot ride through: every axis that still follows
    /// stops on its own jerk-limited ramp from its last setpoint, faulted axes brake in their
    /// drives; the cycles go on until everything is still. Returns the error to report.
    pub(super) fn quick_stop(&mut self, error: RunError) -> RunError {
        let (cause, axis) = match &error {
            RunError::Fault { axis, fault, .. } => {
                let monitor = self.io.feedback().iter().all(|f| f.fault.is_none());
                let cause = match (fault, monitor) {
                    (AxisFault::FollowingError(e), true) => StopCause::FollowingError {
                        error: *e,
                        limit: self
                            .letters
                            .iter()
                            .position(|l| l == axis)
                            .and_then(|i| self.fe_limits[i])
                            .unwrap_or(f64::NAN),
                    },
                    _ => StopCause::AxisFault(fault.clone()),
                };
                (cause, Some(*axis))
            }
            RunError::Backend(e) => (StopCause::Communication(e.to_string()), None),
            // A stop on the path cut short by the operator keeps the cause it had.
            RunError::Operator { .. } => (StopCause::Operator, None),
            RunError::Stopped { .. } => (StopCause::Requested, None),
            RunError::Spindle { message, .. } => (StopCause::Spindle(message.clone()), None),
            RunError::Underrun { late, limit, .. } => (
                StopCause::Underrun {
                    late: *late,
                    limit: *limit,
                },
                None,
            ),
            RunError::Setpoint { violation, .. } => {
                (StopCause::Setpoint(*violation), Some(violation.axis()))
            }
            other => (StopCause::Program(other.to_string()), None),
        };
        self.log
            .send(super::LogRecord::QuickStop { line: self.line });
        let mut report = StopReport {
            cause,
            axis,
            line: self.line,
            block: self.last_loc.and_then(|l| l.block),
            t_fault: self.t,
            t_rest: self.t,
            kind: StopKind::Quick,
            axes: self.figures_now(),
        };
        let period = self.config.servo_period;
        // Axes whose feedback cannot be trusted to show rest (faulted: their drives brake on
        // their own; a lost link shows a stale position, a broken encoder noise) are waited
        // for at most FAULTED_WAIT; the others must be still for REST_CYCLES.
        let tripped = axis.and_then(|a| self.letters.iter().position(|&l| l == a));
        let faulted: Vec<bool> = (0..self.letters.len())
            .map(|i| {
                Some(i) == tripped || self.io.feedback().get(i).is_some_and(|f| f.fault.is_some())
            })
            .collect();
        let mut stops: Vec<AxisStop> = self
            .io
            .setpoints()
            .iter()
            .zip(&self.stop_limits)
            .enumerate()
            .map(|(i, (sp, &(a, j)))| {
                let mut from = *sp;
                if faulted.get(i).copied().unwrap_or(false) {
                    // An axis that faulted or could not follow is held where it is: a ramp
                    // of its command would only pull it on (its drive brakes by itself).
                    if let Some(&x) = self.actual.get(i) {
                        from.position = x;
                    }
                    from.velocity = 0.0;
                    from.acceleration = 0.0;
                } else if let Some(v) = self.config.axes.get(i).map(|c| c.max_velocity) {
                    // Braking never starts from beyond the axis's speed limit.
                    from.velocity = from.velocity.clamp(-v, v);
                }
                AxisStop::new(from, a, j)
            })
            .collect();
        let faulted_wait = self.faulted_wait(&report.axes, &faulted);
        let mut still = 0;
        let mut still_faulted = 0;
        let mut last = self.actual.clone();
        let cycles = (STOP_TIMEOUT / period).ceil() as u64;
        let t_fault = self.t;
        for _ in 0..cycles {
            for (i, (stop, sp)) in stops
                .iter_mut()
                .zip(self.io.setpoints_mut().iter_mut())
                .enumerate()
            {
                *sp = stop.step(period);
                self.commanded[i] = sp.position;
            }
            let t = self.t + period;
            self.wait_until(t);
            self.shift += period;
            if let Err(e) = self.io.cycle(t) {
                self.defer("quick stop: the backend no longer answers", e.into());
                break;
            }
            if let Err(e) = self.record_cycle(t) {
                self.defer("quick stop: trace", e);
            }
            let (mut moved, mut moved_faulted) = (false, false);
            for (i, (f, (a, b))) in self
                .io
                .feedback()
                .iter()
                .zip(self.actual.iter().zip(last.iter_mut()))
                .enumerate()
            {
                let moving = (a - *b).abs() > REST_BAND;
                if moving {
                    *b = *a;
                }
                if f.fault.is_some() || Some(i) == tripped {
                    moved_faulted |= moving;
                } else {
                    moved |= moving;
                }
            }
            still_faulted = if moved_faulted { 0 } else { still_faulted + 1 };
            if stops.iter().all(AxisStop::at_rest) && !moved {
                still += 1;
            } else {
                still = 0;
            }
            let faulted_done = still_faulted >= REST_CYCLES || self.t - t_fault >= faulted_wait;
            if still >= REST_CYCLES && faulted_done {
                break;
            }
        }
        report.t_rest = self.t;
        // At rest the drives are switched off: a faulted machine waits powerless for its
        // reset (an axis the monitor tripped may still pull toward an unreachable command).
        if let Err(e) = self.io.disable() {
            self.defer("quick stop: disabling the drives", e.into());
        }
        if self.report.realtime {
            // A bus backend switches a braking drive off only at its standstill, which can
            // come after the loop above took late (unchanged) answers for rest: one more
            // cycle reads where the drives came to rest.
            let t = self.t + period;
            self.wait_until(t);
            if self.io.cycle(t).is_ok() {
                for (a, f) in self.actual.iter_mut().zip(self.io.feedback()) {
                    *a = f.position;
                }
            }
        }
        for (f, &x) in report.axes.iter_mut().zip(&self.actual) {
            f.position_at_rest = x;
        }
        self.report.stop = Some(report.clone());
        self.stop_report = Some(report);
        error
    }

    /// How long (s) the quick stop waits at most for the faulted axes to come to rest:
    /// [`FAULTED_WAIT`], or longer where a drive's quick-stop deceleration needs longer from
    /// the axis's speed at the fault (with half again as margin).
    fn faulted_wait(&self, figures: &[AxisStopFigures], faulted: &[bool]) -> f64 {
        let mut wait = FAULTED_WAIT;
        for ((axis, f), &is_faulted) in self.config.axes.iter().zip(figures).zip(faulted) {
            let crate::config::BackendConfig::Canopen(c) = &axis.backend else {
                continue;
            };
            if let (true, Some(a)) = (is_faulted, c.drive.quick_stop_deceleration) {
                wait = wait.max(1.5 * f.velocity.abs() / a + 0.1);
            }
        }
        wait.min(STOP_TIMEOUT)
    }

    /// After a stop: clears the faults of every faulted axis (their causes must be gone),
    /// reads the positions back from the drives and makes them the commanded positions, so
    /// the control's idea of where the axes are is the drives' again. The axes are enabled
    /// holding that position. The program does not go on: [`Run::finish`] ends the run.
    pub fn reset_faults(&mut self) -> Result<(), RunError> {
        let faulted: Vec<usize> = self
            .io
            .feedback()
            .iter()
            .enumerate()
            .filter(|(_, f)| f.fault.is_some())
            .map(|(i, _)| i)
            .collect();
        for &i in &faulted {
            self.io.reset_fault(i)?;
        }
        // Every axis is disabled now (the stop switched the drives off, the reset leaves the
        // faulted ones off): one cycle reads their fresh positions (a lost link showed a stale
        // one).
        let period = self.config.servo_period;
        for &i in &faulted {
            if let (Some(sp), Some(f)) = (self.io.setpoints_mut().get_mut(i), self.actual.get(i)) {
                sp.position = *f;
            }
        }
        self.io.hold();
        self.shift += period;
        self.wait_until(self.t + period);
        self.io.cycle(self.t + period)?;
        self.record_cycle(self.t + period)?;
        // The position the drives report becomes the command, then the axes are enabled
        // holding it.
        let measured: Vec<f64> = self.io.feedback().iter().map(|f| f.position).collect();
        for (sp, &x) in self.io.setpoints_mut().iter_mut().zip(&measured) {
            *sp = Setpoint {
                position: x,
                velocity: 0.0,
                acceleration: 0.0,
            };
        }
        self.commanded.clone_from(&measured);
        self.io.enable()?;
        self.shift += period;
        self.wait_until(self.t + period);
        self.io.cycle(self.t + period)?;
        self.record_cycle(self.t + period)?;
        if let Some(i) = self.faulted_axis() {
            return Err(self.axis_fault(i));
        }
        Ok(())
    }
}
