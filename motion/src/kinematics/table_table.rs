//! Table-table 5-axis kinematics: X Y Z move the tool, the workpiece sits on a rotary table
//! (C, about Z) that is carried by a tilting cradle (A about X, or B about Y).
//!
//! Angle convention: a positive table angle turns the *workpiece* in the negative sense about
//! its axis, so that the tool, seen from the workpiece, turns in the positive sense — the same
//! relative motion a swivel head with the unprimed axis would make (the primed table axes of
//! DIN 66217). With tilt angle `t` and table angle `c` the rotation that carries workpiece
//! directions into machine directions is `M = R_tilt(−t) · R_z(−c)`, and the tool axis (machine
//! +Z) seen from the workpiece is `R_z(c) · R_tilt(t) · Z`.
//!
//! Geometry: at zero angles the workpiece frame is the machine frame. The tilt axis is the
//! line through `tilt_pivot` parallel to X (A) or Y (B); the table axis is the line through
//! `table_pivot` parallel to Z, both in machine coordinates at zero angles. A workpiece point
//! `p` then lies at the machine position
//!
//! ```text
//! m = P_t + R_tilt(−t) · ((P_c − P_t) + R_z(−c) · (p − P_c))
//! ```
//!
//! With TCPM off (the default) the kinematics passes every axis through, like
//! [`super::Cartesian`]: program X Y Z are machine X Y Z and turning the table leaves the tool
//! where it is. With TCPM on (M128, FUNCTION TCPM) program X Y Z are the tool tip in workpiece
//! coordinates and the linear axes follow the formula above, so that the tool tip stays on the
//! programmed point of the workpiece while the table turns.

use super::Kinematics;
use klar_interp::{AxisLetter, Pose};
use nalgebra::{Matrix3, Vector3};

/// Which axis tilts the cradle that carries the rotary table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TiltAxis {
    /// A: the cradle turns about a line parallel to X.
    A,
    /// B: the cradle turns about a line parallel to Y.
    B,
}

impl TiltAxis {
    /// The program letter of the tilt axis.
    pub fn letter(self) -> AxisLetter {
        match self {
            TiltAxis::A => AxisLetter::A,
            TiltAxis::B => AxisLetter::B,
        }
    }

    /// Rotation by `deg` degrees about the tilt axis direction (right-hand rule).
    pub fn rotation(self, deg: f64) -> Matrix3<f64> {
        match self {
            TiltAxis::A => rot_x(deg),
            TiltAxis::B => rot_y(deg),
        }
    }

    /// The unit direction of the tilt axis.
    fn direction(self) -> Vector3<f64> {
        match self {
            TiltAxis::A => Vector3::x(),
            TiltAxis::B => Vector3::y(),
        }
    }
}

/// Rotation by `deg` degrees about X (right-hand rule).
pub fn rot_x(deg: f64) -> Matrix3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

/// Rotation by `deg` degrees about Y (right-hand rule).
pub fn rot_y(deg: f64) -> Matrix3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// Rotation by `deg` degrees about Z (right-hand rule).
pub fn rot_z(deg: f64) -> Matrix3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// The skew matrix `K` of a unit vector `u` (`K·v = u × v`).
fn skew(u: Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -u.z, u.y, u.z, 0.0, -u.x, -u.y, u.x, 0.0)
}

/// Table-table kinematics over machine axes named by program letter (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct TableTable {
    axes: Vec<AxisLetter>,
    tilt: TiltAxis,
    tilt_pivot: Vector3<f64>,
    table_pivot: Vector3<f64>,
    tcpm: bool,
}

impl TableTable {
    /// Kinematics for the machine axes listed by letter (in machine order), the tilt axis,
    /// a point on the tilt axis and a point on the table axis (machine coordinates, mm, at
    /// zero angles). TCPM starts off.
    pub fn new(
        axes: &[AxisLetter],
        tilt: TiltAxis,
        tilt_pivot: [f64; 3],
        table_pivot: [f64; 3],
    ) -> TableTable {
        TableTable {
            axes: axes.to_vec(),
            tilt,
            tilt_pivot: Vector3::from(tilt_pivot),
            table_pivot: Vector3::from(table_pivot),
            tcpm: false,
        }
    }

