//! Lathe threading (G33) geared to the measured spindle angle, read back from the trace:
//! on every pass the axes follow pitch × measured angle (also while the simulated spindle
//! slows under the cut), every pass starts at the programmed spindle angle, and `klar check`
//! refuses what the machine cannot cut before anything moves.

mod common;

use common::{program, run, temp_program};
use klar::config::{BUILTIN_LATHE, MachineConfig};
use klar::testrun::test_run;

/// One thread pass found in the trace: the rows whose commanded Z lies within the thread
/// proper (between the end of the run-in and the start of the run-out).
struct Pass {
    /// Commanded X (radius), Z, measured X, Z, spindle angle, per row.
    x: Vec<f64>,
    z: Vec<f64>,
    x_act: Vec<f64>,
    z_act: Vec<f64>,
    angle: Vec<f64>,
}

/// The passes of a trace: maximal runs of rows with commanded Z strictly inside
/// `(z_lo, z_hi)` and commanded X below `x_max`, each at least `min_rows` long.
fn passes(trace: &common::Trace, z_lo: f64, z_hi: f64, x_max: f64, min_rows: usize) -> Vec<Pass> {
    let col = |n: &str| trace.column(n).unwrap_or_else(|| panic!("column {n}"));
    let (x, z, xa, za, s) = (col("X"), col("Z"), col("X_act"), col("Z_act"), col("S_deg"));
    let mut out = Vec::new();
    let mut cur: Option<Pass> = None;
    for i in 0..z.len() {
        let inside = z[i] > z_lo && z[i] < z_hi && x[i] < x_max;
        if inside {
            let p = cur.get_or_insert_with(|| Pass {
                x: Vec::new(),
                z: Vec::new(),
                x_act: Vec::new(),
                z_act: Vec::new(),
                angle: Vec::new(),
            });
            p.x.push(x[i]);
            p.z.push(z[i]);
            p.x_act.push(xa[i]);
            p.z_act.push(za[i]);
            p.angle.push(s[i]);
        } else if let Some(p) = cur.take()
            && p.z.len() >= min_rows
        {
            out.push(p);
        }
    }
    out
}

/// Largest |z − (z0 − pitch·(angle − a0)/360)| over a pass, with the reference (z0, a0)
/// taken at its first row: the lead error, mm. `z` picks the commanded or measured values.
fn lead_error(z: &[f64], angle: &[f64], pitch: f64, dir: f64) -> f64 {
    let (z0, a0) = (z[0], angle[0]);
    z.iter()
        .zip(angle)
        .map(|(&z, &a)| (z - (z0 - dir * pitch * (a - a0) / 360.0)).abs())
        .fold(0.0, f64::max)
}

/// The spindle angle (mod 360) at which the tool, as measured, passes `z_start`: the angle
/// of the pass's first row moved back by the measured Z still to go, at `pitch` per
/// revolution.
fn start_angle(p: &Pass, z_start: f64, pitch: f64, dir: f64) -> f64 {
    (p.angle[0] - dir * (z_start - p.z_act[0]) * 360.0 / pitch).rem_euclid(360.0)
}

