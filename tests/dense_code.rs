//! Dense code end to end on the built-in mill: programs of very many very short moves run
//! to their last block and end on its point.

mod common;

use common::{run, temp_program};
use klar::config::MachineConfig;
use std::fmt::Write;

/// A zigzag of `n` moves of 0.1 µm that turn 90° at every corner (an exact stop each: no
/// blend fits), at F600 after a rapid to the origin.
fn zigzag(n: usize) -> String {
    let mut text = String::from("BEGIN PGM ZIGZAG MM\nL X+0 Y+0 Z+0 FMAX\n");
    for i in 1..=n {
        let feed = if i == 1 { " F600" } else { "" };
        let _ = writeln!(
            text,
            "L X{:+.4} Y{:+.4}{feed}",
            i as f64 * 1e-4,
            (i % 2) as f64 * 1e-4
        );
    }
    text.push_str("END PGM ZIGZAG MM\n");
    text
}

#[test]
fn a_program_that_fills_the_planner_runs_to_its_last_block() {
    // 10 100 moves with a stop after each fill the planner's buffer (a piece and a stop
    // each, 20 000 in all) long before its look-ahead distance: reaching a stop then frees
    // a place and the planner asks for input again. That is not the end of the program.
    let n = 10_100;
    let machine = MachineConfig::builtin_mill();
    let path = temp_program("zigzag.h", &zigzag(n));
    let (result, trace) = run(&path, &machine);
    let report = result.unwrap_or_else(|f| panic!("{}", f.error));
    assert_eq!(report.blocks, n as u64 + 3, "every block runs");
    let column = |l: &str| trace.column(l).expect("axis column");
    let (xs, ys) = (column("X"), column("Y"));
    let (x, y) = (xs[xs.len() - 1], ys[ys.len() - 1]);
    assert!(
        (x - n as f64 * 1e-4).abs() < 1e-9 && y.abs() < 1e-9,
        "ends at ({x}, {y})"
    );
}
