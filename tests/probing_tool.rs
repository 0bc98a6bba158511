//! The stylus ball's radius from the tool table: the probe called as a tool with a radius
//! touches with that radius, a tool without one with `[probe] radius`
//! (`machines/probing-mill.toml`, part top at Z−0.25 in preset 1). Cycle 0 leaves the ball
//! centre at the trigger in Q117, the surface in Q10: their difference is the radius used.
//! The probe's length L runs from the spindle to the stylus tip; klar's axes carry the tip,
//! so L changes neither the axis positions nor the surface found, only the spindle's
//! position in Q117 (the trigger position with the stylus length not taken off).

mod common;

use klar::config::MachineConfig;
use klar_interp::{AxisLetter, Interpreter, Op, OpKind};
use std::path::Path;

/// The top of the part in program coordinates: the machine file's Z offset.
const TOP: f64 = -0.25;

fn machine() -> MachineConfig {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing-mill.toml");
    MachineConfig::load(&p).expect("probing machine loads")
}

/// Probes the top at X0 Y0 downward after `call` (tool definitions and the TOOL CALL).
fn probe_top(m: &MachineConfig, name: &str, call: &str) -> Interpreter {
    probe_with(
        m,
        name,
        call,
        "TCH PROBE 0.0 REF. PLANE Q10 Z-\nTCH PROBE 0.1 X+0 Y+0 Z+10",
    )
    .0
}

/// Runs `probe` (touch-probe blocks) after `call`; the interpreter and the end points of
/// every straight move in machine X, Y, Z.
fn probe_with(
    m: &MachineConfig,
    name: &str,
    call: &str,
    probe: &str,
) -> (Interpreter, Vec<[f64; 3]>) {
    let text = format!(
        "BEGIN PGM BALL MM
BLK FORM 0.1 Z X-50 Y-40 Z-30
BLK FORM 0.2 X+50 Y+40 Z+0
{call}
L Z+50 R0 FMAX
{probe}
M30
END PGM BALL MM
"
    );
    let path = common::temp_program(name, &text);
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    let mut ends = Vec::new();
    for op in it.by_ref() {
        let op: Op = op.unwrap_or_else(|d| panic!("{d}"));
        if let OpKind::Line { to, .. } = op.kind {
            ends.push([to[AxisLetter::X], to[AxisLetter::Y], to[AxisLetter::Z]]);
        }
    }
    (it, ends)
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

/// Cycle 417 probing the top at X0 Y0 (nominal height 0); the surface lands in Q160.
const CYCLE_417: &str = "TCH PROBE 417 DATUM IN TS AXIS ~
  Q263=+0 ;1ST POINT 1ST AXIS ~
  Q264=+0 ;1ST POINT 2ND AXIS ~
  Q294=+0 ;1ST POINT 3RD AXIS ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q305=+0 ;NUMBER IN TABLE ~
  Q333=+0 ;DATUM ~
  Q303=+1 ;MEAS. VALUE TRANSFER";

#[test]
fn the_probes_length_moves_no_axis_and_no_surface() {
    let m = machine();
    let old0 = "TCH PROBE 0.0 REF. PLANE Q10 Z-\nTCH PROBE 0.1 X+0 Y+0 Z+10";
    // two probes with the same ball (R 2) and lengths 50 and 80.25 (L 80 with DL +0.25)
    let short = "TOOL DEF 7 L+50 R+2\nTOOL CALL 7 Z S0";
    let long = "TOOL DEF 8 L+80 R+2\nTOOL CALL 8 Z S0 DL+0.25";
    let (a, a_moves) = probe_with(&m, "len_a.h", short, old0);
    let (b, b_moves) = probe_with(&m, "len_b.h", long, old0);
    // the surface is the part's top whatever the length
    close("Q10 with L 50", a.q(10), TOP);
    close("Q10 with L 80.25", b.q(10), TOP);
    // the axes carry the tool tip: every move ends at the same place
    assert_eq!(a_moves.len(), b_moves.len(), "the same moves");
    assert!(!a_moves.is_empty());
    for (i, (p, q)) in a_moves.iter().zip(&b_moves).enumerate() {
        for k in 0..3 {
            close(&format!("move {i} axis {k}"), p[k], q[k]);
        }
    }
    // Q117: the ball centre at the trigger (top plus the radius) with the length added
    close("Q117 with L 50", a.q(117), TOP + 2.0 + 50.0);
    close("Q117 with L 80.25", b.q(117), TOP + 2.0 + 80.25);
    close("Q117 difference", b.q(117) - a.q(117), 30.25);
    // the in-plane coordinates carry no length
    close("Q115", b.q(115), a.q(115));
    close("Q116", b.q(116), 0.0);
    // cycle 417: the same surface height with either probe
    let (a, _) = probe_with(&m, "len_417a.h", short, CYCLE_417);
    let (b, _) = probe_with(&m, "len_417b.h", long, CYCLE_417);
    close("Q160 with L 50", a.q(160), TOP);
    close("Q160 with L 80.25", b.q(160), TOP);
}