/// Circular distance of two angles, degrees.
fn angle_apart(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

#[test]
fn g33_passes_follow_the_measured_spindle_angle_and_hit_the_same_groove() {
    let machine = MachineConfig::builtin_lathe();
    let (result, trace) = run(&program("lathe/thread_g33.nc"), &machine);
    result.expect("the thread program runs");
    assert!(
        trace.columns.iter().any(|c| c == "S"),
        "{:?}",
        trace.columns
    );
    // Run-in B4 from Z6 and run-out P3 before Z-30: the thread proper is Z2 … Z-27.
    let found = passes(&trace, -27.0, 2.0, 10.5, 100);
    assert_eq!(found.len(), 4, "four passes");
    let pitch = 1.5;
    let mut starts = Vec::new();
    let mut worst_cmd: f64 = 0.0;
    let mut worst_act: f64 = 0.0;
    for (k, p) in found.iter().enumerate() {
        // Each pass at its own depth, X still.
        let x0 = p.x[0];
        assert!(p.x.iter().all(|&x| (x - x0).abs() < 1e-12));
        assert!(
            (x0 - (9.8 - 0.2 * k as f64)).abs() < 1e-9,
            "pass {k} at X {x0}"
        );
        worst_cmd = worst_cmd.max(lead_error(&p.z, &p.angle, pitch, 1.0));
        worst_act = worst_act.max(lead_error(&p.z_act, &p.angle, pitch, 1.0));
        starts.push(start_angle(p, 2.0, pitch, 1.0));
    }
    assert!(worst_cmd < 0.005, "commanded lead error {worst_cmd} mm");
    assert!(worst_act < 0.005, "measured lead error {worst_act} mm");
    // Every pass starts at C30 (within the angle one servo cycle's prediction may be off).
    let spread = starts
        .iter()
        .flat_map(|a| starts.iter().map(move |b| angle_apart(*a, *b)))
        .fold(0.0, f64::max);
    for a in &starts {
        assert!(angle_apart(*a, 30.0) < 1.0, "start angle {a}");
    }
    assert!(spread < 1.0, "phase spread {spread}°");
    // The later passes cut (0.2 mm infeed × 1.5 mm pitch): the spindle measurably slows,
    // and the lead still holds. Speed from the angle over 10 ms windows (1 ms rows).
    let slowest = found
        .iter()
        .flat_map(|p| (10..p.angle.len()).map(|i| (p.angle[i] - p.angle[i - 10]) / 0.010 / 6.0))
        .fold(f64::INFINITY, f64::min);
    assert!(
        slowest < 790.0,
        "the spindle should slow under the cut: {slowest} rpm"
    );
    println!(
        "G33 M20x1.5, 4 passes at 800 rpm (dips to {slowest:.0} rpm): lead error commanded \
         {:.2} µm, measured {:.2} µm; phase spread {spread:.4}°",
        worst_cmd * 1e3,
        worst_act * 1e3
    );
}

#[test]
fn taper_and_multi_start_threads_in_m4() {
    // A taper thread (X 1 mm radius over 20 mm Z) cut in M4, two starts 180° apart.
    let text = "%taper.nc\nMACHINING\nN1 T1\nN2 G97 S600 M4\nN3 G0 X30 Z5\n\
                N4 G0 X20\nN5 G33 X22 Z-20 F2 B3 P3 C0\nN6 G0 X30\nN7 G0 Z5\n\
                N8 G0 X20\nN9 G33 X22 Z-20 F2 B3 P3 C180\nN10 G0 X30\nN11 M30\nEND\n";
    let path = temp_program("taper.nc", text);
    let machine = MachineConfig::builtin_lathe();
    let checked = test_run(&path, &machine);
    assert!(checked.passed(), "{:?}", checked.errors);
    let (result, trace) = run(&path, &machine);
    result.expect("runs");
    // From Z5 to Z-20: run-in to Z2, run-out from Z-17. X radius 10 → 11 over 25 mm of Z.
    let found = passes(&trace, -17.0, 2.0, 12.0, 100);
    assert_eq!(found.len(), 2);
    let (pitch, dir) = (2.0, -1.0);
    let mut starts = Vec::new();
    for p in &found {
        assert!(lead_error(&p.z, &p.angle, pitch, dir) < 0.005);
        assert!(lead_error(&p.z_act, &p.angle, pitch, dir) < 0.005);
        // X on the taper: radius 10 + (5 − Z)/25, so X follows the angle too.
        for (&x, &z) in p.x.iter().zip(&p.z) {
            assert!(
                (x - (10.0 + (5.0 - z) / 25.0)).abs() < 1e-9,
                "X {x} at Z {z}"
            );
        }
        let x_from_angle: Vec<f64> = p
            .angle
            .iter()
            .map(|a| p.x[0] + (p.angle[0] - a) * pitch / 360.0 / 25.0)
            .collect();
        let worst =
            p.x.iter()
                .zip(&x_from_angle)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
        assert!(worst < 0.005, "X lead error {worst}");
        // In M4 the angle counts down; the start angle is the spindle's own angle.
        starts.push((p.angle[0] - dir * (2.0 - p.z[0]) * 360.0 / pitch).rem_euclid(360.0));
    }
    assert!(angle_apart(starts[0], 0.0) < 1.0, "{starts:?}");
    assert!(angle_apart(starts[1], 180.0) < 1.0, "{starts:?}");
}

#[test]
fn face_thread_measures_the_pitch_along_x() {
    // H1: a face thread from radius 20 to radius 5 at Z0, 1 mm per revolution along X.
    let text = "%face.nc\nMACHINING\nN1 T1\nN2 G97 S300 M3\nN3 G0 X44 Z1\nN4 G0 Z0\n\
                N5 G33 X10 F1 B2 P2 H1\nN6 G0 Z2\nN7 M30\nEND\n";
    let path = temp_program("face.nc", text);
    let machine = MachineConfig::builtin_lathe();
    let (result, trace) = run(&path, &machine);
    result.expect("runs");
    let x = trace.column("X").unwrap();
    let z = trace.column("Z").unwrap();
    let s = trace.column("S_deg").unwrap();
    // Thread proper: radius 20 − 2 = 18 down to 5 + 2 = 7, at Z 0.
    let rows: Vec<usize> = (0..x.len())
        .filter(|&i| x[i] < 18.0 && x[i] > 7.0 && z[i].abs() < 1e-9)
        .collect();
    assert!(rows.len() > 100);
    let (x0, a0) = (x[rows[0]], s[rows[0]]);
    let worst = rows
        .iter()
        .map(|&i| (x[i] - (x0 - (s[i] - a0) / 360.0)).abs())
        .fold(0.0, f64::max);
    assert!(worst < 0.005, "face lead error {worst}");
}

#[test]
fn check_refuses_a_pitch_the_axes_cannot_follow_and_a_short_run_in() {
    let machine = MachineConfig::builtin_lathe();
    // 10 mm pitch at 3000 rpm: Z would need 500 mm/s, above its 330 mm/s.
    let fast = temp_program(
        "fast.nc",
        "%fast.nc\nMACHINING\nN1 T1\nN2 G97 S3000 M3\nN3 G0 X20 Z5\n\
         N4 G33 Z-40 F10\nN5 M30\nEND\n",
    );
    let report = test_run(&fast, &machine);
    let e = &report.errors;
    assert!(
        e.iter()
            .any(|d| d.block == Some(4) && d.message.contains("axis Z would need 30000 mm/min")),
        "{e:?}"
    );
    // 3 mm pitch at 2000 rpm is 100 mm/s: 100²/(2·3000) = 1.67 mm of run-in at least.
    let short = temp_program(
        "short.nc",
        "%short.nc\nMACHINING\nN1 T1\nN2 G97 S2000 M3\nN3 G0 X20 Z5\n\
         N4 G33 Z-40 F3 B0.5 P2\nN5 M30\nEND\n",
    );
    let report = test_run(&short, &machine);
    assert!(
        report
            .errors
            .iter()
            .any(|d| d.block == Some(4) && d.message.contains("run-in B0.5 is too short")),
        "{:?}",
        report.errors
    );
    // And the run refuses it before anything moves.
    let (result, trace) = run(&fast, &machine);
    assert!(result.is_err());
    assert!(trace.rows.is_empty(), "nothing moved");
}

#[test]
fn check_refuses_threading_on_a_spindle_without_an_encoder() {
    // The built-in lathe with its spindle behind a Modbus VFD.
    let (head, _) = BUILTIN_LATHE
        .split_once("[spindle]")
        .expect("the lathe has a spindle section");
    let text = format!(
        "{head}[spindle]\nmax_rpm = 5000.0\n[spindle.backend]\nkind = \"modbus\"\n\
         [spindle.backend.vfd]\nunit = 1\nmax_rpm = 6000.0\n[spindle.backend.vfd.serial]\n\
         port = \"/dev/null\"\nbaud = 115200\nparity = \"none\"\n\
         [spindle.backend.vfd.profile]\npreset = \"delta\"\nrpm_per_hz = 60.0\n"
    );
    let machine = MachineConfig::parse("vfd lathe", &text).expect("machine parses");
    let report = test_run(&program("lathe/thread_g33.nc"), &machine);
    let first = report.errors.first().expect("refused");
    assert_eq!(first.block, Some(21), "{first}");
    assert!(
        first
            .message
            .contains("Modbus VFD, which measures no spindle angle"),
        "{first}"
    );
}

#[test]
fn a_stop_requested_inside_a_pass_takes_effect_after_the_pass_and_its_retract() {
    use klar::runtime::{Run, RunOptions};
    let machine = MachineConfig::builtin_lathe();
    let path = program("lathe/thread_g33.nc");
    let mut run = Run::start(
        &path,
        &machine,
        RunOptions {
            realtime: false,
            trace: None,
        },
    )
    .unwrap_or_else(|f| panic!("{}", f.error));
    let z = |r: &mut Run<'_, '_>| r.status().commanded[1];
    // Step until the first pass is inside the thread (Z below 0 with X at the pass depth).
    let mut requested = None;
    let mut end = None;
    for _ in 0..200_000 {
        let s = run.status();
        if requested.is_none() && s.commanded[0] < 10.0 && s.commanded[1] < 0.0 {
            run.request_stop();
            requested = Some(s.commanded[1]);
        }
        match run.step() {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => {
                end = Some((e, z(&mut run), run.status().commanded[0]));
                break;
            }
        }
    }
    let at = requested.expect("the pass was reached");
    assert!(
        at > -27.0,
        "the stop was requested inside the thread, at Z {at}"
    );
    let (e, z_end, x_end) = end.expect("the stop ended the run");
    assert!(matches!(e, klar::runtime::RunError::Stopped { .. }), "{e}");
    // The pass ran to its end point Z-30 at its depth, then the retract N22 G0 X24 (radius
    // 12) out of the groove, and the run stopped there: not in the groove, not on the way
    // back to Z6.
    assert!((z_end + 30.0).abs() < 1e-9, "stopped at Z {z_end}");
    assert!((x_end - 12.0).abs() < 1e-9, "stopped at X {x_end}");
}

#[test]
fn bad_g33_words_are_diagnostics_at_their_word() {
    let machine = MachineConfig::builtin_lathe();
    for (block, want_col, want) in [
        ("N4 G33 Z-40", 4, "G33 needs the thread pitch F"),
        ("N4 G33 Z-40 F1.5 H2", 18, "expected 0 (pitch along Z)"),
        ("N4 G33 Z-40 F1.5 E0.1", 18, "variable pitch"),
        ("N4 G33 Z-40 F-1", 13, "must be positive"),
        ("N4 G33 Z-40 F1.5 B-2", 18, "must be a length"),
        ("N4 G33 X30 F1.5", 4, "does not move Z"),
        ("N4 G33 Z-40 F1.5 B30 P20", 4, "longer than the pass"),
    ] {
        let text = format!(
            "%bad.nc\nMACHINING\nN1 T1\nN2 G97 S500 M3\nN3 G0 X20 Z5\n{block}\nN5 M30\nEND\n"
        );
        let path = temp_program("bad.nc", &text);
        let report = test_run(&path, &machine);
        let first = report
            .errors
            .first()
            .unwrap_or_else(|| panic!("{block}: accepted"));
        assert_eq!((first.line, first.col), (6, want_col), "{block}: {first}");
        assert!(first.message.contains(want), "{block}: {first}");
    }
}
