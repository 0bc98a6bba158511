//! Tests of the old pocket cycles, face milling and the circular slot.

use super::super::{CycleError, CycleFeed, Move, ParamKey, generate};
use super::tests::{rate, run};
use super::testutil::{assert_rapids_above, ctx, ends, sample, sd_rbox};

#[test]
fn old_circular_pocket_sequence() {
    // CYCL DEF 5.1 SET UP 2 / 5.2 DEPTH -6 / 5.3 PECKG 3 F / 5.4 RADIUS 12 / 5.5 F DR-,
    // tool R4 over (10, 20) at 2 above the surface (z 2 → surface 0).
    let src = |k: ParamKey| match k {
        ParamKey::Old { line: 1, index: 0 } => Some(2.0),
        ParamKey::Old { line: 2, index: 0 } => Some(-6.0),
        ParamKey::Old { line: 3, index: 0 } => Some(3.0),
        ParamKey::Old { line: 4, index: 0 } => Some(12.0),
        ParamKey::OldWord("F") => Some(2.0),
        ParamKey::OldWord("DR") => Some(-1.0),
        _ => None,
    };
    let mut out = Vec::new();
    generate(5, &src, &ctx([10.0, 20.0, 2.0], 4.0), &mut out).unwrap();
    let f = CycleFeed::Rate(2.0);
    let cw_circle = |r: f64, z: f64| -> Vec<Move> {
        let pts = [
            [10.0, 20.0 - r],
            [10.0 - r, 20.0],
            [10.0, 20.0 + r],
            [10.0 + r, 20.0],
        ];
        let mut v = vec![Move::Line {
            to: [10.0 + r, 20.0, z],
            feed: f,
        }];
        for p in pts {
            v.push(Move::Arc {
                centre: [10.0, 20.0],
                to: [p[0], p[1], z],
                ccw: false,
                turns: 0,
                feed: f,
            });
        }
        v
    };
    // Wall radius 12 − tool 4 = 8; stepover = tool radius 4: rings of radius 4 and 8.
    let mut want = Vec::new();
    for z in [-3.0, -6.0] {
        want.push(Move::Line {
            to: [10.0, 20.0, z],
            feed: f,
        });
        want.extend(cw_circle(4.0, z));
        want.extend(cw_circle(8.0, z));
        want.push(Move::Line {
            to: [10.0, 20.0, z],
            feed: f,
        });
    }
    want.push(Move::Line {
        to: [10.0, 20.0, 2.0],
        feed: CycleFeed::Rapid,
    });
    assert_eq!(out.len(), want.len());
    for (a, b) in out.iter().zip(&want) {
        let close = match (a, b) {
            (Move::Line { to: t1, feed: f1 }, Move::Line { to: t2, feed: f2 }) => {
                f1 == f2 && (0..3).all(|i| (t1[i] - t2[i]).abs() < 1e-9)
            }
            (
                Move::Arc {
                    centre: c1,
                    to: t1,
                    ccw: d1,
                    turns: n1,
                    feed: f1,
                },
                Move::Arc {
                    centre: c2,
                    to: t2,
                    ccw: d2,
                    turns: n2,
                    feed: f2,
                },
            ) => {
                c1 == c2
                    && d1 == d2
                    && n1 == n2
                    && f1 == f2
                    && (0..3).all(|i| (t1[i] - t2[i]).abs() < 1e-9)
            }
            _ => false,
        };
        assert!(close, "{a:?} != {b:?}");
    }
}

