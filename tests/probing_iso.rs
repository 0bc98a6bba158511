//! TNC ISO touch-probe cycles (`G4nn` with `Q…=` lines) on `machines/probing-mill.toml`: the
//! example program `programs/iso/probing_412.i` against its Klartext twin written here (the
//! same op stream and the same results), and the results against the part's placement (3.2 mm
//! / −1.7 mm off, turned 1.5° about preset 1).

mod common;

use klar::config::MachineConfig;
use klar_interp::{Interpreter, OpKind};
use std::path::Path;

const OFF: [f64; 2] = [3.2, -1.7];
const TURN: f64 = 1.5;
/// The large bore of the machine file: nominal centre and diameter.
const BORE: [f64; 2] = [-25.0, -10.0];
const BORE_D: f64 = 24.0;
/// The simulated probe is exact: results agree with the closed forms to far below 1 nm.
const EXACT: f64 = 1e-9;

/// The Klartext twin of `programs/iso/probing_412.i`.
const TWIN: &str = "BEGIN PGM PROBING_412 MM
BLK FORM 0.1 Z X-50 Y-40 Z-30
BLK FORM 0.2 X+50 Y+40 Z+0
TOOL CALL 1 Z S0
L Z+40 R0 FMAX M5
TCH PROBE 400 BASIC ROTATION ~
  Q263=-20 ;1ST POINT 1ST AXIS ~
  Q264=-40 ;1ST POINT 2ND AXIS ~
  Q265=+25 ;2ND POINT 1ST AXIS ~
  Q266=-40 ;2ND POINT 2ND AXIS ~
  Q272=+1 ;MEASURING AXIS ~
  Q267=+1 ;TRAVERSE DIRECTION ~
  Q261=-12 ;MEASURING HEIGHT ~
  Q320=+4 ;SET-UP CLEARANCE ~
  Q260=+25 ;CLEARANCE HEIGHT ~
  Q301=+1 ;MOVE TO CLEARANCE ~
  Q307=+0 ;PRESET ROTATION ANG. ~
  Q305=+0 ;NUMBER IN TABLE
TCH PROBE 412 PRESET INSIDE CIRCLE ~
  Q321=-25 ;CENTER IN 1ST AXIS ~
  Q322=-10 ;CENTER IN 2ND AXIS ~
  Q262=+22 ;NOMINAL DIAMETER ~
  Q325=+30 ;STARTING ANGLE ~
  Q247=+120 ;STEPPING ANGLE ~
  Q261=-8 ;MEASURING HEIGHT ~
  Q320=+3 ;SET-UP CLEARANCE ~
  Q260=+25 ;CLEARANCE HEIGHT ~
  Q301=+0 ;MOVE TO CLEARANCE ~
  Q305=+0 ;NUMBER IN TABLE ~
  Q331=+0 ;DATUM ~
  Q332=+0 ;DATUM ~
  Q303=+1 ;MEAS. VALUE TRANSFER ~
  Q381=+1 ;PROBE IN TS AXIS ~
  Q382=-5 ;1ST CO. FOR TS AXIS ~
  Q383=+0 ;2ND CO. FOR TS AXIS ~
  Q384=+0 ;3RD CO. FOR TS AXIS ~
  Q333=+0 ;DATUM ~
  Q423=+3 ;NO. OF PROBE POINTS ~
  Q365=+1 ;TYPE OF TRAVERSE
TCH PROBE 421 MEASURE HOLE ~
  Q273=+0 ;CENTER IN 1ST AXIS ~
  Q274=+0 ;CENTER IN 2ND AXIS ~
  Q262=+22 ;NOMINAL DIAMETER ~
  Q325=+0 ;STARTING ANGLE ~
  Q247=+90 ;STEPPING ANGLE ~
  Q261=-8 ;MEASURING HEIGHT ~
  Q320=+3 ;SET-UP CLEARANCE ~
  Q260=+25 ;CLEARANCE HEIGHT ~
  Q301=+1 ;MOVE TO CLEARANCE ~
  Q275=+24.01 ;MAXIMUM LIMIT ~
  Q276=+23.99 ;MINIMUM LIMIT ~
  Q279=+0.01 ;TOLERANCE 1ST CENTER ~
  Q280=+0.01 ;TOLERANCE 2ND CENTER ~
  Q281=+0 ;MEASURING LOG ~
  Q309=+1 ;PGM STOP TOLERANCE ~
  Q330=+0 ;TOOL ~
  Q423=+4 ;NO. OF PROBE POINTS ~
  Q365=+1 ;TYPE OF TRAVERSE
