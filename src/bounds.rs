//! Axis-aligned bounds of the path of a motion op, for the travel check before planning.

use klar_interp::{OpKind, Pose};

/// Lowest and highest value each axis takes along the path of a motion op (None for ops that
/// do not move).
pub fn op_bounds(kind: &OpKind) -> Option<(Pose, Pose)> {
    let mut lo = Pose([f64::INFINITY; 9]);
    let mut hi = Pose([f64::NEG_INFINITY; 9]);
    let mut add = |i: usize, v: f64| {
        lo.0[i] = lo.0[i].min(v);
        hi.0[i] = hi.0[i].max(v);
    };
    match kind {
        OpKind::Line { from, to, .. }
        | OpKind::SpindleSync { from, to, .. }
        | OpKind::RigidTap { from, to, .. } => {
            for i in 0..9 {
                add(i, from.0[i]);
                add(i, to.0[i]);
            }
        }
        OpKind::Arc {
            from,
            to,
            center,
            plane,
            sweep,
            ..
        } => {
            for i in 0..9 {
                add(i, from.0[i]);
                add(i, to.0[i]);
            }
            let (a1, a2, _) = plane.axes();
            let r = (from[a1] - center[0]).hypot(from[a2] - center[1]);
            let start = (from[a2] - center[1])
                .atan2(from[a1] - center[0])
                .to_degrees();
            // Each quadrant point (0°, 90°, 180°, 270°) the arc passes widens the bounds.
            for q in 0..4 {
                let ang = 90.0 * f64::from(q);
                let rel = if *sweep >= 0.0 {
                    (ang - start).rem_euclid(360.0)
                } else {
                    (start - ang).rem_euclid(360.0)
                };
                if rel <= sweep.abs() {
                    add(a1.index(), center[0] + r * ang.to_radians().cos());
                    add(a2.index(), center[1] + r * ang.to_radians().sin());
                }
            }
        }
        OpKind::Spline { from, to, axes, .. } => {
            for i in 0..9 {
                add(i, from.0[i]);
                add(i, to.0[i]);
            }
            // Extremes of each cubic lie at the ends or where its derivative
            // 3·K3·t² + 2·K2·t + K1 vanishes inside (0, 1).
            for s in axes {
                let [k3, k2, k1] = s.k;
                let end = to[s.axis];
                let value = |t: f64| ((k3 * t + k2) * t + k1) * t + end;
                let (a, b, c) = (3.0 * k3, 2.0 * k2, k1);
                let mut roots = [f64::NAN; 2];
                if a != 0.0 {
                    let disc = b * b - 4.0 * a * c;
                    if disc >= 0.0 {
                        let q = disc.sqrt();
                        roots = [(-b + q) / (2.0 * a), (-b - q) / (2.0 * a)];
                    }
                } else if b != 0.0 {
                    roots[0] = -c / b;
                }
                for t in roots {
                    if t > 0.0 && t < 1.0 {
                        add(s.axis.index(), value(t));
                    }
                }
            }
        }
        OpKind::Approach { from, to, .. } => {
            for i in 0..9 {
                add(i, from.0[i]);
                add(i, to.0[i]);
            }
        }
        _ => return None,
    }
    Some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use klar_interp::{AxisLetter, Feed, Plane, SplineAxis};

    #[test]
    fn a_half_circle_reaches_the_top_quadrant_point() {
        // From (10, 0) counter-clockwise 180° about the origin: passes (0, 10), ends (-10, 0).
        let kind = OpKind::Arc {
            from: Pose::xyz(10.0, 0.0, 0.0),
            to: Pose::xyz(-10.0, 0.0, 0.0),
            center: [0.0, 0.0],
            plane: Plane::XY,
            sweep: 180.0,
            feed: Feed::Rate(10.0),
        };
        let (lo, hi) = op_bounds(&kind).unwrap();
        assert_eq!((lo[AxisLetter::X], hi[AxisLetter::X]), (-10.0, 10.0));
        assert!((hi[AxisLetter::Y] - 10.0).abs() < 1e-12);
        assert_eq!(lo[AxisLetter::Y], 0.0);
    }

    #[test]
    fn a_clockwise_quarter_misses_the_other_quadrants() {
        // From (0, 10) clockwise 90° to (10, 0): stays in the first quadrant.
        let kind = OpKind::Arc {
            from: Pose::xyz(0.0, 10.0, 0.0),
            to: Pose::xyz(10.0, 0.0, 0.0),
            center: [0.0, 0.0],
            plane: Plane::XY,
            sweep: -90.0,
            feed: Feed::Rate(10.0),
        };
        let (lo, hi) = op_bounds(&kind).unwrap();
        assert!(lo[AxisLetter::X] >= -1e-12 && lo[AxisLetter::Y] >= -1e-12);
        assert!((hi[AxisLetter::X] - 10.0).abs() < 1e-12);
    }

    #[test]
    fn a_spline_bulge_is_found_between_its_ends() {
        // X(t) = -4t² + 4t + 0 from t=1 (X=0) to t=0 (X=0): maximum 1 at t = 0.5.
        let kind = OpKind::Spline {
            from: Pose::xyz(0.0, 0.0, 0.0),
            to: Pose::xyz(0.0, 5.0, 0.0),
            axes: vec![SplineAxis {
                axis: AxisLetter::X,
                k: [0.0, -4.0, 4.0],
            }],
            feed: Feed::Rate(10.0),
        };
        let (lo, hi) = op_bounds(&kind).unwrap();
        assert_eq!(lo[AxisLetter::X], 0.0);
        assert!((hi[AxisLetter::X] - 1.0).abs() < 1e-12);
    }
}
