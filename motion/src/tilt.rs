//! The tilted working plane at the end of radius compensation: ops of a tilted plane turned
//! into the untilted workpiece system.
//!
//! An interpreter with working-plane ops on (`Interpreter::set_working_plane_ops`) hands out
//! the ops of a tilted plane (PLANE, cycle 19) in the plane's own coordinates and marks every
//! change of the plane with [`OpKind::WorkingPlane`] where it takes effect. Radius
//! compensation and the APPR/DEP constructions work in those coordinates: the tilted plane's
//! X/Y is the plane normal to its tool axis, so the offsets, corner arcs and tangent arcs are
//! the ones a TNC makes on the inclined face. Only then are the points turned:
//! [`TiltStage`] follows the working-plane ops in the compensated stream and multiplies X Y Z
//! of every pose by the active rotation, so a point `p` of the tilted system lies at `R·p` in
//! the workpiece system. Since the rotation keeps lengths and angles, the compensated path
//! turned is the compensation of the turned contour.
//!
//! Lines stay lines. An arc (or helix) of a tilted plane lies in no principal plane of the
//! workpiece system, so it becomes a chain of lines within 1 µm of it. A spline stays a
//! spline with its coefficient vectors turned, which is exact (the polynomial is linear in
//! them). The working-plane ops themselves are consumed here: what leaves the stage is in
//! workpiece coordinates only. The turning itself is the interpreter's
//! ([`OpKind::in_workpiece`]), the same one it applies when it tilts its output itself.
//!
//! [`crate::comp::Compensator`] runs its output through this stage, so its users need only
//! switch the interpreter's working-plane ops on.

use klar_interp::{AxisLetter, Op, OpKind, Pose};
use std::collections::VecDeque;

/// A rotation matrix, row-major; its columns are the tilted X, Y, Z axes in the workpiece
/// system.
pub type Rotation = [[f64; 3]; 3];

/// The rotation of an untilted plane.
pub const IDENTITY: Rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// `r · v`.
pub fn apply(r: &Rotation, v: [f64; 3]) -> [f64; 3] {
    r.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
}

/// The transpose of `r` (its inverse, for a rotation).
pub fn transpose(r: &Rotation) -> Rotation {
    let mut t = [[0.0; 3]; 3];
    for (i, row) in r.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            t[j][i] = *v;
        }
    }
    t
}

/// `p` with X Y Z turned by `r`; the other axes unchanged.
pub fn turn(r: &Rotation, p: &Pose) -> Pose {
    let v = apply(r, [p[AxisLetter::X], p[AxisLetter::Y], p[AxisLetter::Z]]);
    let mut out = *p;
    out[AxisLetter::X] = v[0];
    out[AxisLetter::Y] = v[1];
    out[AxisLetter::Z] = v[2];
    out
}

/// A point `p` of the plane tilted by `from` in the coordinates of the plane tilted by `to`:
/// `toᵀ · from · p`.
pub fn reexpress(from: &Rotation, to: &Rotation, p: &Pose) -> Pose {
    turn(&transpose(to), &turn(from, p))
}

/// The streaming stage that turns ops of tilted planes into the workpiece system. See the
/// module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct TiltStage {
    rotation: Rotation,
}

impl Default for TiltStage {
    fn default() -> Self {
        TiltStage::new()
    }
}

impl TiltStage {
    /// A stage with the plane untilted.
    pub fn new() -> Self {
        TiltStage { rotation: IDENTITY }
    }

    /// The active rotation.
    pub fn rotation(&self) -> Rotation {
        self.rotation
    }

