//! Following the planner's steps the way the run does: samples through the run's command
//! path and setpoint guard, and thread passes at a steady spindle speed.

use super::TestRunReport;
use crate::config::MachineConfig;
use crate::runtime::command::{CommandPath, refused_in_check};
use crate::runtime::guard::Violation;
use crate::runtime::sync::SyncProfile;
use klar_interp::op::{SpindleDir, SpindleSpeed};
use klar_interp::{OpKind, SourceLoc};
use klar_motion::{Sample, Step};
use std::path::Path;

/// Follows one planner step the way the run does: events switch the kinematics, samples
/// become machine-axis setpoints through the run's own command path and its setpoint guard.
/// The run stops at the first setpoint the guard refuses, so the setpoint checks stop there
/// too; a soft-limit refusal at a line whose move the travel check has already reported is
/// the same problem and is not said twice.
pub(super) fn follow(
    command: &mut Option<CommandPath>,
    path: &Path,
    step: &Step,
    report: &mut TestRunReport,
    rpm: &mut f64,
    config: &MachineConfig,
) {
    let sample = match step {
        Step::Sample(s) => s,
        Step::Event(op) => {
            if let Some(c) = command {
                c.event(op);
            }
            if let OpKind::Spindle {
                spindle: klar_interp::op::SpindleId::Main,
                dir,
                speed,
            } = &op.kind
            {
                *rpm = signed_rpm(*dir, *speed, config);
            }
            if let Some(Ok(profile)) = SyncProfile::new(&op.kind, *rpm, config) {
                follow_sync(command, path, op.loc, report, &profile, *rpm, config);
            }
            return;
        }
    };
    report.planned_time = sample.t;
    let Some(c) = command else {
        return;
    };
    let Err(v) = c.positions(sample, sample.t) else {
        return;
    };
    let said = matches!(v, Violation::Travel { .. })
        && report
            .errors
            .iter()
            .any(|d| d.file == path && d.line == sample.loc.line);
    if !said {
        report.errors.push(refused_in_check(path, sample.loc, &v));
    }
    *command = None;
}

/// The main spindle's signed speed after a spindle op; under constant surface speed the
/// machine's highest speed or the G26 limit below it (the worst case for a thread pass).
pub(super) fn signed_rpm(dir: SpindleDir, speed: SpindleSpeed, config: &MachineConfig) -> f64 {
    let max = config.spindle.as_ref().map_or(0.0, |s| s.max_rpm);
    let rpm = match speed {
        SpindleSpeed::Rpm(r) => r,
        SpindleSpeed::SurfaceSpeed(_) => max,
        SpindleSpeed::SurfaceSpeedCapped(_, n) => n.min(max),
    };
    match dir {
        SpindleDir::Off => 0.0,
        SpindleDir::Cw => rpm,
        SpindleDir::Ccw => -rpm,
    }
}

/// Follows a thread pass the way the run does at a steady spindle speed `rpm`: its setpoints
/// go through the run's command path and guard.
fn follow_sync(
    command: &mut Option<CommandPath>,
    path: &Path,
    loc: SourceLoc,
    report: &mut TestRunReport,
    profile: &SyncProfile,
    rpm: f64,
    config: &MachineConfig,
) {
    let Some(c) = command else {
        return;
    };
    let w = rpm.abs() * 6.0;
    let step = w * config.servo_period;
    let total = profile.total_degrees();
    let mut k = 1.0;
    loop {
        let phi = (k * step).min(total);
        let (s, rate) = profile.at(phi);
        let sample = Sample {
            t: report.planned_time,
            pose: profile.pose(s),
            velocity: profile.velocity(rate, w),
            acceleration: [0.0; 9],
            loc,
        };
        if let Err(v) = c.positions(&sample, sample.t) {
            report.errors.push(refused_in_check(path, loc, &v));
            *command = None;
            return;
        }
        if phi >= total {
            return;
        }
        k += 1.0;
    }
}