    /// The tilt axis.
    pub fn tilt(&self) -> TiltAxis {
        self.tilt
    }

    /// True while TCPM is on.
    pub fn tcpm(&self) -> bool {
        self.tcpm
    }

    /// Machine X Y Z of the workpiece point `p` at tilt angle `t` and table angle `c`
    /// (degrees): the formula of the module docs.
    pub fn tip_to_machine(&self, p: Vector3<f64>, t: f64, c: f64) -> Vector3<f64> {
        let q = (self.table_pivot - self.tilt_pivot) + rot_z(-c) * (p - self.table_pivot);
        self.tilt_pivot + self.tilt.rotation(-t) * q
    }

    /// The workpiece point under machine X Y Z `m` at tilt angle `t` and table angle `c`:
    /// the inverse of [`TableTable::tip_to_machine`].
    pub fn machine_to_tip(&self, m: Vector3<f64>, t: f64, c: f64) -> Vector3<f64> {
        let q = self.tilt.rotation(t) * (m - self.tilt_pivot);
        self.table_pivot + rot_z(c) * (q - (self.table_pivot - self.tilt_pivot))
    }

    fn angles(&self, pose: &Pose) -> (f64, f64) {
        (pose[self.tilt.letter()], pose[AxisLetter::C])
    }
}

fn xyz(pose: &Pose) -> Vector3<f64> {
    Vector3::new(
        pose[AxisLetter::X],
        pose[AxisLetter::Y],
        pose[AxisLetter::Z],
    )
}

/// The machine value for `letter` given the transformed X Y Z, else the pose's own value.
fn pick(letter: AxisLetter, m: &Vector3<f64>, pose: &Pose) -> f64 {
    match letter {
        AxisLetter::X => m.x,
        AxisLetter::Y => m.y,
        AxisLetter::Z => m.z,
        other => pose[other],
    }
}

impl Kinematics for TableTable {
    fn machine_axes(&self) -> &[AxisLetter] {
        &self.axes
    }

    fn to_machine(&self, pose: &Pose, machine: &mut [f64]) {
        let m = if self.tcpm {
            let (t, c) = self.angles(pose);
            self.tip_to_machine(xyz(pose), t, c)
        } else {
            xyz(pose)
        };
        for (out, &letter) in machine.iter_mut().zip(&self.axes) {
            *out = pick(letter, &m, pose);
        }
    }

    fn to_program(&self, machine: &[f64]) -> Pose {
        let mut pose = Pose::ZERO;
        for (&m, &letter) in machine.iter().zip(&self.axes) {
            pose[letter] = m;
        }
        if self.tcpm {
            let (t, c) = self.angles(&pose);
            let p = self.machine_to_tip(xyz(&pose), t, c);
            pose[AxisLetter::X] = p.x;
            pose[AxisLetter::Y] = p.y;
            pose[AxisLetter::Z] = p.z;
        }
        pose
    }

    fn rates_to_machine(&self, pose: &Pose, rates: &[f64; 9], machine: &mut [f64]) {
        let v = Vector3::new(
            rates[AxisLetter::X.index()],
            rates[AxisLetter::Y.index()],
            rates[AxisLetter::Z.index()],
        );
        let m = if self.tcpm {
            // d/dθ R(θ) = R(θ)·K for a rotation about unit u with skew K; the angles are in
            // degrees, so each angular rate is converted to rad first.
            let (t, c) = self.angles(pose);
            let p = xyz(pose);
            let rt = self.tilt.rotation(-t);
            let rc = rot_z(-c);
            let q = (self.table_pivot - self.tilt_pivot) + rc * (p - self.table_pivot);
            let t_dot = rates[self.tilt.letter().index()].to_radians();
            let c_dot = rates[AxisLetter::C.index()].to_radians();
            let kt = skew(self.tilt.direction());
            let kz = skew(Vector3::z());
            rt * rc * v - rt * kt * q * t_dot - rt * rc * kz * (p - self.table_pivot) * c_dot
        } else {
            v
        };
        let mut shown = Pose::ZERO;
        shown.0 = *rates;
        for (out, &letter) in machine.iter_mut().zip(&self.axes) {
            *out = pick(letter, &m, &shown);
        }
    }

