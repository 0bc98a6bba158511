//! The tilted working plane (PLANE, cycle 19) and TCPM (M128/M129, FUNCTION TCPM): rotary
//! angles in Q120–Q122 and tilted coordinates, checked against rotations worked out by hand.

mod common;
use common::*;
use klar_interp::{AxisLetter, Diagnostic, Interpreter, Op, OpKind, Pose};

const AC: [AxisLetter; 5] = [
    AxisLetter::X,
    AxisLetter::Y,
    AxisLetter::Z,
    AxisLetter::A,
    AxisLetter::C,
];
const BC: [AxisLetter; 5] = [
    AxisLetter::X,
    AxisLetter::Y,
    AxisLetter::Z,
    AxisLetter::B,
    AxisLetter::C,
];

fn run_on(axes: &[AxisLetter], body: &str) -> Result<Vec<Op>, Diagnostic> {
    Interpreter::from_source("t.h", &program(body), Pose::ZERO)
        .with_rotary_axes(axes)
        .collect()
}

fn ends(ops: &[Op]) -> Vec<Pose> {
    motions(ops)
        .iter()
        .map(|k| match k {
            OpKind::Line { to, .. } => *to,
            other => panic!("not a line: {other:?}"),
        })
        .collect()
}

/// The angles a PLANE block leaves in Q120, Q121, Q122, read back through a move made after
/// PLANE RESET STAY (which zeroes them, so they are copied to Q1–Q3 first); the move starts
/// away from every answer so that it is never of zero length.
fn angles(axes: &[AxisLetter], plane: &str) -> [f64; 3] {
    let body = format!(
        "{plane}\nQ1 = Q120\nQ2 = Q121\nQ3 = Q122\nPLANE RESET STAY\nL X+999 Y+999 Z+999 FMAX\nL X+Q1 Y+Q2 Z+Q3 FMAX"
    );
    let ops = run_on(axes, &body).unwrap_or_else(|d| panic!("{d}"));
    let last = *ends(&ops).last().expect("a move");
    [
        last[AxisLetter::X],
        last[AxisLetter::Y],
        last[AxisLetter::Z],
    ]
}

#[track_caller]
fn close3(a: [f64; 3], b: [f64; 3]) {
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() < 1e-9, "{a:?} vs {b:?}");
    }
}

#[test]
fn spatial_angles_on_an_a_c_table() {
    // Tool axis seen from the workpiece at (A, C): (sin A sin C, −sin A cos C, cos A).
    // SPA+30 alone: Rx(30)·Z = (0, −1/2, √3/2) → A = 30, C = 0.
    close3(
        angles(&AC, "PLANE SPATIAL SPA+30 SPB+0 SPC+0 STAY"),
        [30.0, 0.0, 0.0],
    );
    // SPB+30: Ry(30)·Z = (1/2, 0, √3/2) → A = ±30 with sin C = ±1.
    close3(
        angles(&AC, "PLANE SPATIAL SPA+0 SPB+30 SPC+0 STAY SEQ+"),
        [30.0, 0.0, 90.0],
    );
    close3(
        angles(&AC, "PLANE SPATIAL SPA+0 SPB+30 SPC+0 STAY SEQ-"),
        [-30.0, 0.0, -90.0],
    );
    // SPA+20, SPC+45: Rz(45)·Rx(20)·Z = (sin20·sin45, −sin20·cos45, cos20) → A 20, C 45.
    close3(
        angles(&AC, "PLANE SPATIAL SPA+20 SPB+0 SPC+45 STAY SEQ+"),
        [20.0, 0.0, 45.0],
    );
}

#[test]
fn spatial_angles_on_a_b_c_table() {
    // Tool axis at (B, C): (sin B cos C, sin B sin C, cos B). SPA+30: (0, −1/2, √3/2) →
    // B = 30 with cos C = 0, sin C = −1 → C = −90; Q120 stays 0.
    close3(
        angles(&BC, "PLANE SPATIAL SPA+30 SPB+0 SPC+0 STAY SEQ+"),
        [0.0, 30.0, -90.0],
    );
}

