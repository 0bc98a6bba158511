//! Tests of the drilling cycles against sequences written from the manual, with the
//! numbers worked out by hand.

use super::testutil::{
    Defs, assert_close, assert_no_rapid_into_material, ctx_at, feed_ts, line_ts, qs, with, without,
};
use crate::cycles::{CycleContext, CycleError, CycleFeed, Move, ParamKey, generate};
use crate::op::SpindleDir;

use CycleFeed::{Rapid, Rate};

fn run(n: u32, d: &Defs, ctx: &CycleContext) -> Result<Vec<Move>, CycleError> {
    let mut out = Vec::new();
    generate(n, d, ctx, &mut out)?;
    Ok(out)
}

fn line(a: f64, b: f64, t: f64, feed: CycleFeed) -> Move {
    Move::Line {
        to: [a, b, t],
        feed,
    }
}

/// Rapid safety with the usual direction and nothing pre-cut.
fn safe_rapids(moves: &[Move], start: [f64; 3], safe: f64) {
    assert_no_rapid_into_material(moves, start, -1.0, |_, _| safe, |_, _| safe);
}

fn d200() -> Defs {
    qs(&[
        (200, 2.0),
        (201, -15.0),
        (206, 150.0),
        (202, 5.0),
        (210, 0.5),
        (203, 0.0),
        (204, 50.0),
        (211, 1.0),
    ])
}

#[test]
fn drilling_200_pecks_retracts_and_reenters_at_set_up_clearance() {
    let ctx = ctx_at([10.0, 20.0, 60.0]);
    let m = run(200, &d200(), &ctx).unwrap();
    // 150 mm/min = 2.5 mm/s; infeeds of 5 to -5, -10, -15; re-entry 2 above the depth reached
    let f = Rate(2.5);
    let expected = vec![
        line(10.0, 20.0, 2.0, Rapid),
        line(10.0, 20.0, -5.0, f),
        line(10.0, 20.0, 2.0, Rapid),
        Move::Dwell(0.5),
        line(10.0, 20.0, -3.0, Rapid),
        line(10.0, 20.0, -10.0, f),
        line(10.0, 20.0, 2.0, Rapid),
        Move::Dwell(0.5),
        line(10.0, 20.0, -8.0, Rapid),
        line(10.0, 20.0, -15.0, f),
        Move::Dwell(1.0),
        line(10.0, 20.0, 50.0, Rapid),
    ];
    assert_eq!(m, expected);
    safe_rapids(&m, ctx.pos, 2.0);
}

#[test]
fn drilling_200_plunging_depth_beyond_depth_drills_in_one_move() {
    let ctx = ctx_at([0.0, 0.0, 100.0]);
    let d = with(&with(&d200(), 202, 20.0), 204, 0.0);
    let m = run(200, &d, &ctx).unwrap();
    // Q204 = 0 is not larger than Q200: the cycle ends at the set-up clearance
    assert_close(&line_ts(&m), &[2.0, -15.0, 2.0]);
    assert_close(&feed_ts(&m), &[-15.0]);
}

#[test]
fn depth_zero_runs_nothing() {
    let ctx = ctx_at([0.0, 0.0, 100.0]);
    for n in [200, 201, 203, 205, 206, 207, 208, 209, 240, 241] {
        let d = with(&d200(), 201, 0.0);
        let d = with(&with(&with(&d, 239, 1.0), 334, 1.0), 335, 20.0);
        let d = with(&with(&d, 258, 0.2), 259, 0.2);
        assert_eq!(run(n, &d, &ctx).unwrap(), vec![], "cycle {n}");
    }
}

#[test]
fn positive_depth_mirrors_the_clearance_heights() {
    // Q201 = +10 from the surface 0: set-up clearance 2 *below* (t = -2), bottom at +10,
    // 2nd set-up clearance at -5
    let ctx = ctx_at([0.0, 0.0, -20.0]);
    let d = with(&with(&with(&d200(), 201, 10.0), 202, 10.0), 204, 5.0);
    let m = run(200, &d, &ctx).unwrap();
    assert_close(&line_ts(&m), &[-2.0, 10.0, -5.0]);
    assert_no_rapid_into_material(&m, ctx.pos, 1.0, |_, _| -2.0, |_, _| -2.0);
}

