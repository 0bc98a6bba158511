//! The coordinate transforms of the Klartext cycles 7 (datum shift), 8 (mirror image),
//! 10 (rotation), 11 (scaling), 26 (axis-specific scaling) and 247 (preset), applied to the
//! emitted ops.
//!
//! The executor keeps program coordinates (position, pole, tangent); only the ops handed to
//! motion are mapped. A program point `p` becomes the machine point
//!
//! ```text
//! x = preset + Basic · (shift + Mirror · Rotation · (centre + Scale · (p − centre)))
//! ```
//!
//! i.e. the point is first scaled about the scaling centre (the datum for cycle 11, CCX/CCY
//! for cycle 26), then rotated in the working plane about the datum, then mirrored about the
//! datum, then shifted by the datum shift, turned by the preset's basic rotation about the
//! tool axis Z (written by touch-probe cycle 400) and shifted by the active preset. The order is fixed: it is the
//! chain "datum shift, then mirror, then rotation, then scaling" of the TNC's coordinate
//! transformation cycles, each acting in the system the previous ones set up, whatever order
//! the cycles were defined in.
//!
//! Effects on the geometry beyond the points:
//! - an arc keeps its centre as a point; its direction reverses when exactly one of its two
//!   plane axes is mirrored; its plane must be the rotation plane when a rotation is active;
//!   cycle 26 must scale both of its plane axes by the same factor (an arc cannot become an
//!   ellipse), otherwise the block is refused;
//! - radius compensation swaps sides (RL ↔ RR) when exactly one axis of the working plane is
//!   mirrored, because mirroring reverses the direction of travel around the contour; the
//!   APPR/DEP side swaps likewise and their lengths and radii scale with the plane factor;
//! - spline coefficients are direction vectors: they take the linear part only.

use super::op_points::map_points;
use crate::op::{ApproachShape, CompSide, OpKind, Plane, Pose};

/// Tolerance for "same scaling factor" on the two axes of an arc's plane.
const SAME_FACTOR: f64 = 1e-12;

/// The active transform chain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Transform {
    /// Preset (cycle 247), per axis, mm or degrees.
    pub preset: [f64; 9],
    /// Datum shift (cycle 7), per axis.
    pub shift: [f64; 9],
    /// Basic rotation of the active preset about Z, degrees (touch-probe cycle 400, the
    /// preset table's ROT column).
    pub basic_rot: f64,
    /// Mirrored axes X, Y, Z (cycle 8).
    pub mirror: [bool; 3],
    /// Rotation about the tool axis of `plane`, degrees (cycle 10).
    pub rot: f64,
    /// The working plane when a transform cycle was last defined (rotation plane, and the
    /// plane whose mirroring swaps the compensation side).
    pub plane: Plane,
    /// Scaling factors of X, Y, Z (cycles 11 and 26).
    pub scale: [f64; 3],
    /// Scaling centre (program coordinates of X, Y, Z).
    pub centre: [f64; 3],
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            preset: [0.0; 9],
            shift: [0.0; 9],
            basic_rot: 0.0,
            mirror: [false; 3],
            rot: 0.0,
            plane: Plane::XY,
            scale: [1.0; 3],
            centre: [0.0; 3],
        }
    }
}

/// Turns `q` (X, Y, Z) about Z by `deg` degrees (counter-clockwise seen from +Z).
fn turn_xy(q: &mut [f64; 3], deg: f64) {
    if deg != 0.0 {
        let (s, c) = deg.to_radians().sin_cos();
        let (x, y) = (q[0], q[1]);
        q[0] = x * c - y * s;
        q[1] = x * s + y * c;
    }
}

/// Indices of the plane's (first, second) axes in a pose.
fn plane_idx(plane: Plane) -> (usize, usize) {
    let (a, b, _) = plane.axes();
    (a.index(), b.index())
}

impl Transform {
    /// True when the chain changes nothing.
    pub fn is_identity(&self) -> bool {
        self.preset.iter().all(|v| *v == 0.0)
            && self.shift.iter().all(|v| *v == 0.0)
            && !self.mirror.iter().any(|m| *m)
            && self.rot == 0.0
            && self.basic_rot == 0.0
            && self.scale.iter().all(|f| *f == 1.0)
    }

