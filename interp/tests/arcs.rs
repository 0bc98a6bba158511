//! Arc blocks (C, CR, CT, CP, LP) against geometry worked out by hand.

mod common;
use common::*;
use klar_interp::{AxisLetter, CompSide, OpKind, Plane, Pose};

#[test]
fn c_quarter_and_three_quarter_circles() {
    let ops = run(&program(
        "CC X+0 Y+0\nL X+10 Y+0 Z-1 F100\nC X+0 Y+10 DR+\nC X+10 Y+0 DR-",
    ));
    let m = motions(&ops);
    let (from, to, c, plane, sweep) = arc(&m[1]);
    assert_eq!(plane, Plane::XY);
    assert_eq!(c, [0.0, 0.0]);
    assert_eq!(from, Pose::xyz(10.0, 0.0, -1.0));
    assert_eq!(to, Pose::xyz(0.0, 10.0, -1.0));
    close(sweep, 90.0);
    // back from (0,10) to (10,0) clockwise: a quarter turn the short way round
    let (_, to, _, _, sweep) = arc(&m[2]);
    assert_eq!(to, Pose::xyz(10.0, 0.0, -1.0));
    close(sweep, -90.0);
}

#[test]
fn c_the_long_way_and_full_circles() {
    let ops = run(&program(
        "CC X+0 Y+0\nL X+10 Y+0 F100\nC X+0 Y+10 DR-\nC X+0 Y+10 DR+\nC DR-",
    ));
    let m = motions(&ops);
    close(arc(&m[1]).4, -270.0);
    // end = start: full circle in the programmed direction
    let (from, to, _, _, sweep) = arc(&m[2]);
    assert_eq!(from, to);
    close(sweep, 360.0);
    let (from, to, _, _, sweep) = arc(&m[3]);
    assert_eq!(from, to);
    close(sweep, -360.0);
}

#[test]
fn cr_small_and_large_arcs() {
    // chord (0,0)→(10,0), R = 10: centre 5 along, h = √(10² − 5²) off the chord;
    // minor arc angle = 2·asin(5/10) = 60°
    let h = (100.0f64 - 25.0).sqrt();
    let cases = [
        ("R+10 DR+", [5.0, h], 60.0),
        ("R-10 DR+", [5.0, -h], 300.0),
        ("R+10 DR-", [5.0, -h], -60.0),
        ("R-10 DR-", [5.0, h], -300.0),
    ];
    for (words, centre, sweep) in cases {
        let ops = run(&program(&format!("L X+0 Y+0 F100\nCR X+10 Y+0 {words}")));
        let m = motions(&ops);
        let (from, to, c, _, s) = arc(m.last().unwrap());
        close(c[0], centre[0]);
        close(c[1], centre[1]);
        close(s, sweep);
        // both ends on the circle of radius 10
        close(
            (from[AxisLetter::X] - c[0]).hypot(from[AxisLetter::Y] - c[1]),
            10.0,
        );
        close(
            (to[AxisLetter::X] - c[0]).hypot(to[AxisLetter::Y] - c[1]),
            10.0,
        );
    }
}

#[test]
fn cr_half_circle_and_q_radius() {
    // chord = 2R exactly: centre at the chord midpoint, 180°
    let ops = run(&program(
        "TOOL CALL 1 Z S1000 DR+5\nL X+0 Y+0 F100\nCR X+10 Y+0 RQ108 DR-",
    ));
    let (_, _, c, _, s) = arc(motions(&ops).last().unwrap());
    close(c[0], 5.0);
    close(c[1], 0.0);
    close(s, -180.0);
}

#[test]
fn ct_continues_tangentially() {
    // after a line along +X, an arc tangent to +X from (10,0) to (20,10): centre (10,10)
    let ops = run(&program(
        "L X+0 Y+0 F100\nL X+10\nCT X+20 Y+10\nCT X+30 Y+20",
    ));
    let m = motions(&ops);
    // the L to (0,0) from the origin moves nothing and yields no op
    let (_, to, c, _, s) = arc(&m[1]);
    assert_eq!(c, [10.0, 10.0]);
    close(s, 90.0);
    assert_eq!(to, Pose::xyz(20.0, 10.0, 0.0));
    // the first arc ends heading +Y; an arc tangent to +Y from (20,10) to (30,20) turns right
    // about (30,10)
    let (_, _, c, _, s) = arc(&m[2]);
    close(c[0], 30.0);
    close(c[1], 10.0);
    close(s, -90.0);
}

#[test]
fn ct_behind_the_tangent_takes_the_long_way() {
    // heading +X at (0,0), end point (0,10) lies beside-and-behind: centre (0,5), 180°;
    // end point (-5,5): centre (0,5) again, 270° counter-clockwise
    let ops = run(&program("L X-10 Y+0 F100\nL X+0\nCT X-5 Y+5"));
    let (_, _, c, _, s) = arc(motions(&ops).last().unwrap());
    close(c[0], 0.0);
    close(c[1], 5.0);
    close(s, 270.0);
}

