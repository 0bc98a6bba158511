//! Touch-probe cycles 403 and 405 on the simulated mill with a rotary table
//! (`machines/probing-rotary.toml`): the part sits on the table 3.2 mm / −1.7 mm off and turned
//! 1.5° about Z, preset 1 (X+100 Y+50 Z−60) lies on the table axis C. The cycles align the
//! part by turning C; the expected turns and the part's place afterwards are worked out here
//! from the placement alone (a table turned by c carries the part by −c about its axis).

mod common;

use common::probing::{OFF, TURN, c400, close, program_text, turn};

use klar::config::MachineConfig;
use klar_interp::{AxisLetter, Interpreter, Op, OpKind};
use std::path::Path;

/// The bore of the machine file: nominal centre.
const BORE: [f64; 2] = [0.0, 25.0];
/// The simulated part and probe are exact: results agree to far below a nanometre.
const EXACT: f64 = 1e-9;

fn machine() -> MachineConfig {
    common::probing::machine("probing-rotary.toml")
}

/// Program coordinates of part point `q` with the table at C = `c`.
fn program_of(q: [f64; 2], c: f64) -> [f64; 2] {
    let t = turn(q, TURN);
    turn([OFF[0] + t[0], OFF[1] + t[1]], -c)
}

const C403: &str = "TCH PROBE 403 ROT IN ROTARY AXIS ~
  Q263=-30 ;1ST POINT 1ST AXIS ~
  Q264=-40 ;1ST POINT 2ND AXIS ~
  Q265=+30 ;2ND POINT 1ST AXIS ~
  Q266=-40 ;2ND POINT 2ND AXIS ~
  Q272=+1 ;MEASURING AXIS ~
  Q267=+1 ;TRAVERSE DIRECTION ~
  Q261=-10 ;MEASURING HEIGHT ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+1 ;MOVE TO CLEARANCE ~
  Q312=+6 ;COMPENSATION AXIS ~
  Q337=+0 ;SET TO ZERO ~
  Q305=+0 ;NUMBER IN TABLE ~
  Q303=+1 ;MEAS. VALUE TRANSFER ~
  Q380=+0 ;REFERENCE ANGLE
";

const C405: &str = "TCH PROBE 405 ROT IN C AXIS ~
  Q321=+0 ;CENTER IN 1ST AXIS ~
  Q322=+25 ;CENTER IN 2ND AXIS ~
  Q262=+16 ;NOMINAL DIAMETER ~
  Q325=+0 ;STARTING ANGLE ~
  Q247=+90 ;STEPPING ANGLE ~
  Q261=-5 ;MEASURING HEIGHT ~
  Q320=+0 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+0 ;MOVE TO CLEARANCE ~
  Q337=+0 ;SET TO ZERO ~
  Q305=+0 ;NUMBER IN TABLE ~
  Q303=+1 ;MEAS. VALUE TRANSFER
";

/// 412 on the bore, writing no preset (row 9).
const C412: &str = "TCH PROBE 412 PRESET INSIDE CIRCLE ~
  Q321=+0 ;CENTER IN 1ST AXIS ~
  Q322=+25 ;CENTER IN 2ND AXIS ~
  Q262=+16 ;NOMINAL DIAMETER ~
  Q325=+0 ;STARTING ANGLE ~
  Q247=+90 ;STEPPING ANGLE ~
  Q261=-5 ;MEASURING HEIGHT ~
  Q320=+0 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+0 ;MOVE TO CLEARANCE ~
  Q305=+9 ;NUMBER IN TABLE ~
  Q331=+0 ;DATUM ~
  Q332=+0 ;DATUM ~
  Q303=+1 ;MEAS. VALUE TRANSFER ~
  Q381=+0 ;PROBE IN TS AXIS ~
  Q365=+1 ;TYPE OF TRAVERSE
";

/// Runs `body` after the prelude on the rotary machine: the interpreter and every op.
fn run_body(name: &str, body: &str) -> (Interpreter, Vec<Op>) {
    let (it, ops, _) = common::probing::run_body(&machine(), "ROT", name, body);
    (it, ops)
}

/// The C positions the moves that turn C end on.
fn c_turns(ops: &[Op]) -> Vec<f64> {
    ops.iter()
        .filter_map(|op| match &op.kind {
            OpKind::Line { from, to, .. } if from[AxisLetter::C] != to[AxisLetter::C] => {
                Some(to[AxisLetter::C])
            }
            _ => None,
        })
        .collect()
}

