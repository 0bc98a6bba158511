//! The stylus ball's radius from the tool table: the probe called as a tool with a radius
//! touches with that radius, a tool without one with `[probe] radius`
//! (`machines/probing-mill.toml`, part top at Z−0.25 in preset 1). Cycle 0 leaves the ball
//! centre at the trigger in Q117, the surface in Q10: their difference is the radius used.

mod common;

use klar::config::MachineConfig;
use klar_interp::Interpreter;
use std::path::Path;

/// The top of the part in program coordinates: the machine file's Z offset.
const TOP: f64 = -0.25;

fn machine() -> MachineConfig {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing-mill.toml");
    MachineConfig::load(&p).expect("probing machine loads")
}

/// Probes the top at X0 Y0 downward after `call` (tool definitions and the TOOL CALL).
fn probe_top(m: &MachineConfig, name: &str, call: &str) -> Interpreter {
    let text = format!(
        "BEGIN PGM BALL MM
BLK FORM 0.1 Z X-50 Y-40 Z-30
BLK FORM 0.2 X+50 Y+40 Z+0
{call}
L Z+50 R0 FMAX
TCH PROBE 0.0 REF. PLANE Q10 Z-
TCH PROBE 0.1 X+0 Y+0 Z+10
M30
END PGM BALL MM
"
    );
    let path = common::temp_program(name, &text);
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    for op in it.by_ref() {
        op.unwrap_or_else(|d| panic!("{d}"));
    }
    it
}

fn close(what: &str, got: f64, want: f64) {
    assert!(
        (got - want).abs() <= 1e-9,
        "{what}: got {got}, expected {want}"
    );
}

#[test]
fn the_probe_tools_radius_is_the_ball_radius() {
    let mut m = machine();
    // the machine's own probe data say 1.5 mm; the tool table says otherwise
    if let Some(p) = m.probe.as_mut() {
        p.radius = 1.5;
    }
    // tool 1 of the machine file: R 2
    let it = probe_top(&m, "ball_t1.h", "TOOL CALL 1 Z S0");
    close("Q10", it.q(10), TOP);
    close("Q117 with tool 1", it.q(117), TOP + 2.0);
    // a probe defined in the program with R 3, called with a DR that is an allowance and
    // does not change the ball
    let it = probe_top(
        &m,
        "ball_t5.h",
        "TOOL DEF 5 L+0 R+3\nTOOL CALL 5 Z S0 DR+0.4",
    );
    close("Q10", it.q(10), TOP);
    close("Q117 with tool 5", it.q(117), TOP + 3.0);
    // a tool without a radius: the probe's own
    let it = probe_top(&m, "ball_t6.h", "TOOL DEF 6 L+0 R+0\nTOOL CALL 6 Z S0");
    close("Q117 with tool 6", it.q(117), TOP + 1.5);
}
