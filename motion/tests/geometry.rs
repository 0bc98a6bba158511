//! Geometry primitives against closed forms and independent numerical integration.

use klar_interp::op::SplineAxis;
use klar_interp::{AxisLetter, Plane, Pose};
use klar_motion::geom::{Arc, GeomError, Line, Metric, Poly, Segment};
use std::f64::consts::PI;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

fn pose(v: [f64; 9]) -> Pose {
    Pose(v)
}

#[test]
fn line_points_lie_on_the_straight_line() {
    let from = Pose::xyz(1.0, 2.0, 3.0);
    let to = Pose::xyz(4.0, -2.0, 3.0); // length 5
    let seg = Segment::Line(Line::new(from, to).unwrap().unwrap());
    assert!(close(seg.length(), 5.0, 1e-12));
    for k in 0..=10 {
        let s = 0.5 * k as f64;
        let p = seg.position(s);
        assert!(close(p.0[0], 1.0 + 3.0 * s / 5.0, 1e-12));
        assert!(close(p.0[1], 2.0 - 4.0 * s / 5.0, 1e-12));
        assert!(close(p.0[2], 3.0, 1e-12));
        let tg = seg.tangent(s);
        assert!(close(tg[0], 0.6, 1e-12) && close(tg[1], -0.8, 1e-12));
        assert_eq!(seg.curvature(s), 0.0);
    }
    assert_eq!(seg.position(5.0), to);
    assert_eq!(seg.position(0.0), from);
    assert_eq!(seg.start(), from);
    assert_eq!(seg.end(), to);
}

#[test]
fn zero_length_line_is_none() {
    let p = Pose::xyz(1.0, 1.0, 1.0);
    assert!(Line::new(p, p).unwrap().is_none());
}

#[test]
fn rotary_only_line_is_measured_in_degrees() {
    let from = Pose::ZERO;
    let mut to = Pose::ZERO;
    to.set(AxisLetter::C, 90.0);
    to.set(AxisLetter::A, 120.0);
    let l = Line::new(from, to).unwrap().unwrap();
    assert_eq!(l.metric(), Metric::Rotary);
    assert!(close(l.length(), 150.0, 1e-12));
}

#[test]
fn mixed_line_is_measured_in_linear_axes_only() {
    let from = Pose::ZERO;
    let mut to = Pose::xyz(3.0, 4.0, 0.0);
    to.set(AxisLetter::C, 1000.0);
    let l = Line::new(from, to).unwrap().unwrap();
    assert_eq!(l.metric(), Metric::Linear);
    assert!(close(l.length(), 5.0, 1e-12));
    // C moves in proportion: half way along, half the angle.
    let p = Segment::Line(l).position(2.5);
    assert!(close(p.get(AxisLetter::C), 500.0, 1e-9));
}

#[test]
fn non_finite_line_is_an_error() {
    let r = Line::new(Pose::ZERO, Pose::xyz(f64::NAN, 0.0, 0.0));
    assert!(matches!(r, Err(GeomError::NonFinite(_))));
}

/// Checks an arc in `plane` against the analytic circle; `a`, `b`, `n` are pose indices of
/// the plane's first, second and normal axes.
fn check_arc(plane: Plane, a: usize, b: usize, n: usize) {
    let (cx, cy, r) = (10.0, -5.0, 7.0);
    let phi0 = 30f64.to_radians();
    let sweep: f64 = 250.0;
    let theta = sweep.to_radians();
    let h = 4.0;
    let mut from = [0.0; 9];
    from[a] = cx + r * phi0.cos();
    from[b] = cy + r * phi0.sin();
    from[n] = 2.0;
    let mut to = from;
    to[a] = cx + r * (phi0 + theta).cos();
    to[b] = cy + r * (phi0 + theta).sin();
    to[n] = 2.0 + h;
    let arc = Arc::new(pose(from), pose(to), [cx, cy], plane, sweep)
        .unwrap()
        .unwrap();
    let len = ((r * theta).powi(2) + h * h).sqrt();
    assert!(close(arc.length(), len, 1e-12), "{} vs {len}", arc.length());
    let seg = Segment::Arc(arc);
    for k in 0..=20 {
        let s = len * k as f64 / 20.0;
        let p = seg.position(s);
        let phi = phi0 + theta * s / len;
        assert!(close(p.0[a], cx + r * phi.cos(), 1e-9), "{plane:?} k {k}");
        assert!(close(p.0[b], cy + r * phi.sin(), 1e-9), "{plane:?} k {k}");
        assert!(close(p.0[n], 2.0 + h * s / len, 1e-9), "{plane:?} k {k}");
        // Tangent: derivative of the analytic helix divided by its constant speed.
        let tg = seg.tangent(s);
        let w = theta / len;
        assert!(close(tg[a], -r * phi.sin() * w, 1e-9));
        assert!(close(tg[b], r * phi.cos() * w, 1e-9));
        assert!(close(tg[n], h / len, 1e-9));
        // Helix curvature r / (r² + c²), c = h / θ.
        let c = h / theta;
        assert!(close(seg.curvature(s), r / (r * r + c * c), 1e-9));
    }
    assert_eq!(seg.position(seg.length()), pose(to));
    assert_eq!(seg.position(0.0), pose(from));
}

