//! Tests of the point patterns against closed-form positions.

use crate::cycles::drill::testutil::{Defs, assert_no_rapid_into_material, ctx_at, qs, with};
use crate::cycles::{
    CycleError, CycleFeed, Move, P3, ParamKey, generate_at_points, generate_pattern,
};

/// A cycle 200 whose own heights are deliberately wrong: the pattern must replace them.
fn drill() -> Defs {
    qs(&[
        (200, 99.0),
        (201, -10.0),
        (206, 120.0),
        (202, 10.0),
        (210, 0.0),
        (203, -100.0),
        (204, 500.0),
        (211, 0.0),
    ])
}

/// The plane positions where the machining cycle cut (its feed moves), in order.
fn holes(m: &[Move]) -> Vec<[f64; 2]> {
    let mut out: Vec<[f64; 2]> = Vec::new();
    for mv in m {
        if let Move::Line {
            to,
            feed: CycleFeed::Rate(_),
        } = mv
        {
            out.push([to[0], to[1]]);
        }
    }
    out
}

/// The deepest tool-axis coordinate of the feed moves.
fn bottoms(m: &[Move]) -> Vec<f64> {
    m.iter()
        .filter_map(|mv| match mv {
            Move::Line {
                to,
                feed: CycleFeed::Rate(_),
            } => Some(to[2]),
            _ => None,
        })
        .collect()
}

fn assert_points(got: &[[f64; 2]], want: &[[f64; 2]]) {
    assert_eq!(got.len(), want.len(), "{got:?} vs {want:?}");
    for (g, w) in got.iter().zip(want) {
        assert!(
            (g[0] - w[0]).abs() < 1e-9 && (g[1] - w[1]).abs() < 1e-9,
            "{got:?} vs {want:?}"
        );
    }
}

fn polar(extra: &[(u32, f64)]) -> Defs {
    let mut d = qs(&[
        (216, 50.0),
        (217, 50.0),
        (244, 60.0),
        (245, 0.0),
        (246, 360.0),
        (247, 90.0),
        (241, 4.0),
        (200, 2.0),
        (203, 0.0),
        (204, 50.0),
        (301, 0.0),
        (365, 0.0),
    ]);
    for &(n, v) in extra {
        d = with(&d, n, v);
    }
    d
}

fn run_pattern(n: u32, pp: &Defs, start: P3) -> Result<Vec<Move>, CycleError> {
    let mut out = Vec::new();
    generate_pattern(n, pp, 200, &drill(), &ctx_at(start), &mut out)?;
    Ok(out)
}

fn on_circle(c: [f64; 2], r: f64, degs: &[f64]) -> Vec<[f64; 2]> {
    degs.iter()
        .map(|d| {
            [
                c[0] + r * d.to_radians().cos(),
                c[1] + r * d.to_radians().sin(),
            ]
        })
        .collect()
}

#[test]
fn polar_220_by_stepping_angle() {
    let start = [0.0, 0.0, 100.0];
    let m = run_pattern(220, &polar(&[]), start).unwrap();
    // the stop angle is ignored when Q247 is not 0
    assert_points(
        &holes(&m),
        &on_circle([50.0, 50.0], 30.0, &[0.0, 90.0, 180.0, 270.0]),
    );
    // pattern surface 0 and depth -10 (the cycle's own Q203 = -100 is replaced)
    assert!(bottoms(&m).iter().all(|&t| (t + 10.0).abs() < 1e-9));
    // first: up/down to the 2nd set-up clearance 50, over, down to 2
    assert_eq!(
        m[0],
        Move::Line {
            to: [0.0, 0.0, 50.0],
            feed: CycleFeed::Rapid
        }
    );
    assert_eq!(
        m[1],
        Move::Line {
            to: [80.0, 50.0, 50.0],
            feed: CycleFeed::Rapid
        }
    );
    assert_eq!(
        m[2],
        Move::Line {
            to: [80.0, 50.0, 2.0],
            feed: CycleFeed::Rapid
        }
    );
    // Q301 = 0: sideways travel at the set-up clearance 2; the last hole retracts to 50
    for mv in &m {
        if let Move::Line {
            to,
            feed: CycleFeed::Rapid,
        } = mv
        {
            assert!(to[2] == 2.0 || to[2] == 50.0, "{mv:?}");
        }
    }
    let Some(&Move::Line {
        to,
        feed: CycleFeed::Rapid,
    }) = m.last()
    else {
        panic!("ends with a rapid")
    };
    assert_points(&[[to[0], to[1]]], &[[50.0, 20.0]]);
    assert_eq!(to[2], 50.0);
    assert_no_rapid_into_material(&m, start, -1.0, |_, _| 2.0, |_, _| 2.0);
}

