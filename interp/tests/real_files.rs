//! Forms written by CAM posts and saved by real controls that klar accepts: cycle numbers
//! glued to `DEF`, `~` continuations around comments, SPL coefficient lines, text before
//! BEGIN PGM and a mismatched END PGM name (accepted with warnings), block skip, `F MAX`,
//! tabs in comments and tool names.

mod common;
use common::*;
use klar_interp::{
    AxisLetter, Feed, Interpreter, OpKind, Pose, Tool, ToolTable,
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

/// The example of the SPL manual page (seeds/), blocks 7 and 8 as printed there.
const SEED_SPL: &str = "7 L X+33.909 Y-25.838 Z+75.107 A+17 B-10.103 F MAX
8 SPL X+39.824 Y-28.378 Z+77.425 A+17.32 B-12.75
K3X+0.0983 K2X-0.441 K1X-5.5724
K3Y-0.0422 K2Y+0.1893 K1Y+2.3929
K3Z+0.0015 K2Z-0.9549 K1Z+3.0875
K3A+0.1283 K2A-0.141 K1A-0.5724
K3B+0.0083 K2B-0.413 E+2 K1B-1.5724 E+1 F10000";

/// `text` with its lines that start with a K coefficient joined to the line before them.
fn one_line(text: &str) -> String {
    text.replace("\nK", " K")
}

#[test]
fn spl_coefficient_lines_as_the_manual_prints_them() {
    // block 8 alone, from the point where its polynomials start (t = 1)
    let block8 = SEED_SPL.split_once('\n').map_or("", |(_, b)| b);
    let mut start = Pose::xyz(
        39.824 + 0.0983 - 0.441 - 5.5724,
        -28.378 - 0.0422 + 0.1893 + 2.3929,
        77.425 + 0.0015 - 0.9549 + 3.0875,
    );
    start[AxisLetter::A] = 17.32 + 0.1283 - 0.141 - 0.5724;
    start[AxisLetter::B] = -12.75 + 0.0083 - 41.3 - 15.724;
    let wrapped = run_from(&program(block8), start);
    let joined = run_from(&program(&one_line(block8)), start);
    assert_eq!(motions(&wrapped), motions(&joined));
    match &motions(&wrapped)[..] {
        [OpKind::Spline { to, axes, feed, .. }] => {
            assert_eq!(axes.len(), 5);
            close(to[AxisLetter::B], -12.75);
            close(axes[4].k[1], -41.3);
            close(axes[4].k[2], -15.724);
            assert_eq!(*feed, Feed::Rate(10000.0 / 60.0));
        }
        other => panic!("{other:?}"),
    }
    // the op keeps the line of the SPL keyword; END PGM after it is on line 8
    assert_eq!(wrapped.first().map(|o| o.loc.line), Some(2));
    assert_eq!(wrapped.last().map(|o| o.loc.line), Some(8));
}

#[test]
fn the_manual_example_runs_as_on_one_line() {
    // Blocks 7 and 8 of the page together: the page's numbers do not meet (the polynomial
    // of Z starts 4.4521 mm above block 7's end), in both layouts with the same message.
    let wrapped = program(SEED_SPL);
    let (ops_w, d_w) = run_until_error(&wrapped);
    let (ops_j, d_j) = run_until_error(&program(&one_line(SEED_SPL)));
    assert_eq!(motions(&ops_w), motions(&ops_j));
    assert_eq!(d_w, d_j);
    assert_eq!(
        d_w.to_string(),
        "t.h:3:1: block 8: SPL starts at Z+79.5591, 4.4521 mm away from the previous end point Z+75.1070 (more than 0.001 mm)"
    );
    // the syntax check accepts the page's text
    let path = temp_file("seed_spl.h", wrapped.as_bytes());
    assert_eq!(klar_interp::syntax_check(&path), Ok(()));
    remove_temp(&path);
}

#[test]
fn spl_lines_from_a_cam_post() {
    let body = "7 SPL X+28.338 Y+53.45 Z-2.42\nK3X+0.0983 K2X-0.441 K1X-5.5724\nK3Y+0.0000 K2Y+0.0000 K1Y+0.0000\nK3Z+0.0000 K2Z+0.0000 K1Z-0.3144 F1000\n8 L X+30";
    let start = Pose::xyz(28.338 + 0.0983 - 0.441 - 5.5724, 53.45, -2.42 - 0.3144);
    let ops = run_from(&program(body), start);
    assert_eq!(
        motions(&ops),
        motions(&run_from(&program(&one_line(body)), start))
    );
    let lines: Vec<u32> = ops
        .iter()
        .filter(|o| o.kind.is_motion())
        .map(|o| o.loc.line)
        .collect();
    assert_eq!(lines, vec![2, 6]);
}

#[test]
fn a_coefficient_line_after_another_block_is_an_error() {
    let (_, d) = run_until_error(&program("L X+1 F100\nK3X+0.1 K2X+0 K1X-0.1"));
    assert_eq!(
        d.to_string(),
        "t.h:3:1: unexpected spline coefficients outside an SPL block (a line of K3/K2/K1 words continues the SPL block right before it)"
    );
    // an empty line ends the SPL block: the block misses Y's triple, the K line stays alone
    let (_, d) = run_until_error(&program(
        "SPL X+0 Y+0 K3X+0 K2X+0 K1X+0 F100\n\nK3Y+0 K2Y+0 K1Y+0",
    ));
    assert_eq!(
        d.to_string(),
        "t.h:2:9: SPL: every end coordinate needs its K3, K2 and K1 (an axis is missing its triple)"
    );
}

/// Runs a program to its end; returns the ops and the interpreter's warnings as text.
fn run_with_warnings(text: &str) -> (Vec<klar_interp::Op>, Vec<String>) {
    let mut it = Interpreter::from_source("t.h", text, Pose::ZERO);
    let ops: Vec<_> = it
        .by_ref()
        .map(|r| r.unwrap_or_else(|d| panic!("{d}")))
        .collect();
    let warnings = it.warnings().iter().map(ToString::to_string).collect();
    (ops, warnings)
}

#[test]
fn lines_before_begin_pgm_are_passed_over_with_a_warning() {
    let text =
        "%PART17\nL X+50 F100\n(header of a post)\n\nBEGIN PGM T MM\nL X+1 F100\nEND PGM T MM\n";
    let (ops, warnings) = run_with_warnings(text);
    // the L block before BEGIN PGM does not run
    let m = motions(&ops);
    assert_eq!(m.len(), 1);
    assert!(matches!(m[0], OpKind::Line { to, .. } if to == Pose::xyz(1.0, 0.0, 0.0)));
    assert_eq!(ops[0].loc.line, 6);
    assert_eq!(
        warnings,
        vec!["t.h:1:1: lines 1 to 2 before BEGIN PGM ignored"]
    );
    // one line, indented
    let (_, warnings) = run_with_warnings("  %\nBEGIN PGM T MM\nEND PGM T MM\n");
    assert_eq!(warnings, vec!["t.h:1:3: line 1 before BEGIN PGM ignored"]);
    // comments and empty lines before BEGIN PGM are no news
    let (_, warnings) = run_with_warnings("; made by hand\n\nBEGIN PGM T MM\nEND PGM T MM\n");
    assert!(warnings.is_empty(), "{warnings:?}");
}

#[test]
fn a_program_without_begin_pgm_is_still_refused() {
    // the error stands where the program should have begun
    let (ops, d) = run_until_error("%\nL X+1 F100\nL X+2\n");
    assert!(ops.is_empty());
    assert_eq!(
        d.to_string(),
        "t.h:1:1: missing BEGIN PGM: a Klartext program starts with `BEGIN PGM name MM|INCH`"
    );
    let (_, d) = run_until_error("\n  L X+1 F100\nEND PGM T MM\n");
    assert_eq!((d.line, d.col), (2, 3));
    assert!(d.message.starts_with("missing BEGIN PGM"), "{d}");
    // a broken BEGIN PGM is an error, not text before the program
    let (_, d) = run_until_error("%\nBEGIN PGM T\nEND PGM T MM\n");
    assert_eq!(
        d.to_string(),
        "t.h:2:11: BEGIN PGM needs the unit MM or INCH after the name"
    );
}

#[test]
fn end_pgm_with_another_name_runs_with_a_warning() {
    let (ops, warnings) =
        run_with_warnings("BEGIN PGM PART-1 MM\nL X+1 F100\n3 END PGM PART-2 MM ; saved as\n");
    assert_eq!(motions(&ops).len(), 1);
    assert!(matches!(ops.last().map(|o| &o.kind), Some(OpKind::End)));
    assert_eq!(
        warnings,
        vec!["t.h:3:11: block 3: END PGM PART-2 does not match BEGIN PGM PART-1"]
    );
    let (_, warnings) = run_with_warnings("BEGIN PGM 17 MM\nL X+1 F100\nEND PGM\n");
    assert_eq!(
        warnings,
        vec!["t.h:3:1: END PGM names no program (BEGIN PGM 17)"]
    );
    // the same name, also without the unit, is no news
    let (_, warnings) = run_with_warnings("BEGIN PGM 17 MM\nEND PGM 17\n");
    assert!(warnings.is_empty(), "{warnings:?}");
}

#[test]
fn a_check_reports_the_warnings_apart_from_errors() {
    let path = temp_file(
        "lenient.h",
        b"%LENIENT\nBEGIN PGM LENIENT MM\nL X+1 F100\nEND PGM OTHER MM\n",
    );
    let report = klar_interp::check_report(&path, Pose::ZERO);
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    let shown: Vec<String> = report
        .warnings
        .iter()
        .map(|d| format!("{}:{}: {}", d.line, d.col, d.message))
        .collect();
    assert_eq!(
        shown,
        vec![
            "1:1: line 1 before BEGIN PGM ignored",
            "4:9: END PGM OTHER does not match BEGIN PGM LENIENT"
        ]
    );
    assert_eq!(report.warnings[0].file, path);
    assert_eq!(klar_interp::syntax_check(&path), Ok(()));
    remove_temp(&path);
}

#[test]
fn a_missing_end_pgm_stays_an_error() {
    let (ops, d) = run_until_error("BEGIN PGM T MM\nL X+1 F100\nL X+2\n");
    assert_eq!(motions(&ops).len(), 2);
    assert_eq!(d.to_string(), "t.h:4:1: END PGM missing at end of file");
}

#[test]
fn block_skip_slash_before_the_block_number() {
    let text = program("/12 L X+10 F100\n13 L Y+5 F100\n/ 14 L Z+3");
    assert_eq!(ends(&text), vec![Pose::xyz(0.0, 5.0, 0.0)]);
    let mut it = Interpreter::from_source("t.h", &text, Pose::ZERO);
    it.set_block_skip(false);
    let ops: Vec<_> = it.map(|r| r.unwrap_or_else(|d| panic!("{d}"))).collect();
    let got: Vec<(Option<u64>, Pose)> = ops
        .iter()
        .filter_map(|o| match o.kind {
            OpKind::Line { to, .. } => Some((o.loc.block, to)),
            _ => None,
        })
        .collect();
    assert_eq!(
        got,
        vec![
            (Some(12), Pose::xyz(10.0, 0.0, 0.0)),
            (Some(13), Pose::xyz(10.0, 5.0, 0.0)),
            (Some(14), Pose::xyz(10.0, 5.0, 3.0)),
        ]
    );
}

#[test]
fn f_max_with_a_blank_is_fmax() {
    let feeds = |text: &str| -> Vec<Feed> {
        motions(&run(&program(text)))
            .iter()
            .map(|k| match k {
                OpKind::Line { feed, .. } => *feed,
                other => panic!("{other:?}"),
            })
            .collect()
    };
    let spaced = feeds("L X+10 F300\nL Z+50 F MAX\nL X+20\nL Y+5 F  MAX M3");
    assert_eq!(
        spaced,
        vec![Feed::Rate(5.0), Feed::Rapid, Feed::Rate(5.0), Feed::Rapid]
    );
    assert_eq!(
        spaced,
        feeds("L X+10 F300\nL Z+50 FMAX\nL X+20\nL Y+5 FMAX M3")
    );
}

#[test]
fn tabs_in_comments_and_between_words() {
    let text = program(
        "L X+10 F100 ;\tcomment\twith tabs\n\t;\tcomment line\t\t\n5\tL\tY+3\t;\tend ~\n\tsecond\tline\nL Z+1",
    );
    assert_eq!(
        ends(&text),
        vec![
            Pose::xyz(10.0, 0.0, 0.0),
            Pose::xyz(10.0, 3.0, 0.0),
            Pose::xyz(10.0, 3.0, 1.0)
        ]
    );
    // a tab counts as one column
    let (_, d) = run_until_error(&program("L\tX+1\tF100\t;\tok\nL\tX+1\tQ\t;\tx"));
    assert_eq!(d.to_string(), "t.h:3:7: unknown word 'Q' in L block");
}

#[test]
fn tool_call_by_name() {
    let ops = run(&program(
        "TOOL CALL \"MILL_D10\" Z S3000 DL+0.1\nL X+1 F100 M3",
    ));
    match &ops[0].kind {
        OpKind::ToolChange {
            name, axis, length, ..
        } => {
            assert_eq!(name.as_deref(), Some("MILL_D10"));
            assert_eq!(*axis, AxisLetter::Z);
            close(*length, 0.1);
        }
        other => panic!("{other:?}"),
    }
    // with a tool table the name finds the tool
    let mut table = ToolTable::new();
    table.insert(Tool {
        number: 7,
        name: "MILL_D10".into(),
        length: 80.0,
        radius: 5.0,
        ..Tool::default()
    });
    let text = program("TOOL CALL \"MILL_D10\" Z S3000\nL X+1 F100 M3");
    let ops: Vec<_> = Interpreter::from_source("t.h", &text, Pose::ZERO)
        .with_tools(table)
        .map(|r| r.unwrap_or_else(|d| panic!("{d}")))
        .collect();
    match &ops[0].kind {
        OpKind::ToolChange {
            tool,
            name,
            length,
            radius,
            ..
        } => {
            assert_eq!((*tool, name.as_deref()), (7, Some("MILL_D10")));
            close(*length, 80.0);
            close(*radius, 5.0);
        }
        other => panic!("{other:?}"),
    }
}
