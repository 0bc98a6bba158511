//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod lathe;
pub mod recess;

use klar_interp::{Diagnostic, Interpreter, Op, OpKind, Plane, Pose};
use std::path::PathBuf;

/// Wraps blocks in BEGIN/END PGM.
pub fn program(body: &str) -> String {
    format!("BEGIN PGM T MM\n{body}\nEND PGM T MM\n")
}

/// Runs a program from the origin and returns all ops; panics on a diagnostic.
pub fn run(text: &str) -> Vec<Op> {
    run_from(text, Pose::ZERO)
}

/// Runs a program from `start`; panics on a diagnostic.
pub fn run_from(text: &str, start: Pose) -> Vec<Op> {
    Interpreter::from_source("t.h", text, start)
        .map(|r| r.unwrap_or_else(|d| panic!("{d}")))
        .collect()
}

/// Runs until the first diagnostic: the ops before it and the diagnostic.
pub fn run_until_error(text: &str) -> (Vec<Op>, Diagnostic) {
    run_until_error_named("t.h", text)
}

/// Runs `text` as the file `name` until the first diagnostic: the ops before it and the
/// diagnostic; panics when the program runs through.
pub fn run_until_error_named(name: &str, text: &str) -> (Vec<Op>, Diagnostic) {
    let mut ops = Vec::new();
    for r in Interpreter::from_source(name, text, Pose::ZERO) {
        match r {
            Ok(op) => ops.push(op),
            Err(d) => return (ops, d),
        }
    }
    panic!("expected a diagnostic, got {} ops", ops.len());
}

/// Only the motion ops.
pub fn motions(ops: &[Op]) -> Vec<OpKind> {
    ops.iter()
        .filter(|o| o.kind.is_motion())
        .map(|o| o.kind.clone())
        .collect()
}

/// Unpacks an arc op: (from, to, center, plane, sweep); panics on any other op.
#[track_caller]
pub fn arc(k: &OpKind) -> (Pose, Pose, [f64; 2], Plane, f64) {
    match k {
        OpKind::Arc {
            from,
            to,
            center,
            plane,
            sweep,
            ..
        } => (*from, *to, *center, *plane, *sweep),
        other => panic!("not an arc: {other:?}"),
    }
}

/// A pseudo-random program text for the no-panic tests: `head`, then `len` bytes drawn
/// from `alphabet` by a 32-bit xorshift started from `seed · 2654435761 + salt`.
pub fn random_text(seed: u32, salt: u32, head: &[u8], len: usize, alphabet: &[u8]) -> String {
    let mut x = seed.wrapping_mul(2_654_435_761).wrapping_add(salt);
    let mut bytes = head.to_vec();
    for _ in 0..len {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        bytes.push(alphabet[(x as usize) % alphabet.len()]);
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

/// Asserts two numbers agree within 1e-9.
#[track_caller]
pub fn close(a: f64, b: f64) {
    assert!((a - b).abs() < 1e-9, "{a} != {b}");
}

/// Writes bytes to a fresh file in the system temp directory and returns its path.
pub fn temp_file(name: &str, bytes: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "klar-interp-test-{}-{}",
        std::process::id(),
        name.replace('.', "_")
    ));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let p = dir.join(name);
    std::fs::write(&p, bytes).expect("write temp file");
    p
}

/// Removes a file made by [`temp_file`] together with its directory.
pub fn remove_temp(path: &std::path::Path) {
    if let Some(dir) = path.parent() {
        let _ = std::fs::remove_dir_all(dir);
    }
}
