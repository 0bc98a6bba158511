//! Program structure: labels, jumps, subprograms, section repeats, CALL PGM, FN 14/18 and
//! Q-parameter arithmetic, checked on the order and values of the motion ops.

mod common;
use common::*;
use klar_interp::{AxisLetter, Interpreter, OpKind, Pose};

/// End points (X, Y) of all motion ops, in order.
fn ends(text: &str) -> Vec<(f64, f64)> {
    motions(&run(text))
        .iter()
        .map(|k| match k {
            OpKind::Line { to, .. } | OpKind::Arc { to, .. } => {
                (to[AxisLetter::X], to[AxisLetter::Y])
            }
            other => panic!("unexpected motion {other:?}"),
        })
        .collect()
}

fn xs(text: &str) -> Vec<f64> {
    ends(text).into_iter().map(|p| p.0).collect()
}

#[test]
fn subprogram_calls_return_after_the_call() {
    let body = "L X+1 F100\nCALL LBL 1\nL X+2\nCALL LBL \"two\"\nL X+3 M30\n\
                LBL 1\nL Y+10\nL Y+0\nLBL 0\nLBL \"two\"\nL Y+7\nCALL LBL 1\nLBL 0";
    assert_eq!(
        ends(&program(body)),
        vec![
            (1.0, 0.0),
            (1.0, 10.0),
            (1.0, 0.0),
            (2.0, 0.0),
            (2.0, 7.0),
            (2.0, 10.0),
            (2.0, 0.0),
            (3.0, 0.0)
        ]
    );
}

#[test]
fn section_repeats_run_the_section_rep_plus_one_times() {
    // REP 2: the section runs once, then twice more
    assert_eq!(
        xs(&program("L X+0 F100\nLBL 1\nL IX+1\nCALL LBL 1 REP 2")),
        vec![1.0, 2.0, 3.0]
    );
    // the file form REP k/k and a Q parameter count; a repeat block met again starts anew
    assert_eq!(
        xs(&program(
            "Q5 = 1\nL X+0 F100\nLBL 2\nL IX+10\nCALL LBL 2 REP 1/1\nLBL 3\nL IX+1\nCALL LBL 3 REPQ5"
        )),
        vec![10.0, 20.0, 21.0, 22.0]
    );
    // nested repeats: the inner section is repeated anew in each outer pass
    let n = xs(&program(
        "L X+0 F100\nLBL 1\nLBL 2\nL IX+1\nCALL LBL 2 REP 1\nCALL LBL 1 REP 2",
    ))
    .len();
    assert_eq!(n, 2 * 3);
}

#[test]
fn conditional_jumps_backwards_and_forwards() {
    let loop_body =
        "Q1 = 0\nL X+0 F100\nLBL 5\nQ1 = Q1 + 1\nL X+Q1\nFN 12: IF +Q1 LT +3 GOTO LBL 5";
    assert_eq!(xs(&program(loop_body)), vec![1.0, 2.0, 3.0]);
    // forward jump to a label not read yet; the unconditional idiom IF +0 EQU +0
    let fwd = "L X+1 F100\nFN 9: IF +0 EQU +0 GOTO LBL \"skip\"\nL X+99\nLBL \"skip\"\nL X+5";
    assert_eq!(xs(&program(fwd)), vec![1.0, 5.0]);
    // FN 10 and FN 11 with an unsigned second operand (seen in real files)
    let ne = "Q2 = 4\nQ22 = 3\nL X+1 F100\nFN 11: IF +Q2 GT Q22 GOTO LBL 2\nL X+50\nLBL 2\n\
              FN 10: IF +Q2 NE +4 GOTO LBL 3\nL X+7\nLBL 3";
    assert_eq!(xs(&program(ne)), vec![1.0, 7.0]);
}

#[test]
fn jump_and_call_errors_are_located() {
    let (ops, d) = run_until_error(&program("L X+1 F100\nFN 9: IF +0 EQU +0 GOTO LBL 7\nL X+2"));
    assert_eq!(motions(&ops).len(), 1);
    assert_eq!((d.line, d.col), (3, 1));
    assert_eq!(d.message, "LBL 7 not found in the program");
    // REP whose label does not exist
    let (_, d) = run_until_error(&program("L X+1 F100\nCALL LBL 3 REP 2"));
    assert_eq!(d.message, "LBL 3 not found in the program");
    // a subprogram calling itself runs into the nesting limit
    let (_, d) = run_until_error(&program("CALL LBL 1\nM30\nLBL 1\nCALL LBL 1\nLBL 0"));
    assert!(d.message.contains("nested deeper than 8"), "{}", d.message);
    // FN 14 stops with its number
    let (ops, d) = run_until_error(&program("L X+1 F100\nFN 14: ERROR = 1042\nL X+2"));
    assert_eq!(motions(&ops).len(), 1);
    assert_eq!(d.line, 3);
    assert_eq!(d.message, "FN 14: program stopped with error number 1042");
}