#[test]
fn cycle_403_turns_the_table_so_that_400_then_finds_the_edge_square() {
    let (it, ops) = run_body("probe403.h", &format!("{C403}{}{C412}", c400(1)));
    // Q150 is 400's, after the turn: the edge lies along X
    close("Q150 of 400 after 403", it.q(150), 0.0, EXACT);
    let turns = c_turns(&ops);
    assert_eq!(turns.len(), 1, "one turn of C: {turns:?}");
    close("C after 403", turns[0], TURN, EXACT);
    // the part went round the table axis with it: the bore centre where the closed form puts it
    let c = program_of(BORE, TURN);
    close("Q151 of 412", it.q(151), c[0], EXACT);
    close("Q152 of 412", it.q(152), c[1], EXACT);
    // the table axis is not the part's turning point: the offset turned, the bore lies off Y
    assert!((c[0] - OFF[0]).abs() > 0.01, "{c:?}");
}

#[test]
fn cycle_403_leaves_q150_the_measured_angle_and_q337_zeroes_the_c_display() {
    let body = C403.replace("Q337=+0", "Q337=+1");
    let (it, ops) = run_body("probe403z.h", &body);
    close("Q150", it.q(150), TURN, EXACT);
    close("C after 403", c_turns(&ops)[0], TURN, EXACT);
    // preset row 1 takes the machine position of C: C now reads 0
    let (table, active) = it.presets();
    assert_eq!(active, Some(1));
    let row = table.expect("preset table").row(1).expect("row 1");
    close(
        "preset C",
        row[AxisLetter::C.index()].expect("C written"),
        TURN,
        EXACT,
    );
    close("program C", it.position()[AxisLetter::C], 0.0, EXACT);
}

#[test]
fn cycle_405_turns_the_bore_centre_onto_its_nominal_angle() {
    let (it, ops) = run_body("probe405.h", C405);
    // the bore centre as set up, before any turn; it shall lie at 90° (on +Y)
    let c0 = program_of(BORE, 0.0);
    let want = c0[1].atan2(c0[0]).to_degrees() - 90.0;
    close("Q150", it.q(150), want, EXACT);
    close("C after 405", c_turns(&ops)[0], want, EXACT);
    let (it, _) = run_body("probe405b.h", &format!("{C405}{C412}"));
    close("Q151 of 412 after 405", it.q(151), 0.0, EXACT);
    close(
        "Q152 of 412 after 405",
        it.q(152),
        c0[0].hypot(c0[1]),
        EXACT,
    );
}

#[test]
fn rotary_cycles_refuse_what_they_cannot_do() {
    let m = machine();
    for (name, body, says) in [
        ("bad312.h", C403.replace("Q312=+6", "Q312=+4"), "Q312=4"),
        ("bad337.h", C403.replace("Q337=+0", "Q337=+2"), "Q337=2"),
        ("bad272.h", C403.replace("Q272=+1", "Q272=+3"), "Q272=3"),
    ] {
        let text = program_text("ROT", &body);
        let path = common::temp_program(name, &text);
        let mut it = m.open_program(&path, m.start_pose()).expect("opens");
        let err = it
            .by_ref()
            .find_map(|op| op.err())
            .expect("the cycle is refused");
        assert!(err.to_string().contains(says), "{name}: {err}");
        // nothing turned or moved after the refusal: C never left 0
        assert_eq!(it.position()[AxisLetter::C], 0.0);
    }
}

#[test]
fn the_example_program_checks_and_runs_to_the_aligned_table() {
    let m = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing-rotary.toml");
    let p = common::program("probing/rotary_align.h");
    let (ok, out, err) =
        common::klar_cli(&["check", "--machine", common::arg(&m), common::arg(&p)]);
    assert!(ok, "check: {out}{err}");
    let (report, trace) = common::run(&p, &machine());
    report.expect("the run ends normally");
    let c_col = trace
        .columns
        .iter()
        .position(|c| c == "C")
        .expect("C column");
    let last = trace.rows.last().expect("rows");
    // 403 turns C by 1.5°; the bore centre then lies at the turned offset plus its nominal
    // place, and 405 turns C on by that centre's angle from +Y
    let b = program_of(BORE, TURN);
    let want = TURN + b[1].atan2(b[0]).to_degrees() - 90.0;
    close("machine C at the end", last[c_col], want, 1e-6);
}