    fn set_tcpm(&mut self, on: bool) {
        self.tcpm = on;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const AXES: [AxisLetter; 5] = [
        AxisLetter::X,
        AxisLetter::Y,
        AxisLetter::Z,
        AxisLetter::A,
        AxisLetter::C,
    ];

    fn pose(x: f64, y: f64, z: f64, t: (AxisLetter, f64), c: f64) -> Pose {
        let mut p = Pose::xyz(x, y, z);
        p.set(t.0, t.1);
        p.set(AxisLetter::C, c);
        p
    }

    fn close(a: &[f64], b: &[f64], tol: f64) {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() < tol, "{a:?} vs {b:?}");
        }
    }

    #[test]
    fn without_tcpm_axes_pass_through() {
        let kin = TableTable::new(&AXES, TiltAxis::A, [0.0, 0.0, -50.0], [10.0, 0.0, 0.0]);
        let p = pose(1.0, 2.0, 3.0, (AxisLetter::A, 30.0), 45.0);
        let mut m = [0.0; 5];
        kin.to_machine(&p, &mut m);
        assert_eq!(m, [1.0, 2.0, 3.0, 30.0, 45.0]);
        assert_eq!(kin.to_program(&m), p);
    }

    #[test]
    fn ac_table_with_pivots_at_origin_rotates_by_hand_matrices() {
        let mut kin = TableTable::new(&AXES, TiltAxis::A, [0.0; 3], [0.0; 3]);
        kin.set_tcpm(true);
        // A = 90: the workpiece turns by −90° about X, so workpiece +Y lies along machine −Z
        // and workpiece +Z along machine +Y.
        let mut m = [0.0; 5];
        kin.to_machine(&pose(0.0, 10.0, 0.0, (AxisLetter::A, 90.0), 0.0), &mut m);
        close(&m, &[0.0, 0.0, -10.0, 90.0, 0.0], 1e-12);
        kin.to_machine(&pose(0.0, 0.0, 10.0, (AxisLetter::A, 90.0), 0.0), &mut m);
        close(&m, &[0.0, 10.0, 0.0, 90.0, 0.0], 1e-12);
        // C = 90: the workpiece turns by −90° about Z: workpiece +X lies along machine −Y.
        kin.to_machine(&pose(10.0, 0.0, 5.0, (AxisLetter::A, 0.0), 90.0), &mut m);
        close(&m, &[0.0, -10.0, 5.0, 0.0, 90.0], 1e-12);
        // A = 30, C = 60 with matrices written out by hand (cos 30 = √3/2, sin 30 = 1/2).
        let (s3, h) = (3f64.sqrt() / 2.0, 0.5);
        let rx_m30 = Matrix3::new(1.0, 0.0, 0.0, 0.0, s3, h, 0.0, -h, s3);
        let rz_m60 = Matrix3::new(h, s3, 0.0, -s3, h, 0.0, 0.0, 0.0, 1.0);
        let p = Vector3::new(12.0, -7.0, 4.0);
        let expect = rx_m30 * rz_m60 * p;
        kin.to_machine(&pose(12.0, -7.0, 4.0, (AxisLetter::A, 30.0), 60.0), &mut m);
        close(&m, &[expect.x, expect.y, expect.z, 30.0, 60.0], 1e-12);
    }

    #[test]
    fn bc_table_with_offset_pivots() {
        let axes = [
            AxisLetter::X,
            AxisLetter::Y,
            AxisLetter::Z,
            AxisLetter::B,
            AxisLetter::C,
        ];
        let pt = [0.0, 0.0, -100.0];
        let pc = [20.0, 30.0, 0.0];
        let mut kin = TableTable::new(&axes, TiltAxis::B, pt, pc);
        kin.set_tcpm(true);
        // B = 90: turning by −90° about Y maps (x, y, z) to (−z, y, x) about the pivot.
        // The table centre (20, 30, 0) is 100 above the tilt line: it ends at (−100, 30, −80).
        let mut m = [0.0; 5];
        kin.to_machine(&pose(20.0, 30.0, 0.0, (AxisLetter::B, 90.0), 0.0), &mut m);
        close(&m, &[-100.0, 30.0, -80.0, 90.0, 0.0], 1e-9);
        // C = 180 first swings (25, 30, 0) to (15, 30, 0), then B = 90 maps it like above.
        kin.to_machine(&pose(25.0, 30.0, 0.0, (AxisLetter::B, 90.0), 180.0), &mut m);
        close(&m, &[-100.0, 30.0, -85.0, 90.0, 180.0], 1e-9);
    }

    #[test]
    fn inverse_after_forward_is_identity() {
        let mut kin = TableTable::new(&AXES, TiltAxis::A, [3.0, -4.0, -80.0], [5.0, 7.0, 0.0]);
        kin.set_tcpm(true);
        for &(x, y, z, a, c) in &[
            (0.0, 0.0, 0.0, 0.0, 0.0),
            (12.5, -40.0, 7.0, 35.0, -120.0),
            (-90.0, 33.0, -15.0, -95.0, 400.0),
        ] {
            let p = pose(x, y, z, (AxisLetter::A, a), c);
            let mut m = [0.0; 5];
            kin.to_machine(&p, &mut m);
            let back = kin.to_program(&m);
            close(&back.0, &p.0, 1e-9);
        }
    }

    #[test]
    fn rates_match_finite_differences() {
        let mut kin = TableTable::new(&AXES, TiltAxis::A, [3.0, -4.0, -80.0], [5.0, 7.0, 0.0]);
        kin.set_tcpm(true);
        let p = pose(12.0, -8.0, 6.0, (AxisLetter::A, 25.0), 70.0);
        let mut rates = [0.0; 9];
        rates[0] = 3.0;
        rates[1] = -2.0;
        rates[2] = 1.0;
        rates[AxisLetter::A.index()] = 10.0;
        rates[AxisLetter::C.index()] = -20.0;
        let mut analytic = [0.0; 5];
        kin.rates_to_machine(&p, &rates, &mut analytic);
        let h = 1e-6;
        let mut ahead = p;
        let mut behind = p;
        for (i, r) in rates.iter().enumerate() {
            ahead.0[i] += h * r;
            behind.0[i] -= h * r;
        }
        let (mut m1, mut m0) = ([0.0; 5], [0.0; 5]);
        kin.to_machine(&ahead, &mut m1);
        kin.to_machine(&behind, &mut m0);
        let numeric: Vec<f64> = m1
            .iter()
            .zip(&m0)
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect();
        close(&analytic, &numeric, 1e-5);
    }

    #[test]
    fn tool_axis_seen_from_the_workpiece() {
        // M^T · Z must equal R_z(c)·R_x(a)·Z = (sin a sin c, −sin a cos c, cos a).
        let (a, c) = (40.0f64, 25.0f64);
        let m = rot_x(-a) * rot_z(-c);
        let n = m.transpose() * Vector3::z();
        let (sa, ca) = a.to_radians().sin_cos();
        let (sc, cc) = c.to_radians().sin_cos();
        close(n.as_slice(), &[sa * sc, -sa * cc, ca], 1e-12);
    }
}
