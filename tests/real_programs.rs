//! Programs as CAM posts and TNC operators write them, run on the simulated machines: the
//! retract `M140 MB MAX` to the travel limit, presets from the machine's preset table
//! (cycle 247 and the preset active at start), datum tables, and `klar check` judging a
//! program on the machine `klar run` uses. The programs are written here in the style of the
//! posts (CRLF, header comments, FN 0 feeds with FQ words, cycle 32 without values, cycles
//! with M99, TOOL CALL with DL), not copied from anyone.

mod common;

use common::{arg, commanded, klar_cli, run, temp_program};
use klar::config::{ActivePreset, BUILTIN_MILL, BUILTIN_MILL5, MachineConfig};
use klar::testrun::test_run;
use std::path::PathBuf;

/// A post-style job: outline with one tool, two drilled holes with another, `M140 MB MAX`
/// after each tool call and at the end.
const POSTED: &str = "0  BEGIN PGM BRACKET MM \r
1  BLK FORM 0.1 Z  X-50  Y-40  Z-12\r
2  BLK FORM 0.2  X+50  Y+40  Z+0\r
3  ;-------------------------------------\r
4  ;Tools\r
5  ;  #4 D=8 - ZMIN=-3 - flat end mill\r
6  ;  #7 D=6.8 - ZMIN=-8 - drill\r
7  ;-------------------------------------\r
8  ;\r
9  * - Outline (1)\r
10 FN 0: Q50 =+1500 ; Cutting\r
11 FN 0: Q51 =+500 ; Plunge\r
12 M5\r
13 TOOL CALL 4 Z S9000 DL+0.1\r
14 L M140 MB MAX\r
15 M3\r
16 L  X-45  Y-35 R0 FMAX\r
17 L  Z+15 R0 FMAX\r
18 M8\r
19 CYCL DEF 32.0 TOLERANCE\r
20 CYCL DEF 32.1\r
21 L  Z+2 FMAX\r
22 L  Z-3 FQ51\r
23 L  X+45 FQ50\r
24 L  Y+35\r
25 L  X-45\r
26 L  Y-35\r
27 L  Z+15 FMAX\r
28 M9\r
29 * - Drill (2)\r
30 M5\r
31 TOOL CALL 7 Z S3000\r
32 L M140 MB MAX\r
33 M3\r
34 L  X+20  Y+0 R0 FMAX\r
35 L  Z+15 R0 FMAX\r
36 M8\r
37 CYCL DEF 200 DRILLING ~\r
    Q200=+2 ;SET-UP CLEARANCE ~\r
    Q201=-8 ;DEPTH ~\r
    Q206=+250 ;FEED RATE FOR PLNGNG ~\r
    Q202=+4 ;PLUNGING DEPTH ~\r
    Q210=+0 ;DWELL TIME AT TOP ~\r
    Q203=+0 ;SURFACE COORDINATE ~\r
    Q204=+15 ;2ND SET-UP CLEARANCE ~\r
    Q211=+0 ;DWELL TIME AT BOTTOM\r
38 L  X+20  Y+0 FMAX M99\r
39 L  X-20  Y+0 FMAX M99\r
40 M9\r
41 M5\r
42 L M140 MB MAX\r
43 M30\r
44 END PGM BRACKET MM \r
";

/// Writes `machine` (TOML text) and the given table files into a fresh folder.
fn machine_dir(name: &str, machine: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("klar-test-{}-real-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    for (file, text) in files {
        std::fs::write(dir.join(file), text).expect("write table");
    }
    let path = dir.join("machine.toml");
    std::fs::write(&path, machine).expect("write machine");
    path
}

/// The built-in mill with a tool table of tools 4 and 7 and the given extra keys (which must
/// come before the mill's first table).
fn mill_with(name: &str, keys: &str, files: &[(&str, &str)]) -> MachineConfig {
    let mut all = vec![("TOOL.T", TOOLS)];
    all.extend_from_slice(files);
    let text = format!("tool_table = \"TOOL.T\"\n{keys}\n{BUILTIN_MILL}");
    let path = machine_dir(name, &text, &all);
    MachineConfig::load(&path).expect("machine loads")
}

const TOOLS: &str = "BEGIN TOOL.T MM\r
T    NAME         L         R        DL     DR\r
4    MILL_D8      +60       +4       +0     +0\r
7    DRILL_D6.8   +95       +3.4     +0     +0\r
[END]\r
";

