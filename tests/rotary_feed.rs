//! Feeds of rotary table moves on the 5-axis table-table machine (machines/mill5.toml), end
//! to end: M116 makes F the tool point's speed, M117 returns to degrees per minute, and
//! `M128 F…` keeps TCPM's compensating moves within their own feed.

mod common;

use common::{Trace, run, temp_program};
use klar::config::MachineConfig;
use std::f64::consts::PI;

/// Runs a Klartext body on the 5-axis mill and returns the trace.
fn run_mill5(name: &str, body: &str) -> Trace {
    let text = format!("0 BEGIN PGM T MM\n{body}\n99 END PGM T MM\n");
    let path = temp_program(name, &text);
    let (result, trace) = run(&path, &MachineConfig::builtin_mill5());
    if let Err(f) = result {
        panic!("{}", f.error);
    }
    trace
}

/// The time from the last sample at which `col` is still at `from` to the first at `to`
/// after it.
fn travel_time(trace: &Trace, col: &str, from: f64, to: f64) -> f64 {
    let x = trace.column(col).expect("axis column");
    let near = |v: f64, w: f64| (v - w).abs() < 1e-9;
    let first = x
        .iter()
        .position(|&v| near(v, from))
        .expect("a sample at the start");
    let end = first
        + x[first..]
            .iter()
            .position(|&v| near(v, to))
            .expect("a sample at the end");
    let start = x[..end]
        .iter()
        .rposition(|&v| near(v, from))
        .expect("a sample at the start");
    trace.t[end] - trace.t[start]
}

/// The speed of `col` half way through its first move from `from` to `to` (central difference of the commanded
/// positions), in units per second.
fn mid_rate(trace: &Trace, col: &str, from: f64, to: f64) -> f64 {
    let x = trace.column(col).expect("axis column");
    let mid = 0.5 * (from + to);
    let first = x
        .iter()
        .position(|&v| (v - from).abs() < 1e-9)
        .expect("a sample at the start");
    let i = first
        + x[first..]
            .windows(2)
            .position(|w| (w[0] - mid) * (w[1] - mid) <= 0.0)
            .expect("the middle of the move");
    (x[i + 2] - x[i]) / (trace.t[i + 2] - trace.t[i])
}

/// The most the machine's C axis can lose to its speed ramps on a move at cruise `v` °/s
/// (rest to rest): each of the two ramps takes at most `v/a + a/j` and covers at least
/// half its time's worth of cruise, so together they add at most `v/a + a/j` (C: 1440 °/s²,
/// 20000 °/s³) over `distance / v`; two servo periods for the samples at the ends.
fn ramp_allowance(v: f64) -> f64 {
    v / 1440.0 + 1440.0 / 20000.0 + 0.002
}

#[test]
fn m116_turns_the_table_at_the_tool_points_feed_and_m117_restores_degrees() {
    // The tool point 50 mm from the C axis: a quarter turn is a 25π mm arc, at 1000 mm/min
    // 4.712 s; back at 1000 °/min after M117 it is 5.4 s.
    let trace = run_mill5(
        "m116.h",
        "1 L X+50 Y+0 Z+10 A+0 C+0 R0 FMAX\n2 L C+90 F1000 M116\n3 L C+0 M117",
    );
    let quarter = (PI / 2.0 * 50.0) / 1000.0 * 60.0;
    let cruise = 90.0 / quarter;
    let rate = mid_rate(&trace, "C", 0.0, 90.0);
    assert!(
        (rate - cruise).abs() < 1e-6,
        "C at {rate} °/s, want {cruise}"
    );
    let t = travel_time(&trace, "C", 0.0, 90.0);
    assert!(
        t >= quarter && t <= quarter + ramp_allowance(cruise),
        "block 2 took {t} s, closed form {quarter} s"
    );
    let rate = mid_rate(&trace, "C", 90.0, 0.0);
    assert!(
        (rate + 1000.0 / 60.0).abs() < 1e-6,
        "C at {rate} °/s after M117"
    );
    let t = travel_time(&trace, "C", 90.0, 0.0);
    assert!(
        t >= 5.4 && t <= 5.4 + ramp_allowance(1000.0 / 60.0),
        "block 3 took {t} s"
    );
    // the linear axes stood still (TCPM is off: the table carries the workpiece away)
    let x = trace.column("X").expect("X");
    assert!(x.iter().skip(x.len() / 2).all(|&v| (v - 50.0).abs() < 1e-9));
}

