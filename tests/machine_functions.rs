//! Machine-dependent M functions from the machine file (`[[m_function]]`): a run on the
//! simulated mill stops the path where a `stop` function acts and holds it there for the
//! function's `wait`; a function without `stop` is switched on the fly. Bad entries are
//! refused with the machine file, and `klar check` knows the listed numbers.

mod common;

use common::{run, temp_program};
use klar::config::{BUILTIN_MILL, MachineConfig};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Feed of the program below: 3000 mm/min = 50 mm/s.
const FEED: f64 = 50.0;

/// Straight along X at Y0 Z50 in 50 mm steps: M26 (no stop) at the start of block 3, where
/// the tool passes X50; M25 (stop, 0.5 s) at the end of block 4, at X150; M27 (stop,
/// 0.25 s) at the start of block 6, at X200.
const PROGRAM: &str = "0 BEGIN PGM MF MM\n\
1 L X+0 Y+0 Z+50 R0 FMAX\n\
2 L X+50 F3000\n\
3 L X+100 M26\n\
4 L X+150 M25\n\
5 L X+200\n\
6 L X+250 M27\n\
7 L X+300\n\
8 END PGM MF MM\n";

/// The machine functions of the test machine.
const FUNCTIONS: &str = r#"
[[m_function]]
number = 25
name = "door open"
at = "end"
stop = true
wait = 0.5

[[m_function]]
number = 26
name = "chip conveyor on"
at = "start"
stop = false
wait = 0.3

[[m_function]]
number = 27
name = "door close"
at = "start"
wait = 0.25
"#;

/// Writes the built-in mill plus `extra` as a machine file into a fresh folder.
fn machine_file(name: &str, extra: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("klar-test-{}-machine-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("machine.toml");
    std::fs::write(&path, format!("{BUILTIN_MILL}\n{extra}")).expect("write machine");
    path
}

/// The error message of a machine file with `extra` added to the built-in mill.
fn config_error(name: &str, extra: &str) -> String {
    match MachineConfig::load(&machine_file(name, extra)) {
        Ok(_) => panic!("{name}: the machine file must be refused"),
        Err(e) => e.to_string(),
    }
}

/// Index ranges of consecutive samples with X equal to `x` (within 1e-9 mm).
fn plateaus(xs: &[f64], x: f64) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, v) in xs.iter().enumerate() {
        match ((v - x).abs() <= 1e-9, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                out.push((s, i - 1));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, xs.len() - 1));
    }
    out
}

/// The one stretch of samples at `x` (the path passes each point once).
fn the_plateau(xs: &[f64], x: f64) -> (usize, usize) {
    let p = plateaus(xs, x);
    assert_eq!(p.len(), 1, "X{x}: stretches at the point {p:?}");
    p[0]
}

#[test]
fn stop_functions_stop_the_path_and_hold_it_for_their_wait() {
    let machine = MachineConfig::load(&machine_file("run", FUNCTIONS)).expect("machine");
    let dt = machine.servo_period;
    let path = temp_program("mf.h", PROGRAM);
    let (result, trace) = run(&path, &machine);
    let report = result.unwrap_or_else(|f| panic!("{}", f.error));
    let x = trace.column("X").expect("X column");
    let y = trace.column("Y").expect("Y column");
    assert!(y.iter().all(|v| v.abs() <= 1e-9), "the path stays on Y0");
    let speed = |i: usize| (x[i] - x[i - 1]) / dt;

    // M25 (end of block 4) and M27 (start of block 6): the path arrives at rest, stands for
    // the wait, and leaves again.
    for (at, wait) in [(150.0, 0.5), (200.0, 0.25)] {
        let (first, last) = the_plateau(&x, at);
        let stood = trace.t[last] - trace.t[first];
        assert!(
            stood >= wait - 1e-9 && stood <= wait + 5.0 * dt,
            "X{at}: stood {stood} s, wait {wait} s"
        );
        // the sample before the standstill: the axis has already braked to (almost) zero
        assert!(
            speed(first).abs() < 0.02 * FEED,
            "X{at}: arrives at {} mm/s",
            speed(first)
        );
        // before the brake it ran at the feed
        let running = (1..first).rev().find(|&i| speed(i) >= 0.99 * FEED);
        assert!(running.is_some(), "X{at}: never at feed before the stop");
        assert!(x[last + 1] > at, "X{at}: the path goes on in +X");
    }

    // M26 (start of block 3, no stop): the tool passes X50 at the feed, its 0.3 s wait is
    // not applied.
    assert!(
        plateaus(&x, 50.0).is_empty(),
        "M26 must not stop the path at X50"
    );
    let i = x.iter().position(|&v| v > 50.0).expect("passes X50");
    assert!(
        (speed(i) - FEED).abs() < 0.01 * FEED,
        "speed at X50: {} mm/s",
        speed(i)
    );

    // The same program without the machine functions takes at least the two waits less.
    let plain = temp_program(
        "mf_plain.h",
        &PROGRAM
            .replace(" M25", "")
            .replace(" M26", "")
            .replace(" M27", ""),
    );
    let (plain_result, _) = run(&plain, &MachineConfig::builtin_mill());
    let plain_report = plain_result.unwrap_or_else(|f| panic!("{}", f.error));
    let extra = report.machine_time - plain_report.machine_time;
    assert!(
        extra >= 0.75,
        "the waits add {extra} s, expected at least 0.75 s"
    );
}

