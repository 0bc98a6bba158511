//! Touch-probe cycles on slots, ridges, corners, hole patterns and studs
//! (`machines/probing-features.toml`): the part lies 3.2 mm / −1.7 mm / −0.25 mm off its
//! nominal place and is turned by 1.5° about Z (about preset 1 at X+100 Y+50 Z−60). The
//! expected values are worked out here from the placement and the part's drawing alone.

mod common;

use common::probing::{OFF, ORIGIN, TURN, close, edited, example_cycle, preset1, program_of, turn};
use klar::config::MachineConfig;
use klar_interp::{AxisLetter, Interpreter, OpKind};
use std::path::{Path, PathBuf};

/// The stylus ball's radius (`[probe] radius`).
const BALL: f64 = 2.0;
/// Lengths within 1 µm, angles within 0.001°.
const MM: f64 = 1e-3;
const DEG: f64 = 1e-3;

fn machine_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing-features.toml")
}

fn machine() -> MachineConfig {
    MachineConfig::load(&machine_path()).expect("feature machine loads")
}

/// The coordinate a probing move reports (ball centre at the trigger plus the ball radius
/// along the move) when the ball moves along program axis `k` in direction `sign` on the line
/// where the other axis is `other`, toward the flat wall through part point `w` whose normal
/// (part coordinates, pointing out of the material) is `n`.
fn reported(k: usize, sign: f64, other: f64, w: [f64; 2], n: [f64; 2]) -> f64 {
    let wp = program_of(w);
    let np = turn(n, TURN);
    let mut s = [0.0; 2];
    s[1 - k] = other;
    let mut e = [0.0; 2];
    e[k] = sign;
    // n·(s + t e − w) = r
    let t =
        (BALL - (np[0] * (s[0] - wp[0]) + np[1] * (s[1] - wp[1]))) / (np[0] * e[0] + np[1] * e[1]);
    s[k] + t * sign + BALL * sign
}

const PRELUDE: &str = "BEGIN PGM PROBE MM
BLK FORM 0.1 Z X-80 Y-60 Z-30
BLK FORM 0.2 X+80 Y+60 Z+0
TOOL CALL 1 Z S0
L Z+50 R0 FMAX
";

fn program(name: &str, body: &str) -> (String, PathBuf) {
    let text = format!("{PRELUDE}{body}M30\nEND PGM PROBE MM\n");
    let path = common::temp_program(name, &text);
    (text, path)
}

/// Runs `body` after the prelude and returns the interpreter.
fn run_body(name: &str, body: &str) -> Interpreter {
    let (_, path) = program(name, body);
    let m = machine();
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    for op in it.by_ref() {
        op.expect("the program runs");
    }
    it
}

/// Cycle 408 of the slot example, writing the slot's centre line as X+0.
fn c408() -> String {
    edited(
        &example_cycle("probing/slot_ridge.h", 408),
        &[("Q405=-60 ;", "Q405=+0 ;")],
    )
}

/// The slot's walls at part X−66 and X−54 along program Y+25: (− wall, + wall) reported.
fn slot_walls(y: f64) -> (f64, f64) {
    let lo = reported(0, -1.0, y, [-66.0, 0.0], [1.0, 0.0]);
    let hi = reported(0, 1.0, y, [-54.0, 0.0], [-1.0, 0.0]);
    (lo, hi)
}

/// The slot is 12 wide, but the set-up error (2.6 mm across it) is more than the clearance
/// its nominal width leaves: with Q311=8 both touches start from the nominal centre.
#[test]
fn cycle_408_sets_the_slot_centre_and_the_top_as_datum() {
    let it = run_body("probe408.h", &c408());
    let (lo, hi) = slot_walls(25.0);
    close("Q166", it.q(166), hi - lo, MM);
    close("Q157", it.q(157), (hi + lo) / 2.0, MM);
    // the same from the slot's drawing: along X the turned slot is 12/cos wide, and each
    // touch falls short of its wall by r·(1/cos − 1) (the ball meets the wall at a slant)
    let sec = 1.0 / TURN.to_radians().cos();
    close(
        "Q166 from the drawing",
        it.q(166),
        12.0 * sec - 2.0 * BALL * (sec - 1.0),
        1e-9,
    );
    let (xyz, rot) = preset1(&it);
    close("preset X", xyz[0], ORIGIN[0] + (hi + lo) / 2.0, MM);
    // Y is not the measuring axis: it keeps its datum; Z from the tool-axis touch
    close("preset Y", xyz[1], ORIGIN[1], 1e-12);
    close("preset Z", xyz[2], ORIGIN[2] + OFF[2], MM);
    close("preset ROT", rot, 0.0, 1e-12);
}