fn d203() -> Defs {
    qs(&[
        (200, 2.0),
        (201, -20.0),
        (206, 120.0),
        (202, 5.0),
        (210, 0.0),
        (203, 0.0),
        (204, 30.0),
        (212, 1.0),
        (213, 0.0),
        (205, 2.0),
        (211, 0.0),
        (208, 600.0),
        (256, 0.2),
    ])
}

#[test]
fn universal_drilling_203_decrement_down_to_minimum_plunging_depth() {
    let ctx = ctx_at([5.0, 5.0, 40.0]);
    let m = run(203, &d203(), &ctx).unwrap();
    let cutting: Vec<f64> = m
        .iter()
        .filter_map(|m| match m {
            Move::Line { to, feed } if *feed == Rate(2.0) => Some(to[2]),
            _ => None,
        })
        .collect();
    // infeeds 5, 4, 3, 2, then held at Q205 = 2
    assert_close(&cutting, &[-5.0, -9.0, -12.0, -14.0, -16.0, -18.0, -20.0]);
    // every retraction runs at Q208 = 600 mm/min = 10 mm/s to the set-up clearance
    let retracts = m
        .iter()
        .filter(|m| matches!(m, Move::Line { to, feed } if *feed == Rate(10.0) && to[2] == 2.0))
        .count();
    assert_eq!(retracts, 7);
    assert_eq!(m.last(), Some(&line(5.0, 5.0, 30.0, Rapid)));
    safe_rapids(&m, ctx.pos, 2.0);
}

#[test]
fn universal_drilling_203_chip_breaking_then_full_retraction() {
    let ctx = ctx_at([0.0, 0.0, 40.0]);
    let d = with(
        &with(&with(&with(&d203(), 201, -16.0), 202, 4.0), 212, 0.0),
        213,
        2.0,
    );
    let d = with(&with(&d, 256, 0.5), 208, f64::INFINITY);
    let m = run(203, &d, &ctx).unwrap();
    // two chip breaks (back off 0.5), then a full retraction and re-entry 2 above -12
    assert_close(
        &line_ts(&m),
        &[
            2.0, -4.0, -3.5, -8.0, -7.5, -12.0, 2.0, -10.0, -16.0, 2.0, 30.0,
        ],
    );
    safe_rapids(&m, ctx.pos, 2.0);
}

#[test]
fn universal_drilling_203_without_q208_retracts_at_plunging_feed() {
    let ctx = ctx_at([0.0, 0.0, 40.0]);
    let d = with(&without(&d203(), 208), 202, 30.0);
    let m = run(203, &d, &ctx).unwrap();
    assert_eq!(m[2], line(0.0, 0.0, 2.0, Rate(2.0)));
}

fn d205() -> Defs {
    qs(&[
        (200, 2.0),
        (201, -30.0),
        (206, 300.0),
        (202, 10.0),
        (203, 0.0),
        (204, 20.0),
        (212, 0.0),
        (205, 0.0),
        (258, 0.5),
        (259, 1.5),
        (257, 0.0),
        (256, 0.2),
        (211, 0.0),
        (379, 0.0),
        (253, 750.0),
    ])
}

#[test]
fn universal_pecking_205_advanced_stop_changes_from_upper_to_lower() {
    let ctx = ctx_at([0.0, 0.0, 40.0]);
    let m = run(205, &d205(), &ctx).unwrap();
    // re-entries 0.5 above -10 and 1.5 above -20; retractions at FMAX (no Q208)
    assert_close(
        &line_ts(&m),
        &[2.0, -10.0, 2.0, -9.5, -20.0, 2.0, -18.5, -30.0, 2.0, 20.0],
    );
    assert_close(&feed_ts(&m), &[-10.0, -20.0, -30.0]);
    safe_rapids(&m, ctx.pos, 2.0);
}

