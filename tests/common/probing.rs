//! Shared by the touch-probe tests: the probing machines of `machines/`, where their part
//! really lies, the program text around the cycles, and the comparison of a result with its
//! closed form.

use klar::config::MachineConfig;
use klar_interp::{Interpreter, Op};
use std::path::{Path, PathBuf};

/// Preset 1 of `machines/probing.pr`, machine coordinates.
pub const ORIGIN: [f64; 3] = [100.0, 50.0, -60.0];
/// Where the part really lies off its nominal place (program X, Y, Z, mm).
pub const OFF: [f64; 3] = [3.2, -1.7, -0.25];
/// Its turn about Z (about the program datum), degrees.
pub const TURN: f64 = 1.5;

/// The machine file `machines/<file>`.
pub fn machine(file: &str) -> MachineConfig {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("machines")
        .join(file);
    MachineConfig::load(&p).expect("probing machine loads")
}

/// `v` turned about Z by `deg`.
pub fn turn(v: [f64; 2], deg: f64) -> [f64; 2] {
    let (s, c) = deg.to_radians().sin_cos();
    [v[0] * c - v[1] * s, v[0] * s + v[1] * c]
}

/// `got` within `tol` of `want`; prints how far off it is.
pub fn close(what: &str, got: f64, want: f64, tol: f64) {
    eprintln!("{what}: off by {:e}", (got - want).abs());
    assert!(
        (got - want).abs() <= tol,
        "{what}: got {got}, expected {want} (±{tol})"
    );
}

/// Program `name`: the part's BLK FORM, the probe called as tool 1 over the part, then
/// `body`, then M30.
pub fn program_text(name: &str, body: &str) -> String {
    format!(
        "BEGIN PGM {name} MM
BLK FORM 0.1 Z X-50 Y-40 Z-30
BLK FORM 0.2 X+50 Y+40 Z+0
TOOL CALL 1 Z S0
L Z+50 R0 FMAX
{body}M30
END PGM {name} MM
"
    )
}

/// Runs `body` of program `name` (file `file` in a temporary folder) on `m`: the
/// interpreter afterwards, every op, and the program's path.
pub fn run_body(
    m: &MachineConfig,
    name: &str,
    file: &str,
    body: &str,
) -> (Interpreter, Vec<Op>, PathBuf) {
    let path = super::temp_program(file, &program_text(name, body));
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    let ops: Vec<Op> = it
        .by_ref()
        .map(|op| op.expect("the program runs"))
        .collect();
    (it, ops, path)
}

/// Cycle 400 on the part's front edge (Y−40, from X−30 to X+30), writing preset row `row`
/// (0: the active preset).
pub fn c400(row: u32) -> String {
    format!(
        "TCH PROBE 400 BASIC ROTATION ~
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
  Q307=+0 ;PRESET ROTATION ANG. ~
  Q305=+{row} ;NUMBER IN TABLE
"
    )
}
