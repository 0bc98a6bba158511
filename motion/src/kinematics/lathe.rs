//! Lathe kinematics: X (radius), Z, C (main spindle as rotary axis), Y and B (tool tilt).
//!
//! Lathe ops carry X as a radius (the DIN interpreter halves the programmed diameter), so a
//! lathe with a Y axis maps every program axis onto the machine axis of the same letter. A
//! lathe without a Y axis reaches a point off the X axis (Y ≠ 0, e.g. a slot on the face)
//! by turning the spindle: the point (x, y) in the plane normal to Z becomes the radius
//! X = s·√(x² + y²) and the extra spindle angle atan(y / x), with s the sign of x (1 at
//! x = 0), so that the map is continuous while the path does not cross the spindle axis and
//! reduces to the identity at y = 0 (turning on either side of the centre). B is the tool
//! tilt; the program pose is the tool tip, so B moves no linear axis here.

use super::Kinematics;
use klar_interp::{AxisLetter, Pose};

/// Lathe kinematics over machine axes named by program letter.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Lathe {
    axes: Vec<AxisLetter>,
    has_y: bool,
}

impl Lathe {
    /// Kinematics for the machine axes listed by letter, in machine order.
    pub fn new(axes: &[AxisLetter]) -> Lathe {
        Lathe {
            axes: axes.to_vec(),
            has_y: axes.contains(&AxisLetter::Y),
        }
    }

    /// (X radius, C degrees) for a point (x, y) at spindle angle c on a lathe without Y.
    fn polar(x: f64, y: f64, c: f64) -> (f64, f64) {
        if y == 0.0 {
            return (x, c);
        }
        let s = if x < 0.0 { -1.0 } else { 1.0 };
        let extra = if x == 0.0 {
            90.0f64.copysign(y)
        } else {
            (y / x).atan().to_degrees()
        };
        (s * x.hypot(y), c + extra)
    }
}

impl Kinematics for Lathe {
    fn machine_axes(&self) -> &[AxisLetter] {
        &self.axes
    }

    fn to_machine(&self, pose: &Pose, machine: &mut [f64]) {
        let (x, c) = if self.has_y {
            (pose[AxisLetter::X], pose[AxisLetter::C])
        } else {
            Self::polar(
                pose[AxisLetter::X],
                pose[AxisLetter::Y],
                pose[AxisLetter::C],
            )
        };
        for (m, &letter) in machine.iter_mut().zip(&self.axes) {
            *m = match letter {
                AxisLetter::X => x,
                AxisLetter::C => c,
                other => pose[other],
            };
        }
    }

    fn to_program(&self, machine: &[f64]) -> Pose {
        // without a Y axis the program point is read on the X axis (y = 0)
        let mut pose = Pose::ZERO;
        for (&m, &letter) in machine.iter().zip(&self.axes) {
            pose[letter] = m;
        }
        pose
    }

    fn rates_to_machine(&self, pose: &Pose, rates: &[f64; 9], machine: &mut [f64]) {
        let rate = |a: AxisLetter| rates[a.index()];
        let (x, y) = (pose[AxisLetter::X], pose[AxisLetter::Y]);
        let (xr, cr) = if self.has_y || (x == 0.0 && y == 0.0) {
            (rate(AxisLetter::X), rate(AxisLetter::C))
        } else {
            let rho2 = x * x + y * y;
            let rho = rho2.sqrt();
            let s = if x < 0.0 { -1.0 } else { 1.0 };
            let (vx, vy) = (rate(AxisLetter::X), rate(AxisLetter::Y));
            let k = 180.0 / std::f64::consts::PI;
            (
                s * (x * vx + y * vy) / rho,
                rate(AxisLetter::C) + k * (x * vy - y * vx) / rho2,
            )
        };
        for (m, &letter) in machine.iter_mut().zip(&self.axes) {
            *m = match letter {
                AxisLetter::X => xr,
                AxisLetter::C => cr,
                other => rate(other),
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FULL: [AxisLetter; 5] = [
        AxisLetter::X,
        AxisLetter::Z,
        AxisLetter::C,
        AxisLetter::Y,
        AxisLetter::B,
    ];
    const NO_Y: [AxisLetter; 3] = [AxisLetter::X, AxisLetter::Z, AxisLetter::C];

    fn pose(x: f64, y: f64, z: f64, c: f64, b: f64) -> Pose {
        let mut p = Pose::xyz(x, y, z);
        p.set(AxisLetter::C, c);
        p.set(AxisLetter::B, b);
        p
    }

    #[test]
    fn with_a_y_axis_every_letter_maps_to_itself() {
        let kin = Lathe::new(&FULL);
        let p = pose(25.0, -3.0, -12.0, 240.0, 45.0);
        let mut m = [0.0; 5];
        kin.to_machine(&p, &mut m);
        assert_eq!(m, [25.0, -12.0, 240.0, -3.0, 45.0]);
        assert_eq!(kin.to_program(&m), p);
    }

    #[test]
    fn without_y_a_face_point_is_reached_by_turning_c() {
        let kin = Lathe::new(&NO_Y);
        let mut m = [0.0; 3];
        // (3, 4) at C10: radius 5, C 10 + atan(4/3)
        kin.to_machine(&pose(3.0, 4.0, -1.0, 10.0, 0.0), &mut m);
        assert!((m[0] - 5.0).abs() < 1e-12);
        assert!((m[1] + 1.0).abs() < 1e-12);
        assert!((m[2] - 10.0 - 53.130_102_354_155_98).abs() < 1e-9);
        // on the X axis it is the identity, on both sides of the centre
        kin.to_machine(&pose(-7.0, 0.0, 2.0, 30.0, 0.0), &mut m);
        assert_eq!(m, [-7.0, 2.0, 30.0]);
        // (0, -2): radius 2, C − 90
        kin.to_machine(&pose(0.0, -2.0, 0.0, 0.0, 0.0), &mut m);
        assert!((m[0] - 2.0).abs() < 1e-12 && (m[2] + 90.0).abs() < 1e-12);
    }

    #[test]
    fn rates_are_the_derivative_of_the_map() {
        // finite differences of to_machine against rates_to_machine
        for axes in [&FULL[..], &NO_Y[..]] {
            let kin = Lathe::new(axes);
            let n = axes.len();
            for p in [
                pose(12.0, 5.0, -3.0, 20.0, 10.0),
                pose(-8.0, 2.5, 1.0, -40.0, 0.0),
                pose(30.0, 0.0, 0.0, 0.0, 0.0),
            ] {
                let mut v = [0.0; 9];
                v[AxisLetter::X.index()] = 1.5;
                v[AxisLetter::Y.index()] = -0.7;
                v[AxisLetter::Z.index()] = 2.0;
                v[AxisLetter::C.index()] = 3.0;
                v[AxisLetter::B.index()] = -1.0;
                let h = 1e-6;
                let mut ahead = p;
                let mut back = p;
                for a in AxisLetter::ALL {
                    ahead[a] += h * v[a.index()];
                    back[a] -= h * v[a.index()];
                }
                let mut m1 = vec![0.0; n];
                let mut m0 = vec![0.0; n];
                kin.to_machine(&ahead, &mut m1);
                kin.to_machine(&back, &mut m0);
                let mut r = vec![0.0; n];
                kin.rates_to_machine(&p, &v, &mut r);
                for i in 0..n {
                    let fd = (m1[i] - m0[i]) / (2.0 * h);
                    assert!((fd - r[i]).abs() < 1e-5, "axis {i}: {fd} vs {}", r[i]);
                }
            }
        }
    }
}
