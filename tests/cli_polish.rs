//! The command line for people: diagnostics keep their `file:line:col: message` line and add
//! the source snippet with a suggestion; `--quiet` leaves only errors; a run whose output is
//! not a terminal draws no progress bar.

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