#[test]
fn universal_pecking_205_deepened_start_and_chip_breaking() {
    let ctx = ctx_at([0.0, 0.0, 40.0]);
    // pilot hole 5 deep: pre-position at 750 mm/min to 2 above it, infeeds from -5
    let d = with(&d205(), 379, 5.0);
    let m = run(205, &d, &ctx).unwrap();
    assert_eq!(m[1], line(0.0, 0.0, -3.0, Rate(12.5)));
    assert_close(&feed_ts(&m)[1..], &[-15.0, -25.0, -30.0]);
    assert_no_rapid_into_material(&m, ctx.pos, -1.0, |_, _| 2.0, |_, _| -5.0);
    // chip breaking every 3 mm inside one infeed of 10
    let d = with(&with(&with(&d205(), 201, -10.0), 257, 3.0), 256, 0.2);
    let m = run(205, &d, &ctx).unwrap();
    assert_close(
        &line_ts(&m),
        &[2.0, -3.0, -2.8, -6.0, -5.8, -9.0, -8.8, -10.0, 2.0, 20.0],
    );
    safe_rapids(&m, ctx.pos, 2.0);
    // a deepened start at or below the depth is refused
    let bad = with(&with(&d205(), 379, 30.0), 201, -30.0);
    assert!(matches!(
        run(205, &bad, &ctx),
        Err(CycleError::Geometry { cycle: 205, .. })
    ));
}

#[test]
fn reaming_201_retracts_at_q208_or_reaming_feed() {
    let ctx = ctx_at([1.0, 2.0, 50.0]);
    let d = qs(&[
        (200, 2.0),
        (201, -15.0),
        (206, 100.0),
        (211, 0.5),
        (208, 250.0),
        (203, 20.0),
        (204, 100.0),
    ]);
    let m = run(201, &d, &ctx).unwrap();
    let expected = vec![
        line(1.0, 2.0, 22.0, Rapid),
        line(1.0, 2.0, 5.0, Rate(100.0 / 60.0)),
        Move::Dwell(0.5),
        line(1.0, 2.0, 22.0, Rate(250.0 / 60.0)),
        line(1.0, 2.0, 120.0, Rapid),
    ];
    assert_eq!(m, expected);
    safe_rapids(&m, ctx.pos, 22.0);
    let m = run(201, &with(&d, 208, 0.0), &ctx).unwrap();
    assert_eq!(m[3], line(1.0, 2.0, 22.0, Rate(100.0 / 60.0)));
}

#[test]
fn centering_240_by_depth_and_refuses_diameter() {
    let ctx = ctx_at([0.0, 0.0, 10.0]);
    let d = qs(&[
        (200, 2.0),
        (343, 0.0),
        (201, -1.5),
        (344, -9.0),
        (206, 250.0),
        (211, 0.1),
        (203, 0.0),
        (204, 50.0),
    ]);
    let m = run(240, &d, &ctx).unwrap();
    assert_eq!(
        m,
        vec![
            line(0.0, 0.0, 2.0, Rapid),
            line(0.0, 0.0, -1.5, Rate(250.0 / 60.0)),
            Move::Dwell(0.1),
            line(0.0, 0.0, 50.0, Rapid),
        ]
    );
    let r = run(240, &with(&d, 343, 1.0), &ctx);
    assert!(matches!(r, Err(CycleError::Geometry { cycle: 240, .. })));
}

#[test]
fn single_lip_241_spindle_directions_and_dwell_depth() {
    let ctx = ctx_at([0.0, 0.0, 50.0]);
    let d = qs(&[
        (200, 2.0),
        (201, -80.0),
        (206, 150.0),
        (211, 0.25),
        (203, 0.0),
        (204, 50.0),
        (379, 7.5),
        (253, 750.0),
        (208, 1000.0),
        (426, 4.0),
        (427, 25.0),
        (428, 3000.0),
        (429, 8.0),
        (430, 9.0),
        (435, 60.0),
    ]);
    let m = run(241, &d, &ctx).unwrap();
    let f = Rate(2.5);
    let expected = vec![
        line(0.0, 0.0, 2.0, Rapid),
        Move::Spindle(SpindleDir::Ccw),
        line(0.0, 0.0, -5.5, Rate(12.5)),
        Move::Spindle(SpindleDir::Cw),
        line(0.0, 0.0, -60.0, f),
        Move::Dwell(0.25),
        line(0.0, 0.0, -80.0, f),
        Move::Dwell(0.25),
        Move::Spindle(SpindleDir::Ccw),
        line(0.0, 0.0, 2.0, Rate(1000.0 / 60.0)),
        line(0.0, 0.0, 50.0, Rapid),
        Move::Spindle(SpindleDir::Cw),
    ];
    assert_eq!(m, expected);
    assert_no_rapid_into_material(&m, ctx.pos, -1.0, |_, _| 2.0, |_, _| -7.5);
    let r = run(241, &with(&d, 426, 6.0), &ctx);
    assert!(matches!(r, Err(CycleError::OutOfRange { cycle: 241, .. })));
}

