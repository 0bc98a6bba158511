//! Tool table, TOOL CALL by number and name, TOOL DEF, paraxial compensation and the
//! motion-related M functions.

mod common;
use common::*;
use klar_interp::{AxisLetter, Feed, Interpreter, OpKind, Pose, ToolTable};

const TABLE: &str = "BEGIN TOOL.T MM\n\
T    NAME          L          R          R2       DL       DR       DR2\n\
0    NULL          +0         +0         +0       +0       +0       +0\n\
4    MILL_D10      +50        +5         +0       +0.5     -0.1     +0\n\
9    BALL_8        +70        +4         +4       +0       +0       +0\n\
[END]\n";

fn tool_changes(text: &str, table: &ToolTable) -> Vec<(u32, f64, f64)> {
    Interpreter::from_source("t.h", text, Pose::ZERO)
        .with_tools(table.clone())
        .map(|r| r.unwrap_or_else(|d| panic!("{d}")))
        .filter_map(|o| match o.kind {
            OpKind::ToolChange {
                tool,
                length,
                radius,
                ..
            } => Some((tool, length, radius)),
            _ => None,
        })
        .collect()
}

#[test]
fn tool_call_takes_length_and_radius_from_the_table() {
    let table = ToolTable::parse(TABLE).unwrap();
    let t = tool_changes(
        &program("TOOL CALL 4 Z S3000\nTOOL CALL \"BALL_8\" Z DL+1 DR-0.5\nTOOL CALL DR+0.2"),
        &table,
    );
    // L + DL(table) + DL(call), R + DR(table) + DR(call)
    assert_eq!(t.len(), 3);
    assert_eq!(t[0].0, 4);
    close(t[0].1, 50.5);
    close(t[0].2, 4.9);
    assert_eq!(t[1].0, 9);
    close(t[1].1, 71.0);
    close(t[1].2, 3.5);
    // no tool number: same tool, new deltas
    close(t[2].2, 4.2);
    // a tool the table does not hold
    let mut it =
        Interpreter::from_source("t.h", &program("TOOL CALL 5 Z"), Pose::ZERO).with_tools(table);
    let d = it.find_map(Result::err).unwrap();
    assert_eq!(d.message, "tool 5 is not in the tool table");
    assert_eq!(d.line, 2);
}

#[test]
fn paraxial_compensation_lengthens_and_shortens_by_the_radius() {
    let ops = run(&program(
        "TOOL DEF 1 L+30 R+5\nTOOL CALL 1 Z\nL X+0 Y+0 Z+5 F100\nL X+20 R+\nL X+0 R-\nL Y-10 R+",
    ));
    let ends: Vec<Pose> = motions(&ops)
        .iter()
        .map(|k| match k {
            OpKind::Line { to, .. } => *to,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(ends[1], Pose::xyz(25.0, 0.0, 5.0));
    assert_eq!(ends[2], Pose::xyz(5.0, 0.0, 5.0));
    assert_eq!(ends[3], Pose::xyz(5.0, -15.0, 5.0));
    let (_, d) = run_until_error(&program(
        "TOOL DEF 1 R+5\nTOOL CALL 1 Z\nL X+10 Y+10 R+ F100",
    ));
    assert!(d.message.contains("exactly one axis"), "{}", d.message);
}

#[test]
fn m126_takes_the_short_way_and_m140_retracts() {
    let ops = run(&program(
        "L C+350 F100\nL C+10 M126\nL C+200 M127\nL Z+10\nL X+5 M140 MB 50",
    ));
    let ends: Vec<Pose> = motions(&ops)
        .iter()
        .map(|k| match k {
            OpKind::Line { to, .. } => *to,
            other => panic!("{other:?}"),
        })
        .collect();
    // 350 → 10 with M126: +20 instead of -340
    assert_eq!(ends[1][AxisLetter::C], 370.0);
    // M127: absolute again
    assert_eq!(ends[2][AxisLetter::C], 200.0);
    // M140 MB 50: a rapid retract of 50 mm along the tool axis after the block's motion
    assert_eq!(ends[4][AxisLetter::X], 5.0);
    assert_eq!(ends[5][AxisLetter::Z], 60.0);
    match &motions(&ops)[5] {
        OpKind::Line { feed, .. } => assert_eq!(*feed, Feed::Rapid),
        other => panic!("{other:?}"),
    }
    // MB MAX needs the travel of the tool axis
    let (_, d) = run_until_error(&program("L Z+10 F100\nL M140 MB MAX"));
    assert!(
        d.message.contains("known travel of the tool axis Z"),
        "{}",
        d.message
    );
    let ops: Vec<_> =
        Interpreter::from_source("t.h", &program("L Z+10 F100\nL M140 MB MAX"), Pose::ZERO)
            .with_travel(AxisLetter::Z, [-100.0, 250.0])
            .map(Result::unwrap)
            .collect();
    match motions(&ops).last() {
        Some(OpKind::Line { to, .. }) => assert_eq!(to[AxisLetter::Z], 250.0),
        other => panic!("{other:?}"),
    }
    // accepted without effect here: M91, M92, M97, M98, M6
    assert_eq!(
        motions(&run(&program(
            "L Z-10 FMAX M91\nL Z+5 F100 M92 M97\nM98 M6"
        )))
        .len(),
        2
    );
}

#[test]
fn a_pocket_with_a_tool_nobody_defines_names_the_tool() {
    let pocket = "TOOL CALL 7 Z S3000\nL Z+50 R0 FMAX\n\
        CYCL DEF 251 RECTANGULAR POCKET ~\nQ215=0 ~\nQ218=40 ~\nQ219=30 ~\nQ220=2 ~\n\
        Q368=0 ~\nQ224=0 ~\nQ367=0 ~\nQ207=500 ~\nQ351=+1 ~\nQ201=-5 ~\nQ202=5 ~\nQ369=0 ~\n\
        Q206=150 ~\nQ338=0 ~\nQ200=2 ~\nQ203=+0 ~\nQ204=50 ~\nQ370=1 ~\nQ366=1 ~\nQ385=500\n\
        L X+0 Y+0 FMAX M99";
    let (_, d) = run_until_error(&program(pocket));
    assert_eq!(
        d.message,
        "tool 7 is not in the tool table: cycle 251 needs its radius (give it in the \
         machine's tool table or with TOOL DEF)"
    );
    // With TOOL DEF the same pocket runs.
    let defined = format!("TOOL DEF 7 L+60 R+4\n{pocket}");
    assert!(!motions(&run(&program(&defined))).is_empty());
}