#[test]
fn polar_220_by_stop_angle_and_full_circle_and_clockwise() {
    let start = [0.0, 0.0, 100.0];
    let m = run_pattern(
        220,
        &polar(&[(245, 30.0), (246, 150.0), (247, 0.0), (241, 3.0)]),
        start,
    )
    .unwrap();
    assert_points(
        &holes(&m),
        &on_circle([50.0, 50.0], 30.0, &[30.0, 90.0, 150.0]),
    );
    let m = run_pattern(220, &polar(&[(247, 0.0)]), start).unwrap();
    assert_points(
        &holes(&m),
        &on_circle([50.0, 50.0], 30.0, &[0.0, 90.0, 180.0, 270.0]),
    );
    let m = run_pattern(
        220,
        &polar(&[(245, 90.0), (246, -90.0), (247, 0.0), (241, 3.0)]),
        start,
    )
    .unwrap();
    assert_points(
        &holes(&m),
        &on_circle([50.0, 50.0], 30.0, &[90.0, 0.0, -90.0]),
    );
    let r = run_pattern(220, &polar(&[(245, 10.0), (246, 10.0), (247, 0.0)]), start);
    assert!(matches!(r, Err(CycleError::Geometry { cycle: 220, .. })));
    let r = run_pattern(220, &polar(&[(241, 0.0)]), start);
    assert!(matches!(r, Err(CycleError::OutOfRange { cycle: 220, .. })));
    let r = run_pattern(220, &polar(&[(245, 400.0)]), start);
    assert!(matches!(r, Err(CycleError::OutOfRange { cycle: 220, .. })));
}

#[test]
fn polar_220_travel_on_pitch_circle_at_second_clearance() {
    let start = [0.0, 0.0, 100.0];
    let m = run_pattern(220, &polar(&[(301, 1.0), (365, 1.0), (247, -90.0)]), start).unwrap();
    let arcs: Vec<_> = m
        .iter()
        .filter_map(|mv| match *mv {
            Move::Arc {
                centre,
                to,
                ccw,
                turns,
                feed,
            } => Some((centre, to, ccw, turns, feed)),
            _ => None,
        })
        .collect();
    assert_eq!(arcs.len(), 3);
    let want = on_circle([50.0, 50.0], 30.0, &[-90.0, -180.0, -270.0]);
    for (k, (centre, to, ccw, turns, feed)) in arcs.into_iter().enumerate() {
        assert_eq!(centre, [50.0, 50.0]);
        assert!(!ccw, "negative step runs clockwise");
        assert_eq!(turns, 0);
        assert_eq!(feed, CycleFeed::Rapid);
        assert!(
            (to[2] - 50.0).abs() < 1e-9,
            "travel at the 2nd set-up clearance"
        );
        assert!((to[0] - want[k][0]).abs() < 1e-9 && (to[1] - want[k][1]).abs() < 1e-9);
    }
    assert_no_rapid_into_material(&m, start, -1.0, |_, _| 2.0, |_, _| 2.0);
}

fn cart(extra: &[(u32, f64)]) -> Defs {
    let mut d = qs(&[
        (225, 15.0),
        (226, 15.0),
        (237, 10.0),
        (238, 8.0),
        (242, 3.0),
        (243, 2.0),
        (224, 30.0),
        (200, 2.0),
        (203, 5.0),
        (204, 50.0),
        (301, 1.0),
    ]);
    for &(n, v) in extra {
        d = with(&d, n, v);
    }
    d
}