#[test]
fn call_pgm_shares_parameters_and_refuses_recursion() {
    let sub = temp_file(
        "sub.h",
        b"BEGIN PGM SUB MM\nQ7 = Q7 + 1\nL X+Q7 F100\nEND PGM SUB MM\n",
    );
    let dir = sub.parent().unwrap().to_path_buf();
    let main = dir.join("main.h");
    std::fs::write(
        &main,
        "BEGIN PGM MAIN MM\nQ7 = 10\nCALL PGM sub.h\nCALL PGM TNC:\\sub\nL Y+Q7\nEND PGM MAIN MM\n",
    )
    .unwrap();
    let it = Interpreter::open(&main, Pose::ZERO).unwrap();
    let ops: Vec<_> = it.map(|r| r.unwrap()).collect();
    let m = motions(&ops);
    let to = |k: &OpKind| match k {
        OpKind::Line { to, .. } => *to,
        other => panic!("{other:?}"),
    };
    assert_eq!(m.len(), 3);
    assert_eq!(to(&m[0])[AxisLetter::X], 11.0);
    assert_eq!(to(&m[1])[AxisLetter::X], 12.0);
    assert_eq!(to(&m[2])[AxisLetter::Y], 12.0);
    // ops of the called program name their file
    assert_eq!(ops.iter().filter(|o| o.loc.file == 1).count(), 2);
    // recursion
    let rec = dir.join("rec.h");
    std::fs::write(&rec, "BEGIN PGM REC MM\nCALL PGM rec.h\nEND PGM REC MM\n").unwrap();
    let d = klar_interp::check(&rec, Pose::ZERO);
    assert_eq!(d.len(), 1);
    assert!(d[0].message.contains("recursive"), "{}", d[0]);
    assert_eq!((d[0].line, d[0].col), (2, 1));
    // a missing file
    let missing = dir.join("missing.h");
    std::fs::write(
        &missing,
        "BEGIN PGM M MM\nCALL PGM nothere.h\nEND PGM M MM\n",
    )
    .unwrap();
    let d = klar_interp::check(&missing, Pose::ZERO);
    assert_eq!(d.len(), 1);
    assert!(d[0].message.contains("nothere.h"), "{}", d[0]);
    remove_temp(&sub);
}

/// Value of Qn after `formula`, read back through an L block.
fn q(formula: &str) -> f64 {
    let ops = run(&program(&format!("Q1 = {formula}\nL X+Q1 F100")));
    match &motions(&ops)[0] {
        OpKind::Line { to, .. } => to[AxisLetter::X],
        other => panic!("{other:?}"),
    }
}

