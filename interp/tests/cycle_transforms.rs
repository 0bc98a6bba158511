//! Coordinate transform cycles (7, 8, 10, 11, 26), DEF-active functions (9, 32) and cycle
//! diagnostics, through the public interpreter.

use klar_interp::{CompSide, Interpreter, OpKind, Plane, Pose};

fn ops(src: &str) -> Vec<OpKind> {
    Interpreter::from_source("t.h", src, Pose::ZERO)
        .map(|r| r.expect("runs").kind)
        .collect()
}

fn first_error(src: &str) -> String {
    Interpreter::from_source("t.h", src, Pose::ZERO)
        .find_map(Result::err)
        .expect("an error")
        .to_string()
}

fn line_ends(ops: &[OpKind]) -> Vec<[f64; 3]> {
    ops.iter()
        .filter_map(|o| match o {
            OpKind::Line { to, .. } => Some([to.0[0], to.0[1], to.0[2]]),
            _ => None,
        })
        .collect()
}

fn near(a: [f64; 3], b: [f64; 3]) -> bool {
    a.iter().zip(b.iter()).all(|(x, y)| (x - y).abs() < 1e-9)
}

/// A 40 mm square at Z-2 under datum shift (10, 20), mirror X, rotation 30° and scale 0.5.
/// Closed form per corner (x, y): scale about the datum (x/2, y/2, -1), rotate by 30°
/// (u cos30 − v sin30, u sin30 + v cos30), mirror X (negate the first), shift (+10, +20, 0).
#[test]
fn square_under_shift_mirror_rotation_and_scale() {
    let src = "BEGIN PGM T MM
CYCL DEF 7.0 NULLPUNKT
CYCL DEF 7.1 X+10
CYCL DEF 7.2 Y+20
CYCL DEF 8.0 SPIEGELN
CYCL DEF 8.1 X
CYCL DEF 10.0 DREHUNG
CYCL DEF 10.1 ROT+30
CYCL DEF 11.0 MASSFAKTOR
CYCL DEF 11.1 SCL 0.5
L X+0 Y+0 Z-2 R0 FMAX
L X+40 F100
L Y+40
L X+0
L Y+0
END PGM T MM
";
    let got = line_ends(&ops(src));
    let (s, c) = (0.5, 3f64.sqrt() / 2.0);
    let want: Vec<[f64; 3]> = [
        (0.0, 0.0),
        (40.0, 0.0),
        (40.0, 40.0),
        (0.0, 40.0),
        (0.0, 0.0),
    ]
    .iter()
    .map(|&(x, y)| {
        let (u, v) = (x / 2.0, y / 2.0);
        [-(u * c - v * s) + 10.0, u * s + v * c + 20.0, -1.0]
    })
    .collect();
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(want.iter()) {
        assert!(near(*g, *w), "{g:?} vs {w:?}");
    }
    // the corner (40, 0) by hand: (20, 0) → (17.3205, 10) → (−17.3205, 10) → (−7.3205, 30)
    assert!(near(got[1], [-7.320_508_075_688_772, 30.0, -1.0]));
}

#[test]
fn mirror_reverses_arcs_and_swaps_the_compensation_side() {
    let src = "BEGIN PGM T MM
CYCL DEF 8.0 MIRROR IMAGE
CYCL DEF 8.1 Y
L X+10 Y+0 Z+0 RL F100
CC X+0 Y+0
C X+0 Y+10 DR+
L X+0 Y+20 R0
END PGM T MM
";
    let o = ops(src);
    let sides: Vec<CompSide> = o
        .iter()
        .filter_map(|k| match k {
            OpKind::RadiusComp { side } => Some(*side),
            _ => None,
        })
        .collect();
    assert_eq!(sides, vec![CompSide::Right, CompSide::Off]);
    let arc = o
        .iter()
        .find_map(|k| match k {
            OpKind::Arc {
                to,
                sweep,
                center,
                plane,
                ..
            } => Some((*to, *sweep, *center, *plane)),
            _ => None,
        })
        .expect("an arc");
    assert_eq!(arc.3, Plane::XY);
    assert!((arc.1 + 90.0).abs() < 1e-9, "sweep {}", arc.1);
    assert!(near([arc.0.0[0], arc.0.0[1], 0.0], [0.0, -10.0, 0.0]));
    assert_eq!(arc.2, [0.0, 0.0]);
}

