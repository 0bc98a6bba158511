//! Tests of the SL cycles against the contours' own geometry.

use super::super::pocket::testutil::{assert_rapids_above, ctx, ends, qs, sample};
use super::super::{Contour, ContourSeg, CycleError, CycleFeed, Move, generate_sl};
use std::f64::consts::PI;

/// Pocket: rectangle 0..100 × 0..60 with a half circle of radius 30 on its right side,
/// counter-clockwise with RL. Islands: circle of radius 10 about (40, 30), clockwise with
/// RL; triangle (10, 45) (25, 45) (10, 55) counter-clockwise with RR.
fn contours() -> Vec<Contour> {
    vec![
        Contour {
            start: [0.0, 0.0],
            segs: vec![
                ContourSeg::Line { to: [100.0, 0.0] },
                ContourSeg::Arc {
                    to: [100.0, 60.0],
                    centre: [100.0, 30.0],
                    ccw: true,
                },
                ContourSeg::Line { to: [0.0, 60.0] },
                ContourSeg::Line { to: [0.0, 0.0] },
            ],
            left: Some(true),
        },
        Contour {
            start: [50.0, 30.0],
            segs: vec![ContourSeg::Arc {
                to: [50.0, 30.0],
                centre: [40.0, 30.0],
                ccw: false,
            }],
            left: Some(true),
        },
        Contour {
            start: [10.0, 45.0],
            segs: vec![
                ContourSeg::Line { to: [25.0, 45.0] },
                ContourSeg::Line { to: [10.0, 55.0] },
                ContourSeg::Line { to: [10.0, 45.0] },
            ],
            left: Some(false),
        },
    ]
}

fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// Distance to the true contours (lines, the half circle, the circle).
fn dist(p: [f64; 2]) -> f64 {
    let lines = [
        ([0.0, 0.0], [100.0, 0.0]),
        ([100.0, 60.0], [0.0, 60.0]),
        ([0.0, 60.0], [0.0, 0.0]),
        ([10.0, 45.0], [25.0, 45.0]),
        ([25.0, 45.0], [10.0, 55.0]),
        ([10.0, 55.0], [10.0, 45.0]),
    ];
    let mut d = lines
        .iter()
        .map(|(a, b)| seg_dist(p, *a, *b))
        .fold(f64::INFINITY, f64::min);
    // Half circle x ≥ 100 about (100, 30), radius 30.
    let hc = if p[0] >= 100.0 {
        ((p[0] - 100.0).hypot(p[1] - 30.0) - 30.0).abs()
    } else {
        (p[0] - 100.0)
            .hypot(p[1])
            .min((p[0] - 100.0).hypot(p[1] - 60.0))
    };
    d = d.min(hc);
    d.min(((p[0] - 40.0).hypot(p[1] - 30.0) - 10.0).abs())
}

/// Inside the pocket and outside both islands.
fn in_area(p: [f64; 2]) -> bool {
    let pocket = (p[0] >= 0.0 && p[0] <= 100.0 && p[1] >= 0.0 && p[1] <= 60.0)
        || (p[0] >= 100.0 && (p[0] - 100.0).hypot(p[1] - 30.0) <= 30.0);
    let circle = (p[0] - 40.0).hypot(p[1] - 30.0) < 10.0;
    // Triangle: x ≥ 10, y ≥ 45, and below the line from (25, 45) to (10, 55).
    let tri = p[0] > 10.0 && p[1] > 45.0 && (p[1] - 45.0) * 15.0 + (p[0] - 10.0) * 10.0 < 150.0;
    pocket && !circle && !tri
}

fn data(extra: &[(u32, f64)]) -> Vec<(u32, f64)> {
    let mut v = vec![
        (1, -10.0),
        (2, 1.5),
        (3, 0.5),
        (4, 0.5),
        (5, 0.0),
        (6, 2.0),
        (7, 50.0),
        (8, 0.0),
        (9, 1.0),
    ];
    for &(k, x) in extra {
        v.retain(|(q, _)| *q != k);
        v.push((k, x));
    }
    v
}

fn run(
    cycle: u32,
    c: &[Contour],
    d: &[(u32, f64)],
    q: &[(u32, f64)],
    r: f64,
) -> Result<Vec<Move>, CycleError> {
    let mut out = Vec::new();
    generate_sl(
        cycle,
        c,
        &qs(d),
        &qs(q),
        &ctx([-20.0, -20.0, 100.0], r),
        &mut out,
    )?;
    Ok(out)
}

