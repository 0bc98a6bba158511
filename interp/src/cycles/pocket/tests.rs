//! Tests of the pocket, stud and face-milling cycles against the manual's definitions.

use super::super::{CycleError, CycleFeed, Move, P3, ParamKey, generate};
use super::testutil::{assert_rapids_above, ctx, ends, qs, sample, sd_rbox, to_local};
use crate::op::SpindleDir;

pub(super) fn run(cycle: u32, q: &[(u32, f64)], pos: P3, r: f64) -> Result<Vec<Move>, CycleError> {
    let mut out = Vec::new();
    generate(cycle, &qs(q), &ctx(pos, r), &mut out)?;
    Ok(out)
}

pub(super) fn rate(mm_min: f64) -> CycleFeed {
    CycleFeed::Rate(mm_min / 60.0)
}

/// Circular pocket D60 at (10, 20), surface 0, depth −12, infeeds of 5, tool R5.
fn p252(extra: &[(u32, f64)]) -> Vec<(u32, f64)> {
    let mut v = vec![
        (215, 0.0),
        (223, 60.0),
        (368, 0.5),
        (207, 600.0),
        (351, 1.0),
        (201, -12.0),
        (202, 5.0),
        (369, 0.0),
        (206, 120.0),
        (338, 0.0),
        (200, 2.0),
        (203, 0.0),
        (204, 20.0),
        (370, 0.8),
        (366, 1.0),
        (385, 300.0),
    ];
    for &(k, x) in extra {
        v.retain(|(q, _)| *q != k);
        v.push((k, x));
    }
    v
}

#[test]
fn circular_pocket_finish_lies_on_the_wall_offset_by_the_tool_radius() {
    let pos = [10.0, 20.0, 30.0];
    let m = run(252, &p252(&[]), pos, 5.0).unwrap();
    let fin: Vec<_> = m
        .iter()
        .filter(|mv| matches!(mv, Move::Arc { centre, feed, .. } if *feed == rate(300.0) && (centre[0] - 10.0).abs() < 1e-9 && (centre[1] - 20.0).abs() < 1e-9))
        .collect();
    assert!(!fin.is_empty());
    let s = sample(&m, pos, 0.5);
    let mut on_wall_angles = Vec::new();
    for x in &s {
        let rr = (x.p[0] - 10.0).hypot(x.p[1] - 20.0);
        // Nothing ever reaches beyond the wall minus the tool radius.
        assert!(rr <= 25.0 + 1e-9, "{x:?}");
        if x.feed == rate(600.0) {
            assert!(
                rr <= 25.0 - 0.5 + 1e-9,
                "roughing cuts into the allowance: {x:?}"
            );
        }
        if rr > 25.0 - 1e-9 {
            assert_eq!(x.feed, rate(300.0));
            assert!((x.p[2] + 12.0).abs() < 1e-9, "finish not at depth: {x:?}");
            on_wall_angles.push((x.p[1] - 20.0).atan2(x.p[0] - 10.0));
        }
    }
    // The finishing pass goes all the way round.
    on_wall_angles.sort_by(f64::total_cmp);
    let gaps = on_wall_angles
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(0.0, f64::max);
    assert!(gaps < 0.05 && on_wall_angles[0] < -3.1 && *on_wall_angles.last().unwrap() > 3.1);
    assert_rapids_above(&m, pos, 2.0);
}

#[test]
fn circular_pocket_rings_step_at_most_the_overlap_times_the_diameter() {
    let pos = [0.0, 0.0, 30.0];
    let m = run(252, &p252(&[]), pos, 5.0).unwrap();
    let mut radii: Vec<f64> = Vec::new();
    for mv in &m {
        if let Move::Arc {
            centre, to, feed, ..
        } = *mv
            && feed == rate(600.0)
            && centre == [0.0, 0.0]
        {
            let rr = to[0].hypot(to[1]);
            if !radii.iter().any(|x| (x - rr).abs() < 1e-9) {
                radii.push(rr);
            }
        }
    }
    radii.sort_by(f64::total_cmp);
    // Outer ring: wall radius 30 − tool 5 − allowance 0.5.
    assert!((radii.last().unwrap() - 24.5).abs() < 1e-9);
    let step = 0.8 * 10.0;
    assert!(radii[0] <= step + 1e-9);
    for w in radii.windows(2) {
        assert!(w[1] - w[0] <= step + 1e-9 && w[1] - w[0] > 1.0);
    }
    // 24.5 / 8 → 4 equal steps of 6.125.
    assert_eq!(radii.len(), 4);
}

