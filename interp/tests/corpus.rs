//! Every real program of the shared corpus goes through the syntax check without panicking;
//! the ones that are valid Klartext pass, the two broken templates are refused with the
//! diagnostic that names their problem.

use std::path::{Path, PathBuf};

const CORPUS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/corpus/klartext");

fn programs(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            programs(&p, out);
        } else if p
            .extension()
            .and_then(|x| x.to_str())
            .is_some_and(|x| x.eq_ignore_ascii_case("h"))
        {
            out.push(p);
        }
    }
}

#[test]
fn corpus_parses() {
    let mut files = Vec::new();
    programs(Path::new(CORPUS), &mut files);
    files.sort();
    if files.is_empty() {
        eprintln!("corpus not found at {CORPUS}; skipping");
        return;
    }
    let mut ok = 0;
    for f in &files {
        let name = f.file_name().and_then(|n| n.to_str()).unwrap_or("");
        match klar_interp::syntax_check(f) {
            Ok(()) => {
                ok += 1;
                assert!(!name.starts_with("type2nc"), "{name} must be refused");
            }
            Err(diags) => {
                for d in &diags {
                    eprintln!("{d}");
                }
                if name == "type2nc_pgm_head_template.H" {
                    assert!(
                        diags[0].message.contains("missing BEGIN PGM"),
                        "{}",
                        diags[0]
                    );
                } else if name == "type2nc_demo_pgm_template_cycle.H" {
                    assert!(
                        diags
                            .iter()
                            .any(|d| d.message.contains("template placeholder")),
                        "{diags:?}"
                    );
                } else {
                    panic!("{name} should parse: {}", diags[0]);
                }
            }
        }
    }
    eprintln!(
        "{ok} of {} corpus programs pass the syntax check",
        files.len()
    );
    // Full runs come with a later milestone; show how far a dry run gets today.
    let mut clean = 0;
    for f in &files {
        let diags = klar_interp::check(f, klar_interp::Pose::ZERO);
        match diags.first() {
            None => clean += 1,
            Some(first) => eprintln!("check: {} diagnostics, first: {first}", diags.len()),
        }
    }
    eprintln!(
        "{clean} of {} corpus programs run through `check` without diagnostics",
        files.len()
    );
}
