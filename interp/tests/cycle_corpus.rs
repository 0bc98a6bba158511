//! Real Klartext programs with cycles (../shared/corpus): their CYCL blocks parse and run.

use std::path::PathBuf;

use klar_interp::{Feed, Interpreter, OpKind, Pose, Tool, ToolTable, check, syntax_check};

fn corpus(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/corpus/klartext")
        .join(name)
}

/// Files present in this checkout (the corpus lives outside the repository).
fn present(names: &[&'static str]) -> Vec<&'static str> {
    names
        .iter()
        .copied()
        .filter(|n| corpus(n).exists())
        .collect()
}

#[test]
fn cycle_blocks_of_the_corpus_parse() {
    for name in present(&[
        "drunsinn_668.h",
        "drunsinn_700.h",
        "drunsinn_BewegBlv.h",
        "drunsinn_Krivka.h",
        "drunsinn_SLII001.h",
        "drunsinn_VESELYparametr.h",
        "drunsinn_programm-zirkularnut-fraesen.h",
        "aamorim_CUT.h",
        "aamorim_PRINTR1.h",
        "aamorim_WALLX20X20.h",
        "aamorim_XDIAL.h",
    ]) {
        if let Err(d) = syntax_check(&corpus(name)) {
            panic!("{name}: {d:?}");
        }
    }
}

#[test]
fn transform_programs_of_the_corpus_run_clean() {
    // 700: mirror image (8.1 X, empty 8.1); Krivka: tolerance 32 with HSC-MODE; the aamorim
    // files: datum shifts 7 with Q values, dwell 9
    for name in present(&[
        "drunsinn_700.h",
        "drunsinn_Krivka.h",
        "aamorim_CUT.h",
        "aamorim_PRINTR1.h",
        "aamorim_WALLX20X20.h",
    ]) {
        let d = check(&corpus(name), Pose::ZERO);
        assert!(d.is_empty(), "{name}: {d:?}");
    }
}

#[test]
fn old_machining_cycles_run_with_m99() {
    // BewegBlv defines cycles 1 and 5 and calls them with M99; its only problems are calls
    // of a label the file does not contain, and pockets milled with a tool whose radius the
    // check does not know (no tool table)
    for name in present(&["drunsinn_BewegBlv.h"]) {
        let d = check(&corpus(name), Pose::ZERO);
        assert!(
            d.iter().all(|x| x.message.contains("LBL 3 not found")
                || x.message
                    .contains("tool 15 is not in the tool table: cycle 5 needs its radius")),
            "{name}: {d:?}"
        );
    }
}

/// A tool table with every number the corpus programs call, radius 3 mm.
fn tools() -> ToolTable {
    let mut t = ToolTable::new();
    for number in 1..=40 {
        t.insert(Tool {
            number,
            length: 50.0,
            radius: 3.0,
            ..Tool::default()
        });
    }
    t
}

/// Runs a corpus program to its end with the tool table; returns the ops or the first
/// diagnostic.
fn run(name: &str) -> Result<Vec<OpKind>, String> {
    let it = Interpreter::open(&corpus(name), Pose::ZERO)
        .map_err(|d| d.to_string())?
        .with_tools(tools());
    it.map(|r| r.map(|o| o.kind).map_err(|d| d.to_string()))
        .collect()
}

#[test]
fn sl_programs_collect_their_contours_and_run() {
    // SLII001: cycle 14 with three contours (a pocket RR, an island RL, a full circle),
    // cycle 20, then 22, 22, 23 and 24 via CYCL CALL
    for name in present(&["drunsinn_SLII001.h"]) {
        let ops = run(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let cuts = ops
            .iter()
            .filter(|o| {
                matches!(
                    o,
                    OpKind::Line {
                        feed: Feed::Rate(_),
                        ..
                    } | OpKind::Arc { .. }
                )
            })
            .count();
        assert!(cuts > 20, "{name}: only {cuts} cutting moves");
        // every move lies inside the outer contour (0..100 in X and Y) widened by nothing:
        // the tool centre keeps the radius off the pocket wall
        for o in &ops {
            if let OpKind::Line {
                to,
                feed: Feed::Rate(_),
                ..
            } = o
            {
                assert!(to.0[0] > 0.0 && to.0[0] < 100.0, "{to:?}");
                assert!(to.0[1] > 0.0 && to.0[1] < 100.0, "{to:?}");
            }
        }
    }
}

#[test]
fn parametric_program_with_patterns_pockets_and_sl_runs_to_its_end() {
    // VESELYparametr: SL cycles 14/20/22, pattern 221 calling 252 and 253, CYCL CALL POS
    // calling 251, all with Q-parameter values
    for name in present(&["drunsinn_VESELYparametr.h"]) {
        let ops = run(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(ops.last(), Some(&OpKind::End), "{name}");
    }
}

/// The example programs of the project: cycle_*.h run to their end without diagnostics.
#[test]
fn example_cycle_programs_run() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../programs");
    for name in ["cycle_transforms.h", "cycle_drilling.h", "cycle_sl.h"] {
        let it = Interpreter::open(&dir.join(name), Pose::ZERO).expect("opens");
        let ops: Result<Vec<OpKind>, String> = it
            .map(|r| r.map(|o| o.kind).map_err(|d| d.to_string()))
            .collect();
        let ops = ops.unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(ops.last(), Some(&OpKind::End), "{name}");
    }
}
