//! Forms written by CAM posts and saved by real controls that klar accepts: cycle numbers
//! glued to `DEF`, `~` continuations around comments, SPL coefficient lines, text before
//! BEGIN PGM and a mismatched END PGM name (accepted with warnings), block skip, `F MAX`,
//! tabs in comments and tool names.

mod common;
use common::*;
use klar_interp::{
    AxisLetter, OpKind, Pose,
    op::{SpindleDir, SpindleSpeed},
};

/// The op kinds of a program, without their source locations.
fn kinds(text: &str) -> Vec<OpKind> {
    run(text).into_iter().map(|o| o.kind).collect()
}

/// End points of the motion ops.
fn ends(text: &str) -> Vec<Pose> {
    motions(&run(text))
        .iter()
        .map(|k| match k {
            OpKind::Line { to, .. } | OpKind::Arc { to, .. } | OpKind::Spline { to, .. } => *to,
            other => panic!("unexpected motion {other:?}"),
        })
        .collect()
}

#[test]
fn dwell_cycle_number_glued_to_def() {
    let glued = program(
        "1 TOOL CALL 1 Z S1000\n2 CYCL DEF9 .0 DWELL TIME\n3 CYCL DEF9 .1 V.ZEIT1.5\n4 L Z+5 F200",
    );
    let spaced = program(
        "1 TOOL CALL 1 Z S1000\n2 CYCL DEF 9.0 DWELL TIME\n3 CYCL DEF 9.1 V.ZEIT1.5\n4 L Z+5 F200",
    );
    let k = kinds(&glued);
    assert_eq!(k, kinds(&spaced));
    let dwells: Vec<&OpKind> = k
        .iter()
        .filter(|o| matches!(o, OpKind::Dwell { .. }))
        .collect();
    assert_eq!(dwells, vec![&OpKind::Dwell { seconds: 1.5 }]);
}

#[test]
fn datum_shift_with_blanks_between_number_and_sub_block() {
    let variants = [
        "CYCL DEF7.0 NULLPUNKT\nCYCL DEF7.1 X+10\nCYCL DEF7.2 Y+5",
        "CYCL DEF 7 .0 NULLPUNKT\nCYCL DEF 7 .1 X+10\nCYCL DEF 7 .2 Y+5",
        "CYCL DEF7 .0 NULLPUNKT\nCYCL DEF  7  .1 X+10\nCYCL DEF 7.2 Y+5",
    ];
    for v in variants {
        let p = program(&format!("{v}\nL X+0 Y+0 Z+0 F500\nL X+1"));
        assert_eq!(
            ends(&p),
            vec![Pose::xyz(10.0, 5.0, 0.0), Pose::xyz(11.0, 5.0, 0.0)],
            "{v}"
        );
    }
}

#[test]
fn a_bad_cycl_block_says_what_it_found() {
    let (_, d) = run_until_error(&program("L X+1 F100\nCYCL DEFINE 7.0 NP"));
    assert_eq!(
        d.to_string(),
        "t.h:3:6: unexpected word 'DEFINE' after CYCL (expected DEF or CALL)"
    );
    let (_, d) = run_until_error(&program("L X+1 F100\n5 CYCL"));
    assert_eq!(
        d.to_string(),
        "t.h:3:7: block 5: unexpected end of block after CYCL (expected DEF or CALL)"
    );
}

#[test]
fn a_comment_ending_in_tilde_goes_on_over_the_next_line() {
    let text = program(
        "3 TOOL CALL 1 Z S2000 ; a long comment that the control wrapped~\n continued comment ~\n   and its last line\n4 L X+10 F100 M3",
    );
    let ops = run(&text);
    let tools: Vec<u32> = ops
        .iter()
        .filter_map(|o| match &o.kind {
            OpKind::ToolChange { tool, .. } => Some(*tool),
            _ => None,
        })
        .collect();
    assert_eq!(tools, vec![1]);
    let speeds: Vec<f64> = ops
        .iter()
        .filter_map(|o| match &o.kind {
            OpKind::Spindle {
                dir: SpindleDir::Cw,
                speed: SpindleSpeed::Rpm(s),
                ..
            } => Some(*s),
            _ => None,
        })
        .collect();
    assert_eq!(speeds, vec![2000.0]);
    let lines: Vec<(Pose, u32)> = ops
        .iter()
        .filter_map(|o| match &o.kind {
            OpKind::Line { to, .. } => Some((*to, o.loc.line)),
            _ => None,
        })
        .collect();
    // block 4 sits on line 5 of the file, after the three lines of block 3
    assert_eq!(lines, vec![(Pose::xyz(10.0, 0.0, 0.0), 5)]);
}

#[test]
fn a_tilde_inside_a_comment_is_text() {
    // `; ~ ~ ` ends in `~`: only the empty line after it becomes comment text
    let text = program("L X+5 F100 ; 5 ~ 6 mm\nL Y+5 ;~x\nL Z+5 ; ~ ~ \n");
    assert_eq!(
        ends(&text),
        vec![
            Pose::xyz(5.0, 0.0, 0.0),
            Pose::xyz(5.0, 5.0, 0.0),
            Pose::xyz(5.0, 5.0, 5.0)
        ]
    );
}

/// Cycle 200 at X+10 Y+20, written as a control saves it.
const DRILL: &str = "  Q200=2 ;SICHERHEITS-ABST. ~\n  Q201=-10 ;TIEFE ~\n  Q206=150 ;VORSCHUB TIEFENZ. ~\n  Q202=5 ;ZUSTELL-TIEFE ~\n  Q210=0 ;VERWEILZEIT OBEN ~\n  Q203=+0 ;KOOR. OBERFLAECHE ~\n  Q204=50 ;2. SICHERHEITS-ABST. ~\n  Q211=0 ;VERWEILZEIT UNTEN\n";

#[test]
fn a_comment_after_the_tilde_of_a_cycle_head_keeps_the_parameters_in_the_block() {
    let head = "TOOL CALL 1 Z S2000\nL X+10 Y+20 Z+60 R0 FMAX";
    let commented = program(&format!(
        "{head}\nCYCL DEF 200 BOHREN ~ ;;centre drill\n{DRILL}CYCL CALL"
    ));
    let plain = program(&format!("{head}\nCYCL DEF 200 BOHREN ~\n{DRILL}CYCL CALL"));
    let m = motions(&run(&commented));
    assert_eq!(m, motions(&run(&plain)));
    // the drill goes to Q201 = -10 below Q203 = 0
    let lowest = ends(&commented)
        .iter()
        .map(|p| p[AxisLetter::Z])
        .fold(f64::INFINITY, f64::min);
    close(lowest, -10.0);
    // a bad parameter line is reported on its own line: the lines belong to the cycle block
    let broken = program(&format!(
        "{head}\nCYCL DEF 200 BOHREN ~ ;;centre drill\n  Q200=2 ;SICHERHEITS-ABST. ~\n  Q201= ;TIEFE\nCYCL CALL"
    ));
    let (_, d) = run_until_error(&broken);
    assert_eq!(d.to_string(), "t.h:6:3: missing value after Q201=");
}