#[test]
fn infeeds_are_full_steps_then_the_remainder() {
    let pos = [0.0, 0.0, 30.0];
    let depths = |m: &[Move], feed: CycleFeed| {
        let mut z: Vec<f64> = ends(m)
            .iter()
            .filter(|(_, f)| *f == feed)
            .map(|(p, _)| p[2])
            .collect();
        z.sort_by(|a, b| b.total_cmp(a));
        z.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        z
    };
    let m = run(252, &p252(&[]), pos, 5.0).unwrap();
    assert_eq!(depths(&m, rate(600.0)), vec![-5.0, -10.0, -12.0]);
    // Floor allowance 1: roughing stops at −11, the floor is finished at −12.
    let m = run(252, &p252(&[(369, 1.0)]), pos, 5.0).unwrap();
    assert_eq!(depths(&m, rate(600.0)), vec![-5.0, -10.0, -11.0]);
    assert_eq!(depths(&m, rate(300.0)), vec![-12.0]);
    // Finishing infeed Q338 = 7: walls finished at −7 and −12.
    let m = run(252, &p252(&[(338, 7.0)]), pos, 5.0).unwrap();
    assert_eq!(depths(&m, rate(300.0)), vec![-7.0, -12.0]);
}

#[test]
fn helical_plunge_turns_about_the_centre_with_the_tool_radius() {
    let pos = [3.0, 4.0, 30.0];
    let m = run(252, &p252(&[]), pos, 5.0).unwrap();
    let mut cur = pos;
    let mut helices = 0;
    for mv in &m {
        if let Move::Arc {
            centre,
            to,
            feed,
            ccw,
            ..
        } = *mv
            && to[2] != cur[2]
        {
            helices += 1;
            assert_eq!(feed, rate(120.0));
            assert_eq!(centre, [3.0, 4.0]);
            assert!(((cur[0] - 3.0).hypot(cur[1] - 4.0) - 5.0).abs() < 1e-9);
            assert!(
                ccw,
                "climb milling with M3 turns counter-clockwise in a pocket"
            );
        }
        if let Move::Line { to, .. } | Move::Arc { to, .. } = *mv {
            cur = to;
        }
    }
    assert_eq!(helices, 3);
    // Vertical plunging: no helix at all, straight down at the centre.
    let m = run(252, &p252(&[(366, 0.0)]), pos, 5.0).unwrap();
    let first_cut = m
        .iter()
        .find(|mv| matches!(mv, Move::Line { feed, .. } if *feed == rate(120.0)))
        .unwrap();
    assert_eq!(
        *first_cut,
        Move::Line {
            to: [3.0, 4.0, -5.0],
            feed: rate(120.0)
        }
    );
}

#[test]
fn milling_direction_follows_q351_and_the_spindle() {
    let dirs = |q351: f64, spindle: SpindleDir| {
        let mut c = ctx([0.0, 0.0, 30.0], 5.0);
        c.spindle = spindle;
        let mut out = Vec::new();
        generate(252, &qs(&p252(&[(351, q351)])), &c, &mut out).unwrap();
        let v: Vec<bool> = out
            .iter()
            .filter_map(|m| match m {
                Move::Arc { ccw, feed, .. } if *feed == rate(600.0) => Some(*ccw),
                _ => None,
            })
            .collect();
        assert!(!v.is_empty());
        assert!(v.iter().all(|x| *x == v[0]));
        v[0]
    };
    assert!(dirs(1.0, SpindleDir::Cw));
    assert!(!dirs(-1.0, SpindleDir::Cw));
    assert!(!dirs(1.0, SpindleDir::Ccw));
}

/// Rectangular pocket 80 × 50, corner radius 10, turned 30°, tool R6.
fn p251(extra: &[(u32, f64)]) -> Vec<(u32, f64)> {
    let mut v = vec![
        (215, 0.0),
        (218, 80.0),
        (219, 50.0),
        (220, 10.0),
        (368, 0.4),
        (224, 30.0),
        (367, 0.0),
        (207, 500.0),
        (351, 1.0),
        (201, -9.0),
        (202, 4.0),
        (369, 0.2),
        (206, 150.0),
        (338, 0.0),
        (200, 2.0),
        (203, -1.0),
        (204, 10.0),
        (370, 1.0),
        (366, 1.0),
        (385, 250.0),
    ];
    for &(k, x) in extra {
        v.retain(|(q, _)| *q != k);
        v.push((k, x));
    }
    v
}