#[test]
fn old_syntax_variants_give_identical_ops() {
    let a = "BEGIN PGM T MM
CYCL DEF 7.0 NULLPUNKT
CYCL DEF 7.1 X+10
CYCL DEF 7.2 Y-5,5
CYCL DEF 10.0 DREHUNG
CYCL DEF 10.1 ROT+45
L X+1 Y+1 Z+1 FMAX
END PGM T MM
";
    let b = "BEGIN PGM T MM
Q7 = 10
CYCL DEF 7.0 DATUM SHIFT
CYCL DEF 7.1  X + Q7
CYCL DEF 7.2  Y-5.500
CYCL DEF 10.0 ROTATION
CYCL DEF 10.1  IROT+20
CYCL DEF 10.1  IROT+25
L X+1 Y+1 Z+1 FMAX
END PGM T MM
";
    let (oa, ob) = (ops(a), ops(b));
    assert_eq!(oa.len(), ob.len());
    for (x, y) in line_ends(&oa).iter().zip(line_ends(&ob).iter()) {
        assert!(near(*x, *y), "{x:?} vs {y:?}");
    }
    // (1, 1) turned by 45° is (0, √2); shifted (10, −5.5 + √2)
    assert!(near(line_ends(&oa)[0], [10.0, -5.5 + 2f64.sqrt(), 1.0]));
}

#[test]
fn resets_and_unprogrammed_axes_stay_on_the_machine() {
    let src = "BEGIN PGM T MM
L X+5 Y+5 Z+5 FMAX
CYCL DEF 7.0 NULLPUNKT
CYCL DEF 7.1 X+100
L Z+0 FMAX
L X+0 FMAX
CYCL DEF 7.0 NULLPUNKT
CYCL DEF 7.1 X+0
CYCL DEF 7.2 Y+0
CYCL DEF 7.3 Z+0
CYCL DEF 11.0 SCL
CYCL DEF 11.1 SCL1
CYCL DEF 10.0 ROT
CYCL DEF 10.1 ROT+0
CYCL DEF 8.0 MIRROR
CYCL DEF 8.1
L X+1 Y+2 Z+3 FMAX
END PGM T MM
";
    let got = line_ends(&ops(src));
    // L Z+0 after the shift moves Z only: X stays at 5 on the machine
    assert!(near(got[1], [5.0, 5.0, 0.0]));
    assert!(near(got[2], [100.0, 5.0, 0.0]));
    assert!(near(got[3], [1.0, 2.0, 3.0]));
}

#[test]
fn dwell_and_tolerance() {
    let src = "BEGIN PGM T MM
CYCL DEF 9.0 VERWEILZEIT
CYCL DEF 9.1 V.ZEIT 1,5
CYCL DEF 32.0 TOLERANZ
CYCL DEF 32.1 T0,05
CYCL DEF 32.2 HSC-MODE:0 TA0.5
CYCL DEF 32.0 TOLERANZ
CYCL DEF 32.1
END PGM T MM
";
    let o = ops(src);
    assert!(o.contains(&OpKind::Dwell { seconds: 1.5 }));
    assert!(o.contains(&OpKind::Tolerance { mm: Some(0.05) }));
    assert!(o.contains(&OpKind::Tolerance { mm: None }));
}

