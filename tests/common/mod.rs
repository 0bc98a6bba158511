//! Helpers shared by the end-to-end tests: run a program on the built-in mill and read the
//! trace back, and finite-difference checks that know nothing of the planner.

#![allow(dead_code)]

use klar::config::MachineConfig;
use klar::runtime::{RunFailure, RunOptions, RunReport, run_program};
use klar::trace::Trace;
use std::path::{Path, PathBuf};

/// Path of a file in the repository's programs/ folder.
pub fn program(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("programs")
        .join(name)
}

/// Runs a program on a machine and returns the report and the parsed trace.
pub fn run(path: &Path, machine: &MachineConfig) -> (Result<RunReport, Box<RunFailure>>, Trace) {
    let mut buf = Vec::new();
    let result = run_program(
        path,
        machine,
        RunOptions {
            realtime: false,
            trace: Some(&mut buf),
        },
    );
    let text = String::from_utf8(buf).expect("trace is UTF-8");
    // A run refused before motion writes no trace at all.
    let trace = if text.is_empty() {
        Trace {
            columns: Vec::new(),
            t: Vec::new(),
            rows: Vec::new(),
        }
    } else {
        Trace::parse(&text).expect("trace parses")
    };
    (result, trace)
}

/// Writes a program into a fresh temporary directory and returns its path.
pub fn temp_program(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "klar-test-{}-{}",
        std::process::id(),
        name.replace('.', "_")
    ));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write program");
    p
}

/// Commanded positions per machine axis column, in machine order.
pub fn commanded(trace: &Trace, letters: &[&str]) -> Vec<Vec<f64>> {
    letters
        .iter()
        .map(|l| trace.column(l).expect("axis column"))
        .collect()
}

/// Largest |n-th finite difference| / dt^n of a sampled signal.
pub fn max_derivative(x: &[f64], dt: f64, order: u32) -> f64 {
    let mut d = x.to_vec();
    for _ in 0..order {
        d = d.windows(2).map(|w| (w[1] - w[0]) / dt).collect();
    }
    d.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// Checks per-axis velocity, acceleration and jerk of the commanded trace against the machine
/// limits with 1 % numeric slack; the trace starts and ends at rest, so the differences at the
/// ends are padded with the first and last positions.
pub fn assert_within_limits(trace: &Trace, machine: &MachineConfig) {
    let dt = machine.servo_period;
    for a in &machine.axes {
        let name = a.letter.to_string();
        let mut x = trace.column(&name).expect("axis column");
        // At rest before the first sample (the start position) and after the last one.
        let last = x.last().copied().unwrap_or(a.start);
        let mut padded = vec![a.start; 3];
        padded.append(&mut x);
        padded.extend([last; 3]);
        let v = max_derivative(&padded, dt, 1);
        let acc = max_derivative(&padded, dt, 2);
        let j = max_derivative(&padded, dt, 3);
        assert!(
            v <= a.max_velocity * 1.01,
            "axis {name}: velocity {v} above {}",
            a.max_velocity
        );
        assert!(
            acc <= a.max_acceleration * 1.01,
            "axis {name}: acceleration {acc} above {}",
            a.max_acceleration
        );
        assert!(
            j <= a.max_jerk * 1.01,
            "axis {name}: jerk {j} above {}",
            a.max_jerk
        );
    }
}
