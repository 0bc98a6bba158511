//! The thread cycle G31 on the built-in lathe, read back from the trace: every pass lies at
//! the depth and flank offset the infeed rules give, Z follows pitch × measured spindle
//! angle within 5 µm on every pass, and every pass (and every start of a multi-start
//! thread) begins at its programmed spindle angle.

mod common;

use common::{program, run, temp_program};
use klar::config::MachineConfig;
use klar::testrun::test_run;

/// One pass in the trace: commanded X (radius), Z, measured Z and spindle angle per row.
struct Pass {
    x: Vec<f64>,
    z: Vec<f64>,
    z_act: Vec<f64>,
    angle: Vec<f64>,
}

/// Maximal runs of rows with commanded Z strictly inside `(z_lo, z_hi)` and commanded X
/// below `x_max`, at least `min_rows` long.
fn passes(trace: &common::Trace, z_lo: f64, z_hi: f64, x_max: f64, min_rows: usize) -> Vec<Pass> {
    let col = |n: &str| trace.column(n).unwrap_or_else(|| panic!("column {n}"));
    let (x, z, za, s) = (col("X"), col("Z"), col("Z_act"), col("S_deg"));
    let mut out = Vec::new();
    let mut cur: Option<Pass> = None;
    for i in 0..z.len() {
        if z[i] > z_lo && z[i] < z_hi && x[i] < x_max {
            let p = cur.get_or_insert_with(|| Pass {
                x: Vec::new(),
                z: Vec::new(),
                z_act: Vec::new(),
                angle: Vec::new(),
            });
            p.x.push(x[i]);
            p.z.push(z[i]);
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

/// Largest |z − (z0 − pitch·(angle − a0)/360)| over a pass: the lead error, mm.
fn lead_error(z: &[f64], angle: &[f64], pitch: f64) -> f64 {
    let (z0, a0) = (z[0], angle[0]);
    z.iter()
        .zip(angle)
        .map(|(&z, &a)| (z - (z0 - pitch * (a - a0) / 360.0)).abs())
        .fold(0.0, f64::max)
}

/// The spindle angle (mod 360) at which the measured tool passes `z_start`.
fn start_angle(p: &Pass, z_start: f64, pitch: f64) -> f64 {
    (p.angle[0] - (z_start - p.z_act[0]) * 360.0 / pitch).rem_euclid(360.0)
}

fn angle_apart(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

#[test]
fn g31_passes_sit_at_their_depths_and_offsets_and_follow_the_spindle() {
    let machine = MachineConfig::builtin_lathe();
    let path = program("lathe/thread_g31.nc");
    let checked = test_run(&path, &machine);
    assert!(checked.passed(), "{:?}", checked.errors);
    let (result, trace) = run(&path, &machine);
    result.expect("the G31 program runs");
    // G31 X20 Z-24 F1.5 U-0.9 I0.4 V2 H3 A30 Q1 B4 P3 C30 from X24 Z6.
    // V2: ⌈0.9 / 0.4⌉ = 3 infeeds, the first reduced to 0.9 − 2·0.4 = 0.1, the last 0.4
    // split into 0.2, 0.1, 0.05, 0.05; then one air cut at the full depth.
    let steps = [0.1, 0.4, 0.2, 0.1, 0.05, 0.05, 0.0];
    let depths: Vec<f64> = steps
        .iter()
        .scan(0.0, |s, x| {
            *s += x;
            Some(*s)
        })
        .collect();
    // H3: alternately left (−Z) and right (+Z) by d·tan 30°, the air cut like the last pass.
    let t = 30f64.to_radians().tan();
    let shift = |k: usize| {
        let side = if k.min(5).is_multiple_of(2) {
            -1.0
        } else {
            1.0
        };
        side * depths[k] * t
    };
    let pitch = 1.5;
    // the thread proper of every pass lies within Z 2 … -21 moved by its shift (≤ 0.52)
    let found = passes(&trace, -20.4, 1.4, 10.5, 100);
    assert_eq!(found.len(), depths.len(), "one pass per depth");
    let (mut worst_cmd, mut worst_act): (f64, f64) = (0.0, 0.0);
    for (k, p) in found.iter().enumerate() {
        let x0 = 10.0 - depths[k];
        assert!(
            p.x.iter().all(|&x| (x - x0).abs() < 1e-9),
            "pass {k} at X {} instead of {x0}",
            p.x[0]
        );
        worst_cmd = worst_cmd.max(lead_error(&p.z, &p.angle, pitch));
        worst_act = worst_act.max(lead_error(&p.z_act, &p.angle, pitch));
        // the run-in ends at Z 2 + shift with the spindle at C30: a wrong shift of s mm
        // would show as s·360/1.5 degrees
        let a = start_angle(p, 2.0 + shift(k), pitch);
        assert!(angle_apart(a, 30.0) < 1.0, "pass {k} starts at {a}°");
    }
    assert!(worst_cmd < 0.005, "commanded lead error {worst_cmd} mm");
    assert!(worst_act < 0.005, "measured lead error {worst_act} mm");
    println!(
        "G31 M20x1.5, 7 passes: lead error commanded {:.2} µm, measured {:.2} µm",
        worst_cmd * 1e3,
        worst_act * 1e3
    );
}

#[test]
fn g31_cuts_each_start_of_a_two_start_thread_at_its_own_angle() {
    // D2 C45: starts at 45° and 225°, two depths (IC2 V1: 0.15, 0.3) each.
    let text = "%two.nc\nMACHINING\nN1 T1\nN2 G97 S600 M3\nN3 G0 X24 Z5\n\
                N4 G31 X20 Z-15 F2 U-0.3 IC2 V1 D2 C45 B3 P2\nN5 M30\nEND\n";
    let path = temp_program("two_start.nc", text);
    let machine = MachineConfig::builtin_lathe();
    let (result, trace) = run(&path, &machine);
    result.expect("runs");
    let found = passes(&trace, -13.0, 2.0, 10.5, 50);
    assert_eq!(found.len(), 4);
    for (i, p) in found.iter().enumerate() {
        let depth = [0.15, 0.3][i / 2];
        assert!(
            (p.x[0] - (10.0 - depth)).abs() < 1e-9,
            "pass {i} X {}",
            p.x[0]
        );
        assert!(lead_error(&p.z_act, &p.angle, 2.0) < 0.005);
        let want = [45.0, 225.0][i % 2];
        let a = start_angle(p, 2.0, 2.0);
        assert!(
            angle_apart(a, want) < 1.0,
            "pass {i} starts at {a}°, not {want}°"
        );
    }
}
