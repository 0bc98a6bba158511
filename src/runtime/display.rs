//! What displays read of a run beyond [`super::RunStatus`]: the tool position in the frame
//! of the program's path, the touch-probe results, and the spindle, which a display may
//! hand in before the run and take back after it (a spindle kept turning between runs).

use super::Run;
use crate::machine::Spindle;
use klar_interp::{AxisLetter, ProbeResult};

impl Run<'_, '_> {
    /// The tool's measured position (X, Y, Z) in the frame of the interpreter's motion
    /// ops, the frame of the program's path: the machine positions through the inverse
    /// kinematics (the identity on a Cartesian mill and on a lathe: X a radius there).
    pub fn tool_position(&self) -> [f64; 3] {
        let p = self.command.kinematics().to_program(&self.actual);
        [p[AxisLetter::X], p[AxisLetter::Y], p[AxisLetter::Z]]
    }

    /// What the touch-probe cycles measured so far, in the order they ran.
    pub fn probe_results(&self) -> &[ProbeResult] {
        &self.report.probe_results
    }

    /// Puts `spindle` in place of the run's spindle and returns the run's. Handed in right
    /// after [`Run::start`], a spindle turning from before keeps turning under the run's
    /// commands; taken out (`None`) before [`Run::finish`], it is not stopped there.
    pub fn swap_spindle(&mut self, spindle: Option<Spindle>) -> Option<Spindle> {
        self.io.replace_spindle(spindle)
    }

    /// The spindle's commanded speed, signed rpm, when the machine has a spindle.
    pub fn spindle_commanded(&mut self) -> Option<f64> {
        self.io.spindle_mut().map(|s| s.commanded())
    }
}