#[test]
fn rough_out_keeps_clear_of_pocket_walls_and_islands() {
    let r = 4.0;
    let m = run(
        22,
        &contours(),
        &data(&[]),
        &[(10, 4.0), (11, 100.0), (12, 600.0)],
        r,
    )
    .unwrap();
    let s = sample(&m, [-20.0, -20.0, 100.0], 0.2);
    let mut cuts = 0;
    for x in s.iter().filter(|x| x.p[2] < 0.0) {
        let p = [x.p[0], x.p[1]];
        assert!(in_area(p), "{x:?} outside the area");
        assert!(
            dist(p) >= r + 0.5 - 1e-6,
            "{x:?} only {} from a contour",
            dist(p)
        );
        cuts += 1;
    }
    assert!(cuts > 1000);
    assert_rapids_above(&m, [-20.0, -20.0, 100.0], 2.0);
    // Infeeds of 4 down to −10 + 0.5.
    let mut z: Vec<f64> = ends(&m)
        .iter()
        .filter(|(_, f)| *f == CycleFeed::Rate(10.0))
        .map(|(p, _)| p[2])
        .collect();
    z.sort_by(|a, b| b.total_cmp(a));
    z.dedup();
    assert_eq!(z, vec![-4.0, -8.0, -9.5]);
}

#[test]
fn rough_out_clears_the_area_between_the_walls() {
    let r = 4.0;
    let m = run(
        22,
        &contours(),
        &data(&[]),
        &[(10, 4.0), (11, 100.0), (12, 600.0)],
        r,
    )
    .unwrap();
    let s = sample(&m, [-20.0, -20.0, 100.0], 0.5);
    let last: Vec<[f64; 2]> = s
        .iter()
        .filter(|x| (x.p[2] + 9.5).abs() < 1e-9)
        .map(|x| [x.p[0], x.p[1]])
        .collect();
    // Stepover 1.5 × 4 = 6: every point well inside the tool-centre area lies within the
    // tool radius of a cut.
    let mut checked = 0;
    for i in 0..=130 {
        for j in 0..=60 {
            let p = [i as f64, j as f64];
            if in_area(p) && dist(p) >= r + 0.5 + 6.0 {
                checked += 1;
                assert!(
                    last.iter()
                        .any(|q| (q[0] - p[0]).hypot(q[1] - p[1]) <= r + 0.26),
                    "{p:?} left standing"
                );
            }
        }
    }
    assert!(checked > 500);
}

#[test]
fn floor_finishing_cuts_once_at_the_depth() {
    let m = run(
        23,
        &contours(),
        &data(&[]),
        &[(11, 100.0), (12, 300.0)],
        3.0,
    )
    .unwrap();
    let z: Vec<f64> = ends(&m)
        .iter()
        .filter(|(_, f)| *f == CycleFeed::Rate(5.0))
        .map(|(p, _)| p[2])
        .collect();
    assert!(!z.is_empty() && z.iter().all(|h| *h == -10.0));
    let s = sample(&m, [-20.0, -20.0, 100.0], 0.2);
    for x in s.iter().filter(|x| x.p[2] < 0.0) {
        assert!(dist([x.p[0], x.p[1]]) >= 3.5 - 1e-6);
    }
}

#[test]
fn contour_direction_and_compensation_tell_pocket_from_island() {
    // A clockwise square with RR is a pocket: the tool cuts inside it.
    let sq = |left: Option<bool>| Contour {
        start: [0.0, 0.0],
        segs: vec![
            ContourSeg::Line { to: [0.0, 30.0] },
            ContourSeg::Line { to: [30.0, 30.0] },
            ContourSeg::Line { to: [30.0, 0.0] },
            ContourSeg::Line { to: [0.0, 0.0] },
        ],
        left,
    };
    let m = run(
        22,
        &[sq(Some(false))],
        &data(&[(3, 0.0)]),
        &[(10, 20.0)],
        2.0,
    )
    .unwrap();
    for (p, _) in ends(&m).iter().filter(|(p, _)| p[2] < 0.0) {
        assert!(
            p[0] >= 2.0 - 1e-6 && p[0] <= 28.0 + 1e-6 && p[1] >= 2.0 - 1e-6 && p[1] <= 28.0 + 1e-6
        );
    }
    // The same square with RL is an island; islands alone are an error.
    assert!(matches!(
        run(22, &[sq(Some(true))], &data(&[]), &[(10, 20.0)], 2.0),
        Err(CycleError::Geometry { .. })
    ));
    // Without compensation the first contour is the pocket.
    assert!(run(22, &[sq(None)], &data(&[]), &[(10, 20.0)], 2.0).is_ok());
}

#[test]
fn sl_errors() {
    let c = contours();
    assert!(matches!(
        run(22, &[], &data(&[]), &[(10, 4.0)], 4.0),
        Err(CycleError::Geometry { .. })
    ));
    assert!(matches!(
        run(22, &c, &data(&[(1, 5.0)]), &[(10, 4.0)], 4.0),
        Err(CycleError::OutOfRange { .. })
    ));
    assert!(matches!(
        run(22, &c, &data(&[]), &[], 4.0),
        Err(CycleError::Missing { .. })
    ));
    // A tool wider than the pocket.
    assert!(matches!(
        run(22, &c, &data(&[]), &[(10, 4.0)], 40.0),
        Err(CycleError::Geometry { .. })
    ));
    // Depth 0 does nothing.
    assert!(
        run(22, &c, &data(&[(1, 0.0)]), &[(10, 4.0)], 4.0)
            .unwrap()
            .is_empty()
    );
}

