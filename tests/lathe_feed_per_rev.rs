//! Feed per revolution (lathe G95, Klartext M136) following the measured spindle speed,
//! read back from the trace: while the simulated spindle slows under a cut, the tool still
//! advances F per measured revolution; feed hold and override still act.

mod common;

use common::{Trace, program};
use klar::config::{BUILTIN_MILL, MachineConfig};
use klar::runtime::{Run, RunOptions};

/// Runs `path` on the built-in lathe, putting a chip of `section` mm² on the spindle while
/// the commanded Z lies in `(z_lo, z_hi)`; `act` may hold or override the run by machine
/// time. Returns the trace.
fn run_with_load(
    path: &std::path::Path,
    section: f64,
    window: (f64, f64),
    act: impl FnMut(&mut Run<'_, '_>, f64),
) -> Trace {
    run_on(
        &MachineConfig::builtin_lathe(),
        path,
        section,
        (1, window),
        act,
    )
}

/// Runs `path` on `machine`, putting a chip of `section` mm² on the spindle while commanded
/// axis `axis` (its index) lies in the window; `act` as in [`run_with_load`].
fn run_on(
    machine: &MachineConfig,
    path: &std::path::Path,
    section: f64,
    (axis, (z_lo, z_hi)): (usize, (f64, f64)),
    mut act: impl FnMut(&mut Run<'_, '_>, f64),
) -> Trace {
    let mut buf = Vec::new();
    {
        let mut run = Run::start(
            path,
            machine,
            RunOptions {
                realtime: false,
                trace: Some(&mut buf),
            },
        )
        .unwrap_or_else(|f| panic!("{}", f.error));
        let mut loaded = false;
        loop {
            let s = run.status();
            let z = s.commanded[axis];
            let cut = z < z_hi && z > z_lo;
            if cut != loaded {
                run.set_spindle_load(if cut { section } else { 0.0 });
                loaded = cut;
            }
            act(&mut run, s.t);
            match run.step() {
                Ok(true) => {}
                Ok(false) => break,
                Err(e) => panic!("{e}"),
            }
        }
        run.finish(None).unwrap_or_else(|f| panic!("{}", f.error));
    }
    Trace::parse(&String::from_utf8(buf).expect("utf-8")).expect("trace parses")
}

/// Over every stretch of one measured revolution inside the cut (rows with commanded Z in
/// `(z_lo, z_hi)` on the turning diameter 40, radius 20): the largest |ΔZ − F·Δangle/360|, mm, and the slowest and fastest
/// measured speed, rpm (from the angle over 10 ms).
fn per_rev_error(trace: &Trace, f: f64, (z_lo, z_hi): (f64, f64)) -> (f64, f64, f64) {
    let col = |n: &str| trace.column(n).unwrap_or_else(|| panic!("column {n}"));
    let (x, z, a) = (col("X"), col("Z"), col("S_deg"));
    let rows: Vec<usize> = (0..z.len())
        .filter(|&i| z[i] < z_hi && z[i] > z_lo && (x[i] - 20.0).abs() < 1e-9)
        .collect();
    assert_eq!(
        rows.last().map(|l| l - rows[0] + 1),
        Some(rows.len()),
        "one pass"
    );
    assert!(rows.len() > 1000, "{} rows in the cut", rows.len());
    // Z falls into the part: −F per revolution.
    let worst = common::per_revolution_error(&rows, &z, &a, -f);
    let speeds: Vec<f64> = rows
        .iter()
        .filter(|&&i| i >= 10)
        .map(|&i| (a[i] - a[i - 10]) / 0.010 / 6.0)
        .collect();
    let slow = speeds.iter().copied().fold(f64::INFINITY, f64::min);
    let fast = speeds.iter().copied().fold(0.0, f64::max);
    (worst, slow, fast)
}

#[test]
fn g95_advances_f_per_measured_revolution_while_the_spindle_dips() {
    // F0.3 at S1000 from Z2 to Z-40; a chip of 2 mm² from Z-5 to Z-25 (droop 10 %/mm²: the
    // spindle sinks towards 800 rpm with its 50 ms time constant, and back).
    let f = 0.3;
    let window = (-38.0, 0.0);
    let trace = run_with_load(
        &program("lathe/feed_per_rev.nc"),
        2.0,
        (-25.0, -5.0),
        |_, _| {},
    );
    let (worst, slow, fast) = per_rev_error(&trace, f, window);
    assert!(slow < 830.0, "the spindle dips under the cut: {slow} rpm");
    // The tolerance: two encoder counts at the ends of the revolution (F·2/4096), and the
    // one servo cycle the speed is measured behind, over the whole change of speed
    // (F/60 · period · Δn) — the feed on the commanded speed would be off by F·Δn/n.
    let tol = f * 2.0 / 4096.0 + f / 60.0 * 0.001 * (fast - slow);
    assert!(
        worst < tol,
        "distance per revolution off by {worst} mm (tolerance {tol} mm)"
    );
    let commanded_off = f * (fast - slow) / fast;
    assert!(
        commanded_off > 20.0 * tol,
        "the dip must be large enough to tell"
    );
    println!(
        "G95 F0.3 at S1000 dipping to {slow:.0} rpm: distance per revolution off by {:.3} µm \
         (tolerance {:.3} µm; on the commanded speed it would be {:.1} µm)",
        worst * 1e3,
        tol * 1e3,
        commanded_off * 1e3
    );
}

