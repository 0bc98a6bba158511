//! Bad input: every diagnostic with its line, column and message; nothing panics.

mod common;
use common::*;
use klar_interp::{OpKind, Pose, check, syntax_check};

#[test]
fn unknown_word_is_a_syntax_error() {
    let (ops, d) = run_until_error("0 BEGIN PGM T MM\n1 L X+10 K5 F100\n2 END PGM T MM\n");
    assert!(ops.is_empty());
    assert_eq!((d.line, d.col), (2, 10));
    assert_eq!(d.block, Some(1));
    assert_eq!(d.message, "block 1: unknown word 'K' in L block");
    assert_eq!(
        d.to_string(),
        "t.h:2:10: block 1: unknown word 'K' in L block"
    );
}

#[test]
fn misplaced_and_missing_values() {
    let (_, d) = run_until_error(&program("CC X+1 Y+1 F100"));
    assert_eq!((d.line, d.col), (2, 12));
    assert_eq!(d.message, "word F is not allowed in CC block");
    let (_, d) = run_until_error(&program("L X F100"));
    assert_eq!((d.line, d.col), (2, 3));
    assert_eq!(d.message, "missing value after X");
    let (_, d) = run_until_error(&program("L X+1 X+2 F100"));
    assert_eq!((d.line, d.col), (2, 7));
    assert_eq!(d.message, "word X programmed twice in one block");
    let (_, d) = run_until_error(&program("G01 X+1"));
    assert_eq!((d.line, d.col), (2, 1));
    assert_eq!(d.message, "unknown block type 'G'");
    let (_, d) = run_until_error(&program("Q1 = 2 * (3 + 4"));
    assert_eq!(d.message, "expected ')'");
}

#[test]
fn end_pgm_missing() {
    let (ops, d) = run_until_error("BEGIN PGM T MM\nL X+1 F100\n");
    assert_eq!(ops.len(), 1);
    assert_eq!((d.line, d.col), (3, 1));
    assert_eq!(d.message, "END PGM missing at end of file");
    // without a trailing newline: just after the last character
    let (_, d) = run_until_error("BEGIN PGM T MM\nL X+1 F100");
    assert_eq!((d.line, d.col), (2, 11));
}

#[test]
fn missing_begin_pgm() {
    let (_, d) = run_until_error("L X+1 F100\nEND PGM T MM\n");
    assert_eq!((d.line, d.col), (1, 1));
    assert!(d.message.starts_with("missing BEGIN PGM"), "{d}");
}

#[test]
fn c_end_point_off_the_circle() {
    // start radius 10, end radius √(8² + 7²) ≈ 10.6301 about CC
    let text =
        "0 BEGIN PGM T MM\n1 CC X+0 Y+0\n2 L X+10 Y+0 F100\n3 C X+8 Y+7 DR+\n4 END PGM T MM\n";
    let (ops, d) = run_until_error(text);
    // the line of block 2 was yielded before the error
    assert!(matches!(ops.last().unwrap().kind, OpKind::Line { .. }));
    assert_eq!((d.line, d.col, d.block), (4, 1, Some(3)));
    let end_r = (64.0f64 + 49.0).sqrt();
    assert_eq!(
        d.message,
        format!(
            "block 3: C end point is {end_r:.4} mm from CC, start point 10.0000 mm: radii differ by more than 0.001 mm"
        )
    );
    // 0.5 µm off is accepted (coordinates rounded to the µm)
    let ok = program("CC X+0 Y+0\nL X+10 Y+0 F100\nC X+0 Y+10.0005 DR+");
    assert_eq!(motions(&run(&ok)).len(), 2);
}

#[test]
fn cr_chord_longer_than_diameter() {
    let text = "0 BEGIN PGM T MM\n1 L X+0 Y+0 F100\n12 CR X+30 Y+0 R+10 DR+\n13 END PGM T MM\n";
    let (_, d) = run_until_error(text);
    assert_eq!((d.line, d.col), (3, 1));
    assert_eq!(
        d.message,
        "block 12: CR chord 30.000 mm longer than 2R = 20.000 mm"
    );
}

#[test]
fn arcs_without_cc() {
    for (block, name) in [
        ("C X+1 Y+0 DR+", "C"),
        ("CP IPA+90 DR+", "CP"),
        ("LP PR+5", "LP"),
    ] {
        let (_, d) = run_until_error(&program(&format!("L X+1 F100\n{block}")));
        assert_eq!((d.line, d.col), (3, 1));
        assert_eq!(
            d.message,
            format!("{name} without circle centre: program CC first")
        );
    }
}

