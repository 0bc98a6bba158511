//! Rigid tapping (cycles 207 and 209) geared to the measured spindle angle, read back from
//! the trace: the tool axis follows pitch × measured angle in, through every reversal and
//! out; the depth is reached; the spindle stops and reverses at each stroke's end (S, the
//! commanded speed, changes sign there) and turns at the retraction factor on the way out;
//! `klar check` refuses rigid tapping on a spindle that measures no angle.

mod common;

use common::{Trace, program, run, temp_program};
use klar::config::MachineConfig;
use klar::testrun::test_run;

/// The columns a tap is judged by.
struct Cols {
    x: Vec<f64>,
    z: Vec<f64>,
    z_act: Vec<f64>,
    s: Vec<f64>,
    angle: Vec<f64>,
}

fn cols(trace: &Trace) -> Cols {
    let col = |n: &str| trace.column(n).unwrap_or_else(|| panic!("column {n}"));
    Cols {
        x: col("X"),
        z: col("Z"),
        z_act: col("Z_act"),
        s: col("S"),
        angle: col("S_deg"),
    }
}

/// One tap found in the trace: the rows at X = `x` whose commanded Z lies below the set-up
/// clearance `safe`, and the measured angle of the row before them (where the tool stood at
/// the clearance with the spindle at rest, geared from there).
fn tap_rows(c: &Cols, x: f64, safe: f64) -> (Vec<usize>, f64) {
    let rows: Vec<usize> = (0..c.z.len())
        .filter(|&i| (c.x[i] - x).abs() < 1e-9 && c.z[i] < safe - 1e-9)
        .collect();
    assert!(rows.len() > 100, "a tap at X{x}");
    let before = rows[0] - 1;
    assert!((c.z[before] - safe).abs() < 1e-9);
    // Contiguous: one tap, no other move in between.
    assert_eq!(rows.last().map(|l| l - rows[0] + 1), Some(rows.len()));
    (rows, c.angle[before])
}

/// Largest |z − (safe − pitch·(angle − a0)/360)| over `rows`, mm.
fn lead_error(z: &[f64], angle: &[f64], rows: &[usize], safe: f64, a0: f64, pitch: f64) -> f64 {
    rows.iter()
        .map(|&i| (z[i] - (safe - pitch * (angle[i] - a0) / 360.0)).abs())
        .fold(0.0, f64::max)
}

/// The ends of the strokes: the commanded Z where the commanded spindle speed changes sign
/// (the spindle reverses), in order.
fn reversals(c: &Cols, rows: &[usize]) -> Vec<(f64, f64)> {
    rows.windows(2)
        .filter(|w| c.s[w[0]] * c.s[w[1]] < 0.0)
        .map(|w| (c.z[w[0]], c.z_act[w[0]]))
        .collect()
}

/// Measured spindle speed over the `n` rows before row `i`, rpm (1 ms rows).
fn measured_rpm(c: &Cols, i: usize, n: usize) -> f64 {
    (c.angle[i] - c.angle[i - n]) / (n as f64 * 0.001) / 6.0
}

