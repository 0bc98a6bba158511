//! TCPM switched on and off continues from where the machine stands: M128/M129 and FUNCTION
//! TCPM / FUNCTION RESET TCPM before or after a tilt, with or without every axis in the first
//! block, after PLANE … TURN/STAY and cycle 19, around M91 blocks, tool changes and datum
//! shifts. Each program runs on the simulated 5-axis table-table mill and every machine axis
//! of its trace stays within its velocity, acceleration and jerk limits by finite differences
//! (a switch that re-read the position in the wrong frame would step tens of mm in one cycle).
//! The held point is checked against the table-table formula written out here.

mod common;

use common::mill5::tip_of;
use common::{assert_within_limits, commanded, run, temp_program};
use klar::config::{BUILTIN_MILL5, MachineConfig};

fn mill5() -> MachineConfig {
    MachineConfig::parse("mill5", BUILTIN_MILL5).expect("mill5 parses")
}

/// Runs `body` on mill5, asserts the run ends normally within every limit and returns the
/// commanded X Y Z A C columns.
fn run_clean(name: &str, body: &str) -> Vec<Vec<f64>> {
    let text = format!(
        "BEGIN PGM T MM\nTOOL DEF 5 L+80 R+4\nTOOL DEF 6 L+120 R+3\n{body}\nEND PGM T MM\n"
    );
    let path = temp_program(&format!("{name}.h"), &text);
    let machine = mill5();
    let (result, trace) = run(&path, &machine);
    if let Err(e) = &result {
        panic!("{name}: {}", e.error);
    }
    assert_within_limits(&trace, &machine);
    commanded(&trace, &["X", "Y", "Z", "A", "C"])
}

const TILT_THEN_M128: &str = "L X+0 Y+0 Z+100 A+0 C+0 R0 FMAX\n\
    L A+76.323 C+0 FMAX\nL M128\nL Z-18.674 F3000\nL M129\nL Z+150 FMAX";

#[test]
fn m128_after_a_tilt_holds_the_tool_and_moves_only_what_is_programmed() {
    let cols = run_clean("tilt_m128", TILT_THEN_M128);
    // While the block `L Z-18.674` runs, the tool tip stays on the workpiece point under it
    // at the switch, in X and Y: find the samples at A = 76.323 and Z still moving.
    let a = 76.323;
    let at_switch = (0..cols[0].len())
        .find(|&i| (cols[3][i] - a).abs() < 1e-9)
        .expect("A reaches its angle");
    let m0 = [cols[0][at_switch], cols[1][at_switch], cols[2][at_switch]];
    let tip0 = tip_of(m0, a, 0.0);
    let tips: Vec<[f64; 3]> = (at_switch..cols[0].len())
        .map(|i| tip_of([cols[0][i], cols[1][i], cols[2][i]], cols[3][i], cols[4][i]))
        .collect();
    // the tip reaches the programmed depth ...
    let tip = tips
        .iter()
        .copied()
        .find(|t| (t[2] + 18.674).abs() < 1e-6)
        .expect("the tip reaches Z-18.674");
    // ... on the workpiece point that was under it at the switch
    assert!(
        (tip[0] - tip0[0]).abs() < 1e-6 && (tip[1] - tip0[1]).abs() < 1e-6,
        "tip {tip:?}, at the switch {tip0:?}"
    );
}