#[test]
fn cycle_409_sets_the_ridge_centre_in_y_after_a_turn() {
    // the ridge runs along Y: measured across X with Q272=1, then the same ridge's
    // centre line written as datum X+5
    let body = "TCH PROBE 409 RIDGE CENTER REF PT ~
  Q321=-35 ;CENTER IN 1ST AXIS ~
  Q322=+30 ;CENTER IN 2ND AXIS ~
  Q311=+10 ;RIDGE WIDTH ~
  Q272=+1 ;MEASURING AXIS ~
  Q261=+4 ;MEASURING HEIGHT ~
  Q320=+2 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q305=+1 ;NUMBER IN TABLE ~
  Q405=+5 ;DATUM ~
  Q303=+1 ;MEAS. VALUE TRANSFER ~
  Q381=+0 ;PROBE IN TS AXIS
";
    let it = run_body("probe409.h", body);
    let lo = reported(0, 1.0, 30.0, [-40.0, 0.0], [-1.0, 0.0]);
    let hi = reported(0, -1.0, 30.0, [-30.0, 0.0], [1.0, 0.0]);
    close("Q166", it.q(166), hi - lo, MM);
    close("Q157", it.q(157), (hi + lo) / 2.0, MM);
    let (xyz, _) = preset1(&it);
    close("preset X", xyz[0], ORIGIN[0] + (hi + lo) / 2.0 - 5.0, MM);
    close("preset Y", xyz[1], ORIGIN[1], 1e-12);
}

#[test]
fn cycle_414_finds_the_outside_corner_and_turns_the_preset() {
    let body = "TCH PROBE 414 DATUM OUTSIDE CORNER ~
  Q263=-70 ;1ST POINT 1ST AXIS ~
  Q264=-60 ;1ST POINT 2ND AXIS ~
  Q326=+20 ;SPACING IN 1ST AXIS ~
  Q296=-80 ;3RD POINT 1ST AXIS ~
  Q297=-50 ;3RD POINT 2ND AXIS ~
  Q327=+20 ;SPACING IN 2ND AXIS ~
  Q261=-5 ;MEASURING HEIGHT ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+0 ;MOVE TO CLEARANCE ~
  Q304=+1 ;BASIC ROTATION ~
  Q305=+0 ;NUMBER IN TABLE ~
  Q331=+0 ;DATUM ~
  Q332=+0 ;DATUM ~
  Q303=+1 ;MEAS. VALUE TRANSFER ~
  Q381=+0 ;PROBE IN TS AXIS
";
    let it = run_body("probe414.h", body);
    let c = program_of([-80.0, -60.0]);
    close("Q151", it.q(151), c[0], MM);
    close("Q152", it.q(152), c[1], MM);
    let (xyz, rot) = preset1(&it);
    close("preset X", xyz[0], ORIGIN[0] + c[0], MM);
    close("preset Y", xyz[1], ORIGIN[1] + c[1], MM);
    close("preset ROT", rot, TURN, DEG);
}

#[test]
fn cycle_415_finds_the_inside_corner_of_the_pocket() {
    // the example's inside corner, read as X+10 Y+20 in preset 1
    let body = edited(
        &example_cycle("probing/corners.h", 415),
        &[
            ("Q305=+2 ;", "Q305=+0 ;"),
            ("Q331=+0 ;", "Q331=+10 ;"),
            ("Q332=+0 ;", "Q332=+20 ;"),
        ],
    );
    let it = run_body("probe415.h", &body);
    let c = program_of([-25.0, -15.0]);
    close("Q151", it.q(151), c[0], MM);
    close("Q152", it.q(152), c[1], MM);
    let (xyz, rot) = preset1(&it);
    // the corner reads X+10 Y+20 in the new preset (no basic rotation)
    close("preset X", xyz[0], ORIGIN[0] + c[0] - 10.0, MM);
    close("preset Y", xyz[1], ORIGIN[1] + c[1] - 20.0, MM);
    close("preset ROT", rot, 0.0, 1e-12);
}