#[test]
fn euler_vector_and_projected_angles() {
    // EULER PR 90, NU 30: Rz(90)·Rx(30)·Z = (1/2, 0, √3/2) → A 30, C 90.
    close3(
        angles(&AC, "PLANE EULER EULPR+90 EULNU+30 EULROT+0 STAY SEQ+"),
        [30.0, 0.0, 90.0],
    );
    // VECTOR with N = (0, −1, 1)/√2: cos A = 1/√2 → A 45, C 0.
    close3(
        angles(&AC, "PLANE VECTOR BX+1 BY+0 BZ+0 NX+0 NY-1 NZ+1 STAY SEQ+"),
        [45.0, 0.0, 0.0],
    );
    // PROJECTED PROMIN 25 alone is SPA 25.
    close3(
        angles(&AC, "PLANE PROJECTED PROPR+0 PROMIN+25 ROT+0 STAY SEQ+"),
        [25.0, 0.0, 0.0],
    );
    // POINTS in the plane y = 0 (P1→P2 along X, P3 along −Z): normal (1,0,0)×(0,0,−1) =
    // (0, 1, 0) → cos A = 0, A = ±90 with −sin A cos C = 1 → A 90, C 180 (SEQ+).
    let p = angles(
        &AC,
        "PLANE POINTS P1X+0 P1Y+0 P1Z+0 P2X+1 P2Y+0 P2Z+0 P3X+0 P3Y+0 P3Z-1 STAY SEQ+",
    );
    close3([p[0], p[1], p[2].abs()], [90.0, 0.0, 180.0]);
}

#[test]
fn points_of_the_tilted_plane_reach_the_workpiece_turned() {
    // SPB+90: Ry(90) maps (x, y, z) to (z, y, −x).
    let ops = run_on(
        &AC,
        "PLANE SPATIAL SPA+0 SPB+90 SPC+0 STAY\nL X+10 Y+5 Z+2 FMAX\nL X+0 Y+0 Z+0 FMAX",
    )
    .unwrap();
    let e = ends(&ops);
    close3(
        [
            e[0][AxisLetter::X],
            e[0][AxisLetter::Y],
            e[0][AxisLetter::Z],
        ],
        [2.0, 5.0, -10.0],
    );
    close3(
        [
            e[1][AxisLetter::X],
            e[1][AxisLetter::Y],
            e[1][AxisLetter::Z],
        ],
        [0.0; 3],
    );
    // The plane switched the tool-tip transformation on.
    assert!(ops.iter().any(|o| matches!(
        o.kind,
        OpKind::Tcpm {
            on: true,
            compensation_feed: None,
            ..
        }
    )));
}

#[test]
fn cycle_19_tilts_like_plane_spatial_and_resets_without_angles() {
    let ops = run_on(
        &AC,
        "CYCL DEF 19.0 WORKING PLANE\nCYCL DEF 19.1 A+0 B+90 C+0\nL X+10 Y+5 Z+2 FMAX\n\
         CYCL DEF 19.0 WORKING PLANE\nCYCL DEF 19.1\nL X+10 Y+5 Z+2 FMAX",
    )
    .unwrap();
    let e = ends(&ops);
    close3(
        [
            e[0][AxisLetter::X],
            e[0][AxisLetter::Y],
            e[0][AxisLetter::Z],
        ],
        [2.0, 5.0, -10.0],
    );
    close3(
        [
            e[1][AxisLetter::X],
            e[1][AxisLetter::Y],
            e[1][AxisLetter::Z],
        ],
        [10.0, 5.0, 2.0],
    );
}

#[test]
fn a_circle_in_the_tilted_plane_stays_on_the_turned_circle() {
    // Full circle r = 10 about (0, 0) in the plane tilted by SPA+90 (Rx(90): y → z, z → −y):
    // all points lie on x² + z² = 100, y = 0.
    let ops = run_on(
        &AC,
        "PLANE SPATIAL SPA+90 SPB+0 SPC+0 STAY\nL X+10 Y+0 Z+0 FMAX\nCC X+0 Y+0\nC X+10 Y+0 DR+ F300",
    )
    .unwrap();
    let e = ends(&ops);
    assert!(e.len() > 100, "{} lines", e.len());
    for p in &e {
        assert!(p[AxisLetter::Y].abs() < 1e-9);
        assert!((p[AxisLetter::X].hypot(p[AxisLetter::Z]) - 10.0).abs() < 1e-9);
    }
}