#[test]
fn rectangular_pocket_finish_is_the_offset_outline_rotated() {
    let pos = [100.0, 50.0, 20.0];
    let m = run(251, &p251(&[]), pos, 6.0).unwrap();
    let s = sample(&m, pos, 0.25);
    let mut touching = Vec::new();
    for x in &s {
        let l = to_local([x.p[0], x.p[1]], [100.0, 50.0], 30.0);
        let d = sd_rbox(l, 40.0, 25.0, 10.0);
        // The tool never cuts into the wall.
        assert!(d <= -6.0 + 1e-9, "{x:?} at {d}");
        if x.feed == rate(500.0) {
            assert!(
                d <= -6.4 + 1e-9,
                "roughing cuts into the side allowance: {x:?}"
            );
            assert!(
                x.p[2] >= -10.0 + 0.2 - 1e-9,
                "roughing cuts into the floor allowance"
            );
        }
        if d > -6.0 - 1e-9 {
            assert_eq!(x.feed, rate(250.0));
            assert!((x.p[2] + 10.0).abs() < 1e-9);
            touching.push(l[1].atan2(l[0]));
        }
    }
    touching.sort_by(f64::total_cmp);
    let gap = touching.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    assert!(
        gap < 0.05 && touching[0] < -3.1 && *touching.last().unwrap() > 3.1,
        "gap {gap}"
    );
    assert_rapids_above(&m, pos, 1.0);
    // Ends at the 2nd set-up clearance above the pocket centre.
    assert_eq!(ends(&m).last().unwrap().0, [100.0, 50.0, 9.0]);
}

#[test]
fn rectangular_pocket_position_q367_puts_the_tool_at_a_corner() {
    // Unrotated, tool at the lower left corner: the centre lies half the sides up and right.
    let pos = [0.0, 0.0, 20.0];
    let m = run(251, &p251(&[(224, 0.0), (367, 1.0)]), pos, 6.0).unwrap();
    let s = sample(&m, pos, 0.5);
    let below: Vec<_> = s.iter().filter(|x| x.p[2] < -1.0).collect();
    assert!(!below.is_empty());
    for x in below {
        assert!(
            sd_rbox([x.p[0] - 40.0, x.p[1] - 25.0], 40.0, 25.0, 10.0) <= -6.0 + 1e-9,
            "{x:?}"
        );
    }
    // Turned by 90°: the corner offset turns with the pocket.
    let m = run(251, &p251(&[(224, 90.0), (367, 1.0)]), pos, 6.0).unwrap();
    let last = ends(&m).last().unwrap().0;
    assert!((last[0] + 25.0).abs() < 1e-9 && (last[1] - 40.0).abs() < 1e-9);
}

#[test]
fn rectangular_pocket_rings_keep_the_stepover() {
    // Square 60 × 60, sharp corners, tool R5, overlap 0.5: rings at most 5 apart.
    let q = p251(&[
        (218, 60.0),
        (219, 60.0),
        (220, 0.0),
        (224, 0.0),
        (370, 0.5),
        (368, 0.0),
        (369, 0.0),
    ]);
    let m = run(251, &q, [0.0, 0.0, 10.0], 5.0).unwrap();
    // Each ring starts at (h, 0) with a straight move; h are the half sides of the rings.
    let mut h: Vec<f64> = ends(&m)
        .iter()
        .filter(|(p, f)| {
            *f == rate(500.0) && p[1].abs() < 1e-12 && p[0] > 1e-9 && (p[2] + 5.0).abs() < 1e-9
        })
        .map(|(p, _)| p[0])
        .collect();
    h.sort_by(f64::total_cmp);
    h.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    assert!((h.last().unwrap() - 25.0).abs() < 1e-9);
    assert!(h[0] <= 5.0 + 1e-9);
    for w in h.windows(2) {
        assert!(w[1] - w[0] <= 5.0 + 1e-9);
    }
}

#[test]
fn slot_stays_inside_its_outline() {
    // Slot 70 × 16 turned 45°, tool R5, the tool sits at the left end circle's centre.
    let q = [
        (215, 0.0),
        (218, 70.0),
        (219, 16.0),
        (368, 0.3),
        (374, 45.0),
        (367, 2.0),
        (207, 400.0),
        (351, 1.0),
        (201, -6.0),
        (202, 3.0),
        (369, 0.0),
        (206, 100.0),
        (338, 0.0),
        (200, 2.0),
        (203, 0.0),
        (204, 10.0),
        (366, 2.0),
        (385, 200.0),
        (370, 1.0),
    ];
    let pos = [0.0, 0.0, 10.0];
    let m = run(253, &q, pos, 5.0).unwrap();
    // Centre: 35 − 8 = 27 along the 45° axis from the tool.
    let c = [27.0 * 0.5f64.sqrt(), 27.0 * 0.5f64.sqrt()];
    let s = sample(&m, pos, 0.25);
    let mut touch = 0;
    for x in s.iter().filter(|x| x.p[2] < 0.0) {
        let d = sd_rbox(to_local([x.p[0], x.p[1]], c, 45.0), 35.0, 8.0, 8.0);
        assert!(d <= -5.0 + 1e-9, "{x:?} {d}");
        if d > -5.0 - 1e-9 {
            touch += 1;
            assert_eq!(x.feed, rate(200.0));
        }
    }
    assert!(touch > 100);
    assert_rapids_above(&m, pos, 2.0);
}

