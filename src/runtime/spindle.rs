//! Spindle commands reaching the servo loop: speeds checked against the machine, the wait
//! for at-speed after a command to turn, and constant surface speed following the tool radius.
//!
//! A change of direction (M3 to M4 directly, or M4 while the spindle still turns forward
//! after an M5) first commands 0 rpm and waits until the spindle reports it has stopped
//! (the device acknowledged the stop and the measured speed is within the at-speed window
//! of zero), at most `at_speed_timeout`; only then the new direction is commanded. A drive
//! that is polled (a Modbus VFD) would otherwise see only the newest command and go from
//! forward to reverse without the stop.

use super::stream::OpStream;
use super::{Run, RunError};
use klar_interp::op::{SpindleDir, SpindleSpeed};
use klar_interp::{AxisLetter, SourceLoc};

/// The smallest change of the speed constant surface speed commands, rpm.
pub(super) const CSS_STEP: f64 = 0.1;

impl Run<'_, '_> {
    /// The main spindle speed for constant surface speed `v` (m/min) at the tool's present
    /// radius (program X), limited to `limit` (G26) and the machine's maximum.
    pub(super) fn surface_speed_rpm(&mut self, v: f64, limit: f64) -> f64 {
        let radius = self.command.kinematics().to_program(&self.commanded)[AxisLetter::X];
        let max = self.io.spindle_mut().map_or(0.0, |s| s.max_rpm);
        OpStream::surface_speed_rpm(v, radius, max.min(limit))
    }

    /// Under constant surface speed, follows the tool's radius every servo cycle (without
    /// waiting: the spindle changes speed while the axes move, as on a lathe); a change
    /// below [`CSS_STEP`] rpm is not sent.
    pub(super) fn follow_surface_speed(&mut self) -> Result<(), RunError> {
        let Some((v, limit)) = self.surface_speed else {
            return Ok(());
        };
        let rpm = self.surface_speed_rpm(v, limit);
        if let Some(s) = self.io.spindle_mut() {
            let now = s.commanded();
            if now != 0.0 && (rpm - now.abs()).abs() > CSS_STEP {
                s.command(rpm.copysign(now))?;
            }
        }
        Ok(())
    }

    pub(super) fn spindle_command(
        &mut self,
        loc: SourceLoc,
        dir: SpindleDir,
        speed: SpindleSpeed,
    ) -> Result<(), RunError> {
        let rpm = match speed {
            SpindleSpeed::Rpm(r) => {
                self.surface_speed = None;
                r
            }
            SpindleSpeed::SurfaceSpeed(v) => {
                self.surface_speed = (dir != SpindleDir::Off).then_some((v, f64::INFINITY));
                self.surface_speed_rpm(v, f64::INFINITY)
            }
            SpindleSpeed::SurfaceSpeedCapped(v, n) => {
                self.surface_speed = (dir != SpindleDir::Off).then_some((v, n));
                self.surface_speed_rpm(v, n)
            }
        };
        let signed = match dir {
            SpindleDir::Cw => rpm,
            SpindleDir::Ccw => -rpm,
            SpindleDir::Off => 0.0,
        };
        let Some(spindle) = self.io.spindle_mut() else {
            if signed != 0.0 && !self.warned_no_spindle {
                self.log
                    .send(super::LogRecord::NoSpindle { line: loc.line });
                self.warned_no_spindle = true;
            }
            return Ok(());
        };
        if signed.abs() > spindle.max_rpm {
            let max = spindle.max_rpm;
            return Err(self.diagnostic(
                loc,
                format!("spindle speed S{rpm} is above this machine's {max} rpm"),
            ));
        }
        if signed == spindle.commanded() {
            return Ok(());
        }
        let reversing = signed != 0.0
            && (spindle.direction() * signed < 0.0 || spindle.feedback().rpm * signed < 0.0);
        let timeout = spindle.at_speed_timeout;
        if reversing {
            if spindle.commanded() != 0.0 {
                spindle.command(0.0)?;
            }
            self.wait_at_speed(loc, timeout, |rpm| {
                format!(
                    "did not stop within {timeout} s before reversing to {signed} rpm \
                     (still at {rpm:.0} rpm)"
                )
            })?;
        }
        let Some(spindle) = self.io.spindle_mut() else {
            return Ok(());
        };
        spindle.command(signed)?;
        if signed == 0.0 {
            return Ok(());
        }
        self.wait_at_speed(loc, timeout, |_| {
            format!("did not reach {signed} rpm within {timeout} s")
        })
    }

    /// Holds the axes until the spindle reports at-speed for its present command, at most
    /// `timeout` s; `late` words the error from the measured speed.
    pub(super) fn wait_at_speed(
        &mut self,
        loc: SourceLoc,
        timeout: f64,
        late: impl Fn(f64) -> String,
    ) -> Result<(), RunError> {
        let waited_from = self.t;
        let wall_from = crate::latency::now_ns();
        loop {
            self.hold_cycle()?;
            if let Some(pending) = self.stopping.take() {
                return Err(self.end_path_stop(pending));
            }
            let (at_speed, rpm) = self
                .io
                .spindle_mut()
                .map_or((true, 0.0), |s| (s.feedback().at_speed, s.feedback().rpm));
            if at_speed {
                break;
            }
            if self.t - waited_from > timeout {
                return Err(RunError::Spindle {
                    message: late(rpm),
                    line: loc.line,
                });
            }
        }
        // On the wall clock in realtime runs: a missed servo slot does not advance machine
        // time, but the spindle ramps on regardless.
        self.report.spindle_wait += if self.report.realtime {
            (crate::latency::now_ns() - wall_from) as f64 * 1e-9
        } else {
            self.t - waited_from
        };
        Ok(())
    }
}