#[test]
fn cartesian_221_rotated_meander() {
    let start = [0.0, 0.0, 100.0];
    let m = run_pattern(221, &cart(&[]), start).unwrap();
    let (s, c) = 30f64.to_radians().sin_cos();
    // first line forwards, second line backwards
    let grid = [
        [0.0, 0.0],
        [10.0, 0.0],
        [20.0, 0.0],
        [20.0, 8.0],
        [10.0, 8.0],
        [0.0, 8.0],
    ];
    let want: Vec<[f64; 2]> = grid
        .iter()
        .map(|[u, v]| [15.0 + u * c - v * s, 15.0 + u * s + v * c])
        .collect();
    assert_points(&holes(&m), &want);
    assert!(bottoms(&m).iter().all(|&t| (t + 5.0).abs() < 1e-9));
    // Q301 = 1: every sideways move at the 2nd set-up clearance 5 + 50
    let mut pos = start;
    for mv in &m {
        if let Move::Line { to, .. } = *mv {
            if to[0] != pos[0] || to[1] != pos[1] {
                assert!(
                    (to[2] - 55.0).abs() < 1e-9 && (pos[2] - 55.0).abs() < 1e-9,
                    "{mv:?}"
                );
            }
            pos = to;
        }
    }
    assert_no_rapid_into_material(&m, start, -1.0, |_, _| 7.0, |_, _| 7.0);
    let r = run_pattern(221, &cart(&[(242, 99_999.0), (243, 99_999.0)]), start);
    assert!(matches!(r, Err(CycleError::Geometry { cycle: 221, .. })));
    let r = run_pattern(221, &cart(&[(242, 2.5)]), start);
    assert!(matches!(r, Err(CycleError::OutOfRange { cycle: 221, .. })));
}

#[test]
fn pattern_with_old_cycle_and_errors() {
    let start = [0.0, 0.0, 100.0];
    // old cycle 1 (set-up clearance 1, depth -6, pecks of 6) on a 1 x 2 grid at surface 5
    let old = Defs(vec![
        (ParamKey::Old { line: 1, index: 0 }, 1.0),
        (ParamKey::Old { line: 2, index: 0 }, -6.0),
        (ParamKey::Old { line: 3, index: 0 }, 6.0),
        (ParamKey::OldWord("F"), 2.0),
    ]);
    let mut out = Vec::new();
    generate_pattern(
        221,
        &cart(&[(242, 2.0), (243, 1.0), (224, 0.0)]),
        1,
        &old,
        &ctx_at(start),
        &mut out,
    )
    .unwrap();
    assert_eq!(holes(&out), vec![[15.0, 15.0], [25.0, 15.0]]);
    assert!(bottoms(&out).iter().all(|&t| (t + 1.0).abs() < 1e-9));
    assert_no_rapid_into_material(&out, start, -1.0, |_, _| 6.0, |_, _| 6.0);
    // unknown machining cycle, or an error inside it: nothing is emitted
    let mut out = vec![Move::Dwell(1.0)];
    let r = generate_pattern(220, &polar(&[]), 999, &drill(), &ctx_at(start), &mut out);
    assert_eq!(r, Err(CycleError::Unknown(999)));
    let r = generate_pattern(
        220,
        &polar(&[]),
        200,
        &with(&drill(), 206, -5.0),
        &ctx_at(start),
        &mut out,
    );
    assert!(matches!(r, Err(CycleError::OutOfRange { cycle: 200, .. })));
    assert_eq!(out, vec![Move::Dwell(1.0)]);
    let r = generate_pattern(222, &polar(&[]), 200, &drill(), &ctx_at(start), &mut out);
    assert_eq!(r, Err(CycleError::Unknown(222)));
}

#[test]
fn at_points_surface_from_point_and_clearance_height() {
    let mp = qs(&[
        (200, 2.0),
        (201, -10.0),
        (206, 120.0),
        (202, 10.0),
        (203, 0.0),
        (204, 20.0),
    ]);
    let points = [[10.0, 10.0, 0.0], [30.0, 10.0, -5.0], [30.0, 40.0, 30.0]];
    let start = [0.0, 0.0, 40.0];
    let mut out = Vec::new();
    generate_at_points(&points, 200, &mp, &ctx_at(start), &mut out).unwrap();
    assert_eq!(holes(&out), vec![[10.0, 10.0], [30.0, 10.0], [30.0, 40.0]]);
    // each hole 10 deep from its own surface
    assert_eq!(bottoms(&out), vec![-10.0, -15.0, 20.0]);
    // clearance height: max(call position 40, highest 2nd set-up clearance 30 + 20) = 50;
    // every sideways move happens there
    let mut pos = start;
    for mv in &out {
        if let Move::Line { to, .. } = *mv {
            if to[0] != pos[0] || to[1] != pos[1] {
                assert!(
                    (to[2] - 50.0).abs() < 1e-9 && (pos[2] - 50.0).abs() < 1e-9,
                    "{mv:?}"
                );
            }
            pos = to;
        }
    }
    let safe = |a: f64, b: f64| {
        points
            .iter()
            .find(|p| p[0] == a && p[1] == b)
            .map_or(50.0, |p| p[2] + 2.0)
    };
    assert_no_rapid_into_material(&out, start, -1.0, safe, safe);
}
