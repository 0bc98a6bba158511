//! Linear face patterns (G743) and lateral-surface patterns (G744, G746) against positions
//! computed by hand in machine coordinates (X radius, Z, C degrees).

mod common;
use common::lathe::{first_error, lathe_program, run_named};
use klar_interp::{AxisLetter, Diagnostic, Feed, Op, OpKind, Pose};

const SETUP: &str = "MACHINING\nN1 T1 G197 S1000 G94 F100 M103\nN2 M14\nN3 G0 X100 Z2\n";

/// Runs `body` after the setup blocks as `p.nc`; panics on a diagnostic.
fn run(body: &str) -> Vec<Op> {
    run_named("p.nc", &format!("{SETUP}{body}\nEND\n"))
}

/// The first diagnostic of `body` after the setup blocks, run as `bad.nc`.
fn until_error(body: &str) -> Diagnostic {
    first_error(&format!("{SETUP}{body}\nEND\n"))
}

fn feed_ends(ops: &[Op]) -> Vec<Pose> {
    ops.iter()
        .filter_map(|o| match o.kind {
            OpKind::Line { to, feed, .. } if feed != Feed::Rapid => Some(to),
            _ => None,
        })
        .collect()
}

#[track_caller]
fn at(p: Pose, x: f64, z: f64, c: f64) {
    let ok = (p[AxisLetter::X] - x).abs() < 1e-9
        && (p[AxisLetter::Z] - z).abs() < 1e-9
        && (p[AxisLetter::C] - c).abs() < 1e-9
        && p[AxisLetter::Y].abs() < 1e-12;
    assert!(ok, "{p:?} != X{x} Z{z} C{c}");
}

#[test]
fn g743_end_point_divides_the_span() {
    // (10,0) to (40,30) in 4 positions: steps of (10,10)
    let ops = run("N4 G743 XK10 YK0 I40 J30 Q4 ZS0 ZE-5");
    let bottoms = feed_ends(&ops);
    assert_eq!(bottoms.len(), 4);
    for (k, p) in bottoms.iter().enumerate() {
        let (x, y) = (10.0 + 10.0 * k as f64, 10.0 * k as f64);
        at(*p, x.hypot(y), -5.0, y.atan2(x).to_degrees());
    }
}

#[test]
fn g743_polar_start_with_direction_and_spacing() {
    // first position: diameter 40 at 90° = (0, 20); A180 Ri10: (-10, 0) per step
    let ops = run("N4 G743 X40 C90 A180 Ri10 Q3\nN5 G71 ZS1 ZE-4 F50");
    let bottoms = feed_ends(&ops);
    let expect = [(0.0, 20.0), (-10.0, 20.0), (-20.0, 20.0)];
    assert_eq!(bottoms.len(), 3);
    for (p, (x, y)) in bottoms.iter().zip(expect) {
        let x: f64 = x;
        at(*p, x.hypot(y), -4.0, y.atan2(x).to_degrees());
    }
    // the same row with the total length R20
    let again = feed_ends(&run("N4 G743 X40 C90 A180 R20 Q3\nN5 G71 ZS1 ZE-4 F50"));
    assert_eq!(again, bottoms);
}

#[test]
fn g746_circle_on_the_unrolled_lateral_surface() {
    // reference diameter 50 (radius 25), centre Z-20 C0, pattern diameter 20 (radius 10):
    // unrolled points (z, s) = (-20 + 10 cos a, 10 sin a) at a = 0, 90, 180, 270;
    // c = s / 25 rad
    let ops = run("N4 G746 X50 Z-20 C0 K20 A0 Q4 XS52 XE40");
    let bottoms = feed_ends(&ops);
    assert_eq!(bottoms.len(), 4);
    for (k, p) in bottoms.iter().enumerate() {
        let a = (90.0 * k as f64).to_radians();
        let z = -20.0 + 10.0 * a.cos();
        let c = (10.0 * a.sin() / 25.0).to_degrees();
        // drilled to diameter 40: radius 20
        at(*p, 20.0, z, c);
    }
    // each hole starts with a rapid at the clearance radius 50 onto (z, c), then XS52 → r26
    let rapids: Vec<Pose> = ops
        .iter()
        .filter_map(|o| match o.kind {
            OpKind::Line {
                to,
                feed: Feed::Rapid,
                ..
            } => Some(to),
            _ => None,
        })
        .collect();
    at(rapids[1], 50.0, -10.0, 0.0);
    at(rapids[2], 26.0, -10.0, 0.0);
    at(rapids[3], 50.0, -10.0, 0.0);
}

