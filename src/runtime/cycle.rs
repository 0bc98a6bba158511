//! The servo cycle: pacing on the wall clock, the per-cycle bookkeeping and monitors, and
//! applying the planner's samples to the machine.

use super::command;
use super::log::LogRecord;
use super::{Run, RunError};
use crate::monitor::StopCause;
use crate::trace::SpindleRow;
use klar_motion::{AxisFault, Sample};
use std::time::Duration;

impl Run<'_, '_> {
    /// One servo cycle at machine time `t` with the setpoints already in `io`.
    pub(super) fn servo_cycle(&mut self, t: f64) -> Result<(), RunError> {
        self.wait_until(t);
        let (wall, injected) = self.lateness(t);
        let late = wall + injected;
        if self.wall_late.1 || late > self.config.servo_period {
            self.report.underruns += 1;
        }
        // Simulated plants run on machine time and do not mind a late wall clock: on an
        // all-simulated machine only injected stalls (or an explicit limit) stop the run.
        let counted = if self.enforce_wall_lateness {
            late
        } else {
            injected
        };
        let limit = self.config.setpoint_lateness_limit();
        if counted > limit && self.stopping.is_none() {
            self.log.send(LogRecord::Underrun {
                line: self.line,
                late: counted,
            });
            let block = self.last_loc.and_then(|l| l.block);
            self.begin_path_stop(
                StopCause::Underrun {
                    late: counted,
                    limit,
                },
                None,
                RunError::Underrun {
                    late: counted,
                    limit,
                    line: self.line,
                    block,
                },
            );
        }
        self.io.cycle(t)?;
        self.record_cycle(t)?;
        if let Some(i) = self.faulted_axis() {
            return Err(self.axis_fault(i));
        }
        for i in 0..self.letters.len() {
            if let Some(limit) = self.fe_limits[i] {
                let e = self.reference[i] - self.actual[i];
                if e.abs() > limit || e.is_nan() {
                    return Err(RunError::Fault {
                        axis: self.letters[i],
                        fault: AxisFault::FollowingError(e),
                        origin: None,
                        line: self.line,
                        block: self.last_loc.and_then(|l| l.block),
                    });
                }
            }
        }
        if self.stopping.is_none()
            && let Some(s) = self.io.spindle_mut()
            && let Some(fault) = s.feedback().fault.clone()
        {
            let message = s.describe_fault(&fault);
            self.log.send(LogRecord::SpindleFault { line: self.line });
            self.begin_path_stop(
                StopCause::Spindle(message.clone()),
                None,
                RunError::Spindle {
                    message,
                    line: self.line,
                },
            );
        }
        self.check_operator()
    }

    /// In realtime mode, sleeps until the deadline of the cycle due at machine time `t`
    /// (see [`Pacer`]).
    pub(super) fn wait_until(&mut self, t: f64) {
        if self.report.realtime {
            self.wall_late = self.pacer.wait(t);
        }
    }

    /// How late the setpoints of the cycle due at machine time `t` reach the axes, s: the
    /// wall-clock delay in realtime mode, and any injected stall that strikes now (which a
    /// realtime run also really waits out).
    fn lateness(&mut self, t: f64) -> (f64, f64) {
        let wall = if self.report.realtime {
            self.wall_late.0
        } else {
            0.0
        };
        let mut late = 0.0;
        while let Some(&(at, seconds)) = self.stalls.front() {
            if at > t {
                break;
            }
            self.stalls.pop_front();
            if self.report.realtime {
                std::thread::sleep(Duration::from_secs_f64(seconds));
                self.pacer.delay(seconds);
            }
            late += seconds;
        }
        (wall, late)
    }

    /// Bookkeeping after a cycle: time, measured positions, figures, trace row.
    pub(super) fn record_cycle(&mut self, t: f64) -> Result<(), RunError> {
        self.t = t;
        self.report.cycles += 1;
        self.report.machine_time = t;
        for i in 0..self.commanded.len() {
            let lagging = self.lags.get(i).is_some_and(|&l| l > 0);
            self.reference[i] = if lagging {
                self.last_sent[i]
            } else {
                self.commanded[i]
            };
            self.last_sent[i] = self.commanded[i];
        }
        for (i, f) in self.io.feedback().iter().enumerate() {
            self.actual[i] = f.position;
            let fe = f.following_error.abs();
            if fe > self.report.max_following_error[i].1 {
                self.report.max_following_error[i].1 = fe;
            }
        }
        if let Some(tr) = self.trace.as_mut() {
            let spindle = self
                .io
                .spindle_mut()
                .map(|s| SpindleRow {
                    rpm: s.commanded(),
                    angle: s.feedback().position,
                })
                .unwrap_or_default();
            tr.row(t, &self.commanded, &self.actual, spindle)?;
        }
        Ok(())
    }

    /// Sends one planner sample to the axes. Before the first sample of a new block, every
    /// positioning axis must have reached its last commanded position.
    pub(super) fn apply_sample(&mut self, sample: &Sample) -> Result<(), RunError> {
        if self.last_loc != Some(sample.loc) {
            self.settle_all()?;
            self.last_loc = Some(sample.loc);
        }
        self.line = sample.loc.line;
        // The last line of defence: a setpoint the guard refuses never reaches a backend.
        let t = sample.t + self.shift;
        let positions =
            self.command
                .positions(sample, t)
                .map_err(|violation| RunError::Setpoint {
                    diagnostic: command::refused_in_run(self.path, sample.loc, &violation),
                    violation,
                })?;
        for (c, &x) in self.commanded.iter_mut().zip(positions) {
            *c = x;
        }
        self.command
            .setpoints(sample, &self.commanded, self.io.setpoints_mut());
        // Constant surface speed follows the radius of this cycle's setpoint.
        self.follow_surface_speed()?;
        self.servo_cycle(t)
    }

    /// One cycle holding the last commanded position; planner time stands still.
    pub(super) fn hold_cycle(&mut self) -> Result<(), RunError> {
        self.io.hold();
        self.command.repeat();
        let period = self.config.servo_period;
        self.shift += period;
        self.servo_cycle(self.t + period)
    }
}