#[test]
fn cp_and_lp_about_the_pole() {
    let ops = run(&program(
        "CC X+5 Y+5\nLP PR+10 PA+30 F100\nLP IPA+60\nCP IPA+90 DR+\nCP PA+270 DR-\nLP IPR-4",
    ));
    let m = motions(&ops);
    let r30 = 30f64.to_radians();
    match &m[0] {
        OpKind::Line { to, .. } => {
            close(to[AxisLetter::X], 5.0 + 10.0 * r30.cos());
            close(to[AxisLetter::Y], 5.0 + 10.0 * r30.sin());
        }
        k => panic!("{k:?}"),
    }
    match &m[1] {
        OpKind::Line { to, .. } => {
            close(to[AxisLetter::X], 5.0);
            close(to[AxisLetter::Y], 15.0);
        }
        k => panic!("{k:?}"),
    }
    let (_, to, c, _, s) = arc(&m[2]);
    assert_eq!(c, [5.0, 5.0]);
    close(s, 90.0);
    close(to[AxisLetter::X], -5.0);
    close(to[AxisLetter::Y], 5.0);
    // from 180° clockwise to 270° (= −90°): three quarters of a turn
    let (_, to, _, _, s) = arc(&m[3]);
    close(s, -270.0);
    close(to[AxisLetter::X], 5.0);
    close(to[AxisLetter::Y], -5.0);
    // radius 10 − 4 at the same angle −90°
    match &m[4] {
        OpKind::Line { to, .. } => {
            close(to[AxisLetter::X], 5.0);
            close(to[AxisLetter::Y], -1.0);
        }
        k => panic!("{k:?}"),
    }
}

#[test]
fn cc_in_zx_plane_selects_that_plane() {
    // CC Z/X: arcs run in the Z/X plane (first axis Z, second X)
    let ops = run(&program("L X+10 Y+3 Z+0 F100\nCC Z+0 X+0\nC Z+10 X+0 DR+"));
    let (_, to, c, plane, s) = arc(motions(&ops).last().unwrap());
    assert_eq!(plane, Plane::ZX);
    assert_eq!(c, [0.0, 0.0]);
    // start (Z,X) = (0,10) at 90°, end (10,0) at 0°, counter-clockwise: 270°
    close(s, 270.0);
    assert_eq!(to, Pose::xyz(0.0, 3.0, 10.0));
}

#[test]
fn cc_incremental_is_relative_to_the_position() {
    let ops = run(&program("L X+10 Y+20 F100\nCC IX+5 IY-5\nC X+20 Y+10 DR+"));
    let (_, _, c, _, s) = arc(motions(&ops).last().unwrap());
    assert_eq!(c, [15.0, 15.0]);
    // start (10,20) at 135° about (15,15), end (20,10) at 315°: half a turn
    close(s, 180.0);
}

#[test]
fn helix_thread_from_the_manual_rules() {
    // Internal right-hand thread, work direction Z+ → DR+ and RL (thread table).
    // Pitch 1.5 mm, 4 thread revolutions + 0.5 overrun at start and at end → n = 5.
    let pitch = 1.5;
    let n = 4.0 + 0.5 + 0.5;
    let height = pitch * n; // total height h = P · n
    let ipa = n * 360.0; // incremental total angle
    let z_start = -pitch * (4.0 + 0.5); // P · (thread revolutions + overrun at start)
    let text = program(&format!(
        "TOOL CALL 1 Z S2000\nCC X+0 Y+0\nL X+20 Y+0 Z{z_start:+} R0 F300\nCP IPA{ipa:+} IZ{height:+} DR+ RL F200"
    ));
    let ops = run(&text);
    let comp = ops.iter().position(|o| {
        matches!(
            o.kind,
            OpKind::RadiusComp {
                side: CompSide::Left
            }
        )
    });
    let helix = ops
        .iter()
        .position(|o| matches!(o.kind, OpKind::Arc { .. }));
    assert!(comp.is_some() && comp < helix, "RL comes before the helix");
    let (from, to, c, _, s) = arc(&ops[helix.unwrap()].kind);
    assert_eq!(c, [0.0, 0.0]);
    close(s, 1800.0);
    close(from[AxisLetter::Z], -6.75);
    close(to[AxisLetter::Z], -6.75 + 7.5);
    // a whole number of turns ends where it started in the plane
    close(to[AxisLetter::X], 20.0);
    close(to[AxisLetter::Y], 0.0);
    // downward half-turn helix as CAM writes it
    let ops = run(&program(
        "CC X+0 Y+0\nL X+5 Y+0 Z+0 F100\nCP IPA-180 IZ-0.1 DR-",
    ));
    let (_, to, _, _, s) = arc(motions(&ops).last().unwrap());
    close(s, -180.0);
    close(to[AxisLetter::X], -5.0);
    close(to[AxisLetter::Z], -0.1);
}