    /// True when exactly one of the two axes of `plane` is mirrored.
    pub fn flips(&self, plane: Plane) -> bool {
        let (a, b) = plane_idx(plane);
        let m = |i: usize| self.mirror.get(i).copied().unwrap_or(false);
        m(a) != m(b)
    }

    /// Rotation, mirror and scaling of a direction `v` (X, Y, Z): the linear part.
    pub fn linear(&self, v: [f64; 3]) -> [f64; 3] {
        let mut q = v;
        for (x, f) in q.iter_mut().zip(self.scale) {
            *x *= f;
        }
        self.rotate_mirror(&mut q);
        turn_xy(&mut q, self.basic_rot);
        q
    }

    fn rotate_mirror(&self, q: &mut [f64; 3]) {
        if self.rot != 0.0 {
            let (a, b) = plane_idx(self.plane);
            let (s, c) = self.rot.to_radians().sin_cos();
            if let (Some(&x), Some(&y)) = (q.get(a), q.get(b)) {
                q[a] = x * c - y * s;
                q[b] = x * s + y * c;
            }
        }
        for (x, m) in q.iter_mut().zip(self.mirror) {
            if m {
                *x = -*x;
            }
        }
    }

    /// Program point → machine point.
    pub fn map_point(&self, p: &Pose) -> Pose {
        let mut out = p.0;
        let mut q = [0.0; 3];
        for (i, v) in q.iter_mut().enumerate() {
            *v = self.centre[i] + self.scale[i] * (p.0[i] - self.centre[i]);
        }
        self.rotate_mirror(&mut q);
        for (i, v) in q.iter_mut().enumerate() {
            *v += self.shift[i];
        }
        turn_xy(&mut q, self.basic_rot);
        out[..3].copy_from_slice(&q);
        for (i, x) in out.iter_mut().enumerate() {
            *x += self.preset[i] + if i < 3 { 0.0 } else { self.shift[i] };
        }
        Pose(out)
    }

    /// Machine point → program point (the inverse of [`Transform::map_point`]; scaling
    /// factors are never zero).
    pub fn unmap_point(&self, x: &Pose) -> Pose {
        let mut out = x.0;
        for (i, v) in out.iter_mut().enumerate() {
            *v -= self.preset[i] + if i < 3 { 0.0 } else { self.shift[i] };
        }
        let mut q = [out[0], out[1], out[2]];
        turn_xy(&mut q, -self.basic_rot);
        for (i, v) in q.iter_mut().enumerate() {
            *v -= self.shift[i];
        }
        for (v, m) in q.iter_mut().zip(self.mirror) {
            if m {
                *v = -*v;
            }
        }
        if self.rot != 0.0 {
            let (a, b) = plane_idx(self.plane);
            let (s, c) = (-self.rot).to_radians().sin_cos();
            if let (Some(&u), Some(&w)) = (q.get(a), q.get(b)) {
                q[a] = u * c - w * s;
                q[b] = u * s + w * c;
            }
        }
        for (i, v) in q.iter_mut().enumerate() {
            *v = self.centre[i] + (*v - self.centre[i]) / self.scale[i];
        }
        out[..3].copy_from_slice(&q);
        Pose(out)
    }

    /// The common scaling factor of the plane's axes, or an error when they differ.
    fn plane_factor(&self, plane: Plane, what: &str) -> Result<f64, String> {
        let (a, b) = plane_idx(plane);
        let (fa, fb) = (
            self.scale.get(a).copied().unwrap_or(1.0),
            self.scale.get(b).copied().unwrap_or(1.0),
        );
        if (fa - fb).abs() > SAME_FACTOR {
            return Err(format!(
                "{what} cannot be scaled with different factors on its plane axes ({fa} and {fb}): it would not stay circular"
            ));
        }
        Ok(fa)
    }

    fn swap(side: CompSide) -> CompSide {
        match side {
            CompSide::Left => CompSide::Right,
            CompSide::Right => CompSide::Left,
            CompSide::Off => CompSide::Off,
        }
    }