#[test]
fn move_turns_the_axes_with_the_tip_held_and_reset_turns_back() {
    let ops = run_on(
        &AC,
        "L X+10 Y+20 Z+30 FMAX\nPLANE SPATIAL SPA+30 SPB+0 SPC+0 MOVE FMAX SEQ+\n\
         PLANE RESET MOVE F1000",
    )
    .unwrap();
    let kinds: Vec<&OpKind> = ops.iter().map(|o| &o.kind).collect();
    let tcpm: Vec<bool> = kinds
        .iter()
        .filter_map(|k| match k {
            OpKind::Tcpm { on, .. } => Some(*on),
            _ => None,
        })
        .collect();
    assert_eq!(tcpm, [true, false]);
    let e = ends(&ops);
    // The turn: same tip (10, 20, 30), A to 30; then back to A 0 with the tip unchanged.
    assert_eq!(e.len(), 3);
    close3(
        [
            e[1][AxisLetter::X],
            e[1][AxisLetter::Y],
            e[1][AxisLetter::Z],
        ],
        [10.0, 20.0, 30.0],
    );
    close(e[1][AxisLetter::A], 30.0);
    close(e[2][AxisLetter::A], 0.0);
    close3(
        [
            e[2][AxisLetter::X],
            e[2][AxisLetter::Y],
            e[2][AxisLetter::Z],
        ],
        [10.0, 20.0, 30.0],
    );
}

#[test]
fn move_with_dist_swings_the_tip_about_the_pivot() {
    // From the origin, tool axis Z; pivot 50 up at (0, 0, 50). A 90 makes the tool axis
    // (0, −1, 0) seen from the workpiece, so the tip ends at (0, 0, 50) + 50·(0, 1, 0).
    let ops = run_on(
        &AC,
        "PLANE SPATIAL SPA+90 SPB+0 SPC+0 MOVE DIST50 F500 SEQ+",
    )
    .unwrap();
    let e = ends(&ops);
    assert_eq!(e.len(), 45, "2° steps over 90°");
    let last = e[44];
    close3(
        [
            last[AxisLetter::X],
            last[AxisLetter::Y],
            last[AxisLetter::Z],
        ],
        [0.0, 50.0, 50.0],
    );
    for p in &e {
        // Every intermediate tip stays 50 from the pivot.
        let d = p[AxisLetter::Y].hypot(p[AxisLetter::Z] - 50.0);
        assert!((d - 50.0).abs() < 1e-9);
    }
}

#[test]
fn m128_and_function_tcpm_switch_the_transformation() {
    let ops = run_on(
        &AC,
        "L X+0 Y+0 Z+50 FMAX M128\nL A+30 C+45 FMAX\nL A+0 C+0 FMAX M129\n\
         FUNCTION TCPM F TCP AXIS POS PATHCTRL AXIS\nFUNCTION RESET TCPM",
    )
    .unwrap();
    let tcpm: Vec<bool> = ops
        .iter()
        .filter_map(|o| match o.kind {
            OpKind::Tcpm { on, .. } => Some(on),
            _ => None,
        })
        .collect();
    assert_eq!(tcpm, [true, false, true, false]);
    // M128 acts at block start: before the first move.
    let first = ops.iter().position(|o| o.kind.is_motion()).unwrap();
    let on = ops
        .iter()
        .position(|o| {
            matches!(
                o.kind,
                OpKind::Tcpm {
                    on: true,
                    compensation_feed: None,
                    ..
                }
            )
        })
        .unwrap();
    assert!(on < first);
}

