//! What the machine file tells the interpreter reaches TNC ISO programs as it reaches
//! Klartext ones (tool table, rotary axes, M functions, datum table, working-plane ops), and
//! every front end (`run`, `check`, `ops`, `plot`) opens a program the same way.
//!
//! Expected values are worked out by hand: tool length and radius as written in the machine
//! file, the offset contour of a rectangle in a plane tilted 30° about X, the rotary angle a
//! single spatial angle needs on an A/C and a B/C table.

mod common;

use common::temp_program;
use klar::config::{BUILTIN_MILL5, MachineConfig};
use klar_interp::{AxisLetter, DatumTable, Interpreter, Op, OpKind, Pose};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The built-in 5-axis mill (A/C table) with tool 7 (L 60, R 5) in its tool table.
fn mill5_with_tools() -> MachineConfig {
    let text = format!(
        "{BUILTIN_MILL5}\n[[tool]]\nnumber = 7\nname = \"end mill 10\"\nlength = 60.0\nradius = 5.0\n"
    );
    MachineConfig::parse("mill5 with tools", &text).expect("machine file")
}

/// The same machine with a B/C table: the tilt axis is B.
fn mill5_b_c() -> MachineConfig {
    let text = BUILTIN_MILL5.replace("letter = \"A\"", "letter = \"B\"");
    MachineConfig::parse("mill5 B/C", &text).expect("machine file")
}

/// All ops of an interpreter, panicking on a program error.
fn all_ops(interp: Interpreter) -> Vec<Op> {
    interp
        .map(|op| op.unwrap_or_else(|d| panic!("program error: {d}")))
        .collect()
}

/// The first program error of an interpreter, if any.
fn first_error(interp: Interpreter) -> Option<klar_interp::Diagnostic> {
    interp.filter_map(Result::err).next()
}

/// The op kinds without their source locations (the ISO and Klartext twins differ in lines).
fn kinds(ops: &[Op]) -> Vec<OpKind> {
    ops.iter().map(|o| o.kind.clone()).collect()
}

/// The end pose of the last line of `ops`.
fn last_line_end(ops: &[Op]) -> Pose {
    ops.iter()
        .rev()
        .find_map(|op| match &op.kind {
            OpKind::Line { to, .. } => Some(*to),
            _ => None,
        })
        .expect("a line")
}

const TOOL_ISO: &str = "%TOOL G71 *
N10 T7 G17 S3000 *
N20 G00 G40 X+0 Y+0 Z+50 *
N30 G43 G01 X+50 F500 *
N40 M30 *
N99999999 %TOOL G71 *
";

#[test]
fn an_iso_tool_call_takes_length_and_radius_from_the_machines_table() {
    let prog = temp_program("tool.i", TOOL_ISO);
    let machine = mill5_with_tools();
    let ops = all_ops(
        machine
            .open_program(&prog, machine.start_pose())
            .expect("opens"),
    );
    let change = ops
        .iter()
        .find_map(|op| match &op.kind {
            OpKind::ToolChange {
                tool,
                length,
                radius,
                ..
            } => Some((*tool, *length, *radius)),
            _ => None,
        })
        .expect("a tool change");
    // As written in the machine file: tool 7, L 60, R 5.
    assert_eq!(change, (7, 60.0, 5.0));
    // G43: the one-axis move X0 → X50 is lengthened by the table's radius 5.
    let end = last_line_end(&ops);
    assert!((end[AxisLetter::X] - 55.0).abs() < 1e-12, "{end:?}");
}

#[test]
fn an_iso_call_of_a_tool_missing_from_the_machines_table_is_refused() {
    let prog = temp_program("tool_missing.i", &TOOL_ISO.replace("T7", "T8"));
    let machine = mill5_with_tools();
    let interp = machine
        .open_program(&prog, machine.start_pose())
        .expect("opens");
    let d = first_error(interp).expect("tool 8 is not in the table");
    assert!(d.message.contains("tool 8 is not in the tool table"), "{d}");
    assert_eq!(d.line, 2, "{d}");
}

/// G80 with one spatial angle, then the rotary axes to the computed angles.
fn g80_iso(a: f64, b: f64) -> String {
    format!(
        "%TILT G71 *\nN10 T1 G17 S1000 *\nN20 G80 A{a:+} B{b:+} C+0 *\n\
         N30 G00 G40 A+Q120 B+Q121 C+Q122 *\nN40 M30 *\nN99999999 %TILT G71 *\n"
    )
}