#[test]
fn side_finishing_follows_every_wall_at_the_tool_radius() {
    let r = 3.0;
    // Q14 = 0.2 left on the side; Q10 = 6: cuts at −6 and −10.
    let q = [(9, 1.0), (10, 6.0), (11, 100.0), (12, 300.0), (14, 0.2)];
    let m = run(24, &contours(), &data(&[]), &q, r).unwrap();
    let rho = r + 0.2;
    let s = sample(&m, [-20.0, -20.0, 100.0], 0.1);
    let cut: Vec<_> = s
        .iter()
        .filter(|x| x.p[2] < 0.0 && x.feed == CycleFeed::Rate(5.0))
        .collect();
    let mut bottom_x = Vec::new();
    let mut island = Vec::new();
    let mut z: Vec<f64> = Vec::new();
    for x in &cut {
        let p = [x.p[0], x.p[1]];
        let d = dist(p);
        assert!(in_area(p) && d >= rho - 1e-6, "{x:?} at {d}");
        // On the wall offset, give or take the chords standing for arcs.
        assert!(d <= rho + 3e-3, "{x:?} at {d} off the wall");
        if (x.p[2] + 10.0).abs() < 1e-9 {
            if (p[1] - rho).abs() < 3e-3 {
                bottom_x.push(p[0]);
            }
            if ((p[0] - 40.0).hypot(p[1] - 30.0) - 10.0 - rho).abs() < 3e-3 {
                island.push((x.idx, (p[1] - 30.0).atan2(p[0] - 40.0)));
            }
        }
        if !z.iter().any(|h| (h - x.p[2]).abs() < 1e-9) {
            z.push(x.p[2]);
        }
    }
    z.sort_by(f64::total_cmp);
    assert_eq!(z, vec![-10.0, -6.0]);
    // The pocket's lower wall is followed from the left wall's offset to the half circle.
    bottom_x.sort_by(f64::total_cmp);
    assert!(bottom_x[0] <= rho + 1e-3 && *bottom_x.last().unwrap() >= 100.0 - 1e-3);
    assert!(bottom_x.windows(2).all(|w| w[1] - w[0] < 0.2));
    // The island is followed all the way round, clockwise (climb milling with M3).
    let mut angles: Vec<f64> = island.iter().map(|(_, a)| *a).collect();
    angles.sort_by(f64::total_cmp);
    assert!(angles.windows(2).all(|w| w[1] - w[0] < 0.05));
    assert!(angles[0] < -3.1 && *angles.last().unwrap() > 3.1);
    let turning: f64 = island
        .windows(2)
        .filter(|w| w[0].0 + 1 == w[1].0 || w[0].0 == w[1].0)
        .map(|w| (w[1].1 - w[0].1 + PI).rem_euclid(2.0 * PI) - PI)
        .sum();
    assert!(turning < -6.0, "island turned {turning}");
}

#[test]
fn random_contours_never_panic() {
    let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = move || {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (seed >> 33) as f64 / (1u64 << 31) as f64
    };
    for round in 0..20 {
        let mut cs = Vec::new();
        for k in 0..(1 + round % 3) {
            let n = 3 + (next() * 6.0) as usize;
            let start = [next() * 80.0, next() * 60.0];
            let mut segs = Vec::new();
            for i in 0..n {
                let to = if i + 1 == n {
                    start
                } else {
                    [next() * 80.0, next() * 60.0]
                };
                if next() < 0.3 {
                    // An arc whose centre lies on the perpendicular bisector of its chord.
                    let from = segs.last().map_or(start, |s| match s {
                        ContourSeg::Line { to } | ContourSeg::Arc { to, .. } => *to,
                    });
                    let mid = [(from[0] + to[0]) / 2.0, (from[1] + to[1]) / 2.0];
                    let d = [to[1] - from[1], from[0] - to[0]];
                    let t = next() - 0.5;
                    let centre = [mid[0] + t * d[0], mid[1] + t * d[1]];
                    segs.push(ContourSeg::Arc {
                        to,
                        centre,
                        ccw: next() < 0.5,
                    });
                } else {
                    segs.push(ContourSeg::Line { to });
                }
            }
            let left = match (k + round) % 3 {
                0 => None,
                1 => Some(true),
                _ => Some(false),
            };
            cs.push(Contour { start, segs, left });
        }
        for cycle in [22, 23, 24] {
            let r = 0.5 + next() * 6.0;
            let res = run(cycle, &cs, &data(&[(2, 0.3 + next())]), &[(10, 3.0)], r);
            if let Ok(m) = res {
                for mv in &m {
                    if let Move::Line { to, .. } = mv {
                        assert!(to.iter().all(|c| c.is_finite()));
                    }
                }
            }
        }
    }
}
