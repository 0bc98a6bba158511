//! Lathe DIN programs against geometry worked out by hand: diameter → radius, arcs in the
//! ZX plane, technology words, the manual's G745 example and a self-drilling pattern.

mod common;
use common::lathe::{line_ends as lines, program_file, run_named as run};
use common::{arc, close};
use klar_interp::op::{SpindleDir, SpindleId, SpindleSpeed};
use klar_interp::{AxisLetter, Feed, Interpreter, Op, OpKind, Plane, Pose};

fn pose(x: f64, y: f64, z: f64, c: f64) -> Pose {
    let mut p = Pose::xyz(x, y, z);
    p.set(AxisLetter::C, c);
    p
}

#[track_caller]
fn close_pose(a: Pose, b: Pose) {
    for ax in AxisLetter::ALL {
        assert!((a[ax] - b[ax]).abs() < 1e-9, "{ax}: {a:?} != {b:?}");
    }
}

/// The motion ops of `ops`, in order.
fn motion_of(ops: &[Op]) -> Vec<&OpKind> {
    ops.iter()
        .filter(|o| o.kind.is_motion())
        .map(|o| &o.kind)
        .collect()
}

/// Asserts that `k` is a straight move to `to` (within 1e-9 on every axis) at `feed`.
#[track_caller]
fn line_to(k: &OpKind, to: Pose, feed: Feed) {
    match k {
        OpKind::Line { to: t, feed: f, .. } => {
            close_pose(*t, to);
            assert_eq!(*f, feed);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn manual_g745_example_mills_three_slots_at_0_120_240_degrees() {
    let ops = run("745.nc", &program_file("lathe/g745_face_slots.nc"));
    // technology: driven tool at 1200 rpm counter-clockwise (M104), feed 0.15 mm per
    // driven-tool revolution = 0.15 · 1200 / 60 mm/s
    assert!(ops.iter().any(|o| o.kind
        == OpKind::Spindle {
            spindle: SpindleId::Driven,
            dir: SpindleDir::Ccw,
            speed: SpindleSpeed::Rpm(1200.0)
        }));
    assert!(ops.iter().any(|o| o.kind == OpKind::CAxis { on: true }));
    let moves = lines(&ops);
    // N4: X100 is a diameter: radius 50
    close_pose(moves[0].0, pose(50.0, 0.0, 2.0, 0.0));
    let slot_feed = 0.15 * 1200.0 / 60.0;
    // one slot per pattern angle; each begins with the rapid onto the position at the
    // clearance Z2: pattern diameter 50 → radius 25 on the X axis after turning C
    let starts: Vec<usize> = moves
        .iter()
        .enumerate()
        .filter(|(_, (p, f))| *f == Feed::Rapid && (p[AxisLetter::Z] - 2.0).abs() < 1e-12)
        .filter(|(_, (p, _))| (p[AxisLetter::X] - 25.0).abs() < 1e-9)
        .map(|(i, _)| i)
        .collect();
    assert_eq!(starts.len(), 3, "{moves:?}");
    for (k, &i) in starts.iter().enumerate() {
        let theta = 120.0 * k as f64;
        close_pose(moves[i].0, pose(25.0, 0.0, 2.0, theta));
        // slot end: the face point p + 30·(cos 0°, sin 0°) seen in the system turned by θ
        let t = theta.to_radians();
        let (fx, fy) = (25.0 * t.cos() + 30.0, 25.0 * t.sin());
        let end = pose(
            fx * t.cos() + fy * t.sin(),
            -fx * t.sin() + fy * t.cos(),
            -2.0,
            theta,
        );
        // rapid to ZS0, feed to -2, along the slot, -4, back, -5, along, rapid up to Z2
        close_pose(moves[i + 1].0, pose(25.0, 0.0, 0.0, theta));
        assert_eq!(moves[i + 1].1, Feed::Rapid);
        close_pose(moves[i + 2].0, pose(25.0, 0.0, -2.0, theta));
        close_pose(moves[i + 3].0, end);
        assert_eq!(moves[i + 3].1, Feed::Rate(slot_feed));
        let mut end4 = end;
        end4[AxisLetter::Z] = -4.0;
        close_pose(moves[i + 4].0, end4);
        close_pose(moves[i + 5].0, pose(25.0, 0.0, -4.0, theta));
        close_pose(moves[i + 6].0, pose(25.0, 0.0, -5.0, theta));
        let mut end5 = end;
        end5[AxisLetter::Z] = -5.0;
        close_pose(moves[i + 7].0, end5);
        let mut up = end;
        up[AxisLetter::Z] = 2.0;
        close_pose(moves[i + 8].0, up);
        assert_eq!(moves[i + 8].1, Feed::Rapid);
        // the slot is 30 mm long whatever the angle
        close(
            (moves[i + 3].0[AxisLetter::X] - 25.0).hypot(moves[i + 3].0[AxisLetter::Y]),
            30.0,
        );
    }
    assert!(ops.iter().any(|o| o.kind == OpKind::CAxis { on: false }));
    assert_eq!(ops.last().map(|o| &o.kind), Some(&OpKind::End));
}

#[test]
fn turning_program_halves_x_and_puts_arcs_in_the_zx_plane() {
    let ops = run("shaft.nc", &program_file("lathe/shaft_turning.nc"));
    let tool = ops.iter().find_map(|o| match &o.kind {
        OpKind::ToolChange { tool, name, .. } => Some((*tool, name.clone())),
        _ => None,
    });
    assert_eq!(tool, Some((1, Some("FINISH-TOOL-35".to_string()))));
    assert!(ops.iter().any(|o| o.kind
        == OpKind::Spindle {
            spindle: SpindleId::Main,
            dir: SpindleDir::Ccw,
            // G96 S180 under the G26 S3000 limit
            speed: SpindleSpeed::SurfaceSpeedCapped(180.0, 3000.0)
        }));
    let motion = motion_of(&ops);
    // N13 G0 X62 Z2: radius 31
    line_to(motion[0], Pose::xyz(31.0, 0.0, 2.0), Feed::Rapid);
    // N15 G1 Z-20 at 0.25 mm/rev
    line_to(
        motion[2],
        Pose::xyz(20.0, 0.0, -20.0),
        Feed::PerRevolution(0.25),
    );
    // N16 G13 X50 Z-25 R5: from (Z-20, r20) to (Z-25, r25); R5 → centre 5 away from both:
    // (Z-25, r20) or (Z-20, r25); G13 turns counter-clockwise with Z right and X up, i.e. a
    // positive sweep from Z towards X: the quarter about (Z-25, r20) starts at angle 90°
    // (+X side of the centre… measured in (Z, X): start − centre = (5, 0) → 0°) and ends
    // at (0, 5) → 90°: +90°.
    let (from, to, center, plane, sweep) = arc(motion[3]);
    assert_eq!(plane, Plane::ZX);
    close_pose(from, Pose::xyz(20.0, 0.0, -20.0));
    close_pose(to, Pose::xyz(25.0, 0.0, -25.0));
    close(center[0], -25.0);
    close(center[1], 20.0);
    close(sweep, 90.0);
    // N18 G2 Xi4 Zi-2 I0 K-2 from (Z-25, r28): end (Z-27, r30), centre start + (K, I) =
    // (Z-27, r28); start − centre = (2, 0) → 0°, end − centre = (0, 2) → 90°, clockwise:
    // -270°
    let (from, to, center, _, sweep) = arc(motion[5]);
    close_pose(from, Pose::xyz(28.0, 0.0, -25.0));
    close_pose(to, Pose::xyz(30.0, 0.0, -27.0));
    close(center[0], -27.0);
    close(center[1], 28.0);
    close(sweep, -270.0);
    // N197 G890 NS3 NE6: from X0 Z2 onto the contour start (X0 Z0), face to r17 (the
    // chamfer BR-1 starts 1 mm before the corner r18), chamfer to (Z-1, r18), cylinder to
    // Z-20, face to r26 (BR2: tan 45° · 2 = 2 mm before r28), the rounding arc about
    // (Z-22, r26), cylinder to Z-40
    let fin: Vec<&OpKind> = motion
        .iter()
        .copied()
        .skip_while(
            |k| !matches!(k, OpKind::Line { feed: Feed::PerRevolution(f), .. } if *f == 0.1),
        )
        .take_while(|k| match k {
            OpKind::Line { feed, .. } | OpKind::Arc { feed, .. } => {
                *feed == Feed::PerRevolution(0.1)
            }
            _ => false,
        })
        .collect();
    let ends: Vec<Pose> = fin
        .iter()
        .map(|k| match k {
            OpKind::Line { to, .. } | OpKind::Arc { to, .. } => *to,
            _ => Pose::ZERO,
        })
        .collect();
    let want = [
        Pose::xyz(17.0, 0.0, 0.0),
        Pose::xyz(18.0, 0.0, -1.0),
        Pose::xyz(18.0, 0.0, -20.0),
        Pose::xyz(26.0, 0.0, -20.0),
        Pose::xyz(28.0, 0.0, -22.0),
        Pose::xyz(28.0, 0.0, -40.0),
    ];
    assert_eq!(ends.len(), want.len(), "{fin:?}");
    for (a, b) in ends.iter().zip(want) {
        close_pose(*a, b);
    }
    match fin[4] {
        OpKind::Arc { center, sweep, .. } => {
            close(center[0], -22.0);
            close(center[1], 26.0);
            close(*sweep, 90.0);
        }
        other => panic!("{other:?}"),
    }
    // N21 G14 Q1: X first to the change point (diameter 200 → radius 100), then Z 200
    let all = lines(&ops);
    let q1 = all
        .iter()
        .position(|(p, _)| (p[AxisLetter::X] - 100.0).abs() < 1e-9)
        .expect("tool change point");
    close_pose(all[q1].0, Pose::xyz(100.0, 0.0, -40.0));
    close_pose(all[q1 + 1].0, Pose::xyz(100.0, 0.0, 200.0));
    // N25 G71 Z-25 F0.12 from X0 Z3: feed to Z-25, rapid back to Z3
    let drill = all
        .iter()
        .position(|(p, f)| {
            *f == Feed::PerRevolution(0.12) && (p[AxisLetter::Z] + 25.0).abs() < 1e-9
        })
        .expect("drilling move");
    close_pose(all[drill - 1].0, Pose::xyz(0.0, 0.0, 3.0));
    close_pose(all[drill + 1].0, Pose::xyz(0.0, 0.0, 3.0));
    assert_eq!(all[drill + 1].1, Feed::Rapid);
    assert_eq!(ops.last().map(|o| &o.kind), Some(&OpKind::End));
}

#[test]
fn self_drilling_pattern_with_polar_centre_and_increment() {
    let ops = run("lat.nc", &program_file("lathe/lateral_y_tilted.nc"));
    let moves = lines(&ops);
    // holes at 45°, 135°, 225°, 315° on the pattern diameter 80 about the axis: radius 40
    let feed = 0.05 * 2000.0 / 60.0;
    let bottoms: Vec<Pose> = moves
        .iter()
        .filter(|(_, f)| *f == Feed::Rate(feed))
        .map(|(p, _)| *p)
        .collect();
    assert_eq!(bottoms.len(), 4);
    for (k, p) in bottoms.iter().enumerate() {
        close_pose(*p, pose(40.0, 0.0, -12.0, 45.0 + 90.0 * k as f64));
    }
}

#[test]
fn deep_hole_pecks_follow_first_depth_reduction_and_minimum() {
    // from Z2 (clearance), start ZS0, end ZE-10: infeeds 4, 3, 2, 1 (I1 reduction, J1
    // minimum) → depths -4, -7, -9, -10; return distance B1 after each infeed
    let text = "N1 T1 G197 S1000 G195 F0.1 M103\nN2 M14\nN3 G0 X40 Z2\n\
                N4 G745 XK0 YK0 K30 A0 Q1 ZS0\nN5 G74 ZE-10 P4 I1 B1 J1\nN6 M30\nEND\n";
    let moves = lines(&run("deep.nc", text));
    let zs: Vec<(f64, bool)> = moves
        .iter()
        .skip(1)
        .map(|(p, f)| (p[AxisLetter::Z], *f == Feed::Rapid))
        .collect();
    let expected = [
        (2.0, true),   // onto the position at the clearance
        (0.0, true),   // ZS
        (-4.0, false), // first infeed P4
        (-3.0, true),  // return distance B1
        (-4.0, true),  // back to the depth reached
        (-7.0, false), // 4 − 1
        (-6.0, true),
        (-7.0, true),
        (-9.0, false), // 3 − 1
        (-8.0, true),
        (-9.0, true),
        (-10.0, false), // the rest, 1 = J
        (2.0, true),    // up to the clearance
    ];
    assert_eq!(zs.len(), expected.len(), "{zs:?}");
    for (a, e) in zs.iter().zip(expected) {
        close(a.0, e.0);
        assert_eq!(a.1, e.1);
    }
}

#[test]
fn finishing_cycle_runs_the_finished_part_contour() {
    // contour: start X0 Z0, face up to X40 (radius 20), rounded corner R2 (G12: clockwise
    // seen with Z right and X up, going from the face onto the cylinder), cylinder to Z-30
    let text = "FINISHED PART\nN1 G0 X0 Z0\nN2 G1 X36\nN3 G12 X40 Z-2 R2\nN4 G1 Z-30\n\
                MACHINING\nN10 T1 G96 S200 G95 F0.1 M4\nN11 G0 X50 Z5\nN12 G890 NS2 NE4\n\
                N13 M30\nEND\n";
    let ops = run("fin.nc", text);
    let motion = motion_of(&ops);
    // G0 X50 Z5, the rapid to the contour start (X0 Z0), N2, N3, N4
    assert_eq!(motion.len(), 5, "{motion:?}");
    line_to(motion[1], Pose::xyz(0.0, 0.0, 0.0), Feed::Rapid);
    line_to(
        motion[2],
        Pose::xyz(18.0, 0.0, 0.0),
        Feed::PerRevolution(0.1),
    );
    // (Z0, r18) → (Z-2, r20) with R2: centres (Z-2, r18) or (Z0, r20); clockwise in (Z, X)
    // from the start, the quarter about (Z-2, r18): start − centre = (2, 0) → 0°, end −
    // centre = (0, 2) → 90°: counter-clockwise would be +90, so clockwise takes the other
    // centre (Z0, r20): start − centre = (0, -2) → -90°, end − centre = (-2, 0) → 180°,
    // clockwise from -90° to 180° is -90°
    match motion[3] {
        OpKind::Arc {
            to,
            center,
            sweep,
            feed,
            ..
        } => {
            close_pose(*to, Pose::xyz(20.0, 0.0, -2.0));
            close(center[0], 0.0);
            close(center[1], 20.0);
            close(*sweep, -90.0);
            assert_eq!(*feed, Feed::PerRevolution(0.1));
        }
        other => panic!("{other:?}"),
    }
    match motion[4] {
        OpKind::Line { to, .. } => close_pose(*to, Pose::xyz(20.0, 0.0, -30.0)),
        other => panic!("{other:?}"),
    }
}

/// The motion ops of a G890 run over `contour` (after the set-up and the approach).
fn finished(contour: &str) -> Vec<OpKind> {
    let text = format!(
        "FINISHED PART\n{contour}MACHINING\nN10 T1 G97 S1000 G95 F0.1 M3\nN11 G0 X50 Z5\n\
         N12 G890\nN13 M30\nEND\n"
    );
    run("br.nc", &text)
        .into_iter()
        .filter(|o| o.kind.is_motion())
        .map(|o| o.kind)
        .skip(2)
        .collect()
}

#[test]
fn br_rounds_or_chamfers_the_corner_between_two_lines() {
    // face up to diameter 40, then along the cylinder: the corner is (Z0, r20)
    let m = finished("N1 G0 X0 Z0\nN2 G1 X40 BR2\nN3 G1 Z-30\n");
    assert_eq!(m.len(), 3, "{m:?}");
    // R2 tangent to the face Z0 and to the cylinder r20: centre (Z-2, r18), touching points
    // (Z0, r18) and (Z-2, r20), a quarter turn from +X heading to -Z heading (left turn)
    match &m[0] {
        OpKind::Line { to, .. } => close_pose(*to, Pose::xyz(18.0, 0.0, 0.0)),
        other => panic!("{other:?}"),
    }
    let (from, to, center, _, sweep) = arc(&m[1]);
    close_pose(from, Pose::xyz(18.0, 0.0, 0.0));
    close_pose(to, Pose::xyz(20.0, 0.0, -2.0));
    close(center[0], -2.0);
    close(center[1], 18.0);
    close(sweep, 90.0);
    match &m[2] {
        OpKind::Line { from, to, .. } => {
            close_pose(*from, Pose::xyz(20.0, 0.0, -2.0));
            close_pose(*to, Pose::xyz(20.0, 0.0, -30.0));
        }
        other => panic!("{other:?}"),
    }
    // BR-3: a chamfer from 3 mm before the corner to 3 mm after it
    let m = finished("N1 G0 X0 Z0\nN2 G1 X40 BR-3\nN3 G1 Z-30\n");
    match &m[1] {
        OpKind::Line { from, to, .. } => {
            close_pose(*from, Pose::xyz(17.0, 0.0, 0.0));
            close_pose(*to, Pose::xyz(20.0, 0.0, -3.0));
        }
        other => panic!("{other:?}"),
    }
    // too big for the element: a located error
    let text = "FINISHED PART\nN1 G0 X0 Z0\nN2 G1 X40 BR30\nN3 G1 Z-10\nMACHINING\nEND\n";
    let err = Interpreter::from_source("big.nc", text, Pose::ZERO)
        .find_map(Result::err)
        .expect("error");
    assert_eq!((err.line, err.col), (4, 1), "{err}");
    assert!(err.message.contains("BR of block 2"), "{err}");
}

#[test]
fn tapping_feeds_at_the_pitch_and_reverses_the_driven_tool() {
    let text = "N1 T4 G197 S500 M103\nN2 M14\nN3 G0 X0 Z5\nN4 G36 ZS2 ZE-12 F1.25\nN5 M30\nEND\n";
    let ops = run("tap.nc", text);
    let kinds: Vec<&OpKind> = ops.iter().map(|o| &o.kind).collect();
    let down = kinds
        .iter()
        .position(|k| matches!(k, OpKind::Line { to, feed: Feed::PerRevolution(p), .. } if *p == 1.25 && (to[AxisLetter::Z] + 12.0).abs() < 1e-12))
        .expect("the tapping move");
    // then: driven tool reversed (M103 was clockwise), back to ZS at the same pitch, the
    // spindle forward again, rapid to the clearance Z5
    assert_eq!(
        *kinds[down + 1],
        OpKind::Spindle {
            spindle: SpindleId::Driven,
            dir: SpindleDir::Ccw,
            speed: SpindleSpeed::Rpm(500.0)
        }
    );
    match kinds[down + 2] {
        OpKind::Line { to, feed, .. } => {
            close(to[AxisLetter::Z], 2.0);
            assert_eq!(*feed, Feed::PerRevolution(1.25));
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        kinds[down + 3],
        OpKind::Spindle {
            dir: SpindleDir::Cw,
            ..
        }
    ));
    match kinds[down + 4] {
        OpKind::Line { to, feed, .. } => {
            close(to[AxisLetter::Z], 5.0);
            assert_eq!(*feed, Feed::Rapid);
        }
        other => panic!("{other:?}"),
    }
}
