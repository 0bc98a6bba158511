//! What the test run passes, the run performs: for every example program (on the machine its
//! own tests use) and every real Klartext program of `../shared/corpus/klartext` (on the
//! built-in mill with a shop tool table), either `klar check` refuses it, or `klar run`
//! completes it with every axis within its velocity, acceleration and jerk limits, measured by
//! finite differences of the commanded trace (which know nothing of the planner).
//!
//! The test also measures how much of the setpoint guard's margins a legitimate run uses (the
//! largest step over `v_max·T` and change of step over `a_max·T²`) and prints it.

mod common;

use common::{assert_within, max_derivative, run, temp_program};
use klar::config::MachineConfig;
use klar::runtime::RunError;
use klar::runtime::guard::{ACCELERATION_MARGIN, VELOCITY_MARGIN};
use klar::testrun::test_run;
use std::path::{Path, PathBuf};

/// Programs planned longer than this (machine time, s) are checked but not run, to keep the
/// test's time reasonable in a debug build.
const MAX_RUN_SECONDS: f64 = 600.0;

/// The program of the known TCPM switch bug on mill5: at `L M128` the machine's Y and Z jump
/// by hundreds of millimetres in one servo cycle.
pub const TCPM_JUMP: &str = "BEGIN PGM TCPMJUMP MM\n\
L A+76.323 C+0 FMAX\n\
L M128\n\
L Z-18.674 F3000\n\
END PGM TCPMJUMP MM\n";

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn machine_file(name: &str) -> MachineConfig {
    let p = root().join("machines").join(name);
    MachineConfig::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// Program files (.h, .i, .nc, any case) in `dir` and one folder down.
fn program_files(dir: &Path, depth: u32, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            if depth > 0 {
                program_files(&p, depth - 1, out);
            }
            continue;
        }
        let ext = p
            .extension()
            .map(|x| x.to_string_lossy().to_ascii_lowercase());
        if matches!(ext.as_deref(), Some("h" | "i" | "nc")) {
            out.push(p);
        }
    }
}

/// The machine an example program's own tests run it on: the auxiliary axes on the Modbus
/// machine, programs moving rotary axes (or tilting, or under TCPM) on mill5, probing
/// programs on the probing machine they name (else the probing mill, or its feature part for
/// those in programs/probing/), lathe programs on the lathe, everything else on the built-in
/// mill.
fn machine_for(path: &Path) -> MachineConfig {
    if path.file_name().is_some_and(|n| n == "aux_axes.h") {
        return machine_file("modbus-sim.toml");
    }
    let text = std::fs::read_to_string(path).unwrap_or_default();
    // a probing program that names its machine in its comments runs there
    if let Some(i) = text.find("machines/probing") {
        let rest = &text[i + "machines/".len()..];
        if let Some(j) = rest.find(".toml") {
            return machine_file(&rest[..j + 5]);
        }
    }
    if text.contains("TCH PROBE") {
        let features = path
            .parent()
            .and_then(Path::file_name)
            .is_some_and(|d| d == "probing");
        return machine_file(if features {
            "probing-features.toml"
        } else {
            "probing-mill.toml"
        });
    }
    let rotary = [
        "PLANE",
        "M128",
        "TCPM",
        "M116",
        "CYCL DEF 19",
        " A+",
        " A-",
        " C+",
        " C-",
    ]
    .iter()
    .any(|w| text.contains(w));
    let builtin = MachineConfig::builtin_for(path);
    if builtin.kinematics == klar::config::KinematicsConfig::Lathe || !rotary {
        builtin
    } else {
        machine_file("mill5.toml")
    }
}

/// Largest step over `v_max·T` and change of step over `a_max·T²` of any axis of a trace.
fn margin_use(trace: &common::Trace, machine: &MachineConfig) -> (f64, f64) {
    let dt = machine.servo_period;
    let (mut v, mut a) = (0.0f64, 0.0f64);
    for axis in &machine.axes {
        let Some(x) = trace.column(&axis.letter.to_string()) else {
            continue;
        };
        let mut padded = vec![axis.start; 2];
        padded.extend(x);
        v = v.max(max_derivative(&padded, dt, 1) / axis.max_velocity);
        a = a.max(max_derivative(&padded, dt, 2) / axis.max_acceleration);
    }
    (v, a)
}

#[derive(Default)]
struct Tally {
    programs: usize,
    refused: usize,
    /// First errors of programs the setpoint guard refused.
    guard_refused: Vec<String>,
    ran: usize,
    /// Passed with parts only the run decides (after a program stop).
    undecided: usize,
    /// Of those, runs that stopped at a program error in the undecided part.
    undecided_stopped: Vec<String>,
    long: Vec<String>,
    machine_time: f64,
    velocity_use: f64,
    acceleration_use: f64,
}

