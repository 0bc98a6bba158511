//! Shared by the touch-probe tests: the probing machines of `machines/`, where their part
//! really lies, the program text around the cycles, the cycles of the example programs, and
//! the comparison of a result with its closed form.

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

/// Program coordinates (preset 1, no basic rotation) of part point `q`.
pub fn program_of(q: [f64; 2]) -> [f64; 2] {
    let t = turn(q, TURN);
    [OFF[0] + t[0], OFF[1] + t[1]]
}

/// Preset row 1 after the run: X, Y, Z and ROT.
pub fn preset1(it: &Interpreter) -> ([f64; 3], f64) {
    let (table, active) = it.presets();
    assert_eq!(active, Some(1));
    let t = table.expect("preset table");
    let row = t.row(1).expect("row 1");
    (
        [
            row[0].unwrap_or(0.0),
            row[1].unwrap_or(0.0),
            row[2].unwrap_or(0.0),
        ],
        t.rot(1),
    )
}

/// The block of `TCH PROBE <cycle>` (its first line and the lines it continues onto with
/// `~`) as the example program `programs/<file>` writes it, each line ended by a newline.
pub fn example_cycle(file: &str, cycle: u32) -> String {
    let path = super::program(file);
    let text = std::fs::read_to_string(&path).expect("example program");
    let head = format!("TCH PROBE {cycle} ");
    let mut lines = text.lines().skip_while(|l| !l.starts_with(&head));
    let mut block = String::new();
    for line in lines.by_ref() {
        block.push_str(line);
        block.push('\n');
        if !line.ends_with('~') {
            break;
        }
    }
    assert!(!block.is_empty(), "{file} has no TCH PROBE {cycle}");
    block
}

/// `block` with each `(from, to)` replaced, every `from` standing in it exactly once.
pub fn edited(block: &str, edits: &[(&str, &str)]) -> String {
    let mut out = block.to_string();
    for (from, to) in edits {
        assert_eq!(out.matches(from).count(), 1, "{from} once in {block}");
        out = out.replacen(from, to, 1);
    }
    out
}

/// Cycle 410 in the pocket of the probing mill's part (centre X+20 Y−10, 36 × 28),
/// writing the active preset.
pub const C410: &str = "TCH PROBE 410 PRESET INSIDE RECTAN. ~
  Q321=+20 ;CENTER IN 1ST AXIS ~
  Q322=-10 ;CENTER IN 2ND AXIS ~
  Q323=+36 ;FIRST SIDE LENGTH ~
  Q324=+28 ;2ND SIDE LENGTH ~
  Q261=-10 ;MEASURING HEIGHT ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+0 ;MOVE TO CLEARANCE ~
  Q305=+0 ;NUMBER IN TABLE ~
  Q331=+0 ;DATUM ~
  Q332=+0 ;DATUM ~
  Q303=+1 ;MEAS. VALUE TRANSFER ~
  Q381=+0 ;PROBE IN TS AXIS
";

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
