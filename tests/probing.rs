//! Touch-probe cycles on the simulated machine (`machines/probing-mill.toml`): the part lies
//! 3.2 mm / −1.7 mm / −0.25 mm off its nominal place and is turned by 1.5° about Z (about
//! preset 1 at X+100 Y+50 Z−60). The cycles must find that set-up error; the expected values
//! are worked out here from the placement alone.

mod common;

use common::probing::{
    C410, OFF, ORIGIN, TURN, c400, close, preset1, program_of, program_text, turn,
};

use klar::config::MachineConfig;
use klar_interp::Interpreter;
use std::path::{Path, PathBuf};

/// Lengths within 1 µm (the figure asked for), angles within 0.001°.
const MM: f64 = 1e-3;
/// The stylus ball's radius (`[probe] radius` of the machine file).
const BALL: f64 = 2.0;
const DEG: f64 = 1e-3;

fn machine() -> MachineConfig {
    common::probing::machine("probing-mill.toml")
}

/// Program coordinates of part point `q` once the basic rotation of 1.5° acts.
fn aligned_of(q: [f64; 2]) -> [f64; 2] {
    let o = turn([OFF[0], OFF[1]], -TURN);
    [o[0] + q[0], o[1] + q[1]]
}

/// Runs `body` after the prelude on the probing machine and returns the interpreter.
fn run_body(name: &str, body: &str) -> (Interpreter, PathBuf) {
    let (it, _, path) = common::probing::run_body(&machine(), "PROBE", name, body);
    (it, path)
}

#[test]
fn cycle_400_finds_the_turn_and_writes_it_as_basic_rotation() {
    let (it, _) = run_body("probe400.h", &c400(0));
    close("Q150", it.q(150), TURN, DEG);
    let (xyz, rot) = preset1(&it);
    close("preset ROT", rot, TURN, DEG);
    // the origin of the preset stays where it was
    close("preset X", xyz[0], ORIGIN[0], 1e-12);
}

#[test]
fn cycle_412_from_the_example_program_sets_the_bore_centre_and_the_top() {
    let path = common::program("probing_412.h");
    let m = machine();
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    for op in it.by_ref() {
        op.expect("runs");
    }
    let c = program_of([-25.0, -10.0]);
    close("Q151", it.q(151), c[0], MM);
    close("Q152", it.q(152), c[1], MM);
    close("Q153", it.q(153), 24.0, MM);
    let (xyz, _) = preset1(&it);
    close("preset X", xyz[0], ORIGIN[0] + c[0], MM);
    close("preset Y", xyz[1], ORIGIN[1] + c[1], MM);
    close("preset Z", xyz[2], ORIGIN[2] + OFF[2], MM);
}

#[test]
fn cycle_413_finds_the_boss_centre_and_diameter() {
    let body = "TCH PROBE 413 PRESET OUTSIDE CIRCLE ~
  Q321=+0 ;CENTER IN 1ST AXIS ~
  Q322=+25 ;CENTER IN 2ND AXIS ~
  Q262=+20 ;NOMINAL DIAMETER ~
  Q325=+45 ;STARTING ANGLE ~
  Q247=+90 ;STEPPING ANGLE ~
  Q261=+5 ;MEASURING HEIGHT ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+0 ;MOVE TO CLEARANCE ~
  Q305=+0 ;NUMBER IN TABLE ~
  Q331=+0 ;DATUM ~
  Q332=+0 ;DATUM ~
  Q303=+1 ;MEAS. VALUE TRANSFER ~
  Q381=+0 ;PROBE IN TS AXIS ~
  Q365=+1 ;TYPE OF TRAVERSE
";
    let (it, _) = run_body("probe413.h", body);
    let c = program_of([0.0, 25.0]);
    close("Q151", it.q(151), c[0], MM);
    close("Q152", it.q(152), c[1], MM);
    close("Q153", it.q(153), 20.0, MM);
    let (xyz, _) = preset1(&it);
    close("preset X", xyz[0], ORIGIN[0] + c[0], MM);
    close("preset Y", xyz[1], ORIGIN[1] + c[1], MM);
}

