//! PLANE … TURN on the table-table machine: only the rotary axes move, the machine's linear
//! axes stand still, and the program then positions the linear axes in the tilted plane.

mod common;

use common::mill5::{rx, rz, tip_of};
use common::{run, temp_program};
use klar::config::MachineConfig;

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

const PROGRAM: &str = "BEGIN PGM TURN MM
TOOL CALL 1 Z S6000
L Z+50 R0 FMAX M3
L X+20 Y+10 FMAX
L Z+5 FMAX
PLANE SPATIAL SPA+30 SPB+0 SPC+45 TURN F2000 SEQ+ COORD ROT
L X+10 Y-5 Z+20 F1000
L Z+60 FMAX
PLANE RESET TURN F2000
L Z+100 FMAX M30
END PGM TURN MM
";

#[test]
fn plane_turn_holds_the_linear_axes_and_the_next_move_reaches_its_point() {
    let machine = MachineConfig::builtin_mill5();
    let path = temp_program("plane_turn.h", PROGRAM);
    let (result, trace) = run(&path, &machine);
    result.unwrap_or_else(|f| panic!("{}", f.error));
    common::assert_within_limits(&trace, &machine);
    let cols: Vec<Vec<f64>> = ["X", "Y", "Z", "A", "C"]
        .iter()
        .map(|l| trace.column(l).expect("axis column"))
        .collect();
    let row = |i: usize| [cols[0][i], cols[1][i], cols[2][i], cols[3][i], cols[4][i]];
    let n = cols[0].len();
    let at = |i: usize, a: f64, c: f64| {
        let r = row(i);
        (r[3] - a).abs() < 1e-9 && (r[4] - c).abs() < 1e-9
    };
    // PLANE … TURN: from the first row with A off zero until A 30, C 45 are reached, the
    // machine X Y Z stay at (20, 10, 5), where the tool stood (A = C = 0: machine = workpiece).
    let start = (0..n).find(|&i| !at(i, 0.0, 0.0)).expect("the table turns");
    let tilted = (start..n).find(|&i| at(i, 30.0, 45.0)).expect("A30 C45");
    assert!(tilted - start > 100, "{} rows turning", tilted - start);
    let mut worst = 0.0f64;
    for i in start..=tilted {
        let r = row(i);
        worst = worst.max(dist([r[0], r[1], r[2]], [20.0, 10.0, 5.0]));
    }
    assert!(worst < 1e-3, "linear axes left their place by {worst} mm");
    // The rotary axes really turned both: half way through A passed 15.
    assert!((start..tilted).any(|i| (row(i)[3] - 15.0).abs() < 0.5));
    // The following L X+10 Y-5 Z+20 is in the tilted system R = Rz(45)·Rx(30): its
    // workpiece point is R·(10, −5, 20). The corner into L Z+60 may be crossed within the
    // path tolerance (0.01 mm), passing within twice that of the corner point; L Z+60 ends at R·(10, −5, 60), where the path stops for
    // PLANE RESET, and the tool tip reaches that point exactly.
    let tip = |i: usize| {
        let r = row(i);
        tip_of([r[0], r[1], r[2]], 30.0, 45.0)
    };
    let corner = rz(45.0, rx(30.0, [10.0, -5.0, 20.0]));
    let closest = (tilted..n)
        .filter(|&i| at(i, 30.0, 45.0))
        .map(|i| dist(tip(i), corner))
        .fold(f64::INFINITY, f64::min);
    assert!(
        closest <= 0.02 + 1e-9,
        "the tip passed {closest} mm from {corner:?}"
    );
    let goal = rz(45.0, rx(30.0, [10.0, -5.0, 60.0]));
    let reached = (tilted..n).any(|i| at(i, 30.0, 45.0) && dist(tip(i), goal) < 1e-6);
    assert!(reached, "the tip never reached {goal:?}");
    // PLANE RESET TURN: the axes turn back to zero with X Y Z held where L Z+60 left them.
    let back = (tilted..n)
        .rev()
        .find(|&i| at(i, 30.0, 45.0))
        .expect("tilted");
    let zero = (back..n).find(|&i| at(i, 0.0, 0.0)).expect("back at zero");
    let held = [row(back)[0], row(back)[1], row(back)[2]];
    let top = rz(45.0, rx(30.0, [10.0, -5.0, 60.0]));
    assert!(dist(tip_of(held, 30.0, 45.0), top) < 1e-6, "{held:?}");
    let mut worst = 0.0f64;
    for i in back..=zero {
        let r = row(i);
        worst = worst.max(dist([r[0], r[1], r[2]], held));
    }
    assert!(worst < 1e-3, "linear axes left their place by {worst} mm");
    assert!(zero - back > 100, "{} rows turning back", zero - back);
}