fn d207(pitch: f64) -> Defs {
    qs(&[
        (200, 2.0),
        (201, -12.0),
        (239, pitch),
        (203, 0.0),
        (204, 10.0),
    ])
}

#[test]
fn rigid_tapping_207_hand_from_pitch_sign_per_rev_feed() {
    let ctx = ctx_at([3.0, 4.0, 30.0]);
    // right-hand M8 x 1.25 with the spindle already turning M3: geared from the set-up
    // clearance 2 to the depth -12 and back
    let tap = |pitch, hand, infeed, back, retract_factor| Move::RigidTap {
        to: [3.0, 4.0, -12.0],
        pitch,
        hand,
        lead_in: 2.0,
        infeed,
        back,
        retract_factor,
    };
    let m = run(207, &d207(1.25), &ctx).unwrap();
    assert_eq!(
        m,
        vec![
            line(3.0, 4.0, 2.0, Rapid),
            tap(1.25, SpindleDir::Cw, 0.0, 0.0, 1.0),
            line(3.0, 4.0, 10.0, Rapid),
        ]
    );
    // left-hand thread: enter turning M4, back to M3 at the clearance; Q403 speeds up the
    // retraction
    let m = run(207, &with(&d207(-1.5), 403, 2.0), &ctx).unwrap();
    assert_eq!(
        m,
        vec![
            line(3.0, 4.0, 2.0, Rapid),
            Move::Spindle(SpindleDir::Ccw),
            tap(1.5, SpindleDir::Ccw, 0.0, 0.0, 2.0),
            Move::Spindle(SpindleDir::Cw),
            line(3.0, 4.0, 10.0, Rapid),
        ]
    );
    safe_rapids(&m, ctx.pos, 2.0);
    let no_speed = CycleContext {
        spindle_rpm: 0.0,
        ..ctx
    };
    assert!(matches!(
        run(207, &d207(1.0), &no_speed),
        Err(CycleError::Geometry { .. })
    ));
    assert!(matches!(
        run(207, &d207(0.0), &ctx),
        Err(CycleError::OutOfRange { .. })
    ));
    assert!(matches!(
        run(207, &d207(120.0), &ctx),
        Err(CycleError::OutOfRange { .. })
    ));
}

#[test]
fn tapping_209_chip_breaking_backs_off_or_leaves_the_hole() {
    let ctx = ctx_at([0.0, 0.0, 30.0]);
    let d = with(&with(&with(&d207(1.0), 201, -10.0), 257, 4.0), 256, 0.5);
    let m = run(209, &d, &ctx).unwrap();
    assert_eq!(
        m,
        vec![
            line(0.0, 0.0, 2.0, Rapid),
            Move::RigidTap {
                to: [0.0, 0.0, -10.0],
                pitch: 1.0,
                hand: SpindleDir::Cw,
                lead_in: 2.0,
                infeed: 4.0,
                back: 0.5,
                retract_factor: 1.0,
            },
            line(0.0, 0.0, 10.0, Rapid),
        ]
    );
    // The strokes from the set-up clearance (2 above the surface): infeeds of 4 from the
    // surface, backing off 0.5, or with Q256 = 0 out to the clearance for chip removal.
    let s = crate::cycles::tap_strokes(2.0, 12.0, 4.0, 0.5);
    assert_close(&s, &[6.0, 5.5, 10.0, 9.5, 12.0, 0.0]);
    let s = crate::cycles::tap_strokes(2.0, 12.0, 4.0, 0.0);
    assert_close(&s, &[6.0, 0.0, 10.0, 0.0, 12.0, 0.0]);
    safe_rapids(&m, ctx.pos, 2.0);
}