#[test]
fn feed_hold_and_override_still_act_on_a_feed_per_revolution() {
    let f = 0.3;
    let mut held_at = None;
    let trace = run_with_load(
        &program("lathe/feed_per_rev.nc"),
        2.0,
        (-25.0, -5.0),
        |run, t| {
            let z = run.status().commanded[1];
            // Half feed from Z-10; a hold of 0.3 s from Z-30.
            if z < -10.0 {
                run.set_feed_override(0.5);
            }
            if z < -30.0 && held_at.is_none() {
                run.hold();
                held_at = Some(t);
            }
            if held_at.is_some_and(|h| t > h + 0.3) {
                run.resume();
            }
        },
    );
    let col = |n: &str| trace.column(n).unwrap_or_else(|| panic!("column {n}"));
    let (z, a) = (col("Z"), col("S_deg"));
    // At 50 % override the tool advances F/2 per measured revolution (within the cut and
    // past the override's ramp).
    let half = f * 0.5;
    let (worst, slow, fast) = per_rev_error(&trace, half, (-28.0, -12.0));
    let tol = half * 2.0 / 4096.0 + half / 60.0 * 0.001 * (fast - slow);
    assert!(
        worst < tol,
        "half feed per revolution off by {worst} mm (tolerance {tol})"
    );
    // The hold stops the tool for a while with the spindle turning.
    let still = (1..z.len())
        .filter(|&i| z[i] < -30.0 && z[i] > -40.0 && z[i] == z[i - 1] && a[i] > a[i - 1])
        .count();
    assert!(still > 200, "held for {still} cycles");
}

#[test]
fn m136_feeds_the_mill_per_measured_revolution() {
    // The built-in mill with a spindle that slows under cut like the lathe's.
    let text = BUILTIN_MILL.replace(
        "max_rpm = 12000.0",
        "max_rpm = 12000.0\nbackend = { kind = \"sim\", load_droop = 0.1 }",
    );
    let machine = MachineConfig::parse("mill with droop", &text).expect("machine parses");
    // F0.2 per revolution at S1000 along X from 0 to 30 at Z-2; a chip of 2 mm² from X5 to
    // X20.
    let trace = run_on(
        &machine,
        &program("feed_per_rev_m136.h"),
        2.0,
        (0, (5.0, 20.0)),
        |_, _| {},
    );
    let col = |n: &str| trace.column(n).unwrap_or_else(|| panic!("column {n}"));
    let (x, z, a) = (col("X"), col("Z"), col("S_deg"));
    let f = 0.2;
    let rows: Vec<usize> = (0..x.len())
        .filter(|&i| x[i] > 1.0 && x[i] < 29.0 && (z[i] + 2.0).abs() < 1e-9)
        .collect();
    assert!(rows.len() > 1000);
    let speeds: Vec<f64> = rows
        .iter()
        .map(|&i| (a[i] - a[i - 10]) / 0.010 / 6.0)
        .collect();
    let slow = speeds.iter().copied().fold(f64::INFINITY, f64::min);
    let fast = speeds.iter().copied().fold(0.0, f64::max);
    assert!(slow < 830.0, "the spindle dips: {slow} rpm");
    let tol = f * 2.0 / 4096.0 + f / 60.0 * 0.001 * (fast - slow);
    let worst = common::per_revolution_error(&rows, &x, &a, f);
    assert!(
        worst < tol,
        "X per revolution off by {worst} mm (tolerance {tol})"
    );
}

#[test]
fn a_spindle_fault_in_a_feed_per_revolution_stops_the_path_and_says_so() {
    // The simulated spindle faults 2 s into the run, inside the G95 cut.
    let text = format!(
        "{}\n[[fault]]\nkind = \"spindle\"\nat = 2.0\n",
        klar::config::BUILTIN_LATHE
    );
    let machine = MachineConfig::parse("lathe with a spindle fault", &text).expect("parses");
    let (result, trace) = common::run(&program("lathe/feed_per_rev.nc"), &machine);
    let failure = result.expect_err("the fault stops the run");
    assert!(
        matches!(failure.error, klar::runtime::RunError::Spindle { .. }),
        "{}",
        failure.error
    );
    // Stopped on the path soon after the fault, not after a wait for the spindle.
    let end = trace.t.last().copied().unwrap_or(0.0);
    assert!(end < 3.0, "ended at {end} s");
}
