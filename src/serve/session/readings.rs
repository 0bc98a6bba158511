//! What the snapshot shows of a run besides its positions: the spindle (commanded and
//! measured), the tool in the frame of the program's path, and the last touch-probe results.

use super::MachineLoop;
use super::spindle::SpindleStatus;
use crate::config::MachineConfig;
use crate::runtime::Run;
use klar_interp::AxisLetter;

/// The tool (X, Y, Z) in the frame of the program's path for machine positions `at` (the
/// machine's inverse kinematics; the identity on a Cartesian mill and on a lathe).
pub fn tool_of(config: &MachineConfig, at: &[f64]) -> [f64; 3] {
    let p = config.kinematics().to_program(at);
    [p[AxisLetter::X], p[AxisLetter::Y], p[AxisLetter::Z]]
}

impl MachineLoop {
    /// Reads the spindle, the tool and the probe results of `run` into the snapshot.
    pub(super) fn read_run(&mut self, run: &mut Run<'_, '_>, measured_rpm: Option<f64>) {
        self.snap.spindle = run
            .spindle_commanded()
            .map(|c| SpindleStatus::of(c, measured_rpm.unwrap_or(0.0)));
        self.snap.tool = run.tool_position();
        if let Some(last) = run.probe_results().last()
            && self.snap.probe.as_ref() != Some(last)
        {
            self.snap.probe = Some(last.clone());
        }
    }
}