#[test]
fn ipa_sign_must_match_dr() {
    let (_, d) = run_until_error(&program("CC X+0 Y+0\nL X+5 F100\nCP IPA+720 IZ-2 DR-"));
    assert_eq!((d.line, d.col), (4, 4));
    assert_eq!(d.message, "IPA+720 and DR- have different signs");
    let (_, d) = run_until_error(&program("CC X+0 Y+0\nL X+5 F100\nCP IPA+100000 DR+"));
    assert_eq!(d.message, "IPA+100000 beyond ±99999.9999 degrees");
    // the largest allowed value runs
    let big = program("CC X+0 Y+0\nL X+5 F100\nCP IPA-99999.9999 IZ-10 DR-");
    assert_eq!(motions(&run(&big)).len(), 2);
}

#[test]
fn unsupported_m_and_features() {
    let (_, d) = run_until_error(&program("L Z-10 FMAX M118"));
    assert_eq!((d.line, d.col), (2, 13));
    assert_eq!(d.message, "M118 not supported on this machine");
    let (_, d) = run_until_error(&program("CYCL DEF 262 THREAD MILLING ~\n Q335=10"));
    assert_eq!(d.message, "cycle 262 is not supported");
    let (_, d) = run_until_error(&program("FN 20: WAIT FOR Q1"));
    assert_eq!(d.message, "FN 20 not supported yet");
    let (_, d) = run_until_error(&program("FN 9: IF +0 EQU +0 GOTO LBL 1"));
    assert_eq!(d.message, "LBL 1 not found in the program");
}

#[test]
fn runtime_errors_in_formulas_and_feeds() {
    let (_, d) = run_until_error(&program("Q1 = 0\nQ2 = 5 / Q1"));
    assert_eq!((d.line, d.col), (3, 1));
    assert_eq!(d.message, "division by zero");
    let (_, d) = run_until_error(&program("L X+5"));
    assert_eq!(
        d.message,
        "no feed rate programmed: add F to this or an earlier block"
    );
}

#[test]
fn check_reports_everything_and_syntax_check_only_syntax() {
    let text = b"0 BEGIN PGM T MM\n1 L X+10 K5 F100\n2 L X+10 F100\n3 CR X+50 Y+0 R+10 DR+\n4 L Y F100\n5 C X+1 Y+1 DR+\n";
    let path = temp_file("bad.h", text);
    let all = check(&path, Pose::ZERO);
    let got: Vec<(u32, u32, &str)> = all
        .iter()
        .map(|d| (d.line, d.col, d.message.as_str()))
        .collect();
    assert_eq!(
        got,
        [
            (2, 10, "block 1: unknown word 'K' in L block"),
            (
                4,
                1,
                "block 3: CR chord 40.000 mm longer than 2R = 20.000 mm"
            ),
            (5, 5, "block 4: missing value after Y"),
            (6, 1, "block 5: C without circle centre: program CC first"),
            (7, 1, "END PGM missing at end of file"),
        ]
    );
    let syntax = syntax_check(&path).expect_err("syntax errors");
    let got: Vec<(u32, u32)> = syntax.iter().map(|d| (d.line, d.col)).collect();
    assert_eq!(got, [(2, 10), (5, 5), (7, 1)]);
    let shown = all[0].to_string();
    assert!(shown.ends_with("bad.h:2:10: block 1: unknown word 'K' in L block"));
    remove_temp(&path);
}

#[test]
fn blocks_after_end_pgm_and_other_dialects() {
    let path = temp_file("after.h", b"BEGIN PGM A MM\nEND PGM A MM\nL X+1 F100\n");
    let d = syntax_check(&path).expect_err("block after end");
    assert_eq!((d[0].line, d[0].col), (3, 1));
    assert_eq!(d[0].message, "block after END PGM");
    let iso = temp_file(
        "prog.i",
        b"%PROG G71 *\nN10 G00 X+1 *\nN99999999 %PROG G71 *\n",
    );
    // other dialects run through their own front ends: a clean ISO program checks clean,
    // a lathe program without its END section is reported at the end of the file
    assert!(check(&iso, Pose::ZERO).is_empty());
    let din = temp_file("shaft.nc", b"%shaft.nc\nPROGRAMMKOPF\n");
    let d = check(&din, Pose::ZERO);
    assert_eq!(d.len(), 1);
    assert_eq!(d[0].line, 3);
    assert!(d[0].message.contains("END"), "{}", d[0].message);
    for p in [path, iso, din] {
        remove_temp(&p);
    }
}

#[test]
fn subprograms_after_m30_are_only_syntax_checked() {
    let path = temp_file(
        "m30.h",
        b"BEGIN PGM A MM\nL X+1 F100 M30\nLBL 1\nL X+2\nLBL 0\nEND PGM A MM\n",
    );
    assert!(check(&path, Pose::ZERO).is_empty());
    assert!(syntax_check(&path).is_ok());
    remove_temp(&path);
}
