//! Forms written by CAM posts and saved by real controls that klar accepts: cycle numbers
//! glued to `DEF`, `~` continuations around comments, SPL coefficient lines, text before
//! BEGIN PGM and a mismatched END PGM name (accepted with warnings), block skip, `F MAX`,
//! tabs in comments and tool names.

mod common;
use common::*;
use klar_interp::{OpKind, Pose};

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