#[test]
fn face_milling_covers_the_area_in_even_infeeds() {
    // Area 100 × 45 from (0, 0), from z 2 down to 0 with 0.6 max infeed, tool R10.
    let q = [
        (389, 0.0),
        (225, 0.0),
        (226, 0.0),
        (227, 2.0),
        (386, 0.0),
        (218, 100.0),
        (219, 45.0),
        (202, 0.6),
        (369, 0.0),
        (370, 0.7),
        (207, 800.0),
        (385, 400.0),
        (253, 3000.0),
        (200, 2.0),
        (357, 3.0),
        (204, 20.0),
    ];
    let pos = [-50.0, -50.0, 50.0];
    let m = run(232, &q, pos, 10.0).unwrap();
    // 2 mm in cuts of at most 0.6: 4 cuts of 0.5.
    let mut z: Vec<f64> = ends(&m)
        .iter()
        .filter(|(_, f)| *f == rate(800.0))
        .map(|(p, _)| p[2])
        .collect();
    z.sort_by(|a, b| b.total_cmp(a));
    z.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    assert_eq!(z.len(), 4);
    for (k, h) in z.iter().enumerate() {
        assert!((h - (2.0 - 0.5 * (k as f64 + 1.0))).abs() < 1e-9);
    }
    // Cuts at the last level: straight lines along the first axis; every point of the
    // area lies within the tool radius of one of them.
    let s = sample(&m, pos, 0.5);
    let last: Vec<_> = s
        .iter()
        .filter(|x| x.feed == rate(800.0) && x.p[2].abs() < 1e-9)
        .collect();
    for i in 0..=50 {
        for j in 0..=45 {
            let (a, b) = (2.0 * i as f64, j as f64);
            let near = last
                .iter()
                .any(|x| (x.p[0] - a).hypot(x.p[1] - b) <= 10.0 + 0.3);
            assert!(near, "({a}, {b}) not covered");
        }
    }
    // Passes start and end outside the area by radius + side clearance.
    let xs: Vec<f64> = last.iter().map(|x| x.p[0]).collect();
    assert!(xs.iter().cloned().fold(f64::MAX, f64::min) <= -13.0 + 1e-9);
    assert!(xs.iter().cloned().fold(f64::MIN, f64::max) >= 113.0 - 1e-9);
    assert_rapids_above(&m, pos, 4.0);
}

/// Distance from `p` to the centre line of a circular slot (arc about `c`, radius `rm`,
/// from `a0` over `sweep` degrees counter-clockwise).
fn arc_line_dist(p: [f64; 2], c: [f64; 2], rm: f64, a0: f64, sweep: f64) -> f64 {
    let ang = (p[1] - c[1]).atan2(p[0] - c[0]).to_degrees();
    let rel = (ang - a0).rem_euclid(360.0);
    if rel <= sweep {
        ((p[0] - c[0]).hypot(p[1] - c[1]) - rm).abs()
    } else {
        let e = |a: f64| {
            [
                c[0] + rm * a.to_radians().cos(),
                c[1] + rm * a.to_radians().sin(),
            ]
        };
        let (e0, e1) = (e(a0), e(a0 + sweep));
        (p[0] - e0[0])
            .hypot(p[1] - e0[1])
            .min((p[0] - e1[0]).hypot(p[1] - e1[1]))
    }
}

