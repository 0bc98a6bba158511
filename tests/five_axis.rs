//! The 5-axis table-table machine: its machine file, its kinematics with TCPM, and (with the
//! PLANE functions) the rotary angles and tilted coordinates a program produces.

mod common;

use common::mill5::{rx, rz, tip_of};
use common::{program, run};
use klar::config::{KinematicsConfig, MachineConfig};
use klar_interp::{AxisLetter, Pose};

#[test]
fn builtin_mill5_is_a_table_table_a_c_machine() {
    let m = MachineConfig::builtin_mill5();
    assert_eq!(m.kinematics, KinematicsConfig::TableTable);
    assert_eq!(m.table_table.tilt_pivot, [0.0, 0.0, -100.0]);
    let letters: Vec<AxisLetter> = m.axes.iter().map(|a| a.letter).collect();
    assert_eq!(
        letters,
        [
            AxisLetter::X,
            AxisLetter::Y,
            AxisLetter::Z,
            AxisLetter::A,
            AxisLetter::C
        ]
    );
    let kin = m.kinematics();
    assert_eq!(kin.machine_axes(), letters.as_slice());
}

#[test]
fn with_tcpm_a_fixed_tool_tip_follows_the_closed_form_rotation() {
    let mut kin = MachineConfig::builtin_mill5().kinematics();
    kin.set_tcpm(true);
    // The tool tip stays on workpiece point p while A and C turn; the machine X Y Z are
    // p turned by −C about Z, then about the tilt line (z = −100) by −A.
    let p = [30.0, -20.0, 10.0];
    for &(a, c) in &[(0.0, 0.0), (15.0, 30.0), (45.0, 90.0), (-60.0, 200.0)] {
        let mut pose = Pose::xyz(p[0], p[1], p[2]);
        pose.set(AxisLetter::A, a);
        pose.set(AxisLetter::C, c);
        let mut m = [0.0; 5];
        kin.to_machine(&pose, &mut m);
        let turned = rz(-c, p);
        let lifted = rx(-a, [turned[0], turned[1], turned[2] + 100.0]);
        let expect = [lifted[0], lifted[1], lifted[2] - 100.0, a, c];
        for (got, want) in m.iter().zip(expect) {
            assert!((got - want).abs() < 1e-9, "A{a} C{c}: {m:?} vs {expect:?}");
        }
    }
    // TCPM off: the axes pass through.
    kin.set_tcpm(false);
    let mut pose = Pose::xyz(p[0], p[1], p[2]);
    pose.set(AxisLetter::A, 45.0);
    let mut m = [0.0; 5];
    kin.to_machine(&pose, &mut m);
    assert_eq!(m, [30.0, -20.0, 10.0, 45.0, 0.0]);
}

#[test]
fn table_table_needs_c_and_one_tilt_axis() {
    let text = klar::config::BUILTIN_MILL5.replace("letter = \"C\"", "letter = \"B\"");
    let err = MachineConfig::parse("bad", &text).unwrap_err().to_string();
    assert!(err.contains("needs a C axis and one of A or B"), "{err}");
}

/// Rows of the commanded trace as (X, Y, Z, A, C).
fn rows(trace: &common::Trace) -> Vec<[f64; 5]> {
    let cols: Vec<Vec<f64>> = ["X", "Y", "Z", "A", "C"]
        .iter()
        .map(|l| trace.column(l).expect("axis column"))
        .collect();
    (0..cols[0].len())
        .map(|i| [cols[0][i], cols[1][i], cols[2][i], cols[3][i], cols[4][i]])
        .collect()
}

