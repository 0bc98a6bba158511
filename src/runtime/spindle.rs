//! Spindle commands reaching the servo loop: speeds checked against the machine, the wait
//! for at-speed after a command to turn, and constant surface speed following the tool radius.

use super::stream::OpStream;
use super::{Run, RunError};
use klar_interp::op::{SpindleDir, SpindleSpeed};
use klar_interp::{AxisLetter, SourceLoc};

impl Run<'_, '_> {
    /// The main spindle speed for constant surface speed `v` (m/min) at the tool's present
    /// radius (program X), limited to the machine's maximum.
    pub(super) fn surface_speed_rpm(&mut self, v: f64) -> f64 {
        let radius = self.command.kinematics().to_program(&self.commanded)[AxisLetter::X];
        let max = self.io.spindle_mut().map_or(0.0, |s| s.max_rpm);
        OpStream::surface_speed_rpm(v, radius, max)
    }

    /// Under constant surface speed, follows the tool's radius block by block (without
    /// waiting: the spindle changes speed while the axes move, as on a lathe).
    pub(super) fn follow_surface_speed(&mut self) -> Result<(), RunError> {
        let Some(v) = self.surface_speed else {
            return Ok(());
        };
        let rpm = self.surface_speed_rpm(v);
        if let Some(s) = self.io.spindle_mut() {
            let now = s.commanded();
            if now != 0.0 && (rpm - now.abs()).abs() > 0.01 * now.abs() {
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
                self.surface_speed = (dir != SpindleDir::Off).then_some(v);
                self.surface_speed_rpm(v)
            }
        };
        let signed = match dir {
            SpindleDir::Cw => rpm,
            SpindleDir::Ccw => -rpm,
            SpindleDir::Off => 0.0,
        };
        let Some(spindle) = self.io.spindle_mut() else {
            if signed != 0.0 && !self.warned_no_spindle {
                tracing::warn!(
                    line = loc.line,
                    "this machine has no spindle: S/M3/M4 ignored"
                );
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
        spindle.command(signed)?;
        let timeout = spindle.at_speed_timeout;
        if signed == 0.0 {
            return Ok(());
        }
        let waited_from = self.t;
        let wall_from = crate::latency::now_ns();
        loop {
            self.hold_cycle()?;
            if let Some(pending) = self.stopping.take() {
                return Err(self.end_path_stop(pending));
            }
            let at_speed = self.io.spindle_mut().is_some_and(|s| s.feedback().at_speed);
            if at_speed {
                break;
            }
            if self.t - waited_from > timeout {
                return Err(RunError::Spindle {
                    message: format!("did not reach {signed} rpm within {timeout} s"),
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