#[test]
fn arc_xy_matches_the_circle() {
    check_arc(Plane::XY, 0, 1, 2);
}

#[test]
fn arc_zx_matches_the_circle() {
    check_arc(Plane::ZX, 2, 0, 1);
}

#[test]
fn arc_yz_matches_the_circle() {
    check_arc(Plane::YZ, 1, 2, 0);
}

#[test]
fn clockwise_arc_turns_the_other_way() {
    // Quarter circle clockwise from (10,0) about the origin ends at (0,-10).
    let arc = Arc::new(
        Pose::xyz(10.0, 0.0, 0.0),
        Pose::xyz(0.0, -10.0, 0.0),
        [0.0, 0.0],
        Plane::XY,
        -90.0,
    )
    .unwrap()
    .unwrap();
    let seg = Segment::Arc(arc);
    let mid = seg.position(seg.length() / 2.0);
    let c = (PI / 4.0).cos() * 10.0;
    assert!(close(mid.0[0], c, 1e-9) && close(mid.0[1], -c, 1e-9));
    assert!(close(seg.length(), 5.0 * PI, 1e-12));
}

#[test]
fn helix_of_several_turns_has_closed_form_length() {
    // Two and a half turns, r = 3, rising 12 mm.
    let r = 3.0;
    let sweep: f64 = 900.0;
    let from = Pose::xyz(r, 0.0, 0.0);
    let to = Pose::xyz(-r, 0.0, 12.0);
    let arc = Arc::new(from, to, [0.0, 0.0], Plane::XY, sweep)
        .unwrap()
        .unwrap();
    let theta = sweep.to_radians();
    assert!(close(
        arc.length(),
        ((r * theta).powi(2) + 144.0).sqrt(),
        1e-12
    ));
    // After one full turn it is back above the start, a fifth of the way up.
    let seg = Segment::Arc(arc);
    let p = seg.position(seg.length() * 360.0 / 900.0);
    assert!(close(p.0[0], r, 1e-9) && close(p.0[1], 0.0, 1e-9));
    assert!(close(p.0[2], 12.0 * 0.4, 1e-9));
}

#[test]
fn arc_with_wrong_end_point_is_refused() {
    let r = Arc::new(
        Pose::xyz(10.0, 0.0, 0.0),
        Pose::xyz(0.0, 10.5, 0.0),
        [0.0, 0.0],
        Plane::XY,
        90.0,
    );
    match r {
        Err(GeomError::ArcEnd { deviation }) => assert!(close(deviation, 0.5, 1e-9)),
        other => panic!("expected ArcEnd, got {other:?}"),
    }
}

/// A spline test case: coefficients per axis and the end point.
fn spline_case() -> (Pose, Pose, Vec<SplineAxis>) {
    let to = Pose::xyz(20.0, 5.0, -1.0);
    let axes = vec![
        SplineAxis {
            axis: AxisLetter::X,
            k: [2.0, -3.0, -12.0],
        },
        SplineAxis {
            axis: AxisLetter::Y,
            k: [-1.0, 4.0, -6.0],
        },
        SplineAxis {
            axis: AxisLetter::Z,
            k: [0.5, 0.0, 1.0],
        },
    ];
    // Start = end + K3 + K2 + K1, written out by hand.
    let from = Pose::xyz(
        20.0 + 2.0 - 3.0 - 12.0,
        5.0 - 1.0 + 4.0 - 6.0,
        -1.0 + 0.5 + 1.0,
    );
    (from, to, axes)
}

/// The polynomial of the spline case at parameter t (independent of the crate).
fn spline_at(t: f64) -> [f64; 3] {
    [
        2.0 * t.powi(3) - 3.0 * t * t - 12.0 * t + 20.0,
        -t.powi(3) + 4.0 * t * t - 6.0 * t + 5.0,
        0.5 * t.powi(3) + t - 1.0,
    ]
}