#[test]
fn m128_keeps_the_tool_tip_on_the_workpiece_while_the_table_turns() {
    let machine = MachineConfig::builtin_mill5();
    let (result, trace) = run(&program("m128_swivel.h"), &machine);
    let report = result.unwrap_or_else(|f| panic!("{}", f.error));
    // The linear drives get the machine-axis feed-forward: they follow as closely as on a
    // 3-axis mill (without it Y and Z lag by tenths of a millimetre).
    for (letter, fe) in &report.max_following_error {
        if !letter.is_rotary() {
            assert!(*fe < 0.01, "axis {letter}: following error {fe}");
        }
    }
    common::assert_within_limits(&trace, &machine);
    let rows = rows(&trace);
    let mut turned = 0;
    let (mut max_a, mut max_c) = (0.0f64, 0.0f64);
    for r in &rows {
        let (a, c) = (r[3], r[4]);
        if a.abs() < 1e-9 && c.abs() < 1e-9 {
            continue;
        }
        turned += 1;
        max_a = max_a.max(a.abs());
        max_c = max_c.max(c.abs());
        let p = tip_of([r[0], r[1], r[2]], a, c);
        // With the table turned, the tip is on the workpiece line y 10, z 5 between
        // x −20 and 20 (blocks 10–15), or at (−20, 10, 50) (blocks 18–19).
        let on_cut = (p[2] - 5.0).abs() < 1e-6 && p[0] > -20.0 - 1e-6 && p[0] < 20.0 + 1e-6;
        let at_top = (p[2] - 50.0).abs() < 1e-6 && (p[0] + 20.0).abs() < 1e-6;
        assert!(
            (p[1] - 10.0).abs() < 1e-6 && (on_cut || at_top),
            "tip {p:?} at A{a} C{c}"
        );
    }
    assert!(turned > 1000, "{turned} rows with the table turned");
    assert!((max_a - 30.0).abs() < 1e-6 && (max_c - 180.0).abs() < 1e-6);
    // The machine really moved X Y Z to hold the tip: at A 30, C 0 the tip (20, 10, 5)
    // lies at machine (20, 10·cos30 + 105·sin30, −10·sin30 + 105·cos30 − 100).
    let (s, co) = (30f64.to_radians().sin(), 30f64.to_radians().cos());
    let want = [20.0, 10.0 * co + 105.0 * s, -10.0 * s + 105.0 * co - 100.0];
    assert!(rows.iter().any(|r| (r[3] - 30.0).abs() < 1e-9
        && r[4].abs() < 1e-9
        && (r[0] - want[0]).abs() < 1e-6
        && (r[1] - want[1]).abs() < 1e-6
        && (r[2] - want[2]).abs() < 1e-6));
}

#[test]
fn plane_spatial_cuts_the_pocket_in_the_tilted_face() {
    let machine = MachineConfig::builtin_mill5();
    let (result, trace) = run(&program("plane_spatial.h"), &machine);
    let report = result.unwrap_or_else(|f| panic!("{}", f.error));
    for (letter, fe) in &report.max_following_error {
        if !letter.is_rotary() {
            assert!(*fe < 0.01, "axis {letter}: following error {fe}");
        }
    }
    let rows = rows(&trace);
    let mut cutting = 0;
    for r in &rows {
        if (r[3] - 30.0).abs() > 1e-9 || r[4].abs() > 1e-9 {
            continue;
        }
        // Tilted at A 30: workpiece tip, then into the tilted system (Rx(30)ᵀ = Rx(−30)).
        let w = tip_of([r[0], r[1], r[2]], 30.0, 0.0);
        let t = rx(-30.0, w);
        if (t[2] + 3.0).abs() < 1e-6 {
            cutting += 1;
            // On the outline: inside the 50 × 30 box, on its border band (within the
            // machine's path tolerance, which corner blending may use).
            let tol = machine.tolerance * 1.01;
            assert!(
                t[0].abs() <= 25.0 + tol && t[1].abs() <= 15.0 + tol,
                "{t:?}"
            );
            assert!(
                t[0].abs() >= 20.0 - tol || t[1].abs() >= 10.0 - tol,
                "{t:?}"
            );
        }
    }
    assert!(cutting > 100, "{cutting} rows at the cutting depth");
    let last = rows.last().expect("rows");
    assert!(
        last[3].abs() < 1e-9 && last[4].abs() < 1e-9,
        "untilted at the end"
    );
}

#[test]
fn plane_on_the_three_axis_mill_is_refused_naming_the_block() {
    let (result, _) = run(&program("plane_spatial.h"), &MachineConfig::builtin_mill());
    let err = result.expect_err("refused").error.to_string();
    assert!(
        err.contains(
            "PLANE needs rotary axes A and C (or B and C); this machine has no rotary axes"
        ),
        "{err}"
    );
    assert!(err.contains(":10:"), "{err}");
}

/// Rapids in a tilted plane move several program axes at once; through the table rotation a
/// machine axis receives a sum of them (Y: 166·cos30 + 100·sin30 ≈ 194 mm/s on mill5 at the
/// program axes' own limits). While TCPM is on the planner derates the program axes so that
/// no machine axis leaves its limits; the trace of the machine axes shows it.
#[test]
fn tilted_rapids_stay_within_the_machine_axis_limits() {
    let machine = MachineConfig::builtin_mill5();
    // the tilted pocket, and the table swivelling under M128 with the tool tip held
    for name in ["plane_spatial.h", "m128_swivel.h"] {
        let (result, trace) = run(&program(name), &machine);
        result.unwrap_or_else(|f| panic!("{name}: {}", f.error));
        common::assert_within_limits(&trace, &machine);
    }
}