L X+0 Y+0 Z+40 FMAX
M30
END PGM PROBING_412 MM
";

fn machine_path() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing-mill.toml")
}

fn machine() -> MachineConfig {
    MachineConfig::load(&machine_path()).expect("probing machine loads")
}

/// Runs `path` on the probing machine: the interpreter and the op kinds.
fn run(path: &Path) -> (Interpreter, Vec<OpKind>) {
    let m = machine();
    let mut it = m.open_program(path, m.start_pose()).expect("opens");
    let ops = it
        .by_ref()
        .map(|op| op.unwrap_or_else(|d| panic!("{d}")).kind)
        .collect();
    (it, ops)
}

fn close(what: &str, got: f64, want: f64, tol: f64) {
    eprintln!("{what}: off by {:e}", (got - want).abs());
    assert!(
        (got - want).abs() <= tol,
        "{what}: got {got}, expected {want} (±{tol})"
    );
}

/// `v` turned about Z by `deg`.
fn turn(v: [f64; 2], deg: f64) -> [f64; 2] {
    let (s, c) = deg.to_radians().sin_cos();
    [v[0] * c - v[1] * s, v[0] * s + v[1] * c]
}

#[test]
fn iso_probing_runs_the_same_ops_with_the_same_results_as_its_klartext_twin() {
    let (iso, iso_ops) = run(&common::program("iso/probing_412.i"));
    let (kt, kt_ops) = run(&common::temp_program("probing_412.h", TWIN));
    assert!(iso_ops.len() > 40, "{} ops", iso_ops.len());
    assert_eq!(iso_ops.len(), kt_ops.len());
    for (k, (a, b)) in iso_ops.iter().zip(&kt_ops).enumerate() {
        assert_eq!(a, b, "op {k}");
    }
    for q in [150, 151, 152, 153, 161, 162, 163, 180, 181, 182] {
        assert_eq!(iso.q(q).to_bits(), kt.q(q).to_bits(), "Q{q}");
    }
    assert_eq!(iso.presets().0, kt.presets().0);
}

#[test]
fn iso_probing_finds_the_turn_and_the_bore_of_the_placement() {
    let (it, _) = run(&common::program("iso/probing_412.i"));
    // G400 wrote the basic rotation, G412 the preset in the bore centre: G421 measures the
    // bore at the new datum, its true size, within tolerance (Q180 = 1)
    close("Q151 of 421", it.q(151), 0.0, EXACT);
    close("Q152 of 421", it.q(152), 0.0, EXACT);
    close("Q153 of 421", it.q(153), BORE_D, EXACT);
    assert_eq!((it.q(180), it.q(181), it.q(182)), (1.0, 0.0, 0.0));
    let (table, _) = it.presets();
    let t = table.expect("preset table");
    let row = t.row(1).expect("row 1");
    close("ROT", t.rot(1), TURN, EXACT);
    // the bore centre on the machine: preset 1's origin plus the placement
    let b = turn(BORE, TURN);
    close(
        "preset X",
        row[0].unwrap_or(0.0),
        100.0 + OFF[0] + b[0],
        EXACT,
    );
    close(
        "preset Y",
        row[1].unwrap_or(0.0),
        50.0 + OFF[1] + b[1],
        EXACT,
    );
    close("preset Z", row[2].unwrap_or(0.0), -60.0 - 0.25, EXACT);
}

#[test]
fn the_iso_example_checks_and_runs() {
    let p = common::program("iso/probing_412.i");
    let m = machine_path();
    let (ok, out, err) =
        common::klar_cli(&["check", "--machine", common::arg(&m), common::arg(&p)]);
    assert!(ok, "check: {out}{err}");
    let (report, _) = common::run(&p, &machine());
    report.expect("the run ends normally");
}

#[test]
fn a_probing_cycle_without_a_probe_is_refused_at_its_block() {
    // the plain mill has no [workpiece]: G412 stops the program at its head block
    let m = MachineConfig::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/mill.toml"))
        .expect("mill loads");
    let p = common::program("iso/probing_412.i");
    let mut it = m.open_program(&p, m.start_pose()).expect("opens");
    let d = it.by_ref().find_map(|op| op.err()).expect("refused");
    assert_eq!(d.line, 11, "{d}");
    assert!(d.message.contains("needs a touch probe"), "{d}");
}