const PRESETS: &str = "BEGIN PRESET.PR MM\r
NR   DOC          X          Y          Z\r
0    machine      +0         +0         +0\r
1    vice left    +100       +50        -20\r
2    vice right   -80        +40        -10\r
[END]\r
";

const DATUMS: &str = "BEGIN NULLTAB.D MM\r
NR   X          Y          Z\r
0    +0         +0         +0\r
3    +12.5      -7.5       +0\r
[END]\r
";

fn column(trace: &common::Trace, letter: &str) -> Vec<f64> {
    commanded(trace, &[letter]).remove(0)
}

#[test]
fn a_posted_job_passes_the_check_and_retracts_to_the_travel_limit() {
    let machine = mill_with("posted", "", &[]);
    let path = temp_program("posted.h", POSTED);
    let report = test_run(&path, &machine);
    assert!(report.passed(), "{:?}", report.errors);
    let (result, trace) = run(&path, &machine);
    result.expect("the posted job runs");
    let z = column(&trace, "Z");
    let z_max = machine.axes[2].travel[1];
    assert_eq!(z_max, 200.0);
    // Every MB MAX ends exactly at the travel limit, never beyond it.
    assert!(z.iter().all(|&v| v <= z_max), "Z beyond its travel");
    // Three retracts: count the arrivals at the limit from below.
    let arrivals = z
        .windows(2)
        .filter(|w| w[0] < z_max && w[1] == z_max)
        .count();
    // the program starts at Z100 (the mill's start), so the first MB MAX is an arrival too
    assert_eq!(arrivals, 3, "arrivals at Z{z_max}");
    // The drill reaches its depth, the end mill its own.
    let lowest = z.iter().copied().fold(f64::INFINITY, f64::min);
    assert!((lowest + 8.0).abs() < 1e-9, "lowest Z {lowest}");
    assert_eq!(z.last().copied(), Some(z_max));
}

#[test]
fn mb_max_on_a_tilted_table_moves_only_the_machine_z() {
    // A long tool (L 120) in a plane tilted by 30° about X: on the table-table machine the
    // tilted tool axis is the machine's Z, so the retract runs machine Z up to its limit and
    // holds every other axis.
    let text = "BEGIN PGM TILT MM\n\
        TOOL DEF 9 L+120 R+5\n\
        TOOL CALL 9 Z S4000\n\
        L X+0 Y+0 Z+50 A+0 C+0 R0 FMAX\n\
        PLANE SPATIAL SPA+30 SPB+0 SPC+0 TURN FMAX\n\
        L X+10 Y+5 FMAX\n\
        L Z+20 FMAX\n\
        L M140 MB MAX\n\
        END PGM TILT MM\n";
    let path = temp_program("tilt_mb.h", text);
    let machine = MachineConfig::parse("mill5", BUILTIN_MILL5).expect("mill5");
    let (result, trace) = run(&path, &machine);
    result.expect("the tilted retract runs");
    let cols = commanded(&trace, &["X", "Y", "Z", "A", "C"]);
    let n = cols[0].len() - 1;
    let z_max = machine.axes[2].travel[1];
    assert!(
        (cols[2][n] - z_max).abs() < 1e-9,
        "machine Z ends at {}",
        cols[2][n]
    );
    // Walk back from the end while Z is still rising: X, Y, A, C stay as they were.
    let mut k = n;
    while k > 0 && cols[2][k - 1] < cols[2][k] {
        k -= 1;
    }
    assert!(
        cols[2][n] - cols[2][k] > 50.0,
        "a real retract: from Z {}",
        cols[2][k]
    );
    for (axis, c) in [(0, "X"), (1, "Y"), (3, "A"), (4, "C")] {
        let moved = (k..=n)
            .map(|i| (cols[axis][i] - cols[axis][k]).abs())
            .fold(0.0, f64::max);
        assert!(moved < 1e-6, "{c} moved {moved} during the retract");
    }
    assert!((cols[3][n] - 30.0).abs() < 1e-6, "A at {}", cols[3][n]);
}

