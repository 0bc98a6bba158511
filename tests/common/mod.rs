//! Helpers shared by the end-to-end tests: run a program on the built-in mill and read the
//! trace back, and finite-difference checks that know nothing of the planner.

#![allow(dead_code)]

pub mod hold;
pub mod mill5;
pub mod peers;
pub mod probing;
pub mod threads;
pub mod vfd_peer;

use klar::config::MachineConfig;
use klar::runtime::{RunFailure, RunOptions, RunReport, run_program};
pub use klar::trace::Trace;
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

/// The largest |Δx − `per_rev`·Δangle/360| (mm) over the stretches of one measured spindle
/// revolution among `rows` (sample indices, increasing, at least one): from each row to the
/// first row at least 360° of `angle` (degrees) further on, while there is one. `per_rev` is
/// the signed travel of `x` per revolution.
pub fn per_revolution_error(rows: &[usize], x: &[f64], angle: &[f64], per_rev: f64) -> f64 {
    let mut worst: f64 = 0.0;
    let mut j = rows[0];
    let last = *rows.last().unwrap_or(&0);
    for &i in rows {
        while j <= last && angle[j] - angle[i] < 360.0 {
            j += 1;
        }
        if j > last {
            break;
        }
        worst = worst.max(((x[j] - x[i]) - per_rev * (angle[j] - angle[i]) / 360.0).abs());
    }
    worst
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
    assert_within(trace, machine, true);
}

/// [`assert_within_limits`], with the jerk checked only when `jerk` is true.
pub fn assert_within(trace: &Trace, machine: &MachineConfig, jerk: bool) {
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
            !jerk || j <= a.max_jerk * 1.01,
            "axis {name}: jerk {j} above {}",
            a.max_jerk
        );
    }
}

/// An element of the rectangle contour as written in programs/rectangle.h, with the arc
/// centres worked out by hand in the comments there.
pub enum Element {
    /// from, to
    Line([f64; 2], [f64; 2]),
    /// centre, radius, start angle, end angle (degrees, clockwise from start to end)
    ArcCw([f64; 2], f64, f64, f64),
}

pub fn rectangle_contour() -> Vec<Element> {
    use Element::*;
    vec![
        Line([-10.0, 10.0], [0.0, 10.0]),
        Line([0.0, 10.0], [0.0, 50.0]),
        ArcCw([10.0, 50.0], 10.0, 180.0, 90.0),
        Line([10.0, 60.0], [80.0, 60.0]),
        ArcCw([80.0, 40.0], 20.0, 90.0, 0.0),
        Line([100.0, 40.0], [100.0, 10.0]),
        ArcCw([90.0, 10.0], 10.0, 0.0, -90.0),
        Line([90.0, 0.0], [10.0, 0.0]),
        ArcCw([10.0, 10.0], 10.0, 270.0, 180.0),
    ]
}

pub fn distance_to(e: &Element, p: [f64; 2]) -> f64 {
    match e {
        Element::Line(a, b) => {
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len2 = dx * dx + dy * dy;
            let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0);
            ((p[0] - a[0] - t * dx).powi(2) + (p[1] - a[1] - t * dy).powi(2)).sqrt()
        }
        Element::ArcCw(c, r, start, end) => {
            let ang = (p[1] - c[1]).atan2(p[0] - c[0]).to_degrees();
            // clockwise sweep from start to the point, compared with the whole sweep
            let swept = (start - ang).rem_euclid(360.0);
            let total = (start - end).rem_euclid(360.0);
            if swept <= total + 1e-9 {
                ((p[0] - c[0]).hypot(p[1] - c[1]) - r).abs()
            } else {
                let e0 = [
                    c[0] + r * start.to_radians().cos(),
                    c[1] + r * start.to_radians().sin(),
                ];
                let e1 = [
                    c[0] + r * end.to_radians().cos(),
                    c[1] + r * end.to_radians().sin(),
                ];
                (p[0] - e0[0])
                    .hypot(p[1] - e0[1])
                    .min((p[0] - e1[0]).hypot(p[1] - e1[1]))
            }
        }
    }
}

/// Distance of a point from the rectangle contour of programs/rectangle.h.
pub fn distance_to_rectangle(p: [f64; 2]) -> f64 {
    rectangle_contour()
        .iter()
        .map(|e| distance_to(e, p))
        .fold(f64::INFINITY, f64::min)
}

/// The tool-centre ops of `interp` as `klar run` builds them: working-plane ops on, through
/// the radius compensation stage, starting at `start`.
pub fn compensated(
    mut interp: klar_interp::Interpreter,
    start: klar_interp::Pose,
) -> Vec<klar_interp::Op> {
    interp.set_working_plane_ops(true);
    let mut comp = klar_motion::comp::Compensator::new(start);
    let mut out = Vec::new();
    for op in interp {
        let op = op.unwrap_or_else(|d| panic!("program error: {d}"));
        comp.push(op)
            .unwrap_or_else(|e| panic!("compensation: {e}"));
        while let Some(o) = comp.pop() {
            out.push(o);
        }
    }
    comp.finish()
        .unwrap_or_else(|e| panic!("compensation: {e}"));
    while let Some(o) = comp.pop() {
        out.push(o);
    }
    out
}

/// Runs the `klar` binary with `args`: (success, stdout, stderr).
pub fn klar_cli(args: &[&str]) -> (bool, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_klar"))
        .args(args)
        .output()
        .expect("klar runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A path as a command-line argument.
pub fn arg(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// The built-in mill with a shop tool table: tools 1 to 999, length 60 mm, radius `radius`.
pub fn shop_mill(radius: f64) -> MachineConfig {
    let mut m = MachineConfig::builtin_mill();
    m.tools = Some(
        (1..=999)
            .map(|number| klar::config::ToolConfig {
                number,
                name: None,
                length: 60.0,
                radius,
            })
            .collect(),
    );
    m
}