#[test]
fn cycle_207_follows_the_measured_angle_in_and_out_through_the_reversal() {
    let machine = MachineConfig::builtin_mill();
    let (result, trace) = run(&program("rigid_tapping.h"), &machine);
    result.expect("the tapping program runs");
    let c = cols(&trace);
    // M8 x 1.25 at S800, set-up clearance Z2, depth Z-12, retraction at twice the speed.
    let (safe, pitch, depth) = (2.0, 1.25, -12.0);
    let (rows, a0) = tap_rows(&c, 30.0, safe);
    let cmd = lead_error(&c.z, &c.angle, &rows, safe, a0, pitch);
    let act = lead_error(&c.z_act, &c.angle, &rows, safe, a0, pitch);
    assert!(cmd < 0.005, "commanded lead error {cmd} mm");
    assert!(act < 0.005, "measured lead error {act} mm");
    // The spindle stood still when the tool left the clearance (geared from rest).
    let start = measured_rpm(&c, rows[0] - 1, 5);
    assert!(
        start.abs() < 15.0,
        "spindle at {start} rpm when the tap began"
    );
    // One reversal, at the depth: S from +800 (M3, right-hand) to the retraction speed.
    let rev = reversals(&c, &rows);
    assert_eq!(rev.len(), 1, "{rev:?}");
    let deepest = rows.iter().map(|&i| c.z[i]).fold(f64::INFINITY, f64::min);
    let deepest_act = rows
        .iter()
        .map(|&i| c.z_act[i])
        .fold(f64::INFINITY, f64::min);
    assert!((deepest - depth).abs() < 0.005, "depth {deepest}");
    assert!(
        (deepest_act - depth).abs() < 0.005,
        "measured depth {deepest_act}"
    );
    assert!(
        (rev[0].0 - depth).abs() < 0.005,
        "reversed at Z {}",
        rev[0].0
    );
    let most_in = rows.iter().map(|&i| c.s[i]).fold(0.0, f64::max);
    let most_out = rows.iter().map(|&i| c.s[i]).fold(0.0, f64::min);
    assert_eq!(most_in, 800.0);
    assert_eq!(most_out, -1600.0, "Q403=2 doubles the retraction speed");
    // The spindle really turned back: measured speed near -1600 rpm on the way out.
    let fastest_out = rows
        .iter()
        .filter(|&&i| i > rows[0] + 10)
        .map(|&i| measured_rpm(&c, i, 10))
        .fold(0.0, f64::min);
    assert!(fastest_out < -1500.0, "measured {fastest_out} rpm out");
    // After the tap the spindle turns forward at its speed again.
    let after = *rows.last().unwrap_or(&0) + 2;
    assert_eq!(c.s[after], 800.0);
    println!(
        "207 M8x1.25 S800: lead error commanded {:.2} µm, measured {:.2} µm; depth {:.2} µm \
         (measured {:.2} µm)",
        cmd * 1e3,
        act * 1e3,
        (deepest - depth).abs() * 1e3,
        (deepest_act - depth).abs() * 1e3
    );
}

#[test]
fn cycle_209_breaks_chips_with_the_tool_on_the_spindle() {
    let machine = MachineConfig::builtin_mill();
    let (result, trace) = run(&program("rigid_tapping.h"), &machine);
    result.expect("the tapping program runs");
    let c = cols(&trace);
    // M10 x 1.5 at S600 to Z-10 in infeeds of 4 from the surface Z0, backing off 0.5.
    let (safe, pitch) = (2.0, 1.5);
    let (rows, a0) = tap_rows(&c, 60.0, safe);
    let cmd = lead_error(&c.z, &c.angle, &rows, safe, a0, pitch);
    let act = lead_error(&c.z_act, &c.angle, &rows, safe, a0, pitch);
    assert!(cmd < 0.005, "commanded lead error {cmd} mm");
    assert!(act < 0.005, "measured lead error {act} mm");
    // The manual's sequence: in to -4, back to -3.5, in to -8, back to -7.5, in to -10 and
    // out; the spindle reverses at each of these ends.
    let want = [-4.0, -3.5, -8.0, -7.5, -10.0];
    let rev = reversals(&c, &rows);
    assert_eq!(rev.len(), want.len(), "{rev:?}");
    for ((z, z_act), w) in rev.iter().zip(want) {
        assert!((z - w).abs() < 0.005, "stroke end {z} for {w}");
        assert!(
            (z_act - w).abs() < 0.005,
            "measured stroke end {z_act} for {w}"
        );
    }
    // Q403=1: the same speed both ways.
    let most_out = rows.iter().map(|&i| c.s[i]).fold(0.0, f64::min);
    assert_eq!(most_out, -600.0);
}

