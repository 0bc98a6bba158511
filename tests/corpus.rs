//! The compatibility suite: every real Klartext program of `../shared/corpus/klartext` (written
//! by others, see its INDEX.md) through the test run on the built-in mill, and through a
//! simulated run where the test run passes. The machine gets a shop tool table (tools 1–999,
//! L 60 mm, R 3 mm unless the job needs a smaller tool), as a real machine would have one; the
//! programs are never copied here.
//!
//! Each file has its expected outcome with the reason; the test fails when any file's outcome
//! changes, and prints the score.

mod common;

use klar::runtime::{RunOptions, run_program};
use klar::testrun::test_run;
use std::path::{Path, PathBuf};

/// What must happen to a corpus file.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Expect {
    /// The test run passes with nothing undecided and the program runs to its end.
    Runs,
    /// As `Runs`, with all tools of this radius (mm): the job needs a small tool.
    RunsWithRadius(f64),
    /// The test run passes, but some of it depends on the machine (the reason must appear
    /// among the undecided items); the run is not attempted.
    Undecided(&'static str),
    /// The test run refuses the program with this text in its first error.
    Refused(&'static str),
}

const CASES: &[(&str, Expect)] = &[
    // Operator workflow: STOP, the operator jogs the axes, FN 18 reads the position.
    (
        "aamorim_CIRSTUD.h",
        Expect::Undecided("after a program stop"),
    ),
    ("aamorim_CUT.h", Expect::Runs),
    ("aamorim_MEASTOK.h", Expect::Runs),
    ("aamorim_PRINTR1.h", Expect::Runs),
    ("aamorim_PROFILE.h", Expect::Runs),
    ("aamorim_RECTIFI.h", Expect::Runs),
    ("aamorim_WALLX20X20.h", Expect::Runs),
    ("aamorim_XDIAL.h", Expect::Undecided("after a program stop")),
    // Its called programs were never published (INDEX.md): the check of the file itself
    // passes with a warning, the test run against the machine refuses the run.
    (
        "drunsinn_3170_de.h",
        Expect::Refused("31701_de.h: cannot read program"),
    ),
    // Circular pockets of radius 1.65 mm: tool 3 must be smaller than that.
    ("drunsinn_668.h", Expect::RunsWithRadius(1.0)),
    ("drunsinn_700.h", Expect::Runs),
    ("drunsinn_7025.h", Expect::Runs),
    (
        "drunsinn_9030_de.h",
        Expect::Refused("90301_de.h: cannot read program"),
    ),
    // Calls LBL 3, which the file does not contain: a real control refuses it too.
    ("drunsinn_BewegBlv.h", Expect::Refused("LBL 3 not found")),
    ("drunsinn_Krivka.h", Expect::Runs),
    ("drunsinn_SLII001.h", Expect::Runs),
    // A large part: its moves leave the built-in mill's travel (X ±300 mm).
    (
        "drunsinn_VESELYparametr.h",
        Expect::Refused("outside its travel"),
    ),
    ("drunsinn_programm-zirkularnut-fraesen.h", Expect::Runs),
    // Template with Python format fields; a fragment without BEGIN PGM (INDEX.md).
    (
        "type2nc_demo_pgm_template_cycle.H",
        Expect::Refused("template placeholder '{0:+d}'"),
    ),
    (
        "type2nc_pgm_head_template.H",
        Expect::Refused("missing BEGIN PGM"),
    ),
    // Calls the face-milling cycle Plan.h (checked through the call), then retracts to Z+300,
    // above the built-in mill's Z travel (±200 mm).
    (
        "jstjst/Plan-Beispiel.h",
        Expect::Refused("Z would move to 300.0000, outside its travel"),
    ),
    // The face-milling cycle called on its own: its parameter check stops it (FN 14).
    (
        "jstjst/Plan.h",
        Expect::Refused("FN 14: program stopped with error number"),
    ),
];

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/corpus/klartext")
}

/// Every file of the corpus folder (recursively), relative to it.
fn files(dir: &Path, base: &Path, out: &mut Vec<String>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            files(&p, base, out);
        } else if matches!(p.extension().and_then(|x| x.to_str()), Some("h" | "H"))
            && let Ok(rel) = p.strip_prefix(base)
        {
            out.push(rel.to_string_lossy().replace('\\', "/"));
        }
    }
}

#[test]
fn every_corpus_program_is_handled() {
    let dir = corpus();
    // The unpublished callees: the file's own check passes and names them.
    for (file, callee) in [
        ("drunsinn_3170_de.h", "31701_de.h"),
        ("drunsinn_9030_de.h", "90301_de.h"),
    ] {
        let r = klar_interp::check_report(&dir.join(file), klar_interp::Pose::ZERO);
        assert!(r.errors.is_empty(), "{file}: {:?}", r.errors);
        assert!(
            r.missing.iter().any(|d| d.message.contains(callee)),
            "{file}: {:?}",
            r.missing
        );
    }
    let mut found = Vec::new();
    files(&dir, &dir, &mut found);
    found.sort();
    let mut listed: Vec<String> = CASES.iter().map(|(f, _)| f.to_string()).collect();
    listed.sort();
    assert_eq!(found, listed, "the corpus and the expectations list differ");

    let (mut ran, mut undecided, mut refused) = (0, 0, 0);
    for (file, expect) in CASES {
        let path = dir.join(file);
        let machine = common::shop_mill(match expect {
            Expect::RunsWithRadius(r) => *r,
            _ => 3.0,
        });
        let report = test_run(&path, &machine);
        let first = report.errors.first().map(|d| d.to_string());
        match expect {
            Expect::Refused(text) => {
                let first = first.unwrap_or_else(|| panic!("{file}: not refused"));
                assert!(first.contains(text), "{file}: refused with {first}");
                // the diagnostic names the place: file:line:col
                assert!(first.contains(&format!("{file}:")), "{file}: {first}");
                refused += 1;
            }
            Expect::Undecided(text) => {
                assert!(first.is_none(), "{file}: refused with {first:?}");
                assert!(
                    report.undecided.iter().any(|u| u.contains(text)),
                    "{file}: undecided {:?}",
                    report.undecided
                );
                undecided += 1;
            }
            Expect::Runs | Expect::RunsWithRadius(_) => {
                assert!(first.is_none(), "{file}: refused with {first:?}");
                assert!(
                    report.undecided.is_empty(),
                    "{file}: undecided {:?}",
                    report.undecided
                );
                let result = run_program(
                    &path,
                    &machine,
                    RunOptions {
                        realtime: false,
                        trace: None,
                    },
                );
                let r = result.unwrap_or_else(|f| panic!("{file}: run failed: {}", f.error));
                assert!(r.blocks > 0 && r.machine_time > 0.0, "{file}: {r:?}");
                eprintln!(
                    "{file}: {} blocks, {:.1} s machine time",
                    r.blocks, r.machine_time
                );
                ran += 1;
            }
        }
    }
    eprintln!(
        "corpus: {} files: {ran} run to the end on the built-in mill, {undecided} checked with \
         parts only the machine decides, {refused} refused as a real control would",
        CASES.len()
    );
}
