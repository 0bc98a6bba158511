//! A feed hold during a pass geared to the spindle: the pass runs to its end, the retract
//! after it runs, and only then do the axes stand still until the resume; the thread is
//! then finished in the same groove. The same for a rigid tap, which finishes its stroke
//! in, the reversal and the stroke out before it holds. Read back from the trace.

mod common;

use common::hold::run_with_hold;
use common::program;
use common::threads::{angle_apart, lead_error, passes, start_angle};
use klar::config::MachineConfig;
use klar::runtime::{Run, RunOptions};
use klar::trace::Trace;

/// Rows the axes must stand still before the test resumes.
const REST_ROWS: usize = 400;

fn lathe_canopen() -> MachineConfig {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/lathe-canopen.toml");
    MachineConfig::load(&file).expect("machine loads")
}

/// `thread_g33.nc` with a hold asked for half-way through the second pass (N31, X19.2).
fn hold_in_a_thread_pass(machine: &MachineConfig) {
    let held = run_with_hold(&program("lathe/thread_g33.nc"), machine, REST_ROWS, |s| {
        (s.commanded[0] - 9.6).abs() < 1e-9 && s.commanded[1] < -12.0
    });
    let trace = &held.trace;
    let col = |n: &str| trace.column(n).expect("column");
    let (t, x, z, xa, za) = (&trace.t, col("X"), col("Z"), col("X_act"), col("Z_act"));
    let rows: Vec<usize> = (0..t.len())
        .filter(|&i| t[i] > held.asked && t[i] <= held.resumed)
        .collect();
    // The second pass (radius 9.6) runs on to its end point Z-30 after the request.
    let pass_end = rows
        .iter()
        .copied()
        .find(|&i| z[i] <= -30.0 + 1e-9)
        .expect("the pass reaches its end point");
    assert!(
        rows[..]
            .iter()
            .take_while(|&&i| i < pass_end)
            .all(|&i| (x[i] - 9.6).abs() < 1e-9 && z[i] < z[i - 1])
    );
    // Then the retract to X12 (diameter 24) at Z-30, and the axes stand there, commanded
    // and measured, until the resume: not in the groove, not on the way back to Z6.
    let rest = rows
        .iter()
        .copied()
        .find(|&i| (x[i] - 12.0).abs() < 1e-9)
        .expect("the retract ends");
    assert!(rest > pass_end);
    for &i in rows.iter().filter(|&&i| i >= pass_end) {
        assert!(
            (z[i] + 30.0).abs() < 1e-9,
            "row {i}: Z {} before the resume",
            z[i]
        );
        assert!(
            (9.6 - 1e-9..=12.0 + 1e-9).contains(&x[i]),
            "row {i}: X {}",
            x[i]
        );
    }
    let standing: Vec<usize> = rows.iter().copied().filter(|&i| i >= rest).collect();
    assert!(standing.len() >= REST_ROWS, "stood {} rows", standing.len());
    let settled = standing.len() / 2;
    for &i in &standing {
        assert!((x[i] - 12.0).abs() < 1e-9 && (z[i] + 30.0).abs() < 1e-9);
    }
    for &i in &standing[settled..] {
        assert!(
            (xa[i] - 12.0).abs() < 1e-3 && (za[i] + 30.0).abs() < 1e-3,
            "row {i}: measured X {} Z {}",
            xa[i],
            za[i]
        );
    }
    // After the resume the thread is finished: four passes, each locked to the measured
    // angle, all in the same groove (start angle C30).
    let found = passes(trace, -27.0, 2.0, 10.5, 50);
    assert_eq!(found.len(), 4, "four passes");
    for (k, p) in found.iter().enumerate() {
        assert!((p.x[0] - (9.8 - 0.2 * k as f64)).abs() < 1e-9, "pass {k}");
        let lead = lead_error(&p.z, &p.angle, 1.5, 1.0);
        let lead_act = lead_error(&p.z_act, &p.angle, 1.5, 1.0);
        assert!(
            lead < 0.005 && lead_act < 0.005,
            "pass {k}: {lead} {lead_act} mm"
        );
        let a = start_angle(p, 2.0, 1.5, 1.0);
        assert!(angle_apart(a, 30.0) < 1.0, "pass {k} starts at {a}°");
    }
    // The held pass itself crossed the request: rows before and after it.
    let second = &found[1];
    let first_row = second.rows[0];
    let last_row = second.rows[second.rows.len() - 1];
    assert!(t[first_row] < held.asked && t[last_row] > held.asked);
    // The program ran to its end: it ends where the same program without a hold ends.
    let (result, plain) = common::run(&program("lathe/thread_g33.nc"), machine);
    result.expect("runs without a hold");
    let (n, m) = (z.len() - 1, plain.t.len() - 1);
    let (px, pz) = (col_of(&plain, "X"), col_of(&plain, "Z"));
    assert!(
        (x[n] - px[m]).abs() < 1e-9 && (z[n] - pz[m]).abs() < 1e-9,
        "ends at X {} Z {}, without the hold at X {} Z {}",
        x[n],
        z[n],
        px[m],
        pz[m]
    );
}