#[test]
fn cycle_247_takes_its_preset_from_the_machines_preset_table() {
    let machine = mill_with(
        "presets",
        "preset_table = \"PRESET.PR\"",
        &[("PRESET.PR", PRESETS)],
    );
    let text = "BEGIN PGM P MM\r\n\
        CYCL DEF 247 DATUM SETTING ~\r\n  Q339=+1 ;DATUM NUMBER\r\n\
        L X+0 Y+0 Z+10 R0 FMAX\r\n\
        L X+5 F1000\r\n\
        END PGM P MM\r\n";
    let path = temp_program("p247.h", text);
    let (result, trace) = run(&path, &machine);
    result.expect("runs with preset 1");
    let cols = commanded(&trace, &["X", "Y", "Z"]);
    let n = cols[0].len() - 1;
    // preset 1 is X+100 Y+50 Z-20: program X5 Y0 Z10 is machine X105 Y50 Z-10
    assert_eq!((cols[0][n], cols[1][n], cols[2][n]), (105.0, 50.0, -10.0));
    // Without the table the message names the machine-file key.
    let bare = mill_with("nopresets", "", &[]);
    let report = test_run(&path, &bare);
    let first = report
        .errors
        .first()
        .map(|d| d.to_string())
        .unwrap_or_default();
    assert!(
        first.contains("preset 1 asked for") && first.contains("`preset_table`"),
        "{first}"
    );
}