#[test]
fn m116_with_linear_and_rotary_axes_together() {
    // X 50 → 80 while C turns 90°: √(30² + (25π)²) mm of tool point path at 1000 mm/min.
    let trace = run_mill5(
        "m116_lin.h",
        "1 L X+50 Y+0 Z+10 A+0 C+0 R0 FMAX\n2 L X+80 C+90 F1000 M116",
    );
    let path = (30.0f64.powi(2) + (25.0 * PI).powi(2)).sqrt();
    let want = path / 1000.0 * 60.0;
    let x_rate = mid_rate(&trace, "X", 50.0, 80.0);
    let c_rate = mid_rate(&trace, "C", 0.0, 90.0);
    assert!((x_rate - 30.0 / want).abs() < 1e-6, "X at {x_rate} mm/s");
    assert!((c_rate - 90.0 / want).abs() < 1e-6, "C at {c_rate} °/s");
    let t = travel_time(&trace, "C", 0.0, 90.0);
    assert!(
        t >= want && t <= want + ramp_allowance(90.0 / want),
        "{t} vs {want}"
    );
}

#[test]
fn m128_f_keeps_the_compensating_moves_within_their_feed() {
    // With M128 the machine's X Y Z follow the tip (50, 0, 10) round the C axis; the turn is
    // programmed far faster than the machine may go (F30000 °/min). M128 F500 leaves the
    // turning 500 mm/min for the compensating moves over the planner's reach D = |tip −
    // table pivot| + pivot gap = √(50² + 10²) + 100 mm, shared by the two rotary axes: C
    // turns at ½·(500/60)/D rad/s.
    let body = |m128: &str| {
        format!(
            "1 L X+50 Y+0 Z+10 A+0 C+0 R0 FMAX\n2 L C+30 F30000 {m128}\n3 L C+0\n\
             4 L Z+50 FMAX M129"
        )
    };
    let capped = run_mill5("m128f.h", &body("M128 F500"));
    let d = 50.0f64.hypot(10.0) + 100.0;
    let want = 0.5 * (500.0 / 60.0) / d * 180.0 / PI;
    let rate = mid_rate(&capped, "C", 0.0, 30.0);
    assert!((rate - want).abs() < 1e-6, "C at {rate} °/s, want {want}");
    // the linear machine axes, which only compensate here, stay within 500 mm/min
    let cols: Vec<Vec<f64>> = ["X", "Y", "Z"]
        .iter()
        .map(|l| capped.column(l).expect("axis"))
        .collect();
    let c = capped.column("C").expect("C");
    let mut fastest = 0.0f64;
    for i in 1..c.len() {
        if c[i] > 1e-9 && c[i] < 30.0 - 1e-9 {
            let dt = capped.t[i] - capped.t[i - 1];
            let v = (0..3)
                .map(|k| (cols[k][i] - cols[k][i - 1]).powi(2))
                .sum::<f64>()
                .sqrt()
                / dt;
            fastest = fastest.max(v);
        }
    }
    assert!(fastest > 0.0 && fastest <= 500.0 / 60.0, "{fastest} mm/s");
    // without the F the machine's own share lets the table turn faster
    let free = run_mill5("m128.h", &body("M128"));
    let free_rate = mid_rate(&free, "C", 0.0, 30.0);
    assert!(free_rate > 2.0 * rate, "{free_rate} vs {rate}");
}

#[test]
fn the_example_program_runs_within_the_machine_limits() {
    let machine = MachineConfig::builtin_mill5();
    let (result, trace) = run(&common::program("m116_rotary_feed.h"), &machine);
    if let Err(f) = result {
        panic!("{}", f.error);
    }
    common::assert_within_limits(&trace, &machine);
    // block 7: the quarter turn at 50 mm from C cruises at 90° per (25π mm / 1000 mm/min)
    let rate = mid_rate(&trace, "C", 0.0, 90.0);
    assert!(
        (rate - 90.0 / ((PI / 2.0 * 50.0) / 1000.0 * 60.0)).abs() < 1e-6,
        "{rate}"
    );
}