/// Rectangular stud 50 × 30 from a 70 × 40 blank, corner radius 5, turned 20°.
fn p256() -> Vec<(u32, f64)> {
    vec![
        (218, 50.0),
        (424, 70.0),
        (219, 30.0),
        (425, 40.0),
        (220, 5.0),
        (368, 0.5),
        (224, 20.0),
        (367, 0.0),
        (207, 500.0),
        (351, 1.0),
        (201, -8.0),
        (202, 5.0),
        (206, 150.0),
        (200, 2.0),
        (203, 0.0),
        (204, 15.0),
        (370, 0.6),
        (385, 250.0),
    ]
}

#[test]
fn rectangular_stud_tool_stays_off_the_stud() {
    let pos = [5.0, -5.0, 30.0];
    let m = run(256, &p256(), pos, 4.0).unwrap();
    let s = sample(&m, pos, 0.25);
    let mut finish = 0;
    let mut max_rough: f64 = 0.0;
    for x in s.iter().filter(|x| x.p[2] < 0.0) {
        let d = sd_rbox(
            to_local([x.p[0], x.p[1]], [5.0, -5.0], 20.0),
            25.0,
            15.0,
            5.0,
        );
        assert!(d >= 4.0 - 1e-9, "{x:?} {d}");
        if x.feed == rate(500.0) {
            assert!(d >= 4.5 - 1e-9);
            // Distance of the rough rings' corners from the stud.
            if matches!(m[x.idx], Move::Arc { .. }) {
                max_rough = max_rough.max(d);
            }
        }
        if (d - 4.0).abs() < 1e-9 {
            finish += 1;
            assert_eq!(x.feed, rate(250.0));
        }
    }
    assert!(finish > 100);
    // The blank reaches 10 beyond the stud along the first axis. The first ring takes
    // off at most one stepover (0.6 × 8 = 4.8) of it, so its centre line lies at least
    // 10 − 4.8 + 4 = 9.2 from the stud, and it cuts, so less than 10 + 4.
    assert!((9.2 - 1e-9..14.0).contains(&max_rough), "{max_rough}");
    assert_rapids_above(&m, pos, 2.0);
    // Climb milling with M3 runs clockwise round the stud.
    assert!(
        m.iter()
            .any(|mv| matches!(mv, Move::Arc { ccw: false, .. }))
    );
    assert!(!m.iter().any(|mv| matches!(mv, Move::Arc { ccw: true, .. })));
}

#[test]
fn circular_stud_tool_stays_off_the_stud() {
    let q = [
        (223, 40.0),
        (222, 60.0),
        (368, 0.0),
        (207, 500.0),
        (351, -1.0),
        (201, -5.0),
        (202, 5.0),
        (206, 150.0),
        (200, 2.0),
        (203, 0.0),
        (204, 15.0),
        (370, 1.0),
        (376, 90.0),
    ];
    let pos = [0.0, 0.0, 30.0];
    let m = run(257, &q, pos, 3.0).unwrap();
    let s = sample(&m, pos, 0.25);
    let mut radii = Vec::new();
    for x in s.iter().filter(|x| x.p[2] < 0.0) {
        let rr = x.p[0].hypot(x.p[1]);
        assert!(rr >= 20.0 + 3.0 - 1e-9, "{x:?}");
        radii.push(rr);
    }
    // Blank radius 30, finished 20: 10 mm of material at 6 mm stepover → 2 rings, 5 apart.
    let arcs: Vec<f64> = m
        .iter()
        .filter_map(|mv| match mv {
            Move::Arc { to, .. } => Some(to[0].hypot(to[1])),
            _ => None,
        })
        .collect();
    assert!(
        arcs.iter()
            .all(|r| (r - 28.0).abs() < 1e-9 || (r - 23.0).abs() < 1e-9)
    );
    assert!(arcs.iter().any(|r| (r - 28.0).abs() < 1e-9));
    // Start angle 90°: the plunge happens on the positive second axis.
    let plunge = ends(&m).into_iter().find(|(p, _)| p[2] == -5.0).unwrap().0;
    assert!(plunge[0].abs() < 1e-9 && plunge[1] > 28.0);
    // Up-cut with M3 runs counter-clockwise round a stud.
    assert!(
        m.iter()
            .all(|mv| !matches!(mv, Move::Arc { ccw: false, .. }))
    );
}