    fn map_shape(&self, shape: ApproachShape, f: f64) -> ApproachShape {
        match shape {
            ApproachShape::LineTangent { len } => ApproachShape::LineTangent { len: len * f },
            ApproachShape::LineNormal { len } => ApproachShape::LineNormal { len: len * f },
            ApproachShape::CircleTangent { cca, radius } => ApproachShape::CircleTangent {
                cca,
                radius: radius * f,
            },
            ApproachShape::LineCircleTangent { radius } => {
                ApproachShape::LineCircleTangent { radius: radius * f }
            }
        }
    }

    /// Maps one op from program to machine coordinates.
    ///
    /// Fails for an arc (or APPR/DEP arc) whose plane axes are scaled differently, and for an
    /// arc outside the rotation plane while a rotation is active.
    pub fn map_op(&self, kind: &OpKind) -> Result<OpKind, String> {
        Ok(match kind {
            OpKind::Line { .. } | OpKind::Spline { .. } => self.map_points(kind),
            OpKind::Arc {
                from,
                to,
                center,
                plane,
                sweep,
                feed,
            } => {
                if self.rot != 0.0 && *plane != self.plane {
                    return Err(format!(
                        "an arc in the {plane:?} plane cannot be turned by a rotation in the {:?} plane",
                        self.plane
                    ));
                }
                if self.basic_rot != 0.0 && *plane != Plane::XY {
                    return Err(format!(
                        "an arc in the {plane:?} plane cannot be turned by the basic rotation about Z"
                    ));
                }
                self.plane_factor(*plane, "an arc")?;
                let (a, b) = plane_idx(*plane);
                let mut c = *from;
                c.0[a] = center[0];
                c.0[b] = center[1];
                let c = self.map_point(&c);
                OpKind::Arc {
                    from: self.map_point(from),
                    to: self.map_point(to),
                    center: [c.0[a], c.0[b]],
                    plane: *plane,
                    sweep: if self.flips(*plane) { -sweep } else { *sweep },
                    feed: *feed,
                }
            }
            OpKind::Approach { plane, .. } => {
                let f = self.plane_factor(*plane, "an APPR path")?;
                let mut out = self.map_points(kind);
                if let OpKind::Approach { shape, side, .. } = &mut out {
                    *shape = self.map_shape(*shape, f);
                    if self.flips(*plane) {
                        *side = Self::swap(*side);
                    }
                }
                out
            }
            OpKind::Depart { plane, .. } => {
                let f = self.plane_factor(*plane, "a DEP path")?;
                let mut out = self.map_points(kind);
                if let OpKind::Depart { shape, .. } = &mut out {
                    *shape = self.map_shape(*shape, f);
                }
                out
            }
            OpKind::RadiusComp { side } if self.flips(self.plane) => OpKind::RadiusComp {
                side: Self::swap(*side),
            },
            other => other.clone(),
        })
    }