#[test]
fn cycles_416_and_430_find_the_bolt_hole_circle() {
    // the example's bolt-hole circle with centre tolerances of 0.5 mm and no stop
    let body = edited(
        &example_cycle("probing/hole_patterns.h", 430),
        &[
            ("Q279=+5 ;", "Q279=+0.5 ;"),
            ("Q280=+5 ;", "Q280=+0.5 ;"),
            ("Q309=+1 ;", "Q309=+0 ;"),
        ],
    );
    let it = run_body("probe430.h", &body);
    let c = program_of([30.0, -25.0]);
    close("Q151", it.q(151), c[0], MM);
    close("Q152", it.q(152), c[1], MM);
    close("Q153", it.q(153), 40.0, MM);
    close("Q161", it.q(161), c[0] - 30.0, MM);
    close("Q162", it.q(162), c[1] + 25.0, MM);
    close("Q163", it.q(163), 0.0, MM);
    // the set-up error puts the centre off its 0.5 mm tolerance: scrap, but no stop (Q309=0)
    assert!((c[0] - 30.0).abs() > 0.5);
    assert_eq!((it.q(180), it.q(181), it.q(182)), (0.0, 0.0, 1.0));

    let body = edited(
        &example_cycle("probing/hole_patterns.h", 416),
        &[("Q331=+30 ;", "Q331=+0 ;"), ("Q332=-25 ;", "Q332=+0 ;")],
    );
    let it = run_body("probe416.h", &body);
    close("Q153", it.q(153), 40.0, MM);
    let (xyz, _) = preset1(&it);
    close("preset X", xyz[0], ORIGIN[0] + c[0], MM);
    close("preset Y", xyz[1], ORIGIN[1] + c[1], MM);
}

#[test]
fn cycle_418_sets_the_crossing_of_the_diagonals() {
    // the example's four holes, written to the active preset
    let body = edited(
        &example_cycle("probing/hole_patterns.h", 418),
        &[("Q305=+2 ;", "Q305=+0 ;")],
    );
    let it = run_body("probe418.h", &body);
    let c = program_of([40.0, 35.0]);
    close("Q151", it.q(151), c[0], MM);
    close("Q152", it.q(152), c[1], MM);
    let (xyz, _) = preset1(&it);
    close("preset X", xyz[0], ORIGIN[0] + c[0], MM);
    close("preset Y", xyz[1], ORIGIN[1] + c[1], MM);
}

#[test]
fn cycle_402_turns_the_preset_by_the_line_through_two_studs() {
    let body = example_cycle("probing/studs.h", 402);
    let it = run_body("probe402.h", &body);
    close("Q150", it.q(150), 90.0 + TURN, DEG);
    let (xyz, rot) = preset1(&it);
    close("preset ROT", rot, TURN, DEG);
    close("preset X", xyz[0], ORIGIN[0], 1e-12);
}

/// Cycle 425 of the slot example, writing its measuring log.
fn c425() -> String {
    edited(
        &example_cycle("probing/slot_ridge.h", 425),
        &[("Q281=+0 ;", "Q281=+1 ;")],
    )
}

#[test]
fn cycles_425_and_426_measure_slot_and_ridge_widths() {
    let it = run_body("probe425.h", &c425());
    // both touches on Y+25: +X first, then −X
    let (lo, hi) = slot_walls(25.0);
    close("Q156", it.q(156), hi - lo, MM);
    close("Q157", it.q(157), (hi + lo) / 2.0, MM);
    close("Q166", it.q(166), hi - lo - 12.0, MM);
    assert_eq!((it.q(180), it.q(181), it.q(182)), (1.0, 0.0, 0.0));
    // Q310=+5: the second touch on Y+30; across the turned slot the width grows by
    // 5·tan 1.5°, past the limit: scrap, and with Q309=0 no stop
    let body = c425()
        .replace("Q310=+0", "Q310=+5")
        .replace("Q309=+1", "Q309=+0");
    let it = run_body("probe425_offset.h", &body);
    let hi = slot_walls(25.0).1;
    let lo = slot_walls(30.0).0;
    close("Q156 offset", it.q(156), hi - lo, MM);
    close("Q157 offset", it.q(157), (hi + lo) / 2.0, MM);
    assert!(hi - lo > 12.05);
    assert_eq!((it.q(180), it.q(181), it.q(182)), (0.0, 0.0, 1.0));

    let body = example_cycle("probing/slot_ridge.h", 426);
    let it = run_body("probe426.h", &body);
    let hi = reported(0, -1.0, 25.0, [-30.0, 0.0], [1.0, 0.0]);
    let lo = reported(0, 1.0, 25.0, [-40.0, 0.0], [-1.0, 0.0]);
    close("Q156", it.q(156), hi - lo, MM);
    close("Q157", it.q(157), (hi + lo) / 2.0, MM);
    close("Q166", it.q(166), hi - lo - 10.0, MM);
}