/// The (tilt, C) angles the last line of a program reaches.
fn rotary_end(ops: &[Op], tilt: AxisLetter) -> (f64, f64) {
    let end = last_line_end(ops);
    (end[tilt], end[AxisLetter::C])
}

/// True when (tilt, c) is one of the two hand-computed settings that turn the tool by `deg`
/// about the tilt axis: the tilt alone (tilt = deg, C = 0) or the opposite tilt with the
/// table turned half round (tilt = −deg, C = ±180).
fn is_single_tilt(got: (f64, f64), deg: f64) -> bool {
    let near = |x: f64, y: f64| (x - y).abs() < 1e-9;
    let c = got.1.rem_euclid(360.0);
    (near(got.0, deg) && (near(c, 0.0) || near(c, 360.0))) || (near(got.0, -deg) && near(c, 180.0))
}

#[test]
fn g80_computes_the_angles_of_the_machines_own_rotary_axes() {
    // A/C table: a tilt about X is the A axis alone.
    let prog = temp_program("tilt_a.i", &g80_iso(30.0, 0.0));
    let m = MachineConfig::builtin_mill5();
    let ops = all_ops(m.open_program(&prog, m.start_pose()).expect("opens"));
    let got = rotary_end(&ops, AxisLetter::A);
    assert!(is_single_tilt(got, 30.0), "A/C: {got:?}");

    // B/C table: a tilt about Y is the B axis alone; an interpreter that assumed an A/C
    // table would put A at ±90 and turn C instead.
    let prog = temp_program("tilt_b.i", &g80_iso(0.0, 30.0));
    let m = mill5_b_c();
    let ops = all_ops(m.open_program(&prog, m.start_pose()).expect("opens"));
    let got = rotary_end(&ops, AxisLetter::B);
    assert!(is_single_tilt(got, 30.0), "B/C: {got:?}");
    assert_eq!(last_line_end(&ops)[AxisLetter::A], 0.0);

    // The Klartext twin on the same machine gives the same ops.
    let twin = temp_program(
        "tilt_b.h",
        "BEGIN PGM TILT MM\nTOOL CALL 1 Z S1000\nCYCL DEF 19.0 WORKING PLANE\n\
         CYCL DEF 19.1 A+0 B+30 C+0\nL A+Q120 B+Q121 C+Q122 R0 FMAX\nM30\nEND PGM TILT MM\n",
    );
    let k = all_ops(m.open_program(&twin, m.start_pose()).expect("opens"));
    assert_eq!(kinds(&ops), kinds(&k));
}

#[test]
fn g80_on_a_machine_without_rotary_axes_is_refused() {
    let prog = temp_program("tilt_mill.i", &g80_iso(30.0, 0.0));
    let m = MachineConfig::builtin_mill();
    let d = first_error(m.open_program(&prog, m.start_pose()).expect("opens"))
        .expect("the built-in mill has no rotary axes");
    assert!(d.message.contains("no rotary axes"), "{d}");
    assert_eq!(d.line, 3, "{d}");
}

/// A 40 × 20 rectangle counter-clockwise from (20, 0) with left compensation, in a plane
/// tilted 30° about X (G80 A+30), tool 7 of the machine's table (radius 5).
const RECT_ISO: &str = "%RECT G71 *
N10 T7 G17 S3000 *
N20 G80 A+30 B+0 C+0 *
N30 G00 G40 X+20 Y+10 Z+5 *
N40 G01 Z-2 F300 *
N50 G41 X+20 Y+0 F500 *
N60 X+40 *
N70 Y+20 *
N80 X+0 *
N90 Y+0 *
N100 X+20 *
N110 G40 Y+10 *
N120 G00 Z+5 *
N130 M30 *
N99999999 %RECT G71 *
";

/// The Klartext twin of [`RECT_ISO`].
const RECT_H: &str = "BEGIN PGM RECT MM
TOOL CALL 7 Z S3000
CYCL DEF 19.0 WORKING PLANE
CYCL DEF 19.1 A+30 B+0 C+0
L X+20 Y+10 Z+5 R0 FMAX
L Z-2 F300
L X+20 Y+0 RL F500
L X+40
L Y+20
L X+0
L Y+0
L X+20
L Y+10 R0
L Z+5 FMAX
M30
END PGM RECT MM
";