#[test]
fn cycles_410_and_411_after_400_find_the_pocket_and_the_outline() {
    let (it, _) = run_body("probe410.h", &format!("{}{C410}", c400(0)));
    let c = aligned_of([20.0, -10.0]);
    close("Q151", it.q(151), c[0], MM);
    close("Q152", it.q(152), c[1], MM);
    close("Q154", it.q(154), 36.0, MM);
    close("Q155", it.q(155), 28.0, MM);
    // the new preset is the pocket centre on the machine, the basic rotation kept
    let m = program_of([20.0, -10.0]);
    let (xyz, rot) = preset1(&it);
    close("preset X", xyz[0], ORIGIN[0] + m[0], MM);
    close("preset Y", xyz[1], ORIGIN[1] + m[1], MM);
    close("preset ROT", rot, TURN, DEG);

    let c411 = "TCH PROBE 411 PRESET OUTS. RECTAN. ~
  Q321=+0 ;CENTER IN 1ST AXIS ~
  Q322=+0 ;CENTER IN 2ND AXIS ~
  Q323=+100 ;FIRST SIDE LENGTH ~
  Q324=+80 ;2ND SIDE LENGTH ~
  Q261=-10 ;MEASURING HEIGHT ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+0 ;MOVE TO CLEARANCE ~
  Q305=+1 ;NUMBER IN TABLE ~
  Q331=+0 ;DATUM ~
  Q332=+0 ;DATUM ~
  Q303=+1 ;MEAS. VALUE TRANSFER ~
  Q381=+0 ;PROBE IN TS AXIS
";
    let (it, _) = run_body("probe411.h", &format!("{}{c411}", c400(0)));
    let c = aligned_of([0.0, 0.0]);
    close("Q151", it.q(151), c[0], MM);
    close("Q152", it.q(152), c[1], MM);
    close("Q154", it.q(154), 100.0, MM);
    close("Q155", it.q(155), 80.0, MM);
    let (xyz, _) = preset1(&it);
    close("preset X", xyz[0], ORIGIN[0] + OFF[0], MM);
    close("preset Y", xyz[1], ORIGIN[1] + OFF[1], MM);
}

#[test]
fn cycle_431_measures_the_top_plane() {
    let body = "TCH PROBE 431 MEASURE PLANE ~
  Q263=-40 ;1ST POINT 1ST AXIS ~
  Q264=+30 ;1ST POINT 2ND AXIS ~
  Q294=+0 ;1ST POINT 3RD AXIS ~
  Q265=+40 ;2ND POINT 1ST AXIS ~
  Q266=+30 ;2ND POINT 2ND AXIS ~
  Q295=+0 ;2ND POINT 3RD AXIS ~
  Q296=+40 ;3RD POINT 1ST AXIS ~
  Q297=-35 ;3RD POINT 2ND AXIS ~
  Q298=+0 ;3RD POINT 3RD AXIS ~
  Q320=+0 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q281=+0 ;MEASURING LOG
";
    let (it, _) = run_body("probe431.h", body);
    for q in [173, 174, 175] {
        close(&format!("Q{q}"), it.q(q), OFF[2], MM);
    }
    for q in [158, 159, 170, 171, 172] {
        close(&format!("Q{q}"), it.q(q), 0.0, DEG);
    }
}

#[test]
fn the_example_program_checks_and_runs_to_the_bore_centre() {
    let m = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing-mill.toml");
    let p = common::program("probing_412.h");
    let (ok, out, err) =
        common::klar_cli(&["check", "--machine", common::arg(&m), common::arg(&p)]);
    assert!(ok, "check: {out}{err}");
    let (report, trace) = common::run(&p, &machine());
    report.expect("the run ends normally");
    let col = |name: &str| {
        trace
            .columns
            .iter()
            .position(|c| c == name)
            .expect("trace column")
    };
    let last = trace.rows.last().expect("rows");
    // the program ends with L X+0 Y+0 Z+50 in the preset it found
    let c = program_of([-25.0, -10.0]);
    close("X", last[col("X")], ORIGIN[0] + c[0], MM);
    close("Y", last[col("Y")], ORIGIN[1] + c[1], MM);
    close("Z", last[col("Z")], ORIGIN[2] + OFF[2] + 50.0, MM);
}

