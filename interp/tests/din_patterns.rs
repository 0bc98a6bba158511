//! G745 pattern angles for every V rule of the manual, read back from the drilling moves,
//! and the LATERAL_Y / SURFACE_Y plane against hand-written rotation matrices.

mod common;
use common::close;
use common::lathe::run_named;
use klar_interp::din::{CircleLayout, LateralPlane, PatternEnd};
use klar_interp::{AxisLetter, Feed, OpKind};

/// Runs a G745 block that drills by itself (ZE) and returns (C, X) of each hole bottom.
fn holes(g745: &str) -> Vec<(f64, f64)> {
    let text = format!(
        "N1 T1 G197 S1000 G94 F100 M103\nN2 M14\nN3 G0 X200 Z5\nN4 {g745} ZS1 ZE-3\nN5 M30\nEND\n"
    );
    run_named("p.nc", &text)
        .into_iter()
        .filter_map(|o| match o.kind {
            OpKind::Line { to, feed, .. } if feed != Feed::Rapid => {
                Some((to[AxisLetter::C], to[AxisLetter::X]))
            }
            _ => None,
        })
        .collect()
}

/// Compares angles modulo 360.
#[track_caller]
fn same_angles(got: &[(f64, f64)], want: &[f64]) {
    assert_eq!(got.len(), want.len(), "{got:?} vs {want:?}");
    for ((c, _), w) in got.iter().zip(want) {
        let d = (c - w).rem_euclid(360.0);
        assert!(
            d < 1e-9 || 360.0 - d < 1e-9,
            "{c} != {w} (mod 360): {got:?}"
        );
    }
}

#[test]
fn v0_without_w_divides_the_full_circle() {
    let h = holes("G745 XK0 YK0 K60 A10 Q4");
    same_angles(&h, &[10.0, 100.0, 190.0, 280.0]);
    for (_, x) in &h {
        close(*x, 30.0);
    }
    // Q defaults to 1: one hole at A
    same_angles(&holes("G745 XK0 YK0 K60 A33"), &[33.0]);
}

#[test]
fn v0_with_w_divides_the_longer_arc() {
    // A0 → W60: the counter-clockwise arc is 60°, the clockwise one 300°: 3 holes on the
    // clockwise arc, 150° apart: 0, -150, -300
    same_angles(&holes("G745 XK0 YK0 K60 A0 W60 Q3"), &[0.0, 210.0, 60.0]);
    // A0 → W300: the counter-clockwise arc (300°) is the longer: 0, 100, 200, 300
    same_angles(
        &holes("G745 XK0 YK0 K60 A0 W300 Q4"),
        &[0.0, 100.0, 200.0, 300.0],
    );
}

#[test]
fn v0_with_wi_takes_the_sign_as_direction() {
    same_angles(&holes("G745 XK0 YK0 K60 A90 Wi-30 Q3"), &[90.0, 60.0, 30.0]);
    same_angles(
        &holes("G745 XK0 YK0 K60 A90 Wi30 Q3"),
        &[90.0, 120.0, 150.0],
    );
}

#[test]
fn v1_is_clockwise_and_v2_counter_clockwise_whatever_the_sign_of_wi() {
    // V1 from A0 to W60 clockwise: the 300° arc, 3 holes 150° apart
    same_angles(&holes("G745 XK0 YK0 K60 A0 W60 Q3 V1"), &[0.0, 210.0, 60.0]);
    // V2 from A0 to W60 counter-clockwise: the 60° arc, 30° apart
    same_angles(&holes("G745 XK0 YK0 K60 A0 W60 Q3 V2"), &[0.0, 30.0, 60.0]);
    same_angles(
        &holes("G745 XK0 YK0 K60 A0 Wi30 Q3 V1"),
        &[0.0, 330.0, 300.0],
    );
    same_angles(
        &holes("G745 XK0 YK0 K60 A0 Wi-30 Q3 V1"),
        &[0.0, 330.0, 300.0],
    );
    same_angles(
        &holes("G745 XK0 YK0 K60 A0 Wi-30 Q3 V2"),
        &[0.0, 30.0, 60.0],
    );
}

#[test]
fn off_centre_pattern_positions_in_polar_machine_coordinates() {
    // centre XK20 YK0, pattern radius 10, A90 Q2 (full circle): face points (20, 10) and
    // (20, -10): radius √500, angles ±atan(10/20)
    let h = holes("G745 XK20 YK0 K20 A90 Q2");
    let a = (10.0f64 / 20.0).atan().to_degrees();
    same_angles(&h, &[a, -a]);
    close(h[0].1, 500f64.sqrt());
    close(h[1].1, 500f64.sqrt());
    // the same centre given polar: X40 (diameter) C0
    assert_eq!(h, holes("G745 X40 C0 K20 A90 Q2"));
}