    /// Takes the next op and appends what it becomes in the workpiece system to `out`:
    /// nothing for a working-plane op (it sets the rotation for the ops after it), the op
    /// itself while the plane is untilted, else the turned op (an arc as several lines).
    pub fn push(&mut self, op: Op, out: &mut VecDeque<Op>) {
        match &op.kind {
            OpKind::WorkingPlane { rotation } => self.rotation = *rotation,
            _ if self.rotation == IDENTITY => out.push_back(op),
            kind => out.extend(
                kind.in_workpiece(&self.rotation)
                    .into_iter()
                    .map(|kind| Op { kind, loc: op.loc }),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use klar_interp::{Feed, Plane, SourceLoc, SplineAxis};

    /// Rotation about X by 30° (y → z): rows of Rx(30).
    fn rx30() -> Rotation {
        let (s, c) = 30f64.to_radians().sin_cos();
        [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
    }

    fn op(kind: OpKind) -> Op {
        Op {
            kind,
            loc: SourceLoc::default(),
        }
    }

    fn run(ops: Vec<OpKind>) -> Vec<OpKind> {
        let mut stage = TiltStage::new();
        let mut out = VecDeque::new();
        for k in ops {
            stage.push(op(k), &mut out);
        }
        out.into_iter().map(|o| o.kind).collect()
    }

    #[test]
    fn lines_are_turned_after_a_working_plane_op_and_not_before() {
        let line = OpKind::Line {
            from: Pose::xyz(0.0, 0.0, 0.0),
            to: Pose::xyz(0.0, 10.0, 0.0),
            feed: Feed::Rate(5.0),
        };
        let out = run(vec![
            line.clone(),
            OpKind::WorkingPlane { rotation: rx30() },
            line.clone(),
            OpKind::WorkingPlane { rotation: IDENTITY },
            line.clone(),
        ]);
        assert_eq!(out.len(), 3, "working-plane ops are consumed");
        assert_eq!(out[0], line);
        assert_eq!(out[2], line);
        let OpKind::Line { to, .. } = out[1] else {
            panic!("not a line: {:?}", out[1])
        };
        // (0, 10, 0) turned 30° about X: (0, 10·cos 30°, 10·sin 30°).
        assert!(to[AxisLetter::X].abs() < 1e-12);
        assert!((to[AxisLetter::Y] - 10.0 * 3f64.sqrt() / 2.0).abs() < 1e-12);
        assert!((to[AxisLetter::Z] - 5.0).abs() < 1e-12);
    }

    #[test]
    fn a_tilted_helix_becomes_lines_on_the_turned_helix() {
        // Half a turn of radius 5 about the origin rising 2 mm, in the plane tilted by Rx(30).
        let helix = OpKind::Arc {
            from: Pose::xyz(5.0, 0.0, 0.0),
            to: Pose::xyz(-5.0, 0.0, 2.0),
            center: [0.0, 0.0],
            plane: Plane::XY,
            sweep: 180.0,
            feed: Feed::Rate(5.0),
        };
        let out = run(vec![OpKind::WorkingPlane { rotation: rx30() }, helix]);
        assert!(out.len() > 10);
        let back = transpose(&rx30());
        for k in &out {
            let OpKind::Line { from, to, .. } = k else {
                panic!("not a line: {k:?}")
            };
            for p in [from, to] {
                // Back in the tilted system: on the cylinder r = 5, height = 2·angle/π.
                let q = turn(&back, p);
                let (x, y, z) = (q[AxisLetter::X], q[AxisLetter::Y], q[AxisLetter::Z]);
                assert!((x.hypot(y) - 5.0).abs() < 1e-9);
                let angle = y.atan2(x).rem_euclid(2.0 * std::f64::consts::PI);
                let angle = if angle > 3.2 { 0.0 } else { angle };
                assert!((z - 2.0 * angle / std::f64::consts::PI).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn a_tilted_spline_is_the_turned_polynomial() {
        // P(t) = (t³, 2t², 0) + (1, 0, 0) for t from 1 to 0, in the plane tilted by Rx(30).
        let spline = OpKind::Spline {
            from: Pose::xyz(2.0, 2.0, 0.0),
            to: Pose::xyz(1.0, 0.0, 0.0),
            axes: vec![
                SplineAxis {
                    axis: AxisLetter::X,
                    k: [1.0, 0.0, 0.0],
                },
                SplineAxis {
                    axis: AxisLetter::Y,
                    k: [0.0, 2.0, 0.0],
                },
            ],
            feed: Feed::Rate(5.0),
        };
        let out = run(vec![OpKind::WorkingPlane { rotation: rx30() }, spline]);
        let [OpKind::Spline { to, axes, .. }] = out.as_slice() else {
            panic!("not one spline: {out:?}")
        };
        let r = rx30();
        for t in [0.0, 0.25, 0.5, 1.0] {
            let expect = apply(&r, [t * t * t + 1.0, 2.0 * t * t, 0.0]);
            for (i, letter) in [AxisLetter::X, AxisLetter::Y, AxisLetter::Z]
                .into_iter()
                .enumerate()
            {
                let k = axes
                    .iter()
                    .find(|a| a.axis == letter)
                    .map_or([0.0; 3], |a| a.k);
                let v = k[0] * t * t * t + k[1] * t * t + k[2] * t + to[letter];
                assert!((v - expect[i]).abs() < 1e-12, "t {t} axis {letter}");
            }
        }
    }

    #[test]
    fn reexpress_moves_a_point_between_planes() {
        let p = Pose::xyz(1.0, 2.0, 3.0);
        let q = reexpress(&IDENTITY, &rx30(), &p);
        let back = turn(&rx30(), &q);
        for a in [AxisLetter::X, AxisLetter::Y, AxisLetter::Z] {
            assert!((back[a] - p[a]).abs() < 1e-12);
        }
    }
}
