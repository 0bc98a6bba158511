//! The example programs written on the contour with RL/RR: interpreted, compensated, and
//! checked against the programmed contour the interpreter produced.

mod comp_support;

use comp_support::*;
use klar_interp::{AxisLetter, Interpreter, Op, OpKind, Pose};
use klar_motion::comp::Compensator;

fn ops_of(text: &str) -> Vec<Op> {
    Interpreter::from_source("test.h", text, Pose::ZERO)
        .collect::<Result<Vec<_>, _>>()
        .expect("program runs")
}

fn compensate(ops: &[Op]) -> Vec<Op> {
    let mut c = Compensator::new(Pose::ZERO);
    let mut out = Vec::new();
    for op in ops {
        c.push(op.clone()).expect("valid contour");
        while let Some(o) = c.pop() {
            out.push(o);
        }
    }
    c.finish().expect("valid end");
    while let Some(o) = c.pop() {
        out.push(o);
    }
    out
}

/// The rectangle example with rounded corners, cut with a R5 tool on `side`.
fn rectangle(side: &str) -> String {
    format!(
        "0  BEGIN PGM RECTANGLE MM
1  BLK FORM 0.1 Z X+0 Y+0 Z-20
2  BLK FORM 0.2 X+100 Y+60 Z+0
3  TOOL CALL 1 Z S3000 DR+5
4  L Z+50 R0 FMAX M3
5  L X-10 Y+10 FMAX
6  L Z-5 F300 M8
7  L X+0 Y+10 {side} F600
8  L Y+50
9  CR X+10 Y+60 R+10 DR-
10 L X+80
11 CT X+100 Y+40
12 L Y+10
13 CC X+90 Y+10
14 C X+90 Y+0 DR-
15 L X+10
16 CR X+0 Y+10 R+10 DR-
17 L Z+50 R0 FMAX M9
18 L X-10 Y+10 FMAX M30
19 END PGM RECTANGLE MM
"
    )
}

#[test]
fn rectangle_with_rl_and_rr_keeps_the_tool_radius_from_the_contour() {
    for side in ["RL", "RR"] {
        let ops = ops_of(&rectangle(side));
        let contour_lines = 9..=17; // file lines of blocks 8..16
        let contour: Vec<Op> = ops
            .iter()
            .filter(|o| contour_lines.contains(&o.loc.line))
            .cloned()
            .collect();
        let out = compensate(&ops);
        assert_continuous(Pose::ZERO, &out);
        assert_arcs_consistent(&out);
        let worst =
            worst_offset_error(&out, &pieces(&contour), 5.0, |l| contour_lines.contains(&l));
        assert!(worst < 1e-6, "{side}: offset error {worst}");
        // The clockwise contour has the part on its right: RL runs outside, RR inside.
        let first = motions(&out)
            .into_iter()
            .find(|o| o.loc.line == 9)
            .expect("block 8 is cut");
        let want_x = if side == "RL" { -5.0 } else { 5.0 };
        assert!(
            close(start_xy(first), [want_x, 10.0], 1e-9),
            "{side}: {first:?}"
        );
    }
}

#[test]
fn helix_thread_with_rl_follows_the_compensated_helix() {
    // Internal right-hand thread M40x1.5 programmed on the thread diameter with RL
    // (table: internal, right-hand, Z+ -> DR+ with RL); tool radius 5 -> centre radius 15.
    let text = "0  BEGIN PGM HELIX_THREAD MM
1  BLK FORM 0.1 Z X-40 Y-40 Z-20
2  BLK FORM 0.2 X+40 Y+40 Z+0
3  TOOL CALL 1 Z S2000 DR+5
4  L Z+20 R0 FMAX M3
5  CC X+0 Y+0
6  L X+0 Y+0 FMAX
7  L Z-8.25 FMAX
8  LP PR+20 PA+0 RL F300
9  CP IPA+2160 IZ+9 DR+ F200
10 L X+0 Y+0 R0 F300
11 L Z+20 FMAX M30
12 END PGM HELIX_THREAD MM
";
    let ops = ops_of(text);
    let out = compensate(&ops);
    assert_continuous(Pose::ZERO, &out);
    let helix: Vec<&Op> = out.iter().filter(|o| o.loc.line == 10).collect();
    assert_eq!(helix.len(), 1);
    let OpKind::Arc {
        from,
        to,
        center,
        sweep,
        ..
    } = &helix[0].kind
    else {
        panic!("{:?}", helix[0]);
    };
    assert_eq!(*center, [0.0, 0.0]);
    assert!((sweep - 2160.0).abs() < 1e-9);
    for q in sample(helix[0], 2000) {
        let r = q[AxisLetter::X].hypot(q[AxisLetter::Y]);
        assert!((r - 15.0).abs() < 1e-9, "radius {r}");
    }
    assert!((from[AxisLetter::Z] + 8.25).abs() < 1e-12);
    assert!((to[AxisLetter::Z] - 0.75).abs() < 1e-12);
    // The lead-in arrives at the helix start perpendicular to it, the R0 block leaves it.
    assert!(close(start_xy(helix[0]), [15.0, 0.0], 1e-9));
    assert!(close(end_xy(helix[0]), [15.0, 0.0], 1e-9));
}