#[test]
fn circular_slot_stays_in_its_band_and_repeats() {
    // Slot width 12 on a 80 circle about (5, 5), from 30° over 100°, twice 180° apart;
    // tool R4, allowance 0.3.
    let q = [
        (215, 0.0),
        (219, 12.0),
        (368, 0.3),
        (375, 80.0),
        (367, 0.0),
        (216, 5.0),
        (217, 5.0),
        (376, 30.0),
        (248, 100.0),
        (378, 180.0),
        (377, 2.0),
        (207, 400.0),
        (351, 1.0),
        (201, -5.0),
        (202, 2.5),
        (369, 0.0),
        (206, 100.0),
        (338, 0.0),
        (200, 2.0),
        (203, 0.0),
        (204, 10.0),
        (366, 1.0),
        (385, 200.0),
        (370, 1.0),
    ];
    let pos = [0.0, 0.0, 20.0];
    let m = run(254, &q, pos, 4.0).unwrap();
    let s = sample(&m, pos, 0.25);
    let mut touch = [0, 0];
    for x in s.iter().filter(|x| x.p[2] < 0.0) {
        let p = [x.p[0], x.p[1]];
        let d = arc_line_dist(p, [5.0, 5.0], 40.0, 30.0, 100.0).min(arc_line_dist(
            p,
            [5.0, 5.0],
            40.0,
            210.0,
            100.0,
        ));
        // Slot half width 6 less the tool radius.
        assert!(d <= 2.0 + 1e-9, "{x:?} {d}");
        if x.feed == rate(400.0) {
            assert!(d <= 1.7 + 1e-9);
        }
        if d > 2.0 - 1e-9 {
            assert_eq!(x.feed, rate(200.0));
            let first = arc_line_dist(p, [5.0, 5.0], 40.0, 30.0, 100.0) < 2.0 + 1e-9;
            touch[usize::from(!first)] += 1;
        }
    }
    assert!(touch[0] > 100 && touch[1] > 100, "{touch:?}");
    assert_rapids_above(&m, pos, 2.0);
    // Wider than the pitch circle: refused.
    let mut bad = q.to_vec();
    bad.retain(|(k, _)| *k != 375);
    bad.push((375, 10.0));
    assert!(matches!(
        run(254, &bad, pos, 4.0),
        Err(CycleError::Geometry { .. })
    ));
}

#[test]
fn old_pocket_milling_clears_the_rectangle() {
    // CYCL DEF 4.1 SET UP 2 / 4.2 DEPTH -8 / 4.3 PECKG 4 F / 4.4 X+40 / 4.5 Y+30 /
    // 4.6 F DR+ / 4.7 RADIUS 6, tool R5 over (0, 0) at z 2.
    let src = |k: ParamKey| match k {
        ParamKey::Old { line: 1, index: 0 } => Some(2.0),
        ParamKey::Old { line: 2, index: 0 } => Some(-8.0),
        ParamKey::Old { line: 3, index: 0 } => Some(4.0),
        ParamKey::OldWord("X") => Some(40.0),
        ParamKey::OldWord("Y") => Some(30.0),
        ParamKey::Old { line: 7, index: 0 } => Some(6.0),
        ParamKey::OldWord("F") => Some(3.0),
        ParamKey::OldWord("DR") => Some(1.0),
        _ => None,
    };
    let pos = [0.0, 0.0, 2.0];
    let mut out = Vec::new();
    generate(4, &src, &ctx(pos, 5.0), &mut out).unwrap();
    let s = sample(&out, pos, 0.25);
    let mut touch = 0;
    for x in s.iter().filter(|x| x.p[2] < 0.0) {
        let d = sd_rbox([x.p[0], x.p[1]], 20.0, 15.0, 6.0);
        assert!(d <= -5.0 + 1e-9, "{x:?}");
        if d > -5.0 - 1e-9 {
            touch += 1;
            assert!(x.p[2] == -4.0 || x.p[2] == -8.0);
        }
    }
    assert!(touch > 200);
    assert!(
        out.iter()
            .all(|m| !matches!(m, Move::Arc { ccw: false, .. }))
    );
    assert_eq!(ends(&out).last().unwrap().0, pos);
    // Without a feed the definition is incomplete.
    let no_f = |k: ParamKey| {
        if k == ParamKey::OldWord("F") {
            None
        } else {
            src(k)
        }
    };
    assert!(matches!(
        generate(4, &no_f, &ctx(pos, 5.0), &mut out),
        Err(CycleError::Missing { .. })
    ));
}