fn col_of(trace: &Trace, name: &str) -> Vec<f64> {
    trace.column(name).expect("column")
}

#[test]
fn a_hold_in_a_thread_pass_finishes_the_pass_and_the_retract() {
    hold_in_a_thread_pass(&MachineConfig::builtin_lathe());
}

#[test]
fn a_hold_in_a_thread_pass_on_canopen_drives_finishes_the_pass_and_the_retract() {
    hold_in_a_thread_pass(&lathe_canopen());
}

/// `tapping_g36.nc` (M8×1.25 from Z2 to Z-12) with a hold asked for half-way down the
/// stroke in, at Z-5 by the run's status.
fn hold_in_a_rigid_tap(machine: &MachineConfig) {
    let held = run_with_hold(&program("lathe/tapping_g36.nc"), machine, REST_ROWS, |s| {
        s.line == 13 && s.commanded[0].abs() < 1e-9 && s.commanded[1] < -5.0
    });
    let trace = &held.trace;
    let (t, z, za, s) = (
        &trace.t,
        col_of(trace, "Z"),
        col_of(trace, "Z_act"),
        col_of(trace, "S_deg"),
    );
    let rows: Vec<usize> = (0..t.len())
        .filter(|&i| t[i] > held.asked && t[i] <= held.resumed)
        .collect();
    // The request came inside the stroke in: the slide was going down, half-way.
    let z_asked = held.asked_at.commanded[1];
    assert!((-5.1..-5.0).contains(&z_asked), "asked at Z {z_asked}");
    let first = rows[0];
    assert!(
        z[first] < z[first - 1] && z[first] > -12.0 + 1.0,
        "row {first} after the request: Z {} after {}",
        z[first],
        z[first - 1]
    );
    // The tap goes on to the bottom and back out to its start Z2, geared to the angle all
    // the way (through the reversal), and stands there until the resume.
    let bottom = rows.iter().map(|&i| z[i]).fold(f64::INFINITY, f64::min);
    assert!((bottom + 12.0).abs() < 0.01, "went down to Z {bottom}");
    let rest = rows
        .iter()
        .copied()
        .find(|&i| (z[i] - 2.0).abs() < 1e-9)
        .expect("the tap comes back out");
    let geared: Vec<usize> = rows.iter().copied().filter(|&i| i <= rest).collect();
    let zs: Vec<f64> = geared.iter().map(|&i| z[i]).collect();
    let zas: Vec<f64> = geared.iter().map(|&i| za[i]).collect();
    let angles: Vec<f64> = geared.iter().map(|&i| s[i]).collect();
    let lead = lead_error(&zs, &angles, 1.25, 1.0);
    let lead_act = lead_error(&zas, &angles, 1.25, 1.0);
    assert!(
        lead < 0.005 && lead_act < 0.005,
        "lead {lead} {lead_act} mm"
    );
    let standing: Vec<usize> = rows.iter().copied().filter(|&i| i >= rest).collect();
    assert!(standing.len() >= REST_ROWS, "stood {} rows", standing.len());
    assert!(standing.iter().all(|&i| (z[i] - 2.0).abs() < 1e-9));
    // After the resume the program goes on: G0 Z20.
    assert!(
        z.iter()
            .skip(standing[standing.len() - 1])
            .any(|&v| (v - 20.0).abs() < 1e-9)
    );
}

#[test]
fn a_hold_in_a_rigid_tap_finishes_the_tap_and_holds_out_of_the_hole() {
    hold_in_a_rigid_tap(&MachineConfig::builtin_lathe());
}

#[test]
fn a_hold_in_a_rigid_tap_on_canopen_drives_finishes_the_tap() {
    hold_in_a_rigid_tap(&lathe_canopen());
}

