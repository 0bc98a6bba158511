//! What the snapshot shows of a run besides its positions: the spindle (commanded and
//! measured), the tool in the frame of the program's path, and the last touch-probe results.

use super::Derivatives;
use super::publisher::Record;
use super::spindle::SpindleStatus;
use crate::config::MachineConfig;
use crate::runtime::{Run, RunStatus};
use klar_interp::AxisLetter;

/// The tool (X, Y, Z) in the frame of the program's path for machine positions `at` (the
/// machine's inverse kinematics; the identity on a Cartesian mill and on a lathe).
pub fn tool_of(config: &MachineConfig, at: &[f64]) -> [f64; 3] {
    let p = config.kinematics().to_program(at);
    [p[AxisLetter::X], p[AxisLetter::Y], p[AxisLetter::Z]]
}

/// Reads a servo cycle of `run` into `record`: its status, the commanded velocities and
/// accelerations, the spindle and the tool (allocating nothing once `record` is sized for
/// the machine).
pub(super) fn read_cycle(
    record: &mut Record,
    status: &RunStatus,
    d: &Derivatives,
    run: &mut Run<'_, '_>,
) {
    record.held = status.held;
    record.t = status.t;
    record.line = status.line;
    record.blocks = status.blocks;
    record.commanded.clone_from(&status.commanded);
    record.actual.clone_from(&status.actual);
    record.following_error.clone_from(&status.following_error);
    record.velocity.clone_from(&d.velocity);
    record.acceleration.clone_from(&d.acceleration);
    record.path_speed = status.path_speed;
    record.feed_override = status.feed_override;
    record.spindle_rpm = status.spindle_rpm;
    record.spindle = run
        .spindle_commanded()
        .map(|c| SpindleStatus::of(c, status.spindle_rpm.unwrap_or(0.0)));
    record.tool = run.tool_position();
}