#[test]
fn plane_on_a_machine_without_rotary_axes_names_the_block() {
    let d = run_on(
        &[AxisLetter::X, AxisLetter::Y, AxisLetter::Z],
        "L X+0 FMAX\nPLANE SPATIAL SPA+0 SPB+45 SPC+0 TURN FMAX",
    )
    .unwrap_err();
    assert_eq!(d.line, 3);
    assert!(
        d.message.contains(
            "PLANE needs rotary axes A and C (or B and C); this machine has no rotary axes"
        ),
        "{}",
        d.message
    );
    // PLANE RESET is harmless on such a machine.
    run_on(&[AxisLetter::X], "PLANE RESET STAY").unwrap();
    // A machine with only C.
    let d = run_on(
        &[AxisLetter::X, AxisLetter::C],
        "PLANE SPATIAL SPA+1 SPB+0 SPC+0 STAY",
    )
    .unwrap_err();
    assert!(
        d.message.contains("this machine has rotary axes C"),
        "{}",
        d.message
    );
}

#[test]
fn malformed_plane_blocks_are_refused() {
    for (body, needle) in [
        ("PLANE SPATIAL SPA+0 SPB+45 STAY", "needs SPA, SPB and SPC"),
        ("PLANE SPATIAL SPA+0 SPB+45 SPC+0", "MOVE, TURN or STAY"),
        ("PLANE EULER SPA+1 STAY", "word SPA in this PLANE form"),
        ("PLANE RELATIV SPA+1 SPB+2 STAY", "exactly one"),
        (
            "PLANE VECTOR BX+1 BY+0 BZ+0 NX+0 NY+0 NZ+0 STAY",
            "normal vector",
        ),
        ("PLANE FOO", "PLANE needs SPATIAL"),
    ] {
        let d = run_on(&AC, body).unwrap_err();
        assert!(d.message.contains(needle), "{body}: {}", d.message);
    }
}

#[test]
fn relativ_adds_a_turn_about_the_tilted_axis() {
    // SPA+20 then RELATIV SPA+10: about the tilted X, which is X here → A 30.
    close3(
        angles(
            &AC,
            "PLANE SPATIAL SPA+20 SPB+0 SPC+0 STAY\nPLANE RELATIV SPA+10 STAY SEQ+",
        ),
        [30.0, 0.0, 0.0],
    );
}

#[test]
fn table_rot_turns_c_for_a_plane_rotated_about_z_only() {
    // SPC+45 alone leaves the tool axis on Z: TABLE ROT turns C by 45, COORD ROT keeps C.
    close3(
        angles(&AC, "PLANE SPATIAL SPA+0 SPB+0 SPC+45 STAY TABLE ROT"),
        [0.0, 0.0, 45.0],
    );
    close3(
        angles(&AC, "PLANE SPATIAL SPA+0 SPB+0 SPC+45 STAY COORD ROT"),
        [0.0, 0.0, 0.0],
    );
    // Either way the tilted X axis runs along the workpiece direction (cos45, sin45, 0).
    let ops = run_on(
        &AC,
        "PLANE SPATIAL SPA+0 SPB+0 SPC+45 STAY\nL X+10 Y+0 Z+0 FMAX",
    )
    .unwrap();
    let e = ends(&ops);
    let h = 10.0 * 45f64.to_radians().cos();
    close3(
        [
            e[0][AxisLetter::X],
            e[0][AxisLetter::Y],
            e[0][AxisLetter::Z],
        ],
        [h, h, 0.0],
    );
}

#[test]
fn cam_style_blocks_with_continuation_mb_max_and_sym_parse() {
    // B is not on an A/C table, so AXIAL with B+0 is fine, B+10 is refused.
    close3(
        angles(
            &AC,
            "PLANE SPATIAL SPA+0 SPB+30 SPC+0 TURN MB MAX FMAX SYM- TABLE ROT",
        ),
        [-30.0, 0.0, -90.0],
    );
    close3(
        angles(
            &AC,
            "PLANE VECTOR BX+1 BY+0 BZ+0 ~\n  NX+0 NY-0.5 NZ+0.8660254037844386 STAY SEQ+",
        ),
        [30.0, 0.0, 0.0],
    );
    close3(
        angles(&AC, "PLANE AXIAL A+25 B+0 C+40 MOVE F500"),
        [25.0, 0.0, 40.0],
    );
    let d = run_on(&AC, "PLANE AXIAL B+10 TURN FMAX").unwrap_err();
    assert!(d.message.contains("lacks"), "{}", d.message);
}