#[test]
fn feed_override_does_not_act_inside_a_thread_pass() {
    // Feed override 30 % from half-way through the second pass: the pass stays locked to
    // the spindle (a slide at 30 % would leave the pitch by millimetres), every pass in the
    // same groove; the override holds for the moves after it.
    let machine = MachineConfig::builtin_lathe();
    let file = program("lathe/thread_g33.nc");
    let mut buf = Vec::new();
    let mut set_at = None;
    {
        let mut run = Run::start(
            &file,
            &machine,
            RunOptions {
                realtime: false,
                trace: Some(&mut buf),
            },
        )
        .unwrap_or_else(|f| panic!("{}", f.error));
        loop {
            let status = run.status();
            if set_at.is_none()
                && (status.commanded[0] - 9.6).abs() < 1e-9
                && status.commanded[1] < -12.0
            {
                assert_eq!(run.set_feed_override(0.3), 0.3);
                set_at = Some(status.t);
            }
            match run.step() {
                Ok(true) => {}
                Ok(false) => break,
                Err(e) => panic!("run failed: {e}"),
            }
        }
        assert_eq!(run.status().feed_override, 0.3);
        run.finish(None).unwrap_or_else(|f| panic!("{}", f.error));
    }
    let set_at = set_at.expect("the pass was reached");
    let trace = Trace::parse(&String::from_utf8(buf).expect("UTF-8")).expect("trace parses");
    let found = passes(&trace, -27.0, 2.0, 10.5, 50);
    assert_eq!(found.len(), 4);
    let second = &found[1];
    assert!(
        trace.t[second.rows[0]] < set_at && trace.t[second.rows[second.rows.len() - 1]] > set_at
    );
    for (k, p) in found.iter().enumerate() {
        let lead = lead_error(&p.z, &p.angle, 1.5, 1.0);
        assert!(lead < 0.005, "pass {k}: lead error {lead} mm");
        let a = start_angle(p, 2.0, 1.5, 1.0);
        assert!(angle_apart(a, 30.0) < 1.0, "pass {k} starts at {a}°");
    }
}

#[test]
fn a_hold_in_a_g31_pass_rests_after_the_cycles_retract() {
    let machine = MachineConfig::builtin_lathe();
    let file = program("lathe/thread_g31.nc");
    let (result, plain) = common::run(&file, &machine);
    result.expect("runs without a hold");
    let plain_passes = passes(&plain, -20.0, 1.0, 10.5, 50);
    assert!(plain_passes.len() >= 3, "{} passes", plain_passes.len());
    // Half-way through the second pass: below Z-10 at its depth.
    let second_x = plain_passes[1].x[0];
    let held = run_with_hold(&file, &machine, REST_ROWS, |s| {
        (s.commanded[0] - second_x).abs() < 1e-9 && s.commanded[1] < -10.0
    });
    let trace = &held.trace;
    let (t, x, z) = (&trace.t, col_of(trace, "X"), col_of(trace, "Z"));
    let rows: Vec<usize> = (0..t.len())
        .filter(|&i| t[i] > held.asked && t[i] <= held.resumed)
        .collect();
    // The pass runs on at its depth to its end; from there only X moves (the retract out
    // of the thread, whose outer radius is 10, up to the blend into the way back) and the
    // axes rest outside it until the resume.
    let pass_end = rows
        .iter()
        .copied()
        .find(|&i| (x[i] - second_x).abs() > 1e-9)
        .expect("the pass ends")
        - 1;
    let rest_x = x[rows[rows.len() - 1]];
    assert!(rest_x > 10.0, "rests at X {rest_x}, in the thread");
    for &i in rows.iter().filter(|&&i| i >= pass_end) {
        // Within the corner blend of the retract into the way back.
        assert!(
            (z[i] - z[pass_end]).abs() <= machine.tolerance,
            "row {i}: Z moved to {}",
            z[i]
        );
    }
    let standing = rows
        .iter()
        .filter(|&&i| (x[i] - rest_x).abs() < 1e-12)
        .count();
    assert!(standing >= REST_ROWS, "stood {standing} rows");
    // The cycle then ran to its end: the same passes in the same grooves as without a hold.
    let found = passes(trace, -20.0, 1.0, 10.5, 50);
    assert_eq!(found.len(), plain_passes.len());
    for (k, (p, q)) in found.iter().zip(&plain_passes).enumerate() {
        assert!((p.x[0] - q.x[0]).abs() < 1e-9, "pass {k} depth");
        let lead = lead_error(&p.z, &p.angle, 1.5, 1.0);
        assert!(
            lead < 0.005,
            "pass {k}: lead error {lead} mm over Z {} .. {}, without the hold {}",
            p.z[0],
            p.z[p.z.len() - 1],
            lead_error(&q.z, &q.angle, 1.5, 1.0)
        );
        let (a, b) = (p.angle[0].rem_euclid(360.0), q.angle[0].rem_euclid(360.0));
        let shift = (p.z[0] - q.z[0]) * 360.0 / 1.5;
        assert!(
            angle_apart(a + shift, b) < 1.0,
            "pass {k}: phase {a}° vs {b}° (Z {} vs {})",
            p.z[0],
            q.z[0]
        );
    }
}
