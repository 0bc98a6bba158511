//! End-to-end: bad programs and machine files give `file:line:col: message` diagnostics, exit
//! code 1, and never move an axis past the last good block.

mod common;

use common::{run, temp_program};
use klar::config::MachineConfig;
use klar::runtime::RunError;
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

const GOOD_HEAD: &str = "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S1000\n2 L X+0 Y+0 Z+10 R0 FMAX\n";

#[test]
fn a_syntax_error_refuses_the_run_before_any_motion() {
    let text = format!("{GOOD_HEAD}3 L X+10 F500\n4 L X+20 QQ7 F500\n5 END PGM T MM\n");
    let path = temp_program("syntax.h", &text);
    let (result, trace) = run(&path, &MachineConfig::builtin_mill());
    match result {
        Err(f) => match f.error {
            RunError::Syntax(d) => {
                assert_eq!((d[0].line, d[0].block), (5, Some(4)), "{:?}", d);
            }
            other => panic!("expected a syntax error, got {other}"),
        },
        Ok(_) => panic!("a program with a syntax error ran"),
    }
    assert!(
        trace.t.is_empty(),
        "axes moved: {} trace rows",
        trace.t.len()
    );

    let p = path.to_string_lossy().into_owned();
    let (code, _, err) = klar(&["check", &p]);
    assert_eq!(code, 1);
    assert!(err.contains(&format!("{p}:5:")), "diagnostic was: {err}");
    let (code, _, err) = klar(&["run", &p]);
    assert_eq!(code, 1);
    assert!(err.contains(&format!("{p}:5:")), "diagnostic was: {err}");
}

#[test]
fn a_geometry_error_stops_at_the_end_of_the_previous_block() {
    // CR with a 40 mm chord and R 10: only found when block 4 is reached.
    let text =
        format!("{GOOD_HEAD}3 L X+10 Y+0 F600\n4 CR X+50 Y+0 R+10 DR+\n5 L X+0\n6 END PGM T MM\n");
    let path = temp_program("chord.h", &text);
    // The test run before the start refuses the program outright, nothing moves ...
    let (result, trace) = run(&path, &MachineConfig::builtin_mill());
    match result.expect_err("the test run must refuse it").error {
        RunError::Syntax(d) => assert_eq!((d[0].line, d[0].block), (5, Some(4)), "{d:?}"),
        other => panic!("expected the test run's refusal, got {other}"),
    }
    assert!(trace.t.is_empty(), "axes moved before the refusal");
    // ... and without it the run-time reaction shows: a stop at the end of block 3.
    let mut unchecked = MachineConfig::builtin_mill();
    unchecked.check_before_run = false;
    let (result, trace) = run(&path, &unchecked);
    let failure = result.expect_err("the chord error must stop the run");
    match &failure.error {
        RunError::Program(d) => assert_eq!((d.line, d.block), (5, Some(4)), "{d}"),
        other => panic!("expected a program error, got {other}"),
    }
    // Motion of blocks 2 and 3 completed, nothing of block 4 (line 5) ran.
    let x = trace.column("X").unwrap();
    let y = trace.column("Y").unwrap();
    let z = trace.column("Z").unwrap();
    let n = x.len() - 1;
    assert_eq!((x[n], y[n], z[n]), (10.0, 0.0, 10.0));
    assert!(x.iter().all(|&v| v <= 10.0));

    let p = path.to_string_lossy().into_owned();
    let (code, _, err) = klar(&["check", &p]);
    assert_eq!(code, 1);
    assert!(err.contains(&format!("{p}:5:")), "diagnostic was: {err}");
}

#[test]
fn travel_beyond_the_machine_is_refused_with_the_block() {
    let text = format!("{GOOD_HEAD}3 L X+900 F600\n4 END PGM T MM\n");
    let path = temp_program("travel.h", &text);
    let (result, trace) = run(&path, &MachineConfig::builtin_mill());
    match result.expect_err("the test run must refuse it").error {
        RunError::Syntax(d) => {
            assert_eq!((d[0].line, d[0].block), (4, Some(3)));
            assert!(d[0].message.contains("axis X"), "{d:?}");
        }
        other => panic!("expected the test run's refusal, got {other}"),
    }
    assert!(trace.t.is_empty(), "axes moved before the refusal");
    let mut unchecked = MachineConfig::builtin_mill();
    unchecked.check_before_run = false;
    let (result, trace) = run(&path, &unchecked);
    let failure = result.expect_err("X+900 is outside the travel");
    match &failure.error {
        RunError::Program(d) => {
            assert_eq!((d.line, d.block), (4, Some(3)));
            assert!(d.message.contains("axis X"), "{d}");
        }
        other => panic!("expected a program error, got {other}"),
    }
    let x = trace.column("X").unwrap();
    assert!(x.iter().all(|&v| v == 0.0));
}

#[test]
fn bad_machine_files_are_refused_with_a_reason() {
    let unknown = "name = \"m\"\nservo_period = 0.001\ntolerance = 0.01\ncolour = 3\n";
    let e = MachineConfig::parse("m.toml", unknown)
        .unwrap_err()
        .to_string();
    assert!(e.contains("colour"), "{e}");

    let base = MachineConfig::builtin_mill();
    assert_eq!(base.axes.len(), 3);
    let bad_period =
        klar::config::BUILTIN_MILL.replace("servo_period = 0.001", "servo_period = -1");
    let e = MachineConfig::parse("m.toml", &bad_period)
        .unwrap_err()
        .to_string();
    assert!(e.contains("servo_period"), "{e}");
    let rotary_x = klar::config::BUILTIN_MILL.replacen("kind = \"linear\"", "kind = \"rotary\"", 1);
    let e = MachineConfig::parse("m.toml", &rotary_x)
        .unwrap_err()
        .to_string();
    assert!(e.contains("axis X"), "{e}");
    let inverted = klar::config::BUILTIN_MILL.replacen(
        "travel = [-300.0, 300.0]",
        "travel = [300.0, -300.0]",
        1,
    );
    let e = MachineConfig::parse("m.toml", &inverted)
        .unwrap_err()
        .to_string();
    assert!(e.contains("travel"), "{e}");
}