#[test]
fn probing_a_missing_part_stops_after_the_probing_distance() {
    let body = "TCH PROBE 0.0 REF. PLANE Q10 Z-
TCH PROBE 0.1 X+150 Y+0 Z+0
";
    let text = program_text("PROBE", body);
    let path = common::temp_program("probe_missing.h", &text);
    let m = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing-mill.toml");
    let (ok, out, err) =
        common::klar_cli(&["check", "--machine", common::arg(&m), common::arg(&path)]);
    assert!(!ok);
    assert!(
        format!("{out}{err}").contains(":7:1: touch point inaccessible"),
        "{out}{err}"
    );
    let mut machine = machine();
    machine.check_before_run = false;
    let (report, trace) = common::run(&path, &machine);
    let failure = report.expect_err("the run stops");
    assert!(
        failure
            .error
            .to_string()
            .contains("touch point inaccessible"),
        "{}",
        failure.error
    );
    let z = trace.columns.iter().position(|c| c == "Z").expect("Z");
    let z_act = trace
        .columns
        .iter()
        .position(|c| c == "Z_act")
        .expect("Z_act");
    let distance = machine.probe_data().distance;
    // pre-position at program Z 0, then down by the probing distance and no further
    let lowest = ORIGIN[2] - distance;
    let min_cmd = trace
        .rows
        .iter()
        .map(|r| r[z])
        .fold(f64::INFINITY, f64::min);
    let min_act = trace
        .rows
        .iter()
        .map(|r| r[z_act])
        .fold(f64::INFINITY, f64::min);
    close("lowest commanded Z", min_cmd, lowest, 1e-9);
    assert!(min_act >= lowest - 0.01, "measured Z went to {min_act}");
}

#[test]
fn cycles_0_and_1_measure_from_their_pre_position() {
    // cycle 0 down onto the top at X+30 Y+25 (program): the top is 0.25 mm low
    let body = "TCH PROBE 0.0 REF. PLANE Q10 Z-
TCH PROBE 0.1 X+30 Y+25 Z+5
Q11 = Q117
L Z+20 FMAX
L X+60 Y+0 FMAX
TCH PROBE 1.0 POLAR DATUM
TCH PROBE 1.1 X ANGLE: +180
TCH PROBE 1.2 X+60 Y+0 Z-10
";
    let (it, _) = run_body("probe0.h", body);
    let ball = machine().probe_data().radius;
    close("Q10", it.q(10), OFF[2], MM);
    close("Q117 after cycle 0", it.q(11), OFF[2] + ball, MM);
    // cycle 1 along −X from X+60 at Y 0: the part's +X face (q_x = 50) turned by 1.5° has
    // the unit normal n = (cos, sin); the ball centre stops where n·p − n·(OFF + R(50, 0))
    // equals the ball radius
    let (s, c) = TURN.to_radians().sin_cos();
    let touch_x = (ball + 50.0 + OFF[0] * c + OFF[1] * s) / c;
    close("Q115 after cycle 1", it.q(115), touch_x, MM);
}

/// Runs `body` after the prelude on `m` and asserts that the first error is at `line` and
/// says `says`.
fn refused_at(m: &MachineConfig, name: &str, body: &str, line: u32, says: &str) {
    let path = common::temp_program(name, &program_text("PROBE", body));
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    let err = it.find_map(Result::err).expect("refused");
    assert!(err.message.contains(says), "{name}: {}", err.message);
    assert_eq!(err.line, line, "{name}: {}", err.message);
}