#[test]
fn face_milling_233_line_by_line_along_the_second_axis() {
    // 60 × 40 area centred on the tool at (100, 100), passes along the second axis without
    // overtravel, from z 1 to 0 in cuts of at most 0.6 with 0.2 left for finishing.
    let q = [
        (215, 0.0),
        (389, 3.0),
        (350, 2.0),
        (218, 60.0),
        (219, 40.0),
        (227, 1.0),
        (386, 0.0),
        (369, 0.2),
        (202, 0.6),
        (370, 0.5),
        (207, 600.0),
        (385, 300.0),
        (253, 2000.0),
        (200, 2.0),
        (357, 2.0),
        (204, 30.0),
        (367, 0.0),
    ];
    let pos = [100.0, 100.0, 60.0];
    let m = run(233, &q, pos, 8.0).unwrap();
    // Roughing 0.8 in two cuts of 0.4, finishing at 0.
    let mut cur = pos;
    let mut levels: Vec<(f64, CycleFeed)> = Vec::new();
    let mut passes = Vec::new();
    for mv in &m {
        if let Move::Line { to, feed } = *mv {
            if to[2] < 1.0 && (feed == rate(600.0) || feed == rate(300.0)) && to[2] == cur[2] {
                // A cutting pass: along the second axis only, from below the area to
                // Q357 = 2 beyond its upper edge.
                assert!((to[0] - cur[0]).abs() < 1e-9, "{cur:?} -> {to:?}");
                assert!((cur[1] - (80.0 - 10.0)).abs() < 1e-9 && (to[1] - 122.0).abs() < 1e-9);
                passes.push((to[0], to[2], feed));
                if !levels.iter().any(|(z, _)| (z - to[2]).abs() < 1e-9) {
                    levels.push((to[2], feed));
                }
            }
            cur = to;
        }
    }
    assert_eq!(levels.len(), 3);
    assert!((levels[0].0 - 0.6).abs() < 1e-9 && (levels[1].0 - 0.2).abs() < 1e-9);
    assert_eq!(levels[2], (0.0, rate(300.0)));
    // Passes at one level: across 70..130 at most 8 apart (0.5 × 16), covering both edges.
    let mut xs: Vec<f64> = passes.iter().filter(|p| p.1 == 0.0).map(|p| p.0).collect();
    xs.sort_by(f64::total_cmp);
    assert!((xs[0] - 70.0).abs() < 1e-9 && (xs.last().unwrap() - 130.0).abs() < 1e-9);
    assert!(xs.windows(2).all(|w| w[1] - w[0] <= 8.0 + 1e-9));
    assert_rapids_above(&m, pos, 3.0);
    let bad = |k: u32, v: f64| {
        let mut b = q.to_vec();
        b.retain(|(x, _)| *x != k);
        b.push((k, v));
        run(233, &b, pos, 8.0).unwrap_err()
    };
    assert!(matches!(bad(389, 4.0), CycleError::Geometry { .. }));
    assert!(matches!(bad(347, 1.0), CycleError::Geometry { .. }));
    assert!(matches!(bad(350, 0.0), CycleError::OutOfRange { .. }));
}

#[test]
fn circular_slot_of_a_full_turn_is_a_ring() {
    // Q367 = 1: the tool is over the start end circle at 0°, so the centre lies 30 to its
    // left.
    let q = [
        (219, 10.0),
        (375, 60.0),
        (367, 1.0),
        (376, 0.0),
        (248, 360.0),
        (207, 400.0),
        (201, -3.0),
        (202, 3.0),
        (203, 0.0),
        (366, 0.0),
        (370, 0.5),
    ];
    let pos = [30.0, 0.0, 20.0];
    let m = run(254, &q, pos, 3.0).unwrap();
    let s = sample(&m, pos, 0.25);
    let mut angles = Vec::new();
    for x in s.iter().filter(|x| x.p[2] < 0.0) {
        let rr = x.p[0].hypot(x.p[1]);
        assert!((rr - 30.0).abs() <= 2.0 + 1e-9, "{x:?}");
        if (rr - 32.0).abs() < 1e-9 {
            angles.push(x.p[1].atan2(x.p[0]));
        }
    }
    angles.sort_by(f64::total_cmp);
    assert!(angles.windows(2).all(|w| w[1] - w[0] < 0.05));
    assert!(angles[0] < -3.1 && *angles.last().unwrap() > 3.1);
}