#[test]
fn a_width_out_of_tolerance_stops_the_program_and_logs_the_measurement() {
    let body = c425()
        .replace("Q288=+12.05", "Q288=+11.99")
        .replace("Q289=+11.95", "Q289=+11.9");
    let (text, path) = program("probe425_tol.h", &format!("{body}L X+0 Y+0 Z+30 FMAX\n"));
    let m = machine();
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    let mut after = false;
    let mut err = None;
    for op in it.by_ref() {
        match op {
            Ok(op) => {
                after |= matches!(op.kind, OpKind::Line { to, .. } if (to[AxisLetter::Z] - (ORIGIN[2] + 30.0)).abs() < 1e-9)
            }
            Err(e) => {
                err = Some(e);
                break;
            }
        }
    }
    let err = err.expect("the cycle stops the program");
    let line = text
        .lines()
        .position(|l| l.starts_with("TCH PROBE 425"))
        .map(|i| i as u32 + 1);
    assert_eq!(Some(err.line), line, "{}", err.message);
    assert!(
        err.message
            .contains("tolerance exceeded: TCH PROBE 425, Q156 width"),
        "{}",
        err.message
    );
    assert!(err.message.contains("(scrap)"), "{}", err.message);
    assert!(!after, "no block after the cycle runs");
    // the width measured is nearer 12 than 11.99: too wide a slot is scrap
    let (lo, hi) = slot_walls(25.0);
    assert!(hi - lo > 11.99);
    close("Q156", it.q(156), hi - lo, MM);
    assert_eq!((it.q(180), it.q(181), it.q(182)), (0.0, 0.0, 1.0));
    // the log next to the program
    let log = std::fs::read_to_string(path.with_file_name("TCHPR425.TXT")).expect("log written");
    assert!(log.contains("TCH PROBE 425 measuring log"), "{log}");
    assert!(
        log.contains("Q156 width") && log.contains("above max"),
        "{log}"
    );
    assert!(log.contains(&format!("{:.4}", hi - lo)), "{log}");
    assert!(log.contains("workpiece status: scrap"), "{log}");
}

#[test]
fn q303_0_writes_the_slot_centre_into_the_datum_table() {
    let body = c408()
        .replace("Q303=+1", "Q303=+0")
        .replace("Q305=+0", "Q305=+1")
        .replace("Q381=+1", "Q381=+0");
    let body = format!("{body}CYCL DEF 7.0 DATUM SHIFT\nCYCL DEF 7.1 #1\nL X+0 Y+25 Z+30 FMAX\n");
    let (_, path) = program("probe408_d.h", &body);
    let m = machine();
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    let mut last = None;
    for op in it.by_ref() {
        if let OpKind::Line { to, .. } = op.expect("runs").kind {
            last = Some(to);
        }
    }
    let (lo, hi) = slot_walls(25.0);
    let end = last.expect("moves");
    // datum shift #1 puts X+0 on the slot's centre line; the preset is untouched
    close("X", end[AxisLetter::X], ORIGIN[0] + (hi + lo) / 2.0, MM);
    close("Y", end[AxisLetter::Y], ORIGIN[1] + 25.0, 1e-9);
    let (xyz, _) = preset1(&it);
    close("preset X", xyz[0], ORIGIN[0], 1e-12);
}

#[test]
fn the_example_programs_check_on_the_feature_machine() {
    let m = machine_path();
    for name in [
        "probing/slot_ridge.h",
        "probing/corners.h",
        "probing/hole_patterns.h",
        "probing/studs.h",
    ] {
        let p = common::program(name);
        let (ok, out, err) =
            common::klar_cli(&["check", "--machine", common::arg(&m), common::arg(&p)]);
        assert!(ok, "{name}: {out}{err}");
    }
}

/// Runs `body` after the prelude and asserts that the first error is at `line` (column 1),
/// says `says`, and that nothing of that block moved.
fn refused_at(name: &str, body: &str, line: u32, says: &str) {
    let (_, path) = program(name, body);
    let m = machine();
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    let mut moved_there = false;
    let mut err = None;
    for op in it.by_ref() {
        match op {
            Ok(op) => moved_there |= op.loc.line == line,
            Err(e) => {
                err = Some(e);
                break;
            }
        }
    }
    let err = err.expect("refused");
    assert!(err.message.contains(says), "{name}: {}", err.message);
    assert_eq!((err.line, err.col), (line, 1), "{name}: {}", err.message);
    assert!(!moved_there, "{name}: the refused block moved");
}

