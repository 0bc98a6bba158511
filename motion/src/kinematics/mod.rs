//! Kinematics: the mapping between program poses (tool tip in program axes) and machine axis
//! positions. Implementations: [`Cartesian`] (mills whose axes are the program axes) and
//! [`Lathe`] (X radius, Z, C, Y, B; C turns face points onto X on lathes without Y). 5-axis
//! head/table kinematics implement the same trait.

pub mod cartesian;
pub mod lathe;
pub mod table_table;

pub use cartesian::Cartesian;
pub use lathe::Lathe;
pub use table_table::{TableTable, TiltAxis};

use klar_interp::{AxisLetter, Pose};

/// Maps program poses to machine axis positions and back.
///
/// Machine axes are numbered `0..machine_axes().len()` in the order the machine lists them;
/// slices of machine values follow that order. Slices shorter than the axis list are filled
/// or read as far as they reach (the caller sizes them from [`Kinematics::machine_axes`]).
pub trait Kinematics {
    /// The machine axes, by letter, in machine order.
    fn machine_axes(&self) -> &[AxisLetter];

    /// Machine axis positions for a program pose.
    fn to_machine(&self, pose: &Pose, machine: &mut [f64]);

    /// The program pose of machine axis positions; program axes the machine lacks are zero.
    fn to_program(&self, machine: &[f64]) -> Pose;

    /// Machine axis velocities (or accelerations) for program-axis rates at `pose`: the
    /// Jacobian of [`Kinematics::to_machine`] applied to `rates`.
    fn rates_to_machine(&self, pose: &Pose, rates: &[f64; 9], machine: &mut [f64]);

    /// Switches tool centre point management (M128 / FUNCTION TCPM) on or off. Kinematics
    /// without rotary axes that move the workpiece ignore it (the default).
    fn set_tcpm(&mut self, _on: bool) {}
}
