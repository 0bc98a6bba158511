//! A probing program in the shape Fusion 360's HEIDENHAIN post writes (block numbers, a tool
//! list in comments, `* - …` sections, the probe as tool 100, `M140 MB MAX`, cycle 32 without
//! values, TCH PROBE 417 and 419 with their `Q…` lines): `programs/probing/fusion_style.h`
//! on `machines/probing-mill.toml` passes `klar check` and `klar run` and sets the preset the
//! part's placement gives (3.2 mm / −1.7 mm / −0.25 mm off, turned 1.5° about preset 1).

mod common;

use klar::config::MachineConfig;
use std::path::Path;

const ORIGIN: [f64; 3] = [100.0, 50.0, -60.0];
const OFF: [f64; 3] = [3.2, -1.7, -0.25];
const TURN: f64 = 1.5;
const EXACT: f64 = 1e-9;
/// The stylus ball: tool 100's radius in the machine file (its `[probe] radius` is 2).
const BALL: f64 = 3.0;

/// What a single touch along an axis reports on a side turned by TURN: the ball centre stops
/// BALL from the side along its normal, i.e. BALL / cos(TURN) before it along the axis, and
/// the cycle adds BALL: the side's crossing less BALL · (1 / cos(TURN) − 1).
fn slant() -> f64 {
    BALL * (1.0 / TURN.to_radians().cos() - 1.0)
}

fn machine_path() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing-mill.toml")
}

/// X (preset-1 coordinates) of the part's left side (part X−50) where it crosses Y = `y`.
fn left_side_at(y: f64) -> f64 {
    let (s, c) = TURN.to_radians().sin_cos();
    let t = (y - OFF[1] + 50.0 * s) / c;
    OFF[0] - 50.0 * c - t * s
}

/// Y (preset-1 coordinates) of the part's front side (part Y−40) where it crosses X = `x`.
fn front_side_at(x: f64) -> f64 {
    let (s, c) = TURN.to_radians().sin_cos();
    let t = (x - OFF[0] - 40.0 * s) / c;
    OFF[1] + t * s - 40.0 * c
}

/// The preset the program shall leave in row 1: Z on the top, X so that the left side as
/// probed reads −50 at Y+10, Y so that the front side as probed reads −40 at X+15 of the new
/// X datum.
fn expected_preset() -> [f64; 3] {
    // probed along +X and +Y: the reported coordinate lies short of the side by the slant
    let dx = left_side_at(10.0) - slant() + 50.0;
    let dy = front_side_at(15.0 + dx) - slant() + 40.0;
    [ORIGIN[0] + dx, ORIGIN[1] + dy, ORIGIN[2] + OFF[2]]
}

fn close(what: &str, got: f64, want: f64, tol: f64) {
    eprintln!("{what}: off by {:e}", (got - want).abs());
    assert!(
        (got - want).abs() <= tol,
        "{what}: got {got}, expected {want} (±{tol})"
    );
}

#[test]
fn a_fusion_style_probing_program_checks_runs_and_sets_the_preset() {
    let m = MachineConfig::load(&machine_path()).expect("machine loads");
    let p = common::program("probing/fusion_style.h");
    let (ok, out, err) = common::klar_cli(&[
        "check",
        "--machine",
        common::arg(&machine_path()),
        common::arg(&p),
    ]);
    assert!(ok, "check: {out}{err}");

    let want = expected_preset();
    let mut it = m.open_program(&p, m.start_pose()).expect("opens");
    for op in it.by_ref() {
        op.unwrap_or_else(|d| panic!("{d}"));
    }
    let (table, active) = it.presets();
    assert_eq!(active, Some(1));
    let row = table.expect("preset table").row(1).expect("row 1");
    for (k, axis) in ["X", "Y", "Z"].iter().enumerate() {
        close(
            &format!("preset {axis}"),
            row[k].expect("written"),
            want[k],
            EXACT,
        );
    }

    // klar run: the program's last positioning L X+0 Y+0 stands on the new preset
    let (report, trace) = common::run(&p, &m);
    report.expect("the run ends normally");
    let col = |name: &str| {
        trace
            .columns
            .iter()
            .position(|c| c == name)
            .expect("trace column")
    };
    let last = trace.rows.last().expect("rows");
    close("machine X at the end", last[col("X")], want[0], 1e-6);
    close("machine Y at the end", last[col("Y")], want[1], 1e-6);
}