#[test]
fn tapping_206_reverses_spindle_at_bottom_and_again_at_clearance() {
    let ctx = CycleContext {
        spindle: SpindleDir::Ccw,
        ..ctx_at([0.0, 0.0, 20.0])
    };
    let d = qs(&[
        (200, 2.0),
        (201, -20.0),
        (206, 100.0),
        (211, 0.25),
        (203, 0.0),
        (204, 5.0),
    ]);
    let m = run(206, &d, &ctx).unwrap();
    let f = Rate(100.0 / 60.0);
    assert_eq!(
        m,
        vec![
            line(0.0, 0.0, 2.0, Rapid),
            line(0.0, 0.0, -20.0, f),
            Move::Dwell(0.25),
            Move::Spindle(SpindleDir::Cw),
            line(0.0, 0.0, 2.0, f),
            Move::Spindle(SpindleDir::Ccw),
            line(0.0, 0.0, 5.0, Rapid),
        ]
    );
    let off = CycleContext {
        spindle: SpindleDir::Off,
        ..ctx
    };
    assert!(matches!(
        run(206, &d, &off),
        Err(CycleError::Geometry { .. })
    ));
}

fn d208() -> Defs {
    qs(&[
        (200, 2.0),
        (201, -9.0),
        (206, 300.0),
        (334, 4.0),
        (203, 0.0),
        (204, 20.0),
        (335, 30.0),
        (342, 0.0),
        (351, 1.0),
    ])
}

/// Walks the arcs of `m`, checking each end lies on `radius` about `centre`, and returns
/// (swept angle with sign, tool-axis height) after each arc.
fn arc_walk(m: &[Move], centre: [f64; 2], radius: f64, ccw: bool) -> Vec<(f64, f64)> {
    let mut prev: Option<f64> = None;
    let mut total = 0.0;
    let mut out = Vec::new();
    for mv in m {
        let Move::Arc {
            centre: c,
            to,
            ccw: dir,
            turns,
            ..
        } = *mv
        else {
            continue;
        };
        assert_eq!(c, centre);
        assert_eq!(dir, ccw);
        assert_eq!(turns, 0);
        let r = (to[0] - c[0]).hypot(to[1] - c[1]);
        assert!(
            (r - radius).abs() < 1e-9,
            "arc end off the helix radius: {r}"
        );
        let ang = (to[1] - c[1]).atan2(to[0] - c[0]);
        let start = prev.unwrap_or(0.0);
        let mut d = ang - start;
        // sweep in the arc's direction, in (0, 2π]
        if ccw {
            while d <= 1e-12 {
                d += std::f64::consts::TAU;
            }
        } else {
            while d >= -1e-12 {
                d -= std::f64::consts::TAU;
            }
        }
        assert!(
            d.abs() <= std::f64::consts::PI + 1e-9,
            "arc longer than half a turn"
        );
        total += d;
        prev = Some(ang);
        out.push((total, to[2]));
    }
    out
}

#[test]
fn bore_milling_208_helix_on_radius_with_pitch_then_full_circle() {
    let ctx = ctx_at([40.0, 30.0, 50.0]);
    let m = run(208, &d208(), &ctx).unwrap();
    // helix radius = 30/2 - 5 = 10; climb milling with M3 runs counter-clockwise;
    // starts at (50, 30) at the set-up clearance, descends 4 per turn from +2 to -9
    assert_eq!(m[0], line(40.0, 30.0, 2.0, Rapid));
    assert_eq!(m[1], line(50.0, 30.0, 2.0, Rate(5.0)));
    let walk = arc_walk(&m, [40.0, 30.0], 10.0, true);
    let tau = std::f64::consts::TAU;
    let helix_turns = 11.0 / 4.0;
    let mut reached_bottom_at = None;
    for (i, &(ang, t)) in walk.iter().enumerate() {
        if reached_bottom_at.is_none() {
            // on the helix: height falls 4 per full turn
            assert!(
                (t - (2.0 - 4.0 * ang / tau)).abs() < 1e-9,
                "t {t} at angle {ang}"
            );
            if (t + 9.0).abs() < 1e-9 {
                assert!((ang / tau - helix_turns).abs() < 1e-9);
                reached_bottom_at = Some(i);
            }
        } else {
            assert!((t + 9.0).abs() < 1e-9);
        }
    }
    let b = reached_bottom_at.unwrap();
    let (last_ang, _) = *walk.last().unwrap();
    assert!(
        (last_ang - walk[b].0 - tau).abs() < 1e-9,
        "full circle at the bottom"
    );
    let n = m.len();
    assert_eq!(m[n - 2], line(40.0, 30.0, -9.0, Rate(5.0)));
    assert_eq!(m[n - 1], line(40.0, 30.0, 20.0, Rapid));
    safe_rapids(&m, ctx.pos, 2.0);
}