#[test]
fn every_ordering_of_tilt_and_tcpm_stays_within_the_limits() {
    let cases: [(&str, &str); 12] = [
        ("tilt_m128", TILT_THEN_M128),
        (
            "function_tcpm",
            "L X+0 Y+0 Z+100 A+0 C+0 R0 FMAX\nL A+40 C+30 FMAX\n\
             FUNCTION TCPM F TCP AXIS POS PATHCTRL AXIS\nL Z+20 F3000\nL X+10\n\
             FUNCTION RESET TCPM\nL Z+120 FMAX",
        ),
        (
            "m128_before_tilt",
            "L X+10 Y+5 Z+80 A+0 C+0 R0 FMAX\nL M128\nL A+30 C+45 F2000\nL X+20 F3000\n\
             L M129\nL Z+150 FMAX",
        ),
        (
            "all_axes_first",
            "L X+0 Y+0 Z+100 A+0 C+0 R0 FMAX\nL A+50 FMAX\nL X+5 Y+5 Z+30 F3000 M128\n\
             L X+15\nL M129\nL Z+150 FMAX",
        ),
        (
            "m129_inside_a_move",
            "L X+0 Y+0 Z+60 A+0 C+0 R0 FMAX\nL M128\nL A+30 C+20 F2000\n\
             L X+30 A+0 F2000 M129\nL Z+150 FMAX",
        ),
        (
            "plane_turn_then_m128",
            "L X+0 Y+0 Z+100 A+0 C+0 R0 FMAX\n\
             PLANE SPATIAL SPA+25 SPB+0 SPC+0 TURN FMAX\nL M128\nL X+5 Y+5 F3000\nL M129\n\
             PLANE RESET TURN FMAX\nL Z+150 FMAX",
        ),
        (
            "plane_stay_then_tcpm",
            "L X+0 Y+0 Z+100 A+0 C+0 R0 FMAX\n\
             PLANE SPATIAL SPA+20 SPB+0 SPC+0 STAY\nL A+Q120 C+Q122 FMAX\n\
             FUNCTION TCPM F TCP AXIS POS PATHCTRL AXIS\nL Z+10 F3000\n\
             FUNCTION RESET TCPM\nPLANE RESET STAY\nL A+0 C+0 FMAX\nL Z+150 FMAX",
        ),
        (
            "cycle_19",
            "L X+0 Y+0 Z+100 A+0 C+0 R0 FMAX\nL A-30 C+60 FMAX\n\
             CYCL DEF 19.0 WORKING PLANE\nCYCL DEF 19.1 A-30 C+60\nL M128\nL Z+20 F3000\n\
             L M129\nCYCL DEF 19.0 WORKING PLANE\nCYCL DEF 19.1\nL A+0 C+0 FMAX\nL Z+150 FMAX",
        ),
        (
            "m91_around_tcpm",
            "L X+0 Y+0 Z+100 A+0 C+0 R0 FMAX\nL A+35 FMAX\nL M128\nL Z+30 F3000\nL M129\n\
             L Z+250 R0 FMAX M91\nL A+0 FMAX",
        ),
        (
            "tool_changes",
            "TOOL CALL 5 Z S4000\nL X+0 Y+0 Z+100 A+0 C+0 R0 FMAX\nL A+30 FMAX\nL M128\n\
             L Z+20 F3000\nL M129\nTOOL CALL 6 Z S4000\nL M128\nL Z+25 F3000\nL M129\n\
             L Z+150 FMAX",
        ),
        (
            "datum_shift_tilted",
            "L X+0 Y+0 Z+100 A+0 C+0 R0 FMAX\nCYCL DEF 7.0 DATUM SHIFT\nCYCL DEF 7.1 X+20\n\
             CYCL DEF 7.2 Y-10\nL A+30 C+15 FMAX\nL M128\nL Z+20 F3000\nL X+5\nL M129\n\
             CYCL DEF 7.0 DATUM SHIFT\nCYCL DEF 7.1 X+0\nCYCL DEF 7.2 Y+0\nL Z+150 FMAX",
        ),
        (
            "tcpm_twice_at_angles",
            "L X+0 Y+0 Z+100 A+0 C+0 R0 FMAX\nL A+30 C+45 FMAX\nL M128\nL M129\nL M128\n\
             L C+90 F2000\nL M129\nL C+0 FMAX\nL Z+150 FMAX",
        ),
    ];
    for (name, body) in cases {
        run_clean(name, body);
    }
}