#[test]
fn a_function_the_machine_lacks_refuses_the_run() {
    let path = temp_program("mf_unknown.h", PROGRAM);
    let (result, trace) = run(&path, &MachineConfig::builtin_mill());
    let failure = result.expect_err("M25 is not a function of the built-in mill");
    let text = failure.error.to_string();
    assert!(text.contains("M26 not supported on this machine"), "{text}");
    assert!(trace.t.is_empty(), "nothing may move");
}

#[test]
fn bad_entries_are_refused_with_the_machine_file() {
    let entry = |number: &str, wait: &str| {
        format!("[[m_function]]\nnumber = {number}\nname = \"x\"\nwait = {wait}\n")
    };
    let cases = [
        ("builtin", entry("3", "0"), "klar defines M3 itself"),
        ("builtin140", entry("140", "0"), "klar defines M140 itself"),
        (
            "twice",
            format!("{}{}", entry("25", "0"), entry("25", "1")),
            "m_function M25 is defined twice",
        ),
        (
            "negative_wait",
            entry("25", "-1.0"),
            "wait must be seconds >= 0",
        ),
        ("nan_wait", entry("25", "nan"), "wait must be seconds >= 0"),
        ("inf_wait", entry("25", "inf"), "wait must be seconds >= 0"),
        ("too_big", entry("10000", "0"), "must lie in 0..=9999"),
        ("negative", entry("-1", "0"), "must lie in 0..=9999"),
        (
            "bad_at",
            "[[m_function]]\nnumber = 25\nat = \"middle\"\n".to_string(),
            "unknown variant `middle`",
        ),
        (
            "unknown_key",
            "[[m_function]]\nnumber = 25\nduration = 1.0\n".to_string(),
            "unknown key `duration`",
        ),
    ];
    for (name, extra, expected) in cases {
        let e = config_error(name, &extra);
        assert!(e.contains(expected), "{name}: {e}");
        assert!(e.contains("machine.toml"), "{name}: names the file: {e}");
    }
    // the edges of the range are accepted, defaults as documented
    let path = machine_file(
        "edges",
        &format!("{}{}", entry("0", "0"), entry("9999", "0")),
    );
    let e = MachineConfig::load(&path).expect_err("M0 is built in");
    assert!(e.to_string().contains("klar defines M0 itself"), "{e}");
    let path = machine_file("edge", "[[m_function]]\nnumber = 9999\n");
    let m = MachineConfig::load(&path).expect("M9999 is a valid machine function");
    let f = m.machine_functions();
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].number, 9999);
    assert_eq!(f[0].at, klar_interp::op::MachineFunctionTime::End);
    assert!(f[0].stop);
    assert_eq!(f[0].wait, 0.0);
}

#[test]
fn the_five_axis_machine_has_the_door_example() {
    let m = MachineConfig::builtin_mill5();
    assert_eq!(m.machine_function_name(25), "door open");
    assert_eq!(m.machine_function_name(26), "door close");
}

/// Runs the klar binary; exit status and stderr.
fn klar(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_klar"))
        .args(args)
        .env("RUST_LOG", "info")
        .output()
        .expect("run klar");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn arg(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

#[test]
fn klar_check_and_run_know_the_machines_functions() {
    let program = temp_program("mf_cli.h", PROGRAM);
    let machine = machine_file("cli", FUNCTIONS);
    let (ok, err) = klar(&["check", arg(&program), "--machine", arg(&machine)]);
    assert!(ok, "check with the machine file: {err}");
    let (ok, err) = klar(&["check", arg(&program)]);
    assert!(!ok, "the built-in mill has no M25");
    assert!(err.contains("M26 not supported on this machine"), "{err}");
    assert!(err.contains("M25 not supported on this machine"), "{err}");
    let (ok, err) = klar(&["run", arg(&program), "--machine", arg(&machine)]);
    assert!(ok, "run: {err}");
    for name in ["door open", "chip conveyor on", "door close"] {
        assert!(err.contains(name), "the log names {name}: {err}");
    }
    assert!(err.contains("machine function M25"), "{err}");
}