#[test]
fn left_hand_thread_enters_in_m4() {
    let text = "0 BEGIN PGM LH MM\n1 TOOL CALL 1 Z S500\n2 L X+0 Y+0 Z+20 R0 FMAX M3\n\
                3 CYCL DEF 207 RIGID TAPPING Q200=+2 Q201=-6 Q239=-1 Q203=+0 Q204=+10\n\
                4 L X+10 Y+0 R0 FMAX M99\n5 L Z+50 R0 FMAX M30\n6 END PGM LH MM\n";
    let path = temp_program("lh.h", text);
    let machine = MachineConfig::builtin_mill();
    let (result, trace) = run(&path, &machine);
    result.expect("runs");
    let c = cols(&trace);
    let (rows, a0) = tap_rows(&c, 10.0, 2.0);
    // In M4 the angle counts down while the tool goes in.
    let err = lead_error(&c.z, &c.angle, &rows, 2.0, a0, -1.0);
    assert!(err < 0.005, "lead error {err} mm");
    let rev = reversals(&c, &rows);
    assert_eq!(rev.len(), 1);
    assert!((rev[0].0 + 6.0).abs() < 0.005);
    assert!(c.s[rows[0]] < 0.0, "enters turning M4");
    // Back to M3 after the tap, as at the call.
    let last = *rows.last().unwrap_or(&0);
    assert!(c.s[last..].contains(&500.0));
}

#[test]
fn check_refuses_rigid_tapping_without_a_spindle_angle() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/modbus-sim.toml");
    let machine = MachineConfig::load(&file).expect("machine loads");
    let report = test_run(&program("rigid_tapping.h"), &machine);
    let first = report.errors.first().expect("refused");
    assert_eq!(first.line, 19, "{first}");
    assert!(
        first
            .message
            .contains("Modbus VFD, which measures no spindle angle: it cannot tap rigidly"),
        "{first}"
    );
    // And the run refuses it before the tool enters the hole.
    let (result, trace) = run(&program("rigid_tapping.h"), &machine);
    assert!(result.is_err());
    if let Some(z) = trace.column("Z") {
        assert!(z.iter().all(|&z| z >= 2.0 - 1e-9), "the tool stayed out");
    }
}

#[test]
fn check_refuses_a_pitch_the_tool_axis_cannot_follow() {
    // 10 mm pitch at 1000 rpm: Z would need 166.7 mm/s, above the mill's 100 mm/s.
    let text = "0 BEGIN PGM FAST MM\n1 TOOL CALL 1 Z S1000\n2 L X+0 Y+0 Z+20 R0 FMAX M3\n\
                3 CYCL DEF 207 RIGID TAPPING Q200=+2 Q201=-30 Q239=+10 Q203=+0 Q204=+10\n\
                4 L X+10 Y+0 R0 FMAX M99\n5 L Z+50 R0 FMAX M30\n6 END PGM FAST MM\n";
    let path = temp_program("fast.h", text);
    let machine = MachineConfig::builtin_mill();
    let report = test_run(&path, &machine);
    assert!(
        report
            .errors
            .iter()
            .any(|d| d.message.contains("axis Z would need 10000 mm/min")),
        "{:?}",
        report.errors
    );
}

#[test]
fn lathe_g36_on_the_turning_axis_is_geared_to_the_main_spindle() {
    let machine = MachineConfig::builtin_lathe();
    let (result, trace) = run(&program("lathe/tapping_g36.nc"), &machine);
    result.expect("the lathe tapping program runs");
    let c = cols(&trace);
    // M8 x 1.25 at S400 from ZS2 to ZE-12 on X0 (the lathe's X column is the radius).
    let (safe, pitch, depth) = (2.0, 1.25, -12.0);
    let (rows, a0) = tap_rows(&c, 0.0, safe);
    let cmd = lead_error(&c.z, &c.angle, &rows, safe, a0, pitch);
    let act = lead_error(&c.z_act, &c.angle, &rows, safe, a0, pitch);
    assert!(cmd < 0.005, "commanded lead error {cmd} mm");
    assert!(act < 0.005, "measured lead error {act} mm");
    let rev = reversals(&c, &rows);
    assert_eq!(rev.len(), 1, "{rev:?}");
    assert!(
        (rev[0].0 - depth).abs() < 0.005,
        "reversed at Z {}",
        rev[0].0
    );
    assert!((rev[0].1 - depth).abs() < 0.005, "measured {}", rev[0].1);
}
