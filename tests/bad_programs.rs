//! The bad-input corpus in programs/bad/: every file's first diagnostic is the one written in
//! programs/bad/EXPECTED (line:col and the words naming the problem), no file lacks an entry,
//! and `klar run` refuses every one of them before anything moves.

mod common;

use common::run;
use klar::config::MachineConfig;
use klar_interp::Pose;
use std::path::{Path, PathBuf};

struct Expected {
    file: String,
    line: u32,
    col: u32,
    words: String,
}

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("programs/bad")
}

fn expectations() -> Vec<Expected> {
    let text = std::fs::read_to_string(corpus().join("EXPECTED")).expect("EXPECTED");
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let mut parts = l.split('\t');
            let file = parts.next().expect("file").to_string();
            let (line, col) = parts
                .next()
                .and_then(|p| p.split_once(':'))
                .expect("line:col");
            let words = parts.next().expect("words").to_string();
            Expected {
                file,
                line: line.parse().expect("line"),
                col: col.parse().expect("col"),
                words,
            }
        })
        .collect()
}

#[test]
fn every_bad_program_gives_its_expected_diagnostic() {
    let expected = expectations();
    let mut files: Vec<String> = std::fs::read_dir(corpus())
        .expect("corpus")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n != "EXPECTED")
        .collect();
    files.sort();
    let mut listed: Vec<String> = expected.iter().map(|e| e.file.clone()).collect();
    listed.sort();
    assert_eq!(files, listed, "programs/bad and EXPECTED disagree");
    for e in &expected {
        let path = corpus().join(&e.file);
        let diags = klar_interp::check(&path, Pose::ZERO);
        let first = diags
            .first()
            .unwrap_or_else(|| panic!("{}: no diagnostic", e.file));
        assert_eq!(
            (first.line, first.col),
            (e.line, e.col),
            "{}: got {first}",
            e.file
        );
        assert!(
            first.message.contains(&e.words),
            "{}: expected `{}` in `{}`",
            e.file,
            e.words,
            first.message
        );
        assert!(
            first
                .to_string()
                .starts_with(&format!("{}:{}:{}: ", path.display(), e.line, e.col)),
            "{first}"
        );
    }
}

#[test]
fn no_bad_program_moves_an_axis() {
    let machine = MachineConfig::builtin_mill();
    for e in expectations() {
        let path = corpus().join(&e.file);
        let (result, trace) = run(&path, &machine);
        assert!(result.is_err(), "{}: the run was not refused", e.file);
        assert!(
            trace.t.is_empty(),
            "{}: {} servo cycles ran",
            e.file,
            trace.t.len()
        );
    }
}