/// The tool-centre path of `program` on `machine` as `klar run` builds it: opened by the
/// machine, working-plane ops on, through the compensation stage.
fn tool_centre(program: &Path, machine: &MachineConfig) -> Vec<Op> {
    let start = machine.start_pose();
    common::compensated(machine.open_program(program, start).expect("opens"), start)
}

#[test]
fn g41_in_a_tilted_iso_plane_compensates_like_the_klartext_twin() {
    let machine = mill5_with_tools();
    let iso = tool_centre(&temp_program("rect.i", RECT_ISO), &machine);
    let klartext = tool_centre(&temp_program("rect.h", RECT_H), &machine);
    assert_eq!(kinds(&iso), kinds(&klartext));
    // By hand, in the tilted system: the tool (radius 5) runs the inside offset rectangle
    // (5, 5)–(35, 15) at depth −2, arriving and leaving on the normal at (20, 5); turned by
    // Rx(30°) into the workpiece system.
    let ends: Vec<[f64; 3]> = iso
        .iter()
        .filter_map(|op| match &op.kind {
            OpKind::Line { to, .. } => {
                Some([to[AxisLetter::X], to[AxisLetter::Y], to[AxisLetter::Z]])
            }
            _ => None,
        })
        .collect();
    let expect = common::mill5::RECT_RL_CENTRE;
    assert_eq!(ends.len(), expect.len(), "{ends:?}");
    for (g, e) in ends.iter().zip(expect) {
        let w = common::mill5::rx(30.0, e);
        let d = ((g[0] - w[0]).powi(2) + (g[1] - w[1]).powi(2) + (g[2] - w[2]).powi(2)).sqrt();
        assert!(d < 1e-9, "{g:?} vs {w:?}");
    }
}

#[test]
fn without_working_plane_ops_g41_in_a_tilted_iso_plane_is_refused() {
    let machine = mill5_with_tools();
    let prog = temp_program("rect_off.i", RECT_ISO);
    let interp = machine
        .open_program(&prog, machine.start_pose())
        .expect("opens");
    let d = first_error(interp).expect("refused while the plane is tilted");
    assert!(d.message.contains("radius compensation"), "{d}");
    assert_eq!(d.line, 6, "{d}");
}

#[test]
fn a_check_on_the_machine_accepts_g41_in_a_tilted_iso_plane() {
    let machine = mill5_with_tools();
    let prog = temp_program("rect_check.i", RECT_ISO);
    let report = machine
        .open_program(&prog, machine.start_pose())
        .expect("opens")
        .check_report();
    assert!(report.errors.is_empty(), "{:?}", report.errors);
}

#[test]
fn g53_reads_the_datum_table_given_to_the_interpreter() {
    let table =
        DatumTable::parse("BEGIN NULLTAB.D MM\nNR X Y Z\n0 +0 +0 +0\n2 +25 -10 +0\n[END]\n")
            .expect("table");
    let text = "%DATUM G71 *\nN10 G53 P01 2 *\nN20 G00 G40 X+5 Y+5 Z+10 *\nN30 M30 *\n\
                N99999999 %DATUM G71 *\n";
    let ops =
        all_ops(Interpreter::from_source("datum.i", text, Pose::ZERO).with_datum_table(table));
    // Row 2 shifts the datum by (25, −10, 0): X5 Y5 lands at X30 Y−5.
    let end = last_line_end(&ops);
    assert!((end[AxisLetter::X] - 30.0).abs() < 1e-12, "{end:?}");
    assert!((end[AxisLetter::Y] + 5.0).abs() < 1e-12, "{end:?}");
}

#[test]
fn the_blank_of_an_iso_program_is_reported() {
    let text = "%BLK G71 *\nN10 G30 G17 X+0 Y+0 Z-20 *\nN20 G31 G90 X+100 Y+60 Z+0 *\n\
                N30 M30 *\nN99999999 %BLK G71 *\n";
    let mut interp = Interpreter::from_source("blk.i", text, Pose::ZERO);
    for op in interp.by_ref() {
        op.expect("no error");
    }
    let blank = interp.blank().expect("G30/G31 define the blank");
    assert_eq!(blank.axis, Some(AxisLetter::Z));
    assert_eq!(blank.min[AxisLetter::Z], -20.0);
    assert_eq!(blank.max[AxisLetter::X], 100.0);
    assert_eq!(blank.max[AxisLetter::Y], 60.0);
}

