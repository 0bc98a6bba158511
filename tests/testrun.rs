//! The test run before motion (`klar check PROGRAM --machine FILE`): soft limits per block and
//! axis, spindle speed, tool table, feeds, axes the machine lacks, every interpreter error —
//! and `klar run` refusing what the test run refuses, with nothing moved.

mod common;

use common::{run, temp_program};
use klar::config::{MachineConfig, ToolConfig};
use klar::runtime::RunError;
use klar::testrun::test_run;
use std::process::Command;

fn klar(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_klar"))
        .args(args)
        .output()
        .expect("klar runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn mill_file() -> String {
    format!("{}/machines/mill.toml", env!("CARGO_MANIFEST_DIR"))
}

/// Every problem of this program is on a known line; the built-in mill has X, Y in ±300,
/// Z in ±200, 166 mm/s on X and Y, a 12000 rpm spindle.
const MANY: &str = "0 BEGIN PGM T MM\n\
1 TOOL CALL 1 Z S20000\n\
2 L X+0 Y+0 Z+10 R0 FMAX M3\n\
3 L X+350 F600\n\
4 L X+250 Y+100 F600\n\
5 CC X+0 Y+100\n\
6 C X-250 Y+100 DR+\n\
7 L X+0 Y+0 F20000\n\
8 END PGM T MM\n";

#[test]
fn soft_limits_spindle_and_feed_are_found_with_block_and_axis() {
    let path = temp_program("many.h", MANY);
    let report = test_run(&path, &MachineConfig::builtin_mill());
    let found: Vec<(u32, Option<u64>, &str)> = report
        .errors
        .iter()
        .map(|d| (d.line, d.block, d.message.as_str()))
        .collect();
    assert_eq!(found.len(), 3, "{found:#?}");
    // Block 2 turns the spindle on at the S of the TOOL CALL.
    assert_eq!((found[0].0, found[0].1), (3, Some(2)));
    assert!(found[0].2.contains("S20000") && found[0].2.contains("12000"));
    // Block 3 ends at X+350; block 4 starts there, which is the same excursion (one error).
    assert_eq!((found[1].0, found[1].1), (4, Some(3)));
    assert!(
        found[1].2.contains("axis X would move to 350.0000"),
        "{}",
        found[1].2
    );
    // Block 6: a half circle about (0, 100) of radius 250 from (250, 100) counter-clockwise
    // to (-250, 100) passes its top at Y = 100 + 250 = 350 although both ends are at Y 100.
    assert_eq!((found[2].0, found[2].1), (7, Some(6)));
    assert!(
        found[2].2.contains("axis Y would move to 350.0000"),
        "{}",
        found[2].2
    );
    // Block 7 at 20000 mm/min from (-250, 100) to (0, 0): X carries 250/√(250²+100²) of the
    // path, so X's 166 mm/s allow 166·√72500/250 mm/s = 10727 mm/min.
    let allowed = 166.0 * (250.0f64.powi(2) + 100.0f64.powi(2)).sqrt() / 250.0 * 60.0;
    assert_eq!(report.warnings.len(), 1, "{:#?}", report.warnings);
    let w = &report.warnings[0];
    assert_eq!((w.line, w.block), (8, Some(7)));
    assert!(
        w.message.contains(&format!("({allowed:.0} mm/min)")) && w.message.contains("axis X"),
        "{w}"
    );
    // The envelope covers the arc's top.
    let (_, _, y_max) = report.envelope[1];
    assert!((y_max - 350.0).abs() < 1e-9, "{y_max}");
    assert!(
        report.undecided.iter().any(|u| u.contains("tool table")),
        "{:?}",
        report.undecided
    );
}

#[test]
fn a_tool_missing_from_the_table_is_an_error() {
    let text = "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S1000\n2 L Z+10 R0 FMAX\n\
                3 TOOL CALL 7 Z S1000\n4 L Z+20 FMAX\n5 END PGM T MM\n";
    let path = temp_program("tools.h", text);
    let mut machine = MachineConfig::builtin_mill();
    machine.tools = Some(
        [1, 2]
            .into_iter()
            .map(|number| ToolConfig {
                number,
                name: None,
                length: 50.0,
                radius: 3.0,
            })
            .collect(),
    );
    let report = test_run(&path, &machine);
    assert_eq!(report.errors.len(), 1, "{:#?}", report.errors);
    let d = &report.errors[0];
    assert_eq!((d.line, d.block), (4, Some(3)));
    assert!(d.message.contains("tool 7"), "{d}");
    machine.tools.as_mut().unwrap().push(ToolConfig {
        number: 7,
        name: Some("drill".into()),
        length: 80.0,
        radius: 2.5,
    });
    assert!(test_run(&path, &machine).passed());
}

#[test]
fn an_axis_the_machine_lacks_is_refused_by_the_planner_pass() {
    let text = "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S1000\n2 L Z+10 R0 FMAX\n\
                3 L A+30 F1000\n4 END PGM T MM\n";
    let path = temp_program("absent.h", text);
    let report = test_run(&path, &MachineConfig::builtin_mill());
    assert_eq!(report.errors.len(), 1, "{:#?}", report.errors);
    assert_eq!(report.errors[0].line, 4);
    assert!(
        report.errors[0].message.contains("axis A"),
        "{}",
        report.errors[0]
    );
}

#[test]
fn every_interpreter_error_is_reported_not_just_the_first() {
    // Two impossible chords (40 mm with R 10, 60 mm with R 20) in blocks 4 and 6.
    let text = "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S1000\n2 L X+0 Y+0 Z+10 R0 FMAX\n\
                3 L X+10 Y+0 F600\n4 CR X+50 Y+0 R+10 DR+\n5 L X+0\n\
                6 CR X+60 Y+0 R+20 DR+\n7 END PGM T MM\n";
    let path = temp_program("chords.h", text);
    let report = test_run(&path, &MachineConfig::builtin_mill());
    let lines: Vec<(u32, Option<u64>)> = report.errors.iter().map(|d| (d.line, d.block)).collect();
    assert_eq!(
        lines,
        vec![(5, Some(4)), (7, Some(6))],
        "{:#?}",
        report.errors
    );
    assert!(
        report.undecided.iter().any(|u| u.contains("line 5")),
        "{:?}",
        report.undecided
    );
}

#[test]
fn run_refuses_what_the_test_run_refuses_and_nothing_moves() {
    let path = temp_program("refused.h", MANY);
    let (result, trace) = run(&path, &MachineConfig::builtin_mill());
    match result.expect_err("refused").error {
        RunError::Syntax(d) => assert_eq!(d.len(), 3, "{d:#?}"),
        other => panic!("expected the test run's refusal, got {other}"),
    }
    assert!(trace.t.is_empty(), "{} trace rows", trace.t.len());

    let p = path.to_string_lossy().into_owned();
    let (code, _, err) = klar(&["run", &p]);
    assert_eq!(code, 1);
    assert!(
        err.contains(&format!("{p}:7:1: block 6: axis Y would move to 350.0000")),
        "{err}"
    );
}

#[test]
fn the_command_line_test_run_reports_and_passes_good_programs() {
    let bad = temp_program("cli_bad.h", MANY);
    let b = bad.to_string_lossy().into_owned();
    let machine = mill_file();
    let (code, _, err) = klar(&["check", &b, "--machine", &machine]);
    assert_eq!(code, 1);
    for line in [
        format!("{b}:3:1: block 2: spindle speed S20000"),
        format!("{b}:4:1: block 3: axis X would move to 350.0000"),
        format!("{b}:7:1: block 6: axis Y would move to 350.0000"),
    ] {
        assert!(err.contains(&line), "missing {line} in {err}");
    }
    assert!(err.contains("(warning)"), "{err}");

    let good = format!("{}/programs/rectangle.h", env!("CARGO_MANIFEST_DIR"));
    let (code, out, err) = klar(&["check", &good, "--machine", &machine]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("ok on"), "{out}");
    // The rectangle's XY extent is X -10..100, Y 0..60 (see programs/rectangle.h).
    assert!(out.contains("X: -10.0000 .. 100.0000"), "{out}");
    assert!(out.contains("Y: 0.0000 .. 60.0000"), "{out}");
}