#[test]
fn diagnostics_name_the_block() {
    let e = first_error("BEGIN PGM T MM\nL X+1 FMAX\n3 CYCL CALL\nEND PGM T MM\n");
    assert_eq!(
        e,
        "t.h:3:1: block 3: cycle call without a defined machining cycle: program CYCL DEF first"
    );
    let e = first_error("BEGIN PGM T MM\nCYCL DEF 262 GEWINDEFRAESEN ~\n Q335=10\nEND PGM T MM\n");
    assert_eq!(e, "t.h:2:1: cycle 262 is not supported");
    let e = first_error("BEGIN PGM T MM\nCYCL DEF 7.0 N\nCYCL DEF 7.1 #4\nEND PGM T MM\n");
    assert_eq!(
        e,
        "t.h:3:14: datum 4 asked for, but the machine has no datum table (`datum_table` in \
         the machine file)"
    );
    let e = first_error("BEGIN PGM T MM\nCYCL DEF 8.0 M\nCYCL DEF 8.1 X Z\nEND PGM T MM\n");
    assert_eq!(e, "t.h:3:16: the tool axis Z cannot be mirrored");
    let e = first_error(
        "BEGIN PGM T MM\nL X+0 Y+0 F100\nL X+10\nRND R2\nCYCL DEF 7.0 N\nEND PGM T MM\n",
    );
    assert!(e.starts_with("t.h:5:1: RND/CHF must be followed"), "{e}");
    let e = first_error(
        "BEGIN PGM T MM\nCYCL DEF 26.0 AXIS\nCYCL DEF 26.1 X2 Y1 CCX+0 CCY+0\nL X+10 Y+0 F100\nCC X+0 Y+0\nC X+0 Y+10 DR+\nEND PGM T MM\n",
    );
    assert!(e.starts_with("t.h:6:1: an arc cannot be scaled"), "{e}");
    let e = first_error("BEGIN PGM T MM\nCYCL DEF 11.1 SCL 0\nEND PGM T MM\n");
    assert!(e.starts_with("t.h:2:15: scaling factor 0"), "{e}");
}

#[test]
fn held_contour_element_is_mapped_once_across_a_transform_change() {
    // L X+10 is held back for a possible RND when CYCL DEF 7 arrives; it must leave with the
    // old (empty) transform, and the next move with the new one
    let src = "BEGIN PGM T MM
L X+0 Y+0 Z+5 F100
L X+10
CYCL DEF 7.0 DATUM SHIFT
CYCL DEF 7.1 X+100
L Y+10
END PGM T MM
";
    let got = line_ends(&ops(src));
    assert_eq!(got.len(), 3);
    assert!(near(got[1], [10.0, 0.0, 5.0]));
    // X is not programmed in L Y+10: it stays at 10 on the machine
    assert!(near(got[2], [10.0, 10.0, 5.0]));
}

/// Cycle 200 at the points of a PATTERN DEF, under a datum shift: the deepest point of each
/// hole is the point's surface Z plus the depth Q201, at the shifted X.
#[test]
fn cycle_call_pat_drills_every_pattern_point() {
    let src = "BEGIN PGM T MM
TOOL DEF 1 L+50 R+2
TOOL CALL 1 Z S1000
L Z+20 R0 FMAX M3
CYCL DEF 7.0 DATUM SHIFT
CYCL DEF 7.1 X+100
CYCL DEF 200 DRILLING ~
 Q200=+2 ;SET-UP CLEARANCE ~
 Q201=-5 ;DEPTH ~
 Q206=+100 ;FEED RATE FOR PLNGNG ~
 Q202=+5 ;PLUNGING DEPTH ~
 Q210=+0 ;DWELL TIME AT TOP ~
 Q203=+0 ;SURFACE COORDINATE ~
 Q204=+10 ;2ND SET-UP CLEARANCE ~
 Q211=+0 ;DWELL TIME AT DEPTH
PATTERN DEF ~
 POS1 (X+10 Y+0 Z+0) ~
 POS2 (X+20 Y+5 Z-1)
CYCL CALL PAT FMAX
END PGM T MM
";
    let o = ops(src);
    let deepest = |x: f64, y: f64| {
        line_ends(&o)
            .iter()
            .filter(|p| (p[0] - x).abs() < 1e-9 && (p[1] - y).abs() < 1e-9)
            .map(|p| p[2])
            .fold(f64::INFINITY, f64::min)
    };
    assert!((deepest(110.0, 0.0) + 5.0).abs() < 1e-9);
    assert!((deepest(120.0, 5.0) + 6.0).abs() < 1e-9);
}
