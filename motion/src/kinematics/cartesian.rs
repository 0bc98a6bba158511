//! Cartesian mill kinematics: each machine axis is the program axis of the same letter.

use super::Kinematics;
use klar_interp::{AxisLetter, Pose};

/// Identity kinematics over a list of machine axes named by program letter.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cartesian {
    axes: Vec<AxisLetter>,
}

impl Cartesian {
    /// Kinematics for machine axes listed by letter, in machine order.
    pub fn new(axes: &[AxisLetter]) -> Cartesian {
        Cartesian {
            axes: axes.to_vec(),
        }
    }
}

impl Kinematics for Cartesian {
    fn machine_axes(&self) -> &[AxisLetter] {
        &self.axes
    }

    fn to_machine(&self, pose: &Pose, machine: &mut [f64]) {
        for (m, &letter) in machine.iter_mut().zip(&self.axes) {
            *m = pose[letter];
        }
    }

    fn to_program(&self, machine: &[f64]) -> Pose {
        let mut pose = Pose::ZERO;
        for (&m, &letter) in machine.iter().zip(&self.axes) {
            pose[letter] = m;
        }
        pose
    }

    fn rates_to_machine(&self, _pose: &Pose, rates: &[f64; 9], machine: &mut [f64]) {
        for (m, &letter) in machine.iter_mut().zip(&self.axes) {
            *m = rates[letter.index()];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn machine_values_follow_the_listed_letters() {
        let kin = Cartesian::new(&[AxisLetter::X, AxisLetter::Z, AxisLetter::C]);
        let mut pose = Pose::xyz(1.5, -2.0, 3.25);
        pose.set(AxisLetter::C, 90.0);
        let mut m = [0.0; 3];
        kin.to_machine(&pose, &mut m);
        assert_eq!(m, [1.5, 3.25, 90.0]);
        // Back: Y is not a machine axis, so it reads as zero.
        let back = kin.to_program(&m);
        let mut expect = Pose::xyz(1.5, 0.0, 3.25);
        expect.set(AxisLetter::C, 90.0);
        assert_eq!(back, expect);
        let mut rates = [0.0; 9];
        rates[AxisLetter::Z.index()] = 7.0;
        rates[AxisLetter::Y.index()] = 5.0;
        kin.rates_to_machine(&pose, &rates, &mut m);
        assert_eq!(m, [0.0, 7.0, 0.0]);
        assert_eq!(
            kin.machine_axes(),
            &[AxisLetter::X, AxisLetter::Z, AxisLetter::C]
        );
    }

    #[test]
    fn short_slices_are_filled_as_far_as_they_reach() {
        let kin = Cartesian::new(&[AxisLetter::X, AxisLetter::Y]);
        let mut m = [0.0; 1];
        kin.to_machine(&Pose::xyz(4.0, 5.0, 6.0), &mut m);
        assert_eq!(m, [4.0]);
        assert_eq!(kin.to_program(&[4.0]), Pose::xyz(4.0, 0.0, 0.0));
    }
}
