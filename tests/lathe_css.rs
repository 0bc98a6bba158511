//! Constant surface speed (G96) under the G26 speed limit, read back from the trace: the
//! commanded spindle speed follows the tool's diameter every servo cycle against the closed
//! form n = Vc·1000/(π·D), is clamped at the limit towards the centre, the feed per
//! revolution holds on the measured speed meanwhile, and G97 returns to constant rpm.

mod common;

use common::{program, run, temp_program};
use klar::config::MachineConfig;
use klar::testrun::test_run;

#[test]
fn g96_face_cut_to_the_centre_follows_the_diameter_up_to_the_g26_limit() {
    let machine = MachineConfig::builtin_lathe();
    let (result, trace) = run(&program("lathe/facing_g96.nc"), &machine);
    result.expect("the facing program runs");
    let col = |n: &str| trace.column(n).unwrap_or_else(|| panic!("column {n}"));
    let (x, z, s, a) = (col("X"), col("Z"), col("S"), col("S_deg"));
    // G96 S200 under G26 S2500; the face cut G1 X0 at Z0 from diameter 60 (radius 30).
    let (vc, limit, feed) = (200.0, 2500.0, 0.15);
    let closed = |radius: f64| {
        let d = 2.0 * radius;
        if d <= 0.0 {
            limit
        } else {
            (vc * 1000.0 / (std::f64::consts::PI * d)).min(limit)
        }
    };
    let rows: Vec<usize> = (0..x.len())
        .filter(|&i| z[i].abs() < 1e-9 && x[i] < 30.0 - 1e-9)
        .collect();
    assert!(rows.len() > 1000, "{} rows in the face cut", rows.len());
    // Every cycle: the command within the smallest step the run sends (0.1 rpm).
    let worst = rows
        .iter()
        .map(|&i| (s[i] - closed(x[i])).abs())
        .fold(0.0, f64::max);
    assert!(worst <= 0.1 + 1e-9, "S off the closed form by {worst} rpm");
    // Rising towards the centre, at the limit from D = Vc·1000/(π·2500) = 25.46 mm on.
    let d_limit = vc * 1000.0 / (std::f64::consts::PI * limit);
    assert!(rows.iter().any(|&i| s[i] < 1100.0), "starts near 1061 rpm");
    for &i in &rows {
        if 2.0 * x[i] < d_limit - 0.01 {
            assert_eq!(s[i], limit, "clamped at D {}", 2.0 * x[i]);
        }
    }
    assert_eq!(s[*rows.last().unwrap_or(&0)], limit);
    // Feed per revolution on the measured speed while the spindle speeds up: X (radius)
    // advances F per measured revolution, within two encoder counts and one cycle's lag
    // of the speed over its whole change (see tests/lathe_feed_per_rev.rs). Judged past
    // the path's acceleration from rest and before its braking at the centre.
    let rows: Vec<usize> = rows
        .into_iter()
        .filter(|&i| x[i] < 29.0 && x[i] > 1.0)
        .collect();
    let n_min = rows.iter().map(|&i| s[i]).fold(f64::INFINITY, f64::min);
    let tol = feed * 2.0 / 4096.0 + feed / 60.0 * 0.001 * (limit - n_min);
    // X (the radius) falls towards the centre: −F per revolution.
    let off = common::per_revolution_error(&rows, &x, &a, -feed);
    assert!(
        off < tol,
        "radius per revolution off by {off} mm (tolerance {tol})"
    );
    // G97 S800: the turning cut at radius 30 below Z0 runs at a constant 800 rpm.
    let after: Vec<usize> = (0..x.len())
        .filter(|&i| z[i] < -1e-9 && (x[i] - 30.0).abs() < 1e-9)
        .collect();
    assert!(after.len() > 100);
    assert!(after.iter().all(|&i| s[i] == 800.0));
    println!(
        "G96 S200 G26 S2500 face cut: S within {worst:.3} rpm of Vc·1000/(π·D); radius per \
         measured revolution off by {:.3} µm (tolerance {:.3} µm)",
        off * 1e3,
        tol * 1e3
    );
}

#[test]
fn g26_without_a_positive_speed_is_a_diagnostic_at_its_word() {
    let machine = MachineConfig::builtin_lathe();
    for (block, col, want) in [
        ("N2 G26 S0", 8, "must be positive"),
        ("N2 G26", 4, "G26 needs the speed limit S"),
    ] {
        let text = format!("%b.nc\nMACHINING\nN1 T1\n{block}\nN3 G96 S200 M3\nN4 M30\nEND\n");
        let path = temp_program("b.nc", &text);
        let report = test_run(&path, &machine);
        let first = report
            .errors
            .first()
            .unwrap_or_else(|| panic!("{block}: accepted"));
        assert_eq!((first.line, first.col), (4, col), "{block}: {first}");
        assert!(first.message.contains(want), "{block}: {first}");
    }
}