#[test]
fn bore_milling_208_direction_tool_size_and_equal_diameter() {
    let ctx = ctx_at([0.0, 0.0, 50.0]);
    // up-cut with M3 runs clockwise; climb with M4 as well
    let m = run(208, &with(&d208(), 351, -1.0), &ctx).unwrap();
    arc_walk(&m, [0.0, 0.0], 10.0, false);
    let m4 = CycleContext {
        spindle: SpindleDir::Ccw,
        ..ctx
    };
    let m = run(208, &d208(), &m4).unwrap();
    arc_walk(&m, [0.0, 0.0], 10.0, false);
    // tool diameter 10 > bore 8
    let r = run(208, &with(&d208(), 335, 8.0), &ctx);
    assert!(matches!(r, Err(CycleError::Geometry { cycle: 208, .. })));
    // bore diameter = tool diameter: straight to depth
    let m = run(208, &with(&d208(), 335, 10.0), &ctx).unwrap();
    assert_eq!(
        m,
        vec![
            line(0.0, 0.0, 2.0, Rapid),
            line(0.0, 0.0, -9.0, Rate(5.0)),
            line(0.0, 0.0, 20.0, Rapid),
        ]
    );
    let r = run(208, &with(&d208(), 334, 0.0), &ctx);
    assert!(matches!(r, Err(CycleError::OutOfRange { .. })));
}

fn old(pairs: &[(u8, f64)], f: Option<f64>) -> Defs {
    let mut v: Vec<(ParamKey, f64)> = pairs
        .iter()
        .map(|&(line, x)| (ParamKey::Old { line, index: 0 }, x))
        .collect();
    if let Some(f) = f {
        v.push((ParamKey::OldWord("F"), f));
    }
    Defs(v)
}

#[test]
fn old_pecking_1_as_in_a_field_program() {
    // CYCL DEF 1.1 ABST+1 / 1.2 TIEFE-21 / 1.3 ZUSTLG+3 / 1.4 V.ZEIT0 / 1.5 F150, called at Z+1
    let ctx = ctx_at([27.975, -26.5, 1.0]);
    let d = old(&[(1, 1.0), (2, -21.0), (3, 3.0), (4, 0.0)], Some(2.5));
    let m = run(1, &d, &ctx).unwrap();
    // surface at 0; infeeds of 3; back to the start (1) and down to 0.6 above the depth reached
    let mut expected = Vec::new();
    for k in 1..=7 {
        let depth = -3.0 * k as f64;
        expected.push(depth);
        if k < 7 {
            expected.push(1.0);
            expected.push(depth + 0.6);
        }
    }
    expected.push(1.0);
    assert_close(&line_ts(&m), &expected);
    assert_close(
        &feed_ts(&m),
        &[-3.0, -6.0, -9.0, -12.0, -15.0, -18.0, -21.0],
    );
    assert!(
        m.iter()
            .all(|mv| !matches!(mv, Move::Line { feed: Rate(f), .. } if *f != 2.5))
    );
    assert_no_rapid_into_material(&m, ctx.pos, -1.0, |_, _| 1.0, |_, _| 1.0);
}