/// dP/dt of the spline case, by hand: 3·K3·t² + 2·K2·t + K1.
fn spline_dt(t: f64) -> [f64; 3] {
    [
        6.0 * t * t - 6.0 * t - 12.0,
        -3.0 * t * t + 8.0 * t - 6.0,
        1.5 * t * t + 1.0,
    ]
}

/// Arc length from t = 1 down to t, by composite Simpson on 20 000 panels.
fn spline_length_to(t_end: f64) -> f64 {
    let n = 20_000;
    let h = (1.0 - t_end) / n as f64;
    let f = |t: f64| {
        let d = spline_dt(t);
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    };
    let mut sum = f(1.0) + f(t_end);
    for i in 1..n {
        let t = 1.0 - i as f64 * h;
        sum += if i % 2 == 1 { 4.0 } else { 2.0 } * f(t);
    }
    sum * h / 3.0
}

#[test]
fn spline_starts_at_end_plus_coefficients_and_ends_at_end() {
    let (from, to, axes) = spline_case();
    let poly = Poly::new(from, to, &axes).unwrap().unwrap();
    let seg = Segment::Poly(std::sync::Arc::new(poly));
    assert_eq!(seg.position(0.0), from);
    assert_eq!(seg.position(seg.length()), to);
    let p1 = spline_at(1.0);
    for (x, y) in from.0.iter().zip(p1) {
        assert!(close(*x, y, 1e-12));
    }
}

#[test]
fn spline_tangents_at_both_ends_follow_the_derivative() {
    let (from, to, axes) = spline_case();
    let seg = Segment::Poly(std::sync::Arc::new(
        Poly::new(from, to, &axes).unwrap().unwrap(),
    ));
    // Travel runs from t = 1 to t = 0, so the direction is −dP/dt.
    for (s, t) in [(0.0, 1.0), (seg.length(), 0.0)] {
        let d = spline_dt(t).map(|x| -x);
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let tg = seg.tangent(s);
        for (i, (x, y)) in tg.iter().zip(d).enumerate() {
            assert!(close(*x, y / n, 1e-9), "s {s} axis {i}: {x} vs {}", y / n);
        }
    }
}

#[test]
fn spline_is_parameterised_by_arc_length() {
    let (from, to, axes) = spline_case();
    let seg = Segment::Poly(std::sync::Arc::new(
        Poly::new(from, to, &axes).unwrap().unwrap(),
    ));
    assert!(close(seg.length(), spline_length_to(0.0), 1e-9));
    for t in [0.9, 0.75, 0.5, 0.3, 0.1] {
        let s = spline_length_to(t);
        let p = seg.position(s);
        let expect = spline_at(t);
        for (i, (x, y)) in p.0.iter().zip(expect).enumerate() {
            assert!(close(*x, y, 1e-8), "t {t} axis {i}: {x} vs {y}");
        }
        // Unit tangent in XYZ.
        let tg = seg.tangent(s);
        let n = (tg[0] * tg[0] + tg[1] * tg[1] + tg[2] * tg[2]).sqrt();
        assert!(close(n, 1.0, 1e-9));
    }
}

#[test]
fn spline_curvature_matches_the_cross_product_formula() {
    let (from, to, axes) = spline_case();
    let seg = Segment::Poly(std::sync::Arc::new(
        Poly::new(from, to, &axes).unwrap().unwrap(),
    ));
    for t in [0.8, 0.4] {
        // κ = |P' × P''| / |P'|³ with P'' = 6·K3·t + 2·K2 (sign of t-direction irrelevant).
        let d1 = spline_dt(t);
        let d2 = [12.0 * t - 6.0, -6.0 * t + 8.0, 3.0 * t];
        let cx = [
            d1[1] * d2[2] - d1[2] * d2[1],
            d1[2] * d2[0] - d1[0] * d2[2],
            d1[0] * d2[1] - d1[1] * d2[0],
        ];
        let num = (cx[0] * cx[0] + cx[1] * cx[1] + cx[2] * cx[2]).sqrt();
        let den = (d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]).powf(1.5);
        let s = spline_length_to(t);
        assert!(close(seg.curvature(s), num / den, 1e-7));
    }
}

#[test]
fn spline_not_starting_at_the_tool_is_refused() {
    let (from, to, axes) = spline_case();
    let mut wrong = from;
    wrong.0[1] += 0.5;
    assert!(matches!(
        Poly::new(wrong, to, &axes),
        Err(GeomError::SplineStart {
            axis: AxisLetter::Y,
            ..
        })
    ));
}