#[test]
fn g744_row_with_the_cycle_of_the_next_block() {
    // Z-10 C0, Ki-15, Wi90: (-10, 0), (-25, 90), (-40, 180); deep-hole drilling from
    // diameter 100 (the clearance) to XE80 in first depth P4 (radius) … the last feed
    // end of each hole is at radius 40
    let ops = run("N4 G744 Z-10 C0 Ki-15 Wi90 Q3\nN5 G74 XE80 P4 F50");
    let bottoms: Vec<Pose> = feed_ends(&ops);
    // 10 mm of radius in infeeds of 4: 4, 8, 10 → three feeds per hole
    assert_eq!(bottoms.len(), 9);
    for (k, hole) in bottoms.chunks(3).enumerate() {
        let (z, c) = (-10.0 - 15.0 * k as f64, 90.0 * k as f64);
        at(hole[0], 46.0, z, c);
        at(hole[1], 42.0, z, c);
        at(hole[2], 40.0, z, c);
    }
}

#[test]
fn lateral_pattern_errors() {
    let d = until_error("N4 G744 Z-10 Q3 Ki-5\nN5 G0 X100");
    assert!(d.message.contains("has no XE"), "{d}");
    let d = until_error("N4 G746 X50 Z-10 K10 Q3\nN5 G791 K5 ZE-2");
    assert!(d.message.contains("G791"), "{d}");
    let d = until_error("N4 G743 XK0 YK0 I10 Ii2 Q3 ZE-2");
    assert_eq!((d.line, d.col), (5, 21), "{d}");
    let d = until_error("N4 G746 Z-10 K10 Q3 XE40");
    assert!(d.message.contains("reference diameter"), "{d}");
}

#[test]
fn g793_mills_the_face_contour_in_the_turned_system() {
    let ops = run_named("g793.nc", &lathe_program("face_contour_g793.nc"));
    // face point (x, y) seen with the spindle at C30: rot(-30°)·(x, y)
    let (s, c) = 30f64.to_radians().sin_cos();
    let turned = |x: f64, y: f64| [c * x + s * y, -s * x + c * y];
    let cut: Vec<&OpKind> = ops
        .iter()
        .map(|o| &o.kind)
        .filter(|k| match k {
            OpKind::Line { feed, .. } => *feed != Feed::Rapid,
            OpKind::Arc { .. } => true,
            _ => false,
        })
        .collect();
    // per infeed (Z-1, Z-3): plunge, line, arc, line, arc
    assert_eq!(cut.len(), 10, "{cut:?}");
    for (pass, z) in [(0, -1.0), (1, -3.0)] {
        let k = &cut[pass * 5..pass * 5 + 5];
        let end = |kind: &OpKind| match kind {
            OpKind::Line { to, .. } | OpKind::Arc { to, .. } => *to,
            _ => unreachable!(),
        };
        let check = |p: Pose, f: [f64; 2]| {
            assert!((p[AxisLetter::X] - f[0]).abs() < 1e-9, "{p:?} {f:?}");
            assert!((p[AxisLetter::Y] - f[1]).abs() < 1e-9, "{p:?} {f:?}");
            assert!((p[AxisLetter::Z] - z).abs() < 1e-12, "{p:?}");
            assert!((p[AxisLetter::C] - 30.0).abs() < 1e-12, "{p:?}");
        };
        check(end(k[0]), turned(-10.0, 0.0));
        check(end(k[1]), turned(10.0, 0.0));
        check(end(k[2]), turned(10.0, 10.0));
        check(end(k[3]), turned(-10.0, 10.0));
        check(end(k[4]), turned(-10.0, 0.0));
        for (arc, centre) in [(k[2], turned(10.0, 5.0)), (k[4], turned(-10.0, 5.0))] {
            let OpKind::Arc {
                center,
                plane,
                sweep,
                ..
            } = arc
            else {
                panic!("{arc:?}")
            };
            assert_eq!(*plane, klar_interp::Plane::XY);
            assert!((center[0] - centre[0]).abs() < 1e-9 && (center[1] - centre[1]).abs() < 1e-9);
            assert!((sweep - 180.0).abs() < 1e-9, "{sweep}");
        }
    }
    // G793 without its G80 before other words: a located error
    let d = until_error("N4 G110 C0\nN5 G793 ZE-2 F20\nN6 G0 XK0 YK0\nN7 G1 XK5 M8\nN8 G80");
    assert_eq!((d.line, d.col), (8, 11), "{d}");
}