#[test]
fn old_pecking_1_advanced_stop_for_deep_holes() {
    // depth 40 > 30: t = 40/50 = 0.8
    let ctx = ctx_at([0.0, 0.0, 2.0]);
    let d = old(&[(1, -2.0), (2, -40.0), (3, -25.0), (4, 1.0)], Some(1.0));
    let m = run(1, &d, &ctx).unwrap();
    assert_close(&line_ts(&m), &[-25.0, 2.0, -24.2, -40.0, 2.0]);
    assert_eq!(m[4], Move::Dwell(1.0));
    // depth 1000: t would be 20, capped at 7
    let d = old(&[(1, 2.0), (2, -1000.0), (3, 600.0)], Some(1.0));
    let m = run(1, &d, &ctx).unwrap();
    assert_close(&line_ts(&m), &[-600.0, 2.0, -593.0, -1000.0, 2.0]);
    // no F and no modal feed
    let d = old(&[(1, 2.0), (2, -10.0), (3, 5.0)], None);
    assert!(matches!(
        run(1, &d, &ctx),
        Err(CycleError::Missing { cycle: 1, .. })
    ));
    let modal = CycleContext {
        feed: Some(3.0),
        ..ctx
    };
    assert_eq!(
        run(1, &d, &modal).unwrap()[0],
        line(0.0, 0.0, -5.0, Rate(3.0))
    );
}

#[test]
fn old_tapping_2_reverses_at_depth_and_at_start() {
    let ctx = ctx_at([0.0, 0.0, 3.0]);
    let d = old(&[(1, -3.0), (2, -20.0), (3, 0.4)], Some(2.0));
    let m = run(2, &d, &ctx).unwrap();
    assert_eq!(
        m,
        vec![
            line(0.0, 0.0, -20.0, Rate(2.0)),
            Move::Dwell(0.4),
            Move::Spindle(SpindleDir::Ccw),
            line(0.0, 0.0, 3.0, Rate(2.0)),
            Move::Spindle(SpindleDir::Cw),
        ]
    );
    let off = CycleContext {
        spindle: SpindleDir::Off,
        ..ctx
    };
    assert!(matches!(
        run(2, &d, &off),
        Err(CycleError::Geometry { cycle: 2, .. })
    ));
}

#[test]
fn bad_parameters_are_errors_and_leave_output_alone() {
    let ctx = ctx_at([0.0, 0.0, 50.0]);
    let cases: Vec<(Defs, &str)> = vec![
        (with(&d200(), 200, -1.0), "Q200"),
        (with(&d200(), 206, 0.0), "Q206"),
        (with(&d200(), 206, f64::INFINITY), "Q206"),
        (with(&d200(), 202, 0.0), "Q202"),
        (with(&d200(), 210, 4000.0), "Q210"),
        (with(&d200(), 204, f64::NAN), "Q204"),
        (with(&d200(), 201, 1e6), "Q201"),
        (with(&d200(), 395, 2.0), "Q395"),
    ];
    for (d, param) in cases {
        let mut out = vec![Move::Dwell(9.0)];
        let r = generate(200, &d, &ctx, &mut out);
        match r {
            Err(CycleError::OutOfRange {
                cycle: 200,
                param: p,
                ..
            }) => assert_eq!(p, param),
            other => panic!("{param}: {other:?}"),
        }
        assert_eq!(out, vec![Move::Dwell(9.0)]);
    }
    let r = run(200, &without(&d200(), 201), &ctx);
    assert!(matches!(r, Err(CycleError::Missing { cycle: 200, ref param, .. }) if param == "Q201"));
    let r = run(203, &with(&d203(), 213, 1.5), &ctx);
    assert!(matches!(r, Err(CycleError::OutOfRange { cycle: 203, .. })));
    // too many infeeds is refused instead of producing millions of moves
    let r = run(200, &with(&with(&d200(), 202, 0.0001), 201, -9999.0), &ctx);
    assert!(matches!(r, Err(CycleError::Geometry { cycle: 200, .. })));
    let r = run(200, &with(&d200(), 395, 1.0), &ctx);
    assert!(matches!(r, Err(CycleError::Geometry { cycle: 200, .. })));
    assert!(matches!(
        run(299, &d200(), &ctx),
        Err(CycleError::Unknown(299))
    ));
}

#[test]
fn error_messages_name_cycle_parameter_and_range() {
    let ctx = ctx_at([0.0, 0.0, 50.0]);
    let e = run(200, &with(&d200(), 200, -1.0), &ctx).unwrap_err();
    assert_eq!(
        e.to_string(),
        "cycle 200: Q200 = -1 is out of range (0..=99999.9999)"
    );
    let e = run(200, &without(&d200(), 206), &ctx).unwrap_err();
    assert_eq!(
        e.to_string(),
        "cycle 200: parameter Q206 (feed rate for plunging) is missing"
    );
}