#[test]
fn bad_cycle_parameters_are_refused_at_their_block_before_any_move() {
    refused_at(
        "probe415_q308.h",
        "TCH PROBE 415 ~\n  Q263=-25 ~\n  Q264=-15 ~\n  Q326=+10 ~\n  Q327=+8 ~\n  Q308=+5 ~\n  Q261=-5 ~\n  Q260=+20\n",
        6,
        "Q308=5: the corner is 1, 2, 3 or 4",
    );
    refused_at(
        "probe414_dir.h",
        "TCH PROBE 414 ~\n  Q263=-70 ~\n  Q264=-60 ~\n  Q326=+20 ~\n  Q296=-70 ~\n  Q297=-50 ~\n  Q327=+20 ~\n  Q261=-5 ~\n  Q260=+20\n",
        6,
        "point 3 (Q296/Q297) must lie off point 1",
    );
    refused_at(
        "probe408_axis.h",
        &c408().replace("Q272=+1", "Q272=+3"),
        6,
        "Q272=3: the measuring axis is 1 or 2",
    );
    refused_at(
        "probe430_missing.h",
        "TCH PROBE 430 ~\n  Q273=+30 ~\n  Q274=-25 ~\n  Q262=+40 ~\n  Q291=+30 ~\n  Q292=+150 ~\n  Q261=-5 ~\n  Q260=+20\n",
        6,
        "TCH PROBE 430 needs Q293",
    );
    refused_at(
        "probe425_limits.h",
        &c425().replace("Q289=+11.95", "Q289=+12.5"),
        6,
        "the smallest size 12.5 lies above the largest 12.05",
    );
    // Q303=0 on a machine without a datum table
    let (_, path) = program(
        "probe408_nodatum.h",
        &c408()
            .replace("Q303=+1", "Q303=+0")
            .replace("Q305=+0", "Q305=+2"),
    );
    let mut m = machine();
    m.datum_table = None;
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    let err = it.find_map(Result::err).expect("refused");
    assert!(err.message.contains("no datum table"), "{}", err.message);
}

#[test]
fn bad_features_in_the_machine_file_are_refused_with_their_name() {
    let text = std::fs::read_to_string(machine_path()).expect("machine file");
    for (from, to, says) in [
        (
            "count = 3",
            "count = 0",
            "hole_circle 1 count must lie in 1 … 360",
        ),
        (
            "width = 12.0",
            "width = -12.0",
            "workpiece slot 1 width must be a positive number",
        ),
        (
            "height = 8.0",
            "height = nan",
            "workpiece ridge 1 height must be a positive number",
        ),
    ] {
        let bad = text.replacen(from, to, 1);
        let err = MachineConfig::parse("bad.toml", &bad).expect_err(says);
        assert!(err.to_string().contains(says), "{err}");
    }
}

#[test]
fn measuring_a_stud_too_large_is_rework_and_a_bore_too_small_stops() {
    // 422 on the stud of Ø12 with limits below it: rework, no stop without Q309
    let body = "TCH PROBE 422 MEAS. CIRCLE OUTSIDE ~
  Q273=+0 ;CENTER IN 1ST AXIS ~
  Q274=+15 ;CENTER IN 2ND AXIS ~
  Q262=+12 ;NOMINAL DIAMETER ~
  Q325=+0 ;STARTING ANGLE ~
  Q247=+90 ;STEPPING ANGLE ~
  Q261=+5 ;MEASURING HEIGHT ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+1 ;MOVE TO CLEARANCE ~
  Q275=+11.9 ;MAXIMUM LIMIT ~
  Q276=+11.8 ;MINIMUM LIMIT ~
  Q281=+0 ;MEASURING LOG
";
    let it = run_body("probe422.h", body);
    close("Q153", it.q(153), 12.0, MM);
    assert_eq!((it.q(180), it.q(181), it.q(182)), (0.0, 1.0, 0.0));
    // 421 in the bore of Ø16 at (20, 20) with a smallest diameter above it: rework, and
    // Q309=1 stops at the cycle (a nominal Ø12 keeps the touch points clear of the wall of
    // the bore lying 3 mm off)
    let body = "TCH PROBE 421 MEASURE HOLE ~
  Q273=+20 ;CENTER IN 1ST AXIS ~
  Q274=+20 ;CENTER IN 2ND AXIS ~
  Q262=+12 ;NOMINAL DIAMETER ~
  Q325=+0 ;STARTING ANGLE ~
  Q247=+90 ;STEPPING ANGLE ~
  Q261=-5 ;MEASURING HEIGHT ~
  Q320=+0 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+1 ;MOVE TO CLEARANCE ~
  Q276=+16.01 ;MINIMUM LIMIT ~
  Q309=+1 ;PGM STOP TOLERANCE
";
    refused_at(
        "probe421_tol.h",
        body,
        6,
        "tolerance exceeded: TCH PROBE 421, Q153 diameter measured 16.0000 lies outside at least 16.0100 (rework)",
    );
}