#[test]
fn example_program_drills_every_pattern_position() {
    let ops = run_named("pat.nc", &lathe_program("patterns_linear_lateral.nc"));
    let ends = feed_ends(&ops);
    // G743: (-15,-15) … (15,15) in steps of (10,10): the second hole at (-5,-5) → r √50,
    // C -135°; holes bottom at Z-6
    let face: Vec<&Pose> = ends.iter().filter(|p| p[AxisLetter::Z] == -6.0).collect();
    assert_eq!(face.len(), 4);
    at(*face[1], 50f64.sqrt(), -6.0, -135.0);
    // G744 + G74: the last infeed of each hole reaches radius 30 at Z-10, -22, -34, C0
    let rows: Vec<&Pose> = ends
        .iter()
        .filter(|p| (p[AxisLetter::X] - 30.0).abs() < 1e-9)
        .collect();
    assert_eq!(rows.len(), 3);
    for (k, p) in rows.iter().enumerate() {
        at(**p, 30.0, -10.0 - 12.0 * k as f64, 0.0);
    }
    // G746: six holes to radius 35; the one at A=60°: z = -25 + 8 cos 60°,
    // c = 90° + (8 sin 60° / 40) rad
    let circle: Vec<&Pose> = ends
        .iter()
        .filter(|p| (p[AxisLetter::X] - 35.0).abs() < 1e-9)
        .collect();
    assert_eq!(circle.len(), 6);
    let a = 60f64.to_radians();
    at(
        *circle[1],
        35.0,
        -25.0 + 8.0 * a.cos(),
        90.0 + (8.0 * a.sin() / 40.0).to_degrees(),
    );
}

#[test]
fn g793_after_a_pattern_mills_at_every_position() {
    // positions (20, 0) and (-20, 0); the contour runs from the position 5 mm in +XK
    let ops =
        run("N4 G745 XK0 YK0 K40 A0 Q2 ZS0 \nN5 G793 ZE-1 F20\nN6 G0 XK0 YK0\nN7 G1 XK5\nN8 G80");
    let cut = feed_ends(&ops);
    // per position: plunge to Z-1, the line
    assert_eq!(cut.len(), 4, "{cut:?}");
    at(cut[0], 20.0, -1.0, 0.0);
    at(cut[1], 25.0, -1.0, 0.0);
    // at C180 the face point (-20, 0) lies on +X at 20, (-15, 0) at 15
    at(cut[2], 20.0, -1.0, 180.0);
    at(cut[3], 15.0, -1.0, 180.0);
    let d = until_error("N4 G744 Z-10 Q2 Ki-5\nN5 G793 ZE-1 F20\nN6 G0 XK0 YK0\nN7 G1 XK5\nN8 G80");
    assert!(d.message.contains("lateral pattern"), "{d}");
}