    /// A line, spline or APPR/DEP op with its points mapped and a spline's coefficients
    /// through the linear part (X, Y, Z mix under rotation; the other axes keep theirs);
    /// any other op unchanged.
    fn map_points(&self, kind: &OpKind) -> OpKind {
        map_points(kind, |p| self.map_point(p), |v| self.linear(v)).unwrap_or_else(|| kind.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::op::{AxisLetter, Feed, SplineAxis};

    const EPS: f64 = 1e-9;

    fn close(a: &Pose, b: &Pose) -> bool {
        a.0.iter().zip(b.0.iter()).all(|(x, y)| (x - y).abs() < EPS)
    }

    /// Datum shift (10, 20, 5), rotation 30° in XY, scale 0.5, mirror X: every corner of the
    /// square (0,0)-(40,0)-(40,40)-(0,40) at Z-2 against the chain written out by hand:
    /// scale → (x/2, y/2, -1); rotate 30° → (x' cos30 − y' sin30, x' sin30 + y' cos30);
    /// mirror X → negate the first; shift → add (10, 20, 5).
    #[test]
    fn square_under_shift_rotation_scale_and_mirror() {
        let t = Transform {
            shift: [10.0, 20.0, 5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            mirror: [true, false, false],
            rot: 30.0,
            scale: [0.5; 3],
            ..Transform::default()
        };
        let (s30, c30) = (0.5, 3f64.sqrt() / 2.0);
        let corners = [(0.0, 0.0), (40.0, 0.0), (40.0, 40.0), (0.0, 40.0)];
        // hand values: (x, y) scaled to (u, v) = (x/2, y/2)
        // (40,0): u=20,v=0 → rot (20c, 20s) = (17.3205…, 10) → mirror (−17.3205…, 10) → (−7.3205…, 30)
        let expect_40_0 = Pose::xyz(10.0 - 20.0 * c30, 20.0 + 20.0 * s30, 4.0);
        assert!(close(
            &t.map_point(&Pose::xyz(40.0, 0.0, -2.0)),
            &expect_40_0
        ));
        assert!((expect_40_0.0[0] - (10.0 - 17.320_508_075_688_77)).abs() < EPS);
        for (x, y) in corners {
            let (u, v) = (x * 0.5, y * 0.5);
            let (rx, ry) = (u * c30 - v * s30, u * s30 + v * c30);
            let want = Pose::xyz(-rx + 10.0, ry + 20.0, -1.0 + 5.0);
            let got = t.map_point(&Pose::xyz(x, y, -2.0));
            assert!(close(&got, &want), "{x},{y}: {got:?} vs {want:?}");
            // and back
            assert!(close(&t.unmap_point(&got), &Pose::xyz(x, y, -2.0)));
        }
    }

    #[test]
    fn mirror_reverses_arcs_and_swaps_comp_side() {
        let t = Transform {
            mirror: [true, false, false],
            ..Transform::default()
        };
        let arc = OpKind::Arc {
            from: Pose::xyz(10.0, 0.0, 0.0),
            to: Pose::xyz(0.0, 10.0, 0.0),
            center: [0.0, 0.0],
            plane: Plane::XY,
            sweep: 90.0,
            feed: Feed::Rate(10.0),
        };
        let OpKind::Arc {
            from,
            to,
            sweep,
            center,
            ..
        } = t.map_op(&arc).expect("maps")
        else {
            panic!("not an arc");
        };
        assert_eq!(sweep, -90.0);
        assert!(close(&from, &Pose::xyz(-10.0, 0.0, 0.0)));
        assert!(close(&to, &Pose::xyz(0.0, 10.0, 0.0)));
        assert_eq!(center, [0.0, 0.0]);
        assert_eq!(
            t.map_op(&OpKind::RadiusComp {
                side: CompSide::Left
            }),
            Ok(OpKind::RadiusComp {
                side: CompSide::Right
            })
        );
        // both plane axes mirrored: a point reflection keeps the direction and the side
        let t2 = Transform {
            mirror: [true, true, false],
            ..Transform::default()
        };
        let OpKind::Arc { sweep, .. } = t2.map_op(&arc).expect("maps") else {
            panic!("not an arc");
        };
        assert_eq!(sweep, 90.0);
        assert_eq!(
            t2.map_op(&OpKind::RadiusComp {
                side: CompSide::Left
            }),
            Ok(OpKind::RadiusComp {
                side: CompSide::Left
            })
        );
        // mirroring the tool axis only leaves the plane's direction alone
        assert!(
            !Transform {
                mirror: [false, false, true],
                ..Transform::default()
            }
            .flips(Plane::XY)
        );
    }

    #[test]
    fn rotation_turns_centre_and_keeps_direction() {
        let t = Transform {
            rot: 90.0,
            ..Transform::default()
        };
        let arc = OpKind::Arc {
            from: Pose::xyz(20.0, 10.0, 0.0),
            to: Pose::xyz(10.0, 20.0, 0.0),
            center: [10.0, 10.0],
            plane: Plane::XY,
            sweep: 90.0,
            feed: Feed::Rapid,
        };
        let OpKind::Arc {
            from,
            center,
            sweep,
            ..
        } = t.map_op(&arc).expect("maps")
        else {
            panic!("not an arc");
        };
        // (x, y) → (−y, x)
        assert!(close(&from, &Pose::xyz(-10.0, 20.0, 0.0)));
        assert!((center[0] + 10.0).abs() < EPS && (center[1] - 10.0).abs() < EPS);
        assert_eq!(sweep, 90.0);
        // an arc in another plane cannot follow a rotation in XY
        let zx = OpKind::Arc {
            from: Pose::xyz(20.0, 10.0, 0.0),
            to: Pose::xyz(10.0, 20.0, 0.0),
            center: [0.0, 0.0],
            plane: Plane::ZX,
            sweep: 90.0,
            feed: Feed::Rapid,
        };
        assert!(t.map_op(&zx).is_err());
    }

    #[test]
    fn axis_specific_scaling_refuses_ellipses_and_scales_lines() {
        // cycle 26: X ×2, Y ×1 about (10, 0)
        let t = Transform {
            scale: [2.0, 1.0, 1.0],
            centre: [10.0, 0.0, 0.0],
            ..Transform::default()
        };
        let line = OpKind::Line {
            from: Pose::xyz(10.0, 0.0, 0.0),
            to: Pose::xyz(15.0, 5.0, 0.0),
            feed: Feed::Rapid,
        };
        let OpKind::Line { to, .. } = t.map_op(&line).expect("maps") else {
            panic!("not a line");
        };
        // 10 + 2·(15 − 10) = 20
        assert!(close(&to, &Pose::xyz(20.0, 5.0, 0.0)));
        let arc = OpKind::Arc {
            from: Pose::xyz(20.0, 10.0, 0.0),
            to: Pose::xyz(10.0, 20.0, 0.0),
            center: [10.0, 10.0],
            plane: Plane::XY,
            sweep: 90.0,
            feed: Feed::Rapid,
        };
        let e = t.map_op(&arc).expect_err("ellipse refused");
        assert!(e.contains("different factors"), "{e}");
        // an arc in YZ is fine when Y and Z share their factor
        let yz = OpKind::Arc {
            from: Pose::xyz(0.0, 10.0, 0.0),
            to: Pose::xyz(0.0, 0.0, 10.0),
            center: [0.0, 0.0],
            plane: Plane::YZ,
            sweep: 90.0,
            feed: Feed::Rapid,
        };
        assert!(t.map_op(&yz).is_ok());
    }

    #[test]
    fn spline_coefficients_take_the_linear_part() {
        let t = Transform {
            rot: 90.0,
            scale: [2.0; 3],
            shift: [100.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            ..Transform::default()
        };
        let sp = OpKind::Spline {
            from: Pose::xyz(1.0, 0.0, 0.0),
            to: Pose::ZERO,
            axes: vec![SplineAxis {
                axis: AxisLetter::X,
                k: [0.0, 0.0, 1.0],
            }],
            feed: Feed::Rapid,
        };
        let OpKind::Spline { from, to, axes, .. } = t.map_op(&sp).expect("maps") else {
            panic!("not a spline");
        };
        // K1 = (1, 0) → scaled (2, 0) → rotated (0, 2); no shift on coefficients
        assert!(close(&to, &Pose::xyz(100.0, 0.0, 0.0)));
        assert!(close(&from, &Pose::xyz(100.0, 2.0, 0.0)));
        let y = axes.iter().find(|a| a.axis == AxisLetter::Y).expect("Y");
        assert!((y.k[2] - 2.0).abs() < EPS);
        let x = axes.iter().find(|a| a.axis == AxisLetter::X).expect("X");
        assert!(x.k[2].abs() < EPS);
        // P(1) = to + K1 equals from, as before the mapping
        assert!((to.0[1] + y.k[2] - from.0[1]).abs() < EPS);
    }

    #[test]
    fn identity_leaves_ops_alone() {
        let t = Transform::default();
        assert!(t.is_identity());
        let l = OpKind::Line {
            from: Pose::xyz(1.0, 2.0, 3.0),
            to: Pose::xyz(4.0, 5.0, 6.0),
            feed: Feed::Rapid,
        };
        assert_eq!(t.map_op(&l), Ok(l));
    }
}