#[test]
fn bad_parameters_are_errors() {
    let pos = [0.0, 0.0, 10.0];
    let err = |c, q: &[(u32, f64)], r| run(c, q, pos, r).unwrap_err();
    assert!(matches!(
        err(252, &p252(&[(223, 8.0)]), 5.0),
        CycleError::Geometry { cycle: 252, .. }
    ));
    assert!(matches!(
        err(252, &p252(&[(201, 3.0)]), 5.0),
        CycleError::OutOfRange { cycle: 252, .. }
    ));
    assert!(matches!(
        err(252, &p252(&[(215, 3.0)]), 5.0),
        CycleError::OutOfRange { .. }
    ));
    assert!(matches!(
        err(252, &p252(&[(370, 2.5)]), 5.0),
        CycleError::OutOfRange { .. }
    ));
    assert!(matches!(
        err(252, &p252(&[(202, 0.0)]), 5.0),
        CycleError::OutOfRange { .. }
    ));
    assert!(matches!(
        err(252, &p252(&[(207, -5.0)]), 5.0),
        CycleError::OutOfRange { .. }
    ));
    let no_d: Vec<_> = p252(&[]).into_iter().filter(|(k, _)| *k != 223).collect();
    assert!(
        matches!(err(252, &no_d, 5.0), CycleError::Missing { cycle: 252, ref param, .. } if param == "Q223")
    );
    assert!(matches!(
        err(251, &p251(&[(220, 30.0)]), 5.0),
        CycleError::OutOfRange { .. }
    ));
    assert!(matches!(
        err(251, &p251(&[(219, 11.0), (220, 0.0)]), 6.0),
        CycleError::Geometry { .. }
    ));
    let mut stud = p256();
    stud.retain(|(k, _)| *k != 424);
    stud.push((424, 40.0));
    assert!(matches!(
        err(256, &stud, 4.0),
        CycleError::OutOfRange { .. }
    ));
    // Depth 0: the cycle does nothing.
    assert!(run(252, &p252(&[(201, 0.0)]), pos, 5.0).unwrap().is_empty());
}

#[test]
fn absurd_sizes_are_refused_not_generated() {
    let pos = [0.0, 0.0, 10.0];
    // 100 mm deep in infeeds of 0.00001 mm.
    let e = run(252, &p252(&[(201, -100.0), (202, 0.00001)]), pos, 5.0).unwrap_err();
    assert!(matches!(e, CycleError::Geometry { cycle: 252, .. }), "{e}");
}

#[test]
fn random_parameters_never_panic() {
    // A fixed linear congruential sequence: the same values on every run.
    let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = move || {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        seed >> 33
    };
    let specials = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        0.5,
        2.0,
        1e9,
        -1e9,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        1e-12,
    ];
    let cycles = [4, 5, 232, 233, 251, 252, 253, 254, 256, 257];
    let keys: Vec<u32> = (200..=390).collect();
    for round in 0..300 {
        let cycle = cycles[round % cycles.len()];
        let mut q: Vec<(u32, f64)> = Vec::new();
        for &k in &keys {
            let v = match next() % 4 {
                0 => specials[(next() % specials.len() as u64) as usize],
                _ => (next() % 2000) as f64 / 10.0 - 100.0,
            };
            q.push((k, v));
        }
        let src = qs(&q);
        let old = |k: ParamKey| match k {
            ParamKey::Old { line, .. } => Some(f64::from(line) * 3.0 - 7.0),
            ParamKey::OldWord(_) => Some(1.5),
            other => src(other),
        };
        let mut out = Vec::new();
        let r = [0.0, 0.5, 3.0, 50.0][round % 4];
        let res = generate(cycle, &old, &ctx([1.0, 2.0, 30.0], r), &mut out);
        if res.is_err() {
            assert!(out.is_empty());
        }
        for m in &out {
            if let Move::Line { to, .. } | Move::Arc { to, .. } = m {
                assert!(to.iter().all(|c| c.is_finite()), "cycle {cycle}: {m:?}");
            }
        }
    }
}