#[test]
fn formulas_follow_precedence_and_degrees() {
    close(q("2 + 3 * 4 ^ 2"), 2.0 + 3.0 * 16.0);
    close(q("( 2 + 3 ) * 4"), 20.0);
    close(q("10 - 4 - 3"), 3.0);
    close(q("2 ^ 3 ^ 2"), 2f64.powf(9.0));
    close(q("SIN 30 + COS 60"), 1.0);
    close(q("ATAN 1"), 45.0);
    close(q("ASIN 0.5"), 30.0);
    close(q("SQRT 16 + SQ 3"), 13.0);
    close(q("7 % 3"), 1.0);
    close(q("INT 2.7 + FRAC 2.25"), 2.25);
    close(q("ABS -4 + SGN -9 + NEG 1"), 2.0);
    close(q("LN EXP 2 + LOG 1000"), 5.0);
    close(q("PI"), std::f64::consts::PI);
    let ops = run(&program(
        "FN 8: Q1 = +3 LEN +4\nFN 13: Q2 = +1 ANG +1\nFN 4: Q3 = +9 DIV +2\nL X+Q1 Y+Q2 Z+Q3 F100",
    ));
    match &motions(&ops)[0] {
        OpKind::Line { to, .. } => {
            close(to[AxisLetter::X], 5.0);
            close(to[AxisLetter::Y], 45.0);
            close(to[AxisLetter::Z], 4.5);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn division_by_zero_stops_before_the_block() {
    let (ops, d) = run_until_error(&program("L X+1 F100\nQ2 = 0\nQ1 = 5 / Q2\nL X+Q1"));
    assert_eq!(motions(&ops).len(), 1);
    assert_eq!(d.line, 4);
    assert!(d.message.contains("division by zero"), "{}", d.message);
    let (_, d) = run_until_error(&program("FN 4: Q1 = +1 DIV +0"));
    assert!(d.message.contains("division by zero"));
}

#[test]
fn sysread_reads_positions_tool_and_unit() {
    let ops = run(&program(
        "TOOL DEF 3 L+40 R+4\nTOOL CALL 3 Z S1000 DR+0.5\nL X+12.5 Y-3 Z+7 F100\n\
         FN 18: SYSREAD Q1 = ID270 NR1 IDX1\nFN18: SYSREAD Q2 = ID240 NR1 IDX2\n\
         FN 18: SYSREAD Q3 = ID200 NR1\nFN 18: SYSREAD Q4 = ID20 NR1\nQ6 = 3\n\
         FN 18: SYSREAD Q5 = ID50 NR2 IDXQ6\nL X+Q1 Y+Q2 Z+Q3 F100\nL X+Q4 Y+Q5 Z+Q108",
    ));
    let m = motions(&ops);
    let to = |k: &OpKind| match k {
        OpKind::Line { to, .. } => *to,
        other => panic!("{other:?}"),
    };
    assert_eq!(to(&m[1]), Pose::xyz(12.5, -3.0, 4.5));
    assert_eq!(to(&m[2]), Pose::xyz(3.0, 4.0, 4.5));
}

#[test]
fn block_skip_and_labels_after_m30_only_syntax_checked() {
    let text = program("L X+1 F100\n/ L X+2\nL X+3\nM30\nLBL 9\nL X+50");
    assert_eq!(xs(&text), vec![1.0, 3.0]);
    let mut it = Interpreter::from_source("t.h", &text, Pose::ZERO);
    it.set_block_skip(false);
    let n = it
        .filter(|r| r.as_ref().is_ok_and(|o| o.kind.is_motion()))
        .count();
    assert_eq!(n, 3);
}

/// A loop that neither moves nor switches anything after its first pass (found by fuzzing)
/// ends with an "endless loop" error naming the jump, instead of hanging the run.
#[test]
fn an_endless_loop_without_motion_stops_with_an_error() {
    let text = "0 BEGIN PGM L MM\n1 Q1 = 0\n2 LBL \"LOOP\"\n3 L X+60 Y+Q1 FMAX\n\
                4 FN 12: IF +Q1 LT +3 GOTO LBL \"LOOP\"\n5 END PGM L MM\n";
    let (ops, error) = ops_until_error("loop.h", text);
    // The first pass moves to X60 Y0; every later pass moves nowhere.
    assert_eq!(ops, 1);
    let d = error.expect("the loop must end with an error");
    assert_eq!(d.line, 5, "{d}");
    assert!(d.message.contains("endless loop"), "{d}");
    assert!(
        d.message
            .contains(&klar_interp::RUN_IDLE_JUMP_LIMIT.to_string()),
        "{d}"
    );
}

/// A loop that only computes (fuzz finding `fuzz/findings/pipeline_idle_loop_slow.h`: a
/// counter that steps past zero) stops in a run after as many jumps as the check follows, not
/// ten times more: the test run's op pass and `klar run` give up where `klar check` does.
#[test]
fn an_idle_loop_stops_a_run_where_the_check_stops() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/findings/pipeline_idle_loop_slow.h");
    let text = std::fs::read_to_string(&path).expect("the finding is in the repository");
    let (ops, error) = ops_until_error("idle.h", &text);
    assert_eq!(ops, 0);
    let d = error.expect("the loop must end with an error");
    assert_eq!(d.line, 10, "{d}");
    let limit = klar_interp::CHECK_JUMP_LIMIT.to_string();
    assert!(
        d.message
            .contains(&format!("more than {limit} jumps without any motion")),
        "{d}"
    );
    // The check stops the same program at the same number of jumps.
    let checked = klar_interp::Interpreter::from_source("idle.h", &text, klar_interp::Pose::ZERO)
        .check_report();
    assert!(
        checked.errors.iter().any(|e| e.message.contains(&limit)),
        "{:?}",
        checked.errors
    );
}

/// Runs `text` until its first error: the ops before it and the error.
fn ops_until_error(name: &str, text: &str) -> (usize, Option<klar_interp::Diagnostic>) {
    let interp = klar_interp::Interpreter::from_source(name, text, klar_interp::Pose::ZERO);
    let mut ops = 0;
    for item in interp {
        match item {
            Ok(_) => ops += 1,
            Err(d) => return (ops, Some(d)),
        }
    }
    (ops, None)
}
