//! The command line for people: diagnostics keep their `file:line:col: message` line and add
//! the source snippet with a suggestion; `--quiet` leaves only errors; a run whose output is
//! not a terminal draws no progress bar; machine-file errors carry their line; help and
//! warnings say what the user needs to know.

use std::process::Command;

fn klar(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_klar"))
        .args(args)
        .output()
        .expect("klar runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn program(name: &str, text: &str) -> String {
    let dir = std::env::temp_dir().join(format!("klar-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

#[test]
fn a_slip_is_shown_in_its_line_with_the_likely_word() {
    let p = program(
        "slip.h",
        "0 BEGIN PGM T MM\n1 L Z+50 R0 FMX\n2 END PGM T MM\n",
    );
    let (code, out, err) = klar(&["check", &p]);
    assert_eq!(code, 1);
    assert!(out.is_empty(), "{out}");
    // The contract line first, then the snippet with the block and the suggestion.
    assert!(err.starts_with(&format!("{p}:2:13: ")), "{err}");
    assert!(err.contains("1 L Z+50 R0 FMX"), "{err}");
    assert!(err.contains("did you mean `FMAX`?"), "{err}");
}

#[test]
fn quiet_leaves_only_errors() {
    let good = program(
        "good.h",
        "0 BEGIN PGM T MM\n1 L Z+50 R0 FMAX\n2 END PGM T MM\n",
    );
    let (code, out, _) = klar(&["--quiet", "check", &good]);
    assert_eq!((code, out.as_str()), (0, ""));
    let (code, out, err) = klar(&["run", "-q", &good]);
    assert_eq!((code, out.as_str()), (0, ""));
    assert!(!err.contains('%'), "a progress bar on a pipe: {err}");
    // Without --quiet the summary names the machine time.
    let (code, out, _) = klar(&["run", &good]);
    assert_eq!(code, 0);
    assert!(out.contains("machine time:"), "{out}");
}

#[test]
fn run_help_lists_every_fault_kind() {
    let (code, out, _) = klar(&["run", "--help"]);
    assert_eq!(code, 0);
    for (name, _) in klar::faults::FaultKind::NAMES {
        assert!(
            out.contains(name),
            "`{name}` missing from run --help:\n{out}"
        );
    }
}

#[test]
fn an_unwritable_plot_path_is_a_sentence() {
    let p = program(
        "plot.h",
        "0 BEGIN PGM T MM\n1 L X+10 R0 FMAX\n2 END PGM T MM\n",
    );
    let (code, _, err) = klar(&["plot", &p, "-o", "/nonexistent-folder/x.png"]);
    assert_eq!(code, 1);
    assert!(
        err.starts_with("cannot write the plot to /nonexistent-folder/x.png: "),
        "{err}"
    );
    assert!(
        !err.contains("ImageError") && !err.contains("Os {"),
        "{err}"
    );
}

#[test]
fn logs_to_a_pipe_carry_no_colour_codes() {
    let p = program(
        "log.h",
        "0 BEGIN PGM T MM\n1 L X+10 R0 FMAX\n2 END PGM T MM\n",
    );
    let out = Command::new(env!("CARGO_BIN_EXE_klar"))
        .args(["check", &p])
        .env("RUST_LOG", "debug")
        .output()
        .expect("klar runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("DEBUG"), "no log lines to look at: {err}");
    assert!(!err.contains('\u{1b}'), "colour codes on a pipe: {err:?}");
}

#[test]
fn a_refused_run_prints_no_summary() {
    let p = program(
        "refused.h",
        "0 BEGIN PGM T MM\n1 L X+10 R0 FMX\n2 END PGM T MM\n",
    );
    let (code, out, err) = klar(&["run", &p]);
    assert_eq!(code, 1);
    assert!(err.contains("nothing moved"), "{err}");
    assert!(!out.contains("machine time"), "{out}");
}

/// The built-in mill's file with `from` replaced by `to`, written as `name`.
fn machine(name: &str, from: &str, to: &str) -> String {
    let text = klar::config::BUILTIN_MILL.replacen(from, to, 1);
    assert_ne!(text, klar::config::BUILTIN_MILL, "{from} not found");
    program(name, &text)
}

/// The 1-based line of the first line of the built-in mill's file that contains `what`
/// after `after` (or from the top).
fn line_of(after: &str, what: &str) -> usize {
    let lines: Vec<&str> = klar::config::BUILTIN_MILL.lines().collect();
    let start = lines.iter().position(|l| l.contains(after)).unwrap();
    start
        + 1
        + lines[start..]
            .iter()
            .position(|l| l.contains(what))
            .unwrap()
}

#[test]
fn machine_file_value_errors_point_at_their_line() {
    let prog = program(
        "m.h",
        "0 BEGIN PGM T MM\n1 L X+10 R0 FMAX\n2 END PGM T MM\n",
    );
    // the second axis (Y): its max_velocity
    let y = line_of("letter = \"Y\"", "max_velocity");
    let m = machine(
        "negv.toml",
        "letter = \"Y\"\nkind = \"linear\"\ntravel = [-300.0, 300.0]\nmax_velocity = 166.0",
        "letter = \"Y\"\nkind = \"linear\"\ntravel = [-300.0, 300.0]\nmax_velocity = -166.0",
    );
    let (code, _, err) = klar(&["check", "--machine", &m, &prog]);
    assert_eq!(code, 1);
    assert!(
        err.starts_with(&format!("{m}:{y}:1: axis Y: max_velocity")),
        "{err}"
    );
    let t = line_of("letter = \"Z\"", "travel");
    let m = machine(
        "travel.toml",
        "travel = [-200.0, 200.0]",
        "travel = [200.0, -200.0]",
    );
    let (_, _, err) = klar(&["check", "--machine", &m, &prog]);
    assert!(
        err.starts_with(&format!("{m}:{t}:1: axis Z: travel")),
        "{err}"
    );
}

#[test]
fn a_misspelled_key_gets_its_place_and_a_suggestion() {
    let prog = program(
        "k.h",
        "0 BEGIN PGM T MM\n1 L X+10 R0 FMAX\n2 END PGM T MM\n",
    );
    let l = line_of("letter = \"X\"", "max_jerk");
    let m = machine("typo.toml", "max_jerk = 50000.0", "max_jerck = 50000.0");
    let (code, _, err) = klar(&["check", "--machine", &m, &prog]);
    assert_eq!(code, 1);
    assert!(
        err.starts_with(&format!(
            "{m}:{l}:1: unknown key `max_jerck` — did you mean `max_jerk`?"
        )),
        "{err}"
    );
}

#[test]
fn errors_in_a_nested_spindle_table_point_at_the_key() {
    let prog = program(
        "s.h",
        "0 BEGIN PGM T MM\n1 L X+10 R0 FMAX\n2 END PGM T MM\n",
    );
    let base = klar::config::BUILTIN_MILL;
    let spindle = base.find("[spindle]").unwrap();
    let head = &base[..spindle];
    let extra = "[spindle]\nmax_rpm = 12000.0\n\n[spindle.backend]\nkind = \"sim\"\n";
    let line = head.lines().count() + 6;
    let typo = program("sp1.toml", &format!("{head}{extra}accelration = 300.0\n"));
    let (_, _, err) = klar(&["check", "--machine", &typo, &prog]);
    assert!(
        err.starts_with(&format!(
            "{typo}:{line}:1: unknown key `accelration` — did you mean `acceleration`?"
        )),
        "{err}"
    );
    let typed = program(
        "sp2.toml",
        &format!("{head}{extra}acceleration = \"fast\"\n"),
    );
    let (_, _, err) = klar(&["check", "--machine", &typed, &prog]);
    assert!(
        err.starts_with(&format!("{typed}:{line}:1: acceleration: invalid type")),
        "{err}"
    );
}

#[test]
fn a_real_port_under_simulate_is_named_as_simulated() {
    let prog = program(
        "p.h",
        "0 BEGIN PGM T MM\n1 L X+10 R0 FMAX\n2 END PGM T MM\n",
    );
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/machines/modbus-sim.toml"
    ))
    .unwrap();
    let real = text.replacen("port = \"simulated\"", "port = \"/dev/ttyUSB7\"", 1);
    assert_ne!(real, text);
    let m = program("real-port.toml", &real);
    let (_, _, err) = klar(&["check", "--machine", &m, &prog]);
    assert!(
        err.contains("`simulate` is set") && err.contains("does not use port /dev/ttyUSB7"),
        "{err}"
    );
}

#[test]
fn serve_without_a_programs_folder_says_so() {
    // `timeout` ends the server after a second; the warning comes before it listens
    let out = Command::new("timeout")
        .args(["1", env!("CARGO_BIN_EXE_klar"), "serve", "--port", "0"])
        .args(["--programs", "/nonexistent-programs"])
        .output()
        .expect("timeout and klar run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no programs folder /nonexistent-programs"),
        "{err}"
    );
}

#[test]
fn a_lathe_check_reports_x_as_a_diameter() {
    // the recess floor Ø30 is the smallest X; the built-in tool change point is X200
    let (code, out, err) = klar(&["check", "programs/lathe/groove_g866_g870.nc"]);
    assert_eq!(code, 0, "{err}");
    let all = format!("{out}{err}");
    assert!(all.contains("X (diameter): 30.0000 .. 200.0000"), "{all}");
}
