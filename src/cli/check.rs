//! The commands that read a program without moving anything: `klar check` (the syntax check
//! and the test run against a machine) and `klar ops`.

use crate::{load_machine_for, print_diagnostics, start_pose};
use klar::config::MachineConfig;
use klar_motion::comp::Compensator;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::process::ExitCode;

/// `klar check PROGRAM`: the syntax check alone (`--program-only`), else the test run on the
/// machine `klar run` would use.
pub(crate) fn cmd_check(
    program: &Path,
    machine: Option<&Path>,
    program_only: bool,
    limits: &klar::testrun::TestRunLimits,
    quiet: bool,
) -> ExitCode {
    let config = match load_machine_for(program, machine) {
        Ok(c) => c,
        Err(code) => return code,
    };
    if !program_only {
        return cmd_test_run(program, &config, limits, quiet);
    }
    // the program checked on its own, on no machine
    let report = match klar::config::open_on(None, program, start_pose(&config)) {
        Ok(it) => it.check_report(),
        Err(d) => klar_interp::CheckReport {
            errors: vec![d],
            ..Default::default()
        },
    };
    for w in &report.warnings {
        eprintln!("{w} (warning)");
    }
    for m in &report.missing {
        eprintln!("{m} (warning: a run stops here)");
    }
    for u in &report.undecided {
        eprintln!("{u} (decided only when the program runs)");
    }
    let diags = report.errors;
    if diags.is_empty() {
        if !quiet {
            say!("{}: ok", program.display());
        }
        ExitCode::SUCCESS
    } else {
        print_diagnostics(&diags);
        ExitCode::FAILURE
    }
}

/// `klar ops PROGRAM`: prints the interpreter's ops (the tool-centre path with
/// `--compensated`), at most `max_ops` of them.
pub(crate) fn cmd_ops(
    program: &Path,
    machine: Option<&Path>,
    compensated: bool,
    max_ops: u64,
) -> ExitCode {
    let config = match load_machine_for(program, machine) {
        Ok(c) => c,
        Err(code) => return code,
    };
    if let Err(diags) = klar_interp::syntax_check(program) {
        print_diagnostics(&diags);
        return ExitCode::FAILURE;
    }
    let start = start_pose(&config);
    let mut interp = match config.open_program(program, start) {
        Ok(i) => i,
        Err(d) => {
            print_diagnostics(&[d]);
            return ExitCode::FAILURE;
        }
    };
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let mut comp = compensated.then(|| Compensator::new(start));
    // Ops of a tilted working plane reach the output in workpiece coordinates: turned after
    // the compensation (which runs in the tilted plane) or, without it, by the tilt stage alone.
    interp.set_working_plane_ops(true);
    let mut tilt = klar_motion::tilt::TiltStage::new();
    let mut turned = std::collections::VecDeque::new();
    let mut write = |op: &klar_interp::Op| -> bool {
        match serde_json::to_string(op) {
            Ok(line) => writeln!(out, "{line}").is_ok(),
            Err(e) => {
                eprintln!("cannot encode op: {e}");
                false
            }
        }
    };
    let comp_failed = |e: &dyn std::fmt::Display| {
        eprintln!("{}: {e}", program.display());
        ExitCode::FAILURE
    };
    let mut count = 0u64;
    for item in interp {
        let op = match item {
            Ok(op) => op,
            Err(d) => {
                print_diagnostics(&[d]);
                return ExitCode::FAILURE;
            }
        };
        count += 1;
        if max_ops != 0 && count > max_ops {
            let _ = out.flush();
            eprintln!(
                "{}:{}:{}: undecided: the program did not end within {max_ops} ops; `klar ops` \
                 stops here (an endless loop?); --max-ops 0 lifts the limit",
                program.display(),
                op.loc.line,
                op.loc.col
            );
            return ExitCode::from(2);
        }
        match comp.as_mut() {
            None => {
                tilt.push(op, &mut turned);
                while let Some(o) = turned.pop_front() {
                    if !write(&o) {
                        return ExitCode::FAILURE;
                    }
                }
            }
            Some(c) => {
                if let Err(e) = c.push(op) {
                    return comp_failed(&e);
                }
                while let Some(o) = c.pop() {
                    if !write(&o) {
                        return ExitCode::FAILURE;
                    }
                }
            }
        }
    }
    if let Some(c) = comp.as_mut() {
        if let Err(e) = c.finish() {
            return comp_failed(&e);
        }
        while let Some(o) = c.pop() {
            if !write(&o) {
                return ExitCode::FAILURE;
            }
        }
    }
    if out.flush().is_err() {
        return ExitCode::FAILURE;
    }
    ExitCode::SUCCESS
}

/// `klar check PROGRAM --machine FILE`: the test run.
fn cmd_test_run(
    program: &Path,
    config: &MachineConfig,
    limits: &klar::testrun::TestRunLimits,
    quiet: bool,
) -> ExitCode {
    // A machine with drives that measure their own position is checked from where they
    // stand, as `klar run` would start (no drive is enabled to read it).
    let standing = match klar::machine::standing(config) {
        Some(Ok(at)) => at,
        Some(Err(e)) => {
            eprintln!(
                "warning: could not read where the drives stand ({e}): checked from the \
                 machine file's start"
            );
            Vec::new()
        }
        None => Vec::new(),
    };
    let measured;
    let config = if standing.is_empty() {
        config
    } else {
        measured = config.starting_at(standing.iter().map(|s| s.position));
        &measured
    };
    let report = klar::testrun::test_run_within(program, config, limits);
    print_diagnostics(&report.errors);
    for w in &report.warnings {
        eprintln!("{w} (warning)");
    }
    for u in &report.undecided {
        eprintln!("{}: not checked: {u}", program.display());
    }
    if !report.passed() {
        return ExitCode::FAILURE;
    }
    if let Some(d) = &report.gave_up {
        // neither passed nor refused: the operator decides whether to run it
        eprintln!("{d}");
        return ExitCode::from(2);
    }
    if quiet {
        return ExitCode::SUCCESS;
    }
    say!(
        "{}: ok on {} ({} moves, {:.3} s planned)",
        program.display(),
        config.name,
        report.motion_ops,
        report.planned_time
    );
    let lathe = config.kinematics == klar::config::KinematicsConfig::Lathe;
    for (l, lo, hi) in &report.envelope {
        if lathe && *l == klar_interp::AxisLetter::X {
            // a lathe's X runs in radius; the operator reads it as a diameter
            say!("  X (diameter): {:.4} .. {:.4}", lo * 2.0, hi * 2.0);
        } else {
            say!("  {l}: {lo:.4} .. {hi:.4}");
        }
    }
    if let Ok(preset) = config.active_preset() {
        say!("  preset at start: {preset}");
    }
    for s in &standing {
        say!("  {s}");
    }
    ExitCode::SUCCESS
}