fn check_then_run(path: &Path, machine: &MachineConfig, tally: &mut Tally) {
    let name = path.display().to_string();
    tally.programs += 1;
    let report = test_run(path, machine);
    if let Some(first) = report.errors.first() {
        tally.refused += 1;
        if first.message.contains("setpoint guard") {
            tally.guard_refused.push(first.to_string());
        }
        return;
    }
    if report.planned_time > MAX_RUN_SECONDS {
        tally
            .long
            .push(format!("{name} ({:.0} s)", report.planned_time));
        return;
    }
    let mut config = machine.clone();
    // The test run above is the check; the run itself must not depend on it.
    config.check_before_run = false;
    let (result, trace) = run(path, &config);
    // (Tool existence without a tool table is not a question of positions.)
    let undecided = report
        .undecided
        .iter()
        .any(|u| !u.contains("no tool table"));
    match result {
        Ok(r) => tally.machine_time += r.machine_time,
        // What the check lists as undecided (positions the operator may have moved during a
        // program stop) may stop the run with a program error there: the motion before it
        // must still be within the limits.
        Err(f) if undecided && matches!(f.error, RunError::Program(_)) => {
            tally.machine_time += f.report.machine_time;
            tally.undecided_stopped.push(name.clone());
        }
        Err(f) => panic!("{name}: the test run passed, the run stopped: {}", f.error),
    }
    if undecided {
        tally.undecided += 1;
    }
    // A thread pass follows the measured spindle angle: each setpoint is pitch × an encoder
    // reading, so its third difference is the encoder's quantisation (0.37 µm of Z per count
    // at 1.5 mm pitch, i.e. up to ~1.5e6 mm/s³ at 1 ms) and the spindle's speed ripple, not a
    // planner's jerk. Velocity and acceleration, which the setpoint guard bounds, are still
    // checked; the jerk is checked on programs without such passes.
    assert_within(&trace, &config, report.geared_ops == 0);
    let (v, a) = margin_use(&trace, &config);
    tally.velocity_use = tally.velocity_use.max(v);
    tally.acceleration_use = tally.acceleration_use.max(a);
    tally.ran += 1;
}

#[test]
fn every_program_is_refused_by_check_or_runs_within_the_limits() {
    let started = std::time::Instant::now();
    let mut tally = Tally::default();
    let mut examples = Vec::new();
    program_files(&root().join("programs"), 1, &mut examples);
    examples.sort();
    assert!(examples.len() > 40, "{} example programs", examples.len());
    for p in &examples {
        check_then_run(p, &machine_for(p), &mut tally);
    }
    let mut corpus = Vec::new();
    let dir = root().join("../shared/corpus/klartext");
    program_files(&dir, 3, &mut corpus);
    corpus.sort();
    if corpus.is_empty() {
        eprintln!("{}: no corpus here, only the examples", dir.display());
    }
    // radius-3 tools, as the corpus test uses
    let shop = common::shop_mill(3.0);
    for p in &corpus {
        check_then_run(p, &shop, &mut tally);
    }
    eprintln!(
        "check = run: {} programs ({} examples, {} corpus): {} refused by check ({} by the \
         setpoint guard: {:?}), {} run to the \
         end or to a program error in what check could not decide ({} programs with an \
         undecided part, stopped: {:?}) within the limits ({:.1} s machine time), {} checked \
         but not run (planned longer \
         than {MAX_RUN_SECONDS} s: {:?}); largest use of the guard's bounds: velocity {:.6} of \
         v_max (guard {VELOCITY_MARGIN}), acceleration {:.6} of a_max (guard \
         {ACCELERATION_MARGIN}); {:.1} s",
        tally.programs,
        examples.len(),
        corpus.len(),
        tally.refused,
        tally.guard_refused.len(),
        tally.guard_refused,
        tally.ran,
        tally.undecided,
        tally.undecided_stopped,
        tally.machine_time,
        tally.long.len(),
        tally.long,
        tally.velocity_use,
        tally.acceleration_use,
        started.elapsed().as_secs_f64()
    );
    assert_eq!(tally.refused + tally.ran + tally.long.len(), tally.programs);
    assert!(tally.ran >= 30, "only {} programs ran", tally.ran);
    // A legitimate run keeps well inside the guard's bounds.
    assert!(tally.velocity_use <= 1.0 + 1e-6, "{}", tally.velocity_use);
    assert!(tally.acceleration_use <= 1.01, "{}", tally.acceleration_use);
}

#[test]
fn check_and_run_agree_on_the_tilt_then_tcpm_program() {
    // Tilted, then TCPM on, then a move: once a 190 mm jump at the switch. Check accepts it
    // now, and the run follows it within every limit.
    let path = temp_program("tcpm_jump.h", TCPM_JUMP);
    let machine = machine_file("mill5.toml");
    let report = test_run(&path, &machine);
    assert!(report.passed(), "{:?}", report.errors);
    let (result, trace) = run(&path, &machine);
    if let Err(failure) = result {
        panic!("{}", failure.error);
    }
    common::assert_within_limits(&trace, &machine);
}