#[test]
fn probing_errors_name_their_cause_at_their_block() {
    // a machine without a probe
    let mill = MachineConfig::builtin_mill();
    refused_at(
        &mill,
        "probe_nomachine.h",
        &c400(0),
        6,
        "needs a touch probe",
    );
    let m = machine();
    refused_at(
        &m,
        "probe_missing_q.h",
        "TCH PROBE 412 ~\n  Q322=+0 ~\n  Q262=+24\n",
        6,
        "TCH PROBE 412 needs Q321",
    );
    // a pre-position inside the part: the stylus meets it on the way there
    refused_at(
        &m,
        "probe_collision.h",
        "TCH PROBE 0.0 REF. PLANE Q10 X+\nTCH PROBE 0.1 X+0 Y+20 Z-5\n",
        7,
        "touch probe collision",
    );
    // a probe standing inside the part (moved there by an ordinary block): already in contact
    refused_at(
        &m,
        "probe_inside.h",
        "L X+0 Y+20 Z-5 FMAX\nTCH PROBE 0.0 REF. PLANE Q10 X+\nTCH PROBE 0.1 X+0 Y+20 Z-5\n",
        8,
        "stylus already in contact",
    );
}

#[test]
fn measuring_cycles_421_424_427_report_size_and_deviation() {
    let c421 = "TCH PROBE 421 MEASURE HOLE ~
  Q273=-25 ;CENTER IN 1ST AXIS ~
  Q274=-10 ;CENTER IN 2ND AXIS ~
  Q262=+24 ;NOMINAL DIAMETER ~
  Q325=+0 ;STARTING ANGLE ~
  Q247=+120 ;STEPPING ANGLE ~
  Q261=-10 ;MEASURING HEIGHT ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+1 ;MOVE TO CLEARANCE ~
  Q275=+24.1 ;MAXIMUM LIMIT ~
  Q276=+23.9 ;MINIMUM LIMIT ~
  Q423=+3 ;NO. OF PROBE POINTS
";
    let (it, _) = run_body("probe421.h", c421);
    let c = program_of([-25.0, -10.0]);
    close("Q151", it.q(151), c[0], MM);
    close("Q153", it.q(153), 24.0, MM);
    close("Q161", it.q(161), c[0] + 25.0, MM);
    close("Q162", it.q(162), c[1] + 10.0, MM);
    close("Q163", it.q(163), 0.0, MM);

    let c424 = "TCH PROBE 424 MEAS. RECTAN. OUTS. ~
  Q273=+0 ;CENTER IN 1ST AXIS ~
  Q274=+0 ;CENTER IN 2ND AXIS ~
  Q282=+100.5 ;1ST SIDE LENGTH ~
  Q283=+80 ;2ND SIDE LENGTH ~
  Q261=-10 ;MEASURING HEIGHT ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+1 ;MOVE TO CLEARANCE
TCH PROBE 427 MEASURE COORDINATE ~
  Q263=+70 ;1ST POINT 1ST AXIS ~
  Q264=+0 ;1ST POINT 2ND AXIS ~
  Q261=-10 ;MEASURING HEIGHT ~
  Q320=+0 ;SET-UP CLEARANCE ~
  Q272=+1 ;MEASURING AXIS ~
  Q267=-1 ;TRAVERSE DIRECTION ~
  Q260=+20 ;CLEARANCE HEIGHT
";
    let (it, _) = run_body("probe424.h", &format!("{}{c424}", c400(0)));
    let c = aligned_of([0.0, 0.0]);
    close("Q154", it.q(154), 100.0, MM);
    close("Q164", it.q(164), -0.5, MM);
    close("Q161", it.q(161), c[0], MM);
    close("Q160", it.q(160), aligned_of([50.0, 0.0])[0], MM);
    // a measuring cycle leaves the preset alone
    let (xyz, _) = preset1(&it);
    close("preset X", xyz[0], ORIGIN[0], 1e-12);
}

