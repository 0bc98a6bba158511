//! Helpers for the executor's unit tests: a fresh folder and a block runner.

use super::parser::Parser;
use crate::op::SourceLoc;
use crate::tnc::exec::Machine;
use std::path::PathBuf;

/// A fresh, empty folder for one test.
pub(crate) fn folder(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("klar-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Parses and runs `blocks` (one a line) on `m`; the first error as text.
pub(crate) fn run(m: &mut Machine, blocks: &str) -> Result<(), String> {
    let mut p = Parser::default();
    for (i, line) in blocks.lines().enumerate() {
        let b = p.parse(line.as_bytes()).map_err(|e| e.error.to_string())?;
        let loc = SourceLoc {
            file: 0,
            line: i as u32 + 1,
            col: 1,
            block: None,
        };
        let mut out = std::collections::VecDeque::new();
        m.exec(&b.stmt, &p, line.as_bytes(), loc, &mut out)
            .map_err(|e| format!("block {}: {}", i + 1, e.1))?;
    }
    Ok(())
}

/// Runs `text` on the table-table geometry of machines/mill5.toml (the tilt axis A 100 mm
/// below the table, the table axis C through the origin); the ops or the first error as
/// `line:col: message`.
pub(crate) fn mill5_ops(name: &str, text: &str) -> Result<Vec<crate::op::Op>, String> {
    crate::interpreter::Interpreter::from_source(name, text, crate::op::Pose::ZERO)
        .with_table_geometry(
            crate::op::AxisLetter::A,
            [0.0, 0.0, -100.0],
            [0.0, 0.0, 0.0],
        )
        .collect::<Result<Vec<_>, _>>()
        .map_err(|d| format!("{}:{}: {}", d.line, d.col, d.message))
}

/// `body` as a whole Klartext program.
pub(crate) fn klartext(body: &str) -> String {
    format!("0 BEGIN PGM T MM\n{body}\n99 END PGM T MM\n")
}
