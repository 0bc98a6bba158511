//! External subprograms: a call `L"name"` whose SUBPROGRAM is not in the program file runs
//! the file `name.ncs` next to the program. That file holds a `SUBPROGRAM "name"` section
//! closed by RETURN, like one after END in the program. While it runs, diagnostics point
//! into it; RETURN goes back to the calling file. Calls inside an external subprogram look
//! for `.ncs` files only. Nesting is bounded by the call depth limit of `control`, so an
//! external subprogram that calls itself ends in a nesting diagnostic at the call.

use std::fs::File;
use std::io::BufReader;
use std::path::PathBuf;

use super::block::{DinLine, parse_line};
use super::run::DinProgram;
use crate::diag::{Diagnostic, ProgramError};
use crate::source::{BlockReader, BlockStart};

/// A file left for an external subprogram: the call depth it was left at, its path and
/// its reader.
pub(crate) struct Outer {
    /// Number of active calls when the external file was entered.
    pub depth: usize,
    /// The calling file.
    pub file: PathBuf,
    /// Its reader, positioned where it was left.
    pub reader: BlockReader,
}

impl DinProgram {
    /// True while an external subprogram runs.
    pub(super) fn in_external(&self) -> bool {
        !self.outer.is_empty()
    }

    /// Switches to `name.ncs` next to the current file and returns where its body starts;
    /// errors are located at the call (`line`, `col`).
    pub(super) fn enter_external(
        &mut self,
        name: &str,
        (line, col): (u32, u32),
    ) -> Result<BlockStart, Diagnostic> {
        let at =
            |file: &PathBuf, e: ProgramError| Diagnostic::new(file.clone(), line, col, None, &e);
        if name.is_empty() || name.contains(['/', '\\']) || name.contains("..") {
            return Err(at(
                &self.file,
                ProgramError::OutOfRange(format!(
                    "subprogram name \"{name}\": an external subprogram is named without a folder"
                )),
            ));
        }
        let path = self
            .file
            .parent()
            .map(|d| d.join(format!("{name}.ncs")))
            .unwrap_or_else(|| PathBuf::from(format!("{name}.ncs")));
        let file = File::open(&path).map_err(|e| {
            at(
                &self.file,
                ProgramError::Io(format!(
                    "no SUBPROGRAM \"{name}\" in this file and cannot open {}: {e}",
                    path.display()
                )),
            )
        })?;
        let mut reader = BlockReader::new(Box::new(BufReader::new(file)));
        let mut body = None;
        while let Ok(Some(_)) = reader.next_block() {
            if let Ok(DinLine::Subprogram { name: n }) = parse_line(reader.text())
                && n == name
            {
                body = Some(reader.next_start());
                break;
            }
        }
        let Some(body) = body else {
            return Err(at(
                &self.file,
                ProgramError::Missing(
                    "the external subprogram file holds no SUBPROGRAM section of its name",
                ),
            ));
        };
        let depth = self.control.depth();
        let reader = std::mem::replace(&mut self.reader, reader);
        let file = std::mem::replace(&mut self.file, path);
        self.outer.push(Outer {
            depth,
            file,
            reader,
        });
        Ok(body)
    }

    /// After a RETURN left `depth` calls active: back to the calling file when the
    /// external subprogram entered at that depth has ended.
    pub(super) fn leave_external(&mut self, depth: usize) {
        if self.outer.last().is_some_and(|o| o.depth == depth)
            && let Some(o) = self.outer.pop()
        {
            self.reader = o.reader;
            self.file = o.file;
        }
    }
}