#[test]
fn layout_api_steps_match_the_rules() {
    let l = |end, count, direction| CircleLayout {
        start: 0.0,
        end,
        count,
        direction,
    };
    close(l(PatternEnd::None, 6, 0).step().unwrap(), 60.0);
    close(l(PatternEnd::EndAngle(90.0), 4, 2).step().unwrap(), 30.0);
    close(l(PatternEnd::EndAngle(90.0), 4, 1).step().unwrap(), -90.0);
    close(l(PatternEnd::Increment(-15.0), 4, 2).step().unwrap(), 15.0);
}

/// R_y(b) written out: rows of the right-handed rotation about +Y.
fn rot_y(b: f64) -> [[f64; 3]; 3] {
    let (s, c) = b.to_radians().sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

/// The manual's three steps as homogeneous 4×4 matrices multiplied out by hand:
/// T(I, 0, K) · R_y(B) · T(−I, 0, 0) (the last only for H=0).
fn manual_steps(b: f64, i: f64, k: f64, h0: bool, p: [f64; 3]) -> [f64; 3] {
    let shift = |m: [[f64; 4]; 4], t: [f64; 3]| -> [[f64; 4]; 4] {
        let tm = [
            [1.0, 0.0, 0.0, t[0]],
            [0.0, 1.0, 0.0, t[1]],
            [0.0, 0.0, 1.0, t[2]],
            [0.0, 0.0, 0.0, 1.0],
        ];
        matmul(m, tm)
    };
    let r = rot_y(b);
    let rot4 = [
        [r[0][0], r[0][1], r[0][2], 0.0],
        [r[1][0], r[1][1], r[1][2], 0.0],
        [r[2][0], r[2][1], r[2][2], 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let ident = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let mut m = shift(ident, [i, 0.0, k]);
    m = matmul(m, rot4);
    if h0 {
        m = shift(m, [-i, 0.0, 0.0]);
    }
    let v = [p[0], p[1], p[2], 1.0];
    let mut out = [0.0; 3];
    for (r, o) in out.iter_mut().enumerate() {
        *o = (0..4).map(|c| m[r][c] * v[c]).sum();
    }
    out
}

fn matmul(a: [[f64; 4]; 4], b: [[f64; 4]; 4]) -> [[f64; 4]; 4] {
    let mut m = [[0.0; 4]; 4];
    for (r, row) in m.iter_mut().enumerate() {
        for (c, cell) in row.iter_mut().enumerate() {
            *cell = (0..4).map(|k| a[r][k] * b[k][c]).sum();
        }
    }
    m
}

#[test]
fn surface_y_plane_matches_the_three_manual_steps() {
    // the manual's example SURFACE_Y X118 C0 B130 I59 K0, H0 and H1
    for h1 in [false, true] {
        let plane = LateralPlane {
            reference_diameter: 118.0,
            c: 0.0,
            b: Some(130.0),
            i: 59.0,
            k: 0.0,
            no_back_shift: h1,
        };
        for (xd, y, z) in [(118.0, 0.0, 0.0), (100.0, 7.0, -12.5), (130.0, -3.0, 4.0)] {
            let got = plane.to_workpiece(Some(xd), y, z);
            let want = manual_steps(130.0, 59.0, 0.0, !h1, [xd / 2.0, y, z]);
            for a in 0..3 {
                close(got[a], want[a]);
            }
        }
    }
}

#[test]
fn surface_y_properties_independent_of_the_formula() {
    let plane = |b, h1| LateralPlane {
        reference_diameter: 118.0,
        c: 0.0,
        b,
        i: 59.0,
        k: -20.0,
        no_back_shift: h1,
    };
    // with H0 the reference diameter lands on the pivot (I, K) whatever B is
    for b in [0.0, 30.0, 90.0, 130.0, 245.0] {
        let p = plane(Some(b), false).to_workpiece(None, 0.0, 0.0);
        close(p[0], 59.0);
        close(p[2], -20.0);
        // with H1 the tilted origin is the pivot
        let q = plane(Some(b), true).to_workpiece(Some(0.0), 0.0, 0.0);
        close(q[0], 59.0);
        close(q[2], -20.0);
    }
    // B90 turns the tilted Z axis onto +X: one mm along local Z moves +1 in X
    let pl = plane(Some(90.0), false);
    let a = pl.to_workpiece(None, 0.0, 0.0);
    let b = pl.to_workpiece(None, 0.0, 1.0);
    close(b[0] - a[0], 1.0);
    close(b[2] - a[2], 0.0);
    // the transform is rigid: distances are kept
    let pl = plane(Some(130.0), false);
    let p = pl.to_workpiece(Some(100.0), 3.0, 4.0);
    let q = pl.to_workpiece(Some(106.0), -1.0, 8.0);
    let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
    let want = (3.0f64.powi(2) + 4.0f64.powi(2) + 4.0f64.powi(2)).sqrt();
    close(d, want);
    // without B: the contour lies at the reference radius, unrotated
    let flat = plane(None, false).to_workpiece(None, 5.0, -7.0);
    assert_eq!(flat, [59.0, 5.0, -7.0]);
}