#[test]
fn cycle_401_turns_the_preset_by_the_line_through_two_bores() {
    let body = "Q1 = ATAN(35 / 60)
TCH PROBE 401 ROT OF 2 HOLES ~
  Q268=-25 ;1ST CENTER 1ST AXIS ~
  Q269=-10 ;1ST CENTER 2ND AXIS ~
  Q270=+35 ;2ND CENTER 1ST AXIS ~
  Q271=+25 ;2ND CENTER 2ND AXIS ~
  Q261=-5 ;MEASURING HEIGHT ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q307=+Q1 ;PRESET ROTATION ANG. ~
  Q305=+0 ;NUMBER IN TABLE ~
  Q402=+0 ;COMPENSATION ~
  Q337=+0 ;SET TO ZERO
";
    let (it, _) = run_body("probe401.h", body);
    let nominal = 35.0f64.atan2(60.0).to_degrees();
    close("Q150", it.q(150), nominal + TURN, DEG);
    let (_, rot) = preset1(&it);
    close("preset ROT", rot, TURN, DEG);
}

#[test]
fn a_preset_written_to_another_row_acts_when_cycle_247_activates_it() {
    let body = "TCH PROBE 412 PRESET INSIDE CIRCLE ~
  Q321=-25 ;CENTER IN 1ST AXIS ~
  Q322=-10 ;CENTER IN 2ND AXIS ~
  Q262=+24 ;NOMINAL DIAMETER ~
  Q325=+0 ;STARTING ANGLE ~
  Q261=-10 ;MEASURING HEIGHT ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+1 ;MOVE TO CLEARANCE ~
  Q305=+2 ;NUMBER IN TABLE ~
  Q331=+10 ;DATUM ~
  Q332=-5 ;DATUM ~
  Q303=+1 ;MEAS. VALUE TRANSFER ~
  Q381=+1 ;PROBE IN TS AXIS ~
  Q382=-40 ;1ST CO. FOR TS AXIS ~
  Q383=+30 ;2ND CO. FOR TS AXIS ~
  Q384=+0 ;3RD CO. FOR TS AXIS ~
  Q333=+1 ;DATUM
L X+0 Y+0 Z+50 FMAX
CYCL DEF 247 DATUM SETTING ~
  Q339=+2 ;DATUM NUMBER
L X+10 Y-5 Z+1 FMAX
";
    let text = program_text("PROBE", body);
    let path = common::temp_program("probe_row2.h", &text);
    let m = machine();
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    let line_of = |start: &str| {
        text.lines()
            .position(|l| l.starts_with(start))
            .map(|i| i as u32 + 1)
    };
    let over_old = line_of("L X+0 Y+0 Z+50");
    let mut last = None;
    let mut before_247 = None;
    for op in it.by_ref() {
        let op = op.expect("runs");
        if let klar_interp::OpKind::Line { to, .. } = op.kind {
            if Some(op.loc.line) == over_old {
                before_247 = Some(to);
            }
            last = Some(to);
        }
    }
    // row 1 stays active until 247: the move to X+0 Y+0 is the old datum
    let b = before_247.expect("the move before 247");
    close("X before 247", b[klar_interp::AxisLetter::X], ORIGIN[0], MM);
    // after 247 the point Q331/Q332/Q333 of row 2 is the bore centre on the top
    let c = program_of([-25.0, -10.0]);
    let end = last.expect("moves");
    close("X", end[klar_interp::AxisLetter::X], ORIGIN[0] + c[0], MM);
    close("Y", end[klar_interp::AxisLetter::Y], ORIGIN[1] + c[1], MM);
    close("Z", end[klar_interp::AxisLetter::Z], ORIGIN[2] + OFF[2], MM);
    let (table, active) = it.presets();
    assert_eq!(active, Some(2));
    assert!(table.and_then(|t| t.row(2)).is_some());
}

