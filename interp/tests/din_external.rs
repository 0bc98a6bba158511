//! External `.ncs` subprograms: the same ops as the program with a local subprogram,
//! errors in the external file located there, missing files and recursion as diagnostics.

mod common;
use common::lathe::lathe_path as lathe;
use klar_interp::{Interpreter, OpKind, Pose};
use std::path::{Path, PathBuf};

/// The motion of a program file, or its first diagnostic.
fn motion(path: &Path) -> Result<Vec<OpKind>, String> {
    let interp = Interpreter::open(path, Pose::ZERO).map_err(|d| d.to_string())?;
    let mut out = Vec::new();
    for r in interp {
        let op = r.map_err(|d| d.to_string())?;
        if matches!(op.kind, OpKind::Line { .. } | OpKind::Arc { .. }) {
            out.push(op.kind);
        }
    }
    Ok(out)
}

fn scratch(files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("klar-ncs-{}-{}", files[0].0, std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (n, t) in files {
        std::fs::write(dir.join(n), t).unwrap();
    }
    dir
}

#[test]
fn an_external_subprogram_moves_as_the_local_one() {
    let local = motion(&lathe("subprogram_grooves.nc")).unwrap();
    let external = motion(&lathe("external_subprogram.nc")).unwrap();
    assert!(local.len() > 10);
    assert_eq!(local, external);
}

#[test]
fn missing_files_errors_inside_and_recursion_are_diagnostics() {
    let main = "MACHINING\nN1 G0 X10 Z2\nN2 L\"sub\"\nN3 M30\nEND\n";
    let dir = scratch(&[("missing.nc", main)]);
    let e = motion(&dir.join("missing.nc")).unwrap_err();
    assert!(e.contains("missing.nc:3:"), "{e}");
    assert!(e.contains("sub.ncs"), "{e}");
    let dir = scratch(&[
        ("inside.nc", main),
        ("sub.ncs", "SUBPROGRAM \"sub\"\nN10 G1 X5 Z0\nRETURN\n"),
    ]);
    let e = motion(&dir.join("inside.nc")).unwrap_err();
    // no feed programmed: the error points into sub.ncs, line 2
    assert!(e.contains("sub.ncs:2:"), "{e}");
    let dir = scratch(&[
        ("loop.nc", main),
        (
            "sub.ncs",
            "SUBPROGRAM \"sub\"\nN10 G0 X5\nL\"sub\"\nRETURN\n",
        ),
    ]);
    let e = motion(&dir.join("loop.nc")).unwrap_err();
    assert!(
        e.contains("sub.ncs:3:") && e.contains("nested deeper"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(dir);
}