/// A Klartext program with the machine function M25 (defined by the built-in 5-axis mill).
const DOOR_H: &str = "BEGIN PGM DOOR MM
TOOL CALL 1 Z S3000
L X+0 Y+0 Z+50 R0 FMAX M25
L X+40 Y+0 Z+50 R0 F500
L X+40 Y+30 R0 F500
END PGM DOOR MM
";

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("klar-iso-machine-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

#[test]
fn a_plot_on_a_machine_knows_its_m_functions() {
    let prog = temp_program("door.h", DOOR_H);
    let out = scratch("plot").join("door.svg");
    let m5 = MachineConfig::builtin_mill5();
    klar::plot::plot_program_with(&prog, Some(&m5), m5.start_pose(), &out, None)
        .expect("M25 is a function of the 5-axis mill");
    let svg = std::fs::read_to_string(&out).expect("written");
    assert!(
        svg.contains("<polyline") || svg.contains("<path"),
        "nothing drawn"
    );
    // The toolpath reaches the last point (40, 30).
    let strokes = klar::plot::toolpath(&prog, Some(&m5), m5.start_pose()).expect("plots");
    let last = strokes
        .last()
        .and_then(|s| s.points.last())
        .expect("points");
    assert_eq!(last[..2], [40.0, 30.0]);

    let _ = std::fs::remove_file(&out);
    let mill = MachineConfig::builtin_mill();
    for machine in [Some(&mill), None] {
        let err = klar::plot::plot_program_with(&prog, machine, mill.start_pose(), &out, None)
            .expect_err("no M25 there");
        let text = err.to_string();
        assert!(text.contains("door.h:3:"), "{text}");
        assert!(text.contains("M25 not supported on this machine"), "{text}");
        assert!(!out.exists(), "a picture of a refused program");
    }
}

fn klar(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_klar"))
        .args(args)
        .env("NO_COLOR", "1")
        .output()
        .expect("klar runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn arg(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

#[test]
fn klar_plot_with_the_machine_draws_what_it_runs() {
    let prog = temp_program("door_cli.h", DOOR_H);
    let dir = scratch("cli");
    let out = dir.join("door.png");
    let mill5 = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/mill5.toml");
    let (ok, _, err) = klar(&[
        "plot",
        arg(&prog),
        "-o",
        arg(&out),
        "--machine",
        arg(&mill5),
    ]);
    assert!(ok, "{err}");
    assert!(out.exists());
    let out2 = dir.join("door2.png");
    let (ok, _, err) = klar(&["plot", arg(&prog), "-o", arg(&out2)]);
    assert!(!ok, "plotted without the machine that defines M25");
    assert!(err.contains("door_cli.h:3:"), "{err}");
    assert!(err.contains("M25 not supported on this machine"), "{err}");
    assert!(!out2.exists());
}

#[test]
fn klar_ops_of_an_iso_program_uses_the_machines_tool_table() {
    let dir = scratch("ops");
    let machine = dir.join("m5t.toml");
    std::fs::write(
        &machine,
        format!("{BUILTIN_MILL5}\n[[tool]]\nnumber = 7\nlength = 60.0\nradius = 5.0\n"),
    )
    .expect("machine file");
    let prog = temp_program("ops_rect.i", RECT_ISO);
    let (ok, out, err) = klar(&[
        "ops",
        arg(&prog),
        "--machine",
        arg(&machine),
        "--compensated",
    ]);
    assert!(ok, "{err}");
    let change: serde_json::Value = out
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .find(|v| v["op"] == "tool_change")
        .expect("a tool change");
    assert_eq!(change["tool"], 7);
    assert_eq!(change["length"], 60.0);
    assert_eq!(change["radius"], 5.0);
    let (ok, out, err) = klar(&["check", arg(&prog), "--machine", arg(&machine)]);
    assert!(ok, "{out}{err}");
}