#[test]
fn cycles_417_and_419_set_the_datum_one_axis_at_a_time() {
    // As a CAM post writes them: the top as Z0, the left edge as X-40, the back edge as Y+30.
    let body = "TCH PROBE 417 DATUM IN TS AXIS ~
  Q263=-40 ;1ST POINT 1ST AXIS ~
  Q264=+25 ;1ST POINT 2ND AXIS ~
  Q294=+0 ;1ST POINT 3RD AXIS ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q305=+0 ;NUMBER IN TABLE ~
  Q333=+0 ;DATUM ~
  Q303=+1 ;MEAS. VALUE TRANSFER
TCH PROBE 419 DATUM IN ONE AXIS ~
  Q263=-55 ;1ST POINT 1ST AXIS ~
  Q264=+0 ;1ST POINT 2ND AXIS ~
  Q261=-4 ;MEASURING HEIGHT ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q272=+1 ;MEASURING AXIS ~
  Q267=+1 ;TRAVERSE DIRECTION ~
  Q305=+0 ;NUMBER IN TABLE ~
  Q333=-40 ;DATUM ~
  Q303=+1 ;MEAS. VALUE TRANSFER
TCH PROBE 419 DATUM IN ONE AXIS ~
  Q263=-22.5 ;1ST POINT 1ST AXIS ~
  Q264=+45 ;1ST POINT 2ND AXIS ~
  Q261=-4 ;MEASURING HEIGHT ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q272=+2 ;MEASURING AXIS ~
  Q267=-1 ;TRAVERSE DIRECTION ~
  Q305=+0 ;NUMBER IN TABLE ~
  Q333=+30 ;DATUM ~
  Q303=+1 ;MEAS. VALUE TRANSFER
";
    let (it, _) = run_body("probe417_419.h", body);
    let (s, c) = TURN.to_radians().sin_cos();
    // 417: the top lies OFF[2] below its nominal Z0
    close("Q160", it.q(160), OFF[2], MM);
    // 419 in X at program Y0: the left edge, part points (-50, t)
    let t = (50.0 * s - OFF[1]) / c;
    // A ball probing a face turned by TURN touches it off its axis: the coordinate reported
    // (ball centre plus its radius along the probing direction) falls short of the face
    // where the probing line crosses it by r·(1/cos − 1), as on a real machine.
    let slant = BALL * (1.0 / c - 1.0);
    let x1 = OFF[0] - 50.0 * c - t * s - slant;
    // 419 in Y at of the shifted datum: the back edge, part points (t, 40)
    let x_probe = -22.5 + x1 + 40.0;
    let t = (x_probe - OFF[0] + 40.0 * s) / c;
    let y1 = OFF[1] + t * s + 40.0 * c + slant;
    let (xyz, rot) = preset1(&it);
    close("preset X", xyz[0], ORIGIN[0] + x1 + 40.0, 1e-9);
    close("preset Y", xyz[1], ORIGIN[1] + y1 - 30.0, 1e-9);
    close("preset Z", xyz[2], ORIGIN[2] + OFF[2], 1e-9);
    close("preset ROT", rot, 0.0, 1e-12);
}

#[test]
fn a_probe_cycle_reports_its_results_and_the_preset_it_wrote_as_an_op() {
    let path = common::program("probing_412.h");
    let m = machine();
    let it = m.open_program(&path, m.start_pose()).expect("opens");
    let results: Vec<klar_interp::ProbeResult> = it
        .map(|op| op.expect("runs"))
        .filter_map(|op| match op.kind {
            klar_interp::OpKind::ProbeResult { result } => Some(result),
            _ => None,
        })
        .collect();
    assert_eq!(results.len(), 1, "one probing cycle, one result");
    let r = &results[0];
    assert_eq!(r.cycle, 412);
    let c = program_of([-25.0, -10.0]);
    let q = |n: u32| r.params.iter().find(|p| p.0 == n).map(|p| p.1);
    close("Q151", q(151).expect("Q151 reported"), c[0], MM);
    close("Q152", q(152).expect("Q152 reported"), c[1], MM);
    close("Q153", q(153).expect("Q153 reported"), 24.0, MM);
    let preset = r.preset.as_ref().expect("the cycle wrote a preset");
    assert_eq!((preset.row, preset.active), (Some(1), true));
    let v = |a: klar_interp::AxisLetter| preset.values.iter().find(|p| p.0 == a).map(|p| p.1);
    close(
        "preset X",
        v(klar_interp::AxisLetter::X).expect("X"),
        ORIGIN[0] + c[0],
        MM,
    );
    close(
        "preset Z",
        v(klar_interp::AxisLetter::Z).expect("Z"),
        ORIGIN[2] + OFF[2],
        MM,
    );
}
