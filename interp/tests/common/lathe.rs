//! Helpers shared by the lathe DIN tests: reading the example programs, running a program
//! text, and reading its moves back as (z, x radius) pairs.

use klar_interp::{AxisLetter, Diagnostic, Feed, Interpreter, Op, OpKind, Pose};
use std::path::PathBuf;

/// The text of a file below `programs/` of the repository (`rel` such as
/// `lathe/shaft_turning.nc`); panics naming the path when it cannot be read.
pub fn program_file(rel: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("programs")
        .join(rel);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The text of the lathe example program `name` in `programs/lathe/`.
pub fn lathe_program(name: &str) -> String {
    program_file(&format!("lathe/{name}"))
}

/// The path of the lathe example program `name` in `programs/lathe/`.
pub fn lathe_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../programs/lathe")
        .join(name)
}

/// Runs `text` as the file `name` from the origin and returns all ops; panics on a
/// diagnostic.
pub fn run_named(name: &str, text: &str) -> Vec<Op> {
    Interpreter::from_source(name, text, Pose::ZERO)
        .map(|r| r.unwrap_or_else(|d| panic!("{d}")))
        .collect()
}

/// Runs `text` as `t.nc`; panics on a diagnostic.
pub fn run_nc(text: &str) -> Vec<Op> {
    run_named("t.nc", text)
}

/// Runs the lathe example program `name` under its own name; panics on a diagnostic.
pub fn run_lathe(name: &str) -> Vec<Op> {
    run_named(name, &lathe_program(name))
}

/// Runs `text` as `t.nc`: all ops, or the first diagnostic as its `file:line:col` text.
pub fn run_text(text: &str) -> Result<Vec<Op>, String> {
    Interpreter::from_source("t.nc", text, Pose::ZERO)
        .map(|r| r.map_err(|d| d.to_string()))
        .collect()
}

/// Runs `text` as `bad.nc` until its first diagnostic: the ops before it and the
/// diagnostic; panics when the program runs through.
pub fn until_error(text: &str) -> (Vec<Op>, Diagnostic) {
    super::run_until_error_named("bad.nc", text)
}

/// The first diagnostic of `text` run as `bad.nc`; panics when the program runs through.
pub fn first_error(text: &str) -> Diagnostic {
    for r in Interpreter::from_source("bad.nc", text, Pose::ZERO) {
        if let Err(d) = r {
            return d;
        }
    }
    panic!("expected a diagnostic");
}

/// (z, x radius) of a pose.
pub fn zx(p: &Pose) -> [f64; 2] {
    [p[AxisLetter::Z], p[AxisLetter::X]]
}

/// The ops of the block with number `n`.
pub fn block(ops: &[Op], n: u64) -> Vec<Op> {
    ops.iter()
        .filter(|o| o.loc.block == Some(n))
        .cloned()
        .collect()
}

/// The straight moves of `ops` as (feed, from, to), each point as (z, x radius).
pub fn lines(ops: &[Op]) -> Vec<(Feed, [f64; 2], [f64; 2])> {
    ops.iter()
        .filter_map(|o| match o.kind {
            OpKind::Line { from, to, feed } => Some((feed, zx(&from), zx(&to))),
            _ => None,
        })
        .collect()
}

/// The straight moves of the block with number `n` as (feed, from, to), (z, x radius).
pub fn block_lines(ops: &[Op], n: u64) -> Vec<(Feed, [f64; 2], [f64; 2])> {
    lines(&block(ops, n))
}

/// The end pose and feed of every straight move, in machine coordinates.
pub fn line_ends(ops: &[Op]) -> Vec<(Pose, Feed)> {
    ops.iter()
        .filter_map(|o| match o.kind {
            OpKind::Line { to, feed, .. } => Some((to, feed)),
            _ => None,
        })
        .collect()
}

/// Asserts two (z, x) points agree within 1e-9 in both coordinates.
#[track_caller]
pub fn near(a: [f64; 2], b: [f64; 2]) {
    assert!(
        (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9,
        "{a:?} != {b:?}"
    );
}

/// Asserts a move list (feed, from, to) has as many moves as `want` and that each has the
/// wanted feed and ends within 1e-8 of the wanted (z, x radius).
#[track_caller]
pub fn check_moves(got: &[(Feed, [f64; 2], [f64; 2])], want: &[(Feed, [f64; 2])]) {
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(g.0, w.0, "move {i}: {g:?}");
        assert!(
            (g.2[0] - w.1[0]).abs() < 1e-8 && (g.2[1] - w.1[1]).abs() < 1e-8,
            "move {i}: {:?} != {:?}",
            g.2,
            w.1
        );
    }
}

/// 51 points evenly spaced from `from` to `to`, both ends included.
pub fn samples(from: [f64; 2], to: [f64; 2]) -> impl Iterator<Item = [f64; 2]> {
    (0..=50).map(move |k| {
        let t = f64::from(k) / 50.0;
        [
            from[0] + t * (to[0] - from[0]),
            from[1] + t * (to[1] - from[1]),
        ]
    })
}