#[test]
fn the_active_preset_holds_from_the_start_and_the_check_names_it() {
    let machine = mill_with(
        "active",
        "preset_table = \"PRESET.PR\"\nactive_preset = 2",
        &[("PRESET.PR", PRESETS)],
    );
    assert_eq!(
        machine.active_preset(),
        Ok(ActivePreset::Row {
            nr: 2,
            values: [-80.0, 40.0, -10.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        })
    );
    let text = "BEGIN PGM A MM\nL X+0 Y+0 Z+10 R0 FMAX\nL X+20 F1000\nEND PGM A MM\n";
    let path = temp_program("active.h", text);
    let (result, trace) = run(&path, &machine);
    result.expect("runs");
    let cols = commanded(&trace, &["X", "Y", "Z"]);
    let n = cols[0].len() - 1;
    assert_eq!((cols[0][n], cols[1][n], cols[2][n]), (-60.0, 40.0, 0.0));
    // A row that is not in the table refuses the machine file.
    let dir = machine_dir(
        "badactive",
        &format!("preset_table = \"PRESET.PR\"\nactive_preset = 9\n{BUILTIN_MILL}"),
        &[("PRESET.PR", PRESETS)],
    );
    let err = MachineConfig::load(&dir)
        .expect_err("row 9 is missing")
        .to_string();
    assert!(err.contains("active_preset = 9"), "{err}");
    // The check report says which preset is active.
    let (ok, out, err) = klar_cli(&[
        "check",
        arg(&path),
        "--machine",
        arg(&machine_path("active")),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("preset at start: 2 X-80 Y+40 Z-10"), "{out}");
}

#[test]
fn a_datum_table_row_shifts_the_program() {
    let machine = mill_with(
        "datums",
        "datum_table = \"NULLTAB.D\"",
        &[("NULLTAB.D", DATUMS)],
    );
    let text = "BEGIN PGM D MM\n\
        CYCL DEF 7.0 DATUM SHIFT\n\
        CYCL DEF 7.1 #3\n\
        L X+0 Y+0 Z+10 R0 FMAX\n\
        END PGM D MM\n";
    let path = temp_program("datum.h", text);
    let (result, trace) = run(&path, &machine);
    result.expect("runs");
    let cols = commanded(&trace, &["X", "Y", "Z"]);
    let n = cols[0].len() - 1;
    assert_eq!((cols[0][n], cols[1][n], cols[2][n]), (12.5, -7.5, 10.0));
}

fn machine_path(name: &str) -> PathBuf {
    std::env::temp_dir()
        .join(format!("klar-test-{}-real-{name}", std::process::id()))
        .join("machine.toml")
}

#[test]
fn check_judges_a_program_on_the_machine_run_uses() {
    // C is not an axis of the built-in mill: check and run both refuse, at the same line.
    let text = "BEGIN PGM AUX MM\nL X+0 Y+0 Z+50 R0 FMAX\nL C+90 FMAX\nEND PGM AUX MM\n";
    let path = temp_program("aux.h", text);
    let (ok, _, check_err) = klar_cli(&["check", arg(&path)]);
    assert!(!ok, "check must refuse what run refuses");
    assert!(check_err.contains(":3:"), "{check_err}");
    assert!(
        check_err.contains("axis C is not on this machine"),
        "{check_err}"
    );
    let (ok, _, run_err) = klar_cli(&["run", arg(&path)]);
    assert!(!ok);
    assert!(run_err.contains(":3:"), "{run_err}");
    // On its own, without a machine, the program is fine.
    let (ok, _, err) = klar_cli(&["check", "--program-only", arg(&path)]);
    assert!(ok, "{err}");
    // The plain check says which machine it used.
    let good = temp_program("good.h", "BEGIN PGM G MM\nL Z+50 R0 FMAX\nEND PGM G MM\n");
    let (ok, out, err) = klar_cli(&["check", arg(&good)]);
    assert!(ok, "{err}");
    assert!(out.contains("ok on klar simulated 3-axis mill"), "{out}");
}

#[test]
fn one_excursion_beyond_the_travel_is_one_error() {
    // X is sent to 1000 once; the blocks that start there are its consequences. The later
    // Z-500 is an error of its own.
    let text = "BEGIN PGM TR MM\nL X+0 Y+0 Z+50 R0 FMAX\nL X+1000 F500\nL Y+10\nL Y+20\n\
                L X+0\nL Z-500 FMAX\nEND PGM TR MM\n";
    let path = temp_program("travel.h", text);
    let report = test_run(&path, &MachineConfig::builtin_mill());
    let lines: Vec<u32> = report.errors.iter().map(|d| d.line).collect();
    assert_eq!(lines, [3, 7], "{:?}", report.errors);
    assert!(
        report.errors[0]
            .message
            .contains("axis X would move to 1000.0000")
    );
    assert!(
        report.errors[1]
            .message
            .contains("axis Z would move to -500.0000")
    );
}

#[test]
fn radius_compensation_with_an_undefined_tool_warns() {
    let text = "BEGIN PGM R MM\nTOOL CALL 5 Z S1000\nL X+0 Y+0 Z+5 R0 FMAX\n\
                L X+10 Y+0 RL F300\nL X+20\nL X+30 R0\nEND PGM R MM\n";
    let path = temp_program("rl0.h", text);
    let report = test_run(&path, &MachineConfig::builtin_mill());
    assert!(report.passed(), "{:?}", report.errors);
    let w: Vec<String> = report.warnings.iter().map(|d| d.to_string()).collect();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains(":4:") && w[0].contains("tool 5") && w[0].contains("radius 0"));
    // a tool with a radius gives no warning
    let defined = text.replace("TOOL CALL 5", "TOOL DEF 5 L+50 R+3\nTOOL CALL 5");
    let path = temp_program("rl3.h", &defined);
    assert!(
        test_run(&path, &MachineConfig::builtin_mill())
            .warnings
            .is_empty()
    );
}

#[test]
fn m91_positions_in_machine_coordinates_past_the_preset() {
    let machine = mill_with(
        "m91",
        "preset_table = \"PRESET.PR\"\nactive_preset = 1",
        &[("PRESET.PR", PRESETS)],
    );
    // preset 1: X+100 Y+50 Z-20. M91 blocks ignore it (and the datum shift of cycle 7).
    let text = "BEGIN PGM M MM\n\
        CYCL DEF 7.0 DATUM SHIFT\nCYCL DEF 7.1 X+5\n\
        L Z+150 R0 FMAX M91\n\
        L X+0 Y+0 FMAX\n\
        L X-250 FMAX M92\n\
        L Z+10 FMAX\n\
        END PGM M MM\n";
    let path = temp_program("m91.h", text);
    let (result, trace) = run(&path, &machine);
    result.expect("runs");
    let cols = commanded(&trace, &["X", "Y", "Z"]);
    let at_end_of = |pred: &dyn Fn(usize) -> bool| (0..cols[0].len()).filter(|&i| pred(i)).count();
    // The corners between the rapids may be crossed within the path tolerance (0.01 mm):
    // the path passes within twice that of each corner point; each move's own end is
    // reached exactly.
    let near = |v: f64, w: f64| (v - w).abs() <= 0.02 + 1e-9;
    // Z went to machine 150 exactly (not 130), and X then to 105 (preset 100 + shift 5)
    assert!(at_end_of(&|i| cols[2][i] == 150.0) > 0);
    assert!(at_end_of(&|i| cols[0][i] == 105.0) > 0);
    assert!(at_end_of(&|i| near(cols[2][i], 150.0) && near(cols[0][i], 105.0)) > 0);
    // M92 X-250: machine X -250 with Y held at the preset's 50
    assert!(at_end_of(&|i| cols[0][i] == -250.0 && cols[1][i] == 50.0) > 0);
    assert!(at_end_of(&|i| near(cols[0][i], -250.0) && near(cols[2][i], 150.0)) > 0);
    let n = cols[0].len() - 1;
    // the last block is back in program coordinates: Z10 is machine Z -10
    assert_eq!((cols[0][n], cols[1][n], cols[2][n]), (-250.0, 50.0, -10.0));
}

/// A five-axis job in the style of an NX post: FUNCTION RESET TCPM and PLANE RESET STAY at
/// the top, an M91 retract, a tool called by name with a preselected next tool, PLANE
/// SPATIAL … STAY SEQ- TABLE ROT positioned through Q120/Q122, `F MAX` with a blank, a
/// skipped block, a string label, and PLANE RESET MOVE at the end.
const NX_STYLE: &str = "0  BEGIN PGM NXPART MM\r
1  ; NX POST - 5X TABLE-TABLE\r
2  BLK FORM 0.1 Z X-60 Y-60 Z-40\r
3  BLK FORM 0.2 X+60 Y+60 Z+0\r
4  FUNCTION RESET TCPM\r
5  PLANE RESET STAY\r
6  L Z+250 R0 FMAX M91\r
7  TOOL CALL \"EM_D10\" Z S8000 DL+0 DR+0\r
8  TOOL DEF 12\r
9  M3\r
10 M8\r
11 PLANE SPATIAL SPA+20 SPB+0 SPC+0 STAY SEQ- TABLE ROT\r
12 L A+Q120 C+Q122 R0 FMAX\r
13 L X+0 Y+0 R0 FMAX\r
14 L Z+50 F MAX\r
15 L Z+5 F2000\r
16 L X+20 F800\r
17 L Y+20\r
18 /L X+0\r
19 L Y+0\r
20 L Z+50 FMAX\r
21 LBL \"UP\"\r
22 L Z+60 FMAX\r
23 LBL 0\r
24 CALL LBL \"UP\"\r
25 PLANE RESET MOVE FMAX SEQ+\r
26 L Z+250 R0 FMAX M91\r
27 M9\r
28 M5\r
29 M30\r
30 END PGM NXPART MM\r
";

#[test]
fn an_nx_style_five_axis_job_runs_within_the_limits() {
    let tools = "BEGIN TOOL.T MM\nT    NAME     L      R\n10   EM_D10   +60    +5\n\
                 12   DRILL_6  +80    +3\n[END]\n";
    let path = machine_dir(
        "nx",
        &format!("tool_table = \"TOOL.T\"\n{BUILTIN_MILL5}"),
        &[("TOOL.T", tools)],
    );
    let machine = MachineConfig::load(&path).expect("mill5 with tools");
    let program = temp_program("nx.h", NX_STYLE);
    let report = test_run(&program, &machine);
    assert!(report.passed(), "{:?}", report.errors);
    let (result, trace) = run(&program, &machine);
    result.expect("the NX-style job runs");
    common::assert_within_limits(&trace, &machine);
    let cols = commanded(&trace, &["X", "Y", "Z", "A", "C"]);
    let n = cols[0].len() - 1;
    // SEQ- tilts the table the negative way: A-20 (written to Q120 by the PLANE block)
    let a_min = cols[3].iter().copied().fold(f64::INFINITY, f64::min);
    assert!((a_min + 20.0).abs() < 1e-9, "A reached {a_min}");
    // The skipped block 18 never sends X back to 0 while Y is at 20.
    let back = (0..=n).any(|i| cols[0][i].abs() < 1e-6 && (cols[1][i] - 20.0).abs() < 1e-6);
    assert!(!back, "block 18 (/L X+0) ran");
    // PLANE RESET MOVE brings the table back; the M91 block ends at machine Z250.
    assert!(cols[3][n].abs() < 1e-9 && cols[4][n].abs() < 1e-9);
    assert!((cols[2][n] - 250.0).abs() < 1e-9, "Z {}", cols[2][n]);
}
