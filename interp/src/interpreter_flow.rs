//! Control flow of the Klartext interpreter: labels, jumps, subprogram and program calls,
//! and the contour subprograms of SL cycles.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};

use super::{
    CHECK_JUMP_LIMIT, Interpreter, MAX_PROGRAM_DEPTH, MAX_SUBPROGRAM_DEPTH, Mode,
    RUN_IDLE_JUMP_LIMIT, Unit, open_any, whole_file_error,
};
use crate::diag::{Diagnostic, ProgramError};
use crate::dialect::Dialect;
use crate::klartext::parser::{LabelRef, Stmt};
use crate::op::SourceLoc;
use crate::source::{BlockStart, ProgramInput};
use crate::tnc::exec::{Flow, LabelKey};

/// Opens a Klartext file for reading, checking its dialect.
fn open_klartext(path: &Path) -> Result<Box<dyn ProgramInput>, Diagnostic> {
    match open_any(path)? {
        (Dialect::Klartext, reader) => Ok(reader),
        (other, _) => Err(whole_file_error(
            path,
            &ProgramError::DialectNotSupported(other.name()),
        )),
    }
}

/// The file a `CALL PGM` names, relative to the calling program's folder. A TNC drive prefix
/// (`TNC:\`) and backslashes are accepted; without an extension `.h` is added.
fn called_path(caller: &Path, written: &str) -> PathBuf {
    let mut name = written.trim().replace('\\', "/");
    if let Some(rest) = name
        .strip_prefix("TNC:")
        .or_else(|| name.strip_prefix("tnc:"))
    {
        name = rest.trim_start_matches('/').to_string();
    }
    let mut p = PathBuf::from(&name);
    if p.extension().is_none() {
        p.set_extension("h");
    }
    let dir = caller.parent().unwrap_or(Path::new(""));
    let joined = dir.join(&p);
    if joined.exists() {
        return joined;
    }
    // a TNC path names folders of the control: try the file name next to the caller
    match p.file_name() {
        Some(f) => dir.join(f),
        None => joined,
    }
}

impl Interpreter {
    /// Records a label block read at `start` (the first definition counts).
    pub(super) fn note_label(&mut self, text_label: Option<LabelKey>, start: BlockStart) {
        if let (Some(key), Some(u)) = (text_label, self.units.last_mut()) {
            u.labels.entry(key).or_insert(start);
        }
    }

    /// Marks the blocks up to the reader's position as read.
    pub(super) fn note_seen(&mut self) {
        if let Some(u) = self.units.last_mut() {
            let next = u.reader.next_start();
            if next.offset > u.seen_to.offset {
                u.seen_to = next;
            }
        }
    }

    /// Where a label's block starts; reads ahead from the furthest block read so far when
    /// the label has not been seen yet.
    fn find_label(&mut self, key: &LabelKey) -> Result<BlockStart, ProgramError> {
        let missing = || ProgramError::NoLabel(key.to_string());
        let Some(u) = self.units.last_mut() else {
            return Err(missing());
        };
        if let Some(s) = u.labels.get(key) {
            return Ok(*s);
        }
        let resume = u.reader.next_start();
        let io = |e: std::io::Error| ProgramError::Io(e.to_string());
        u.reader.seek(u.seen_to).map_err(io)?;
        let mut found = None;
        while let Some(start) = u.reader.next_block().map_err(io)? {
            let next = u.reader.next_start();
            if next.offset > u.seen_to.offset {
                u.seen_to = next;
            }
            if let Ok(block) = self.parser.parse(u.reader.text())
                && let Stmt::Label(r) = block.stmt
            {
                let k = LabelKey::from_ref(r, u.reader.text());
                let hit = k == *key;
                u.labels.entry(k).or_insert(start);
                if hit {
                    found = Some(start);
                    break;
                }
            }
        }
        u.reader.seek(resume).map_err(io)?;
        found.ok_or_else(missing)
    }

    /// Continues reading at a label.
    fn jump(&mut self, key: &LabelKey, mode: Mode) -> Result<(), ProgramError> {
        self.jumps += 1;
        self.idle_jumps += 1;
        if mode == Mode::Run && self.idle_jumps > RUN_IDLE_JUMP_LIMIT {
            return Err(ProgramError::Nesting(format!(
                "more than {RUN_IDLE_JUMP_LIMIT} jumps without any motion: endless loop"
            )));
        }
        if mode == Mode::Check && self.jumps > CHECK_JUMP_LIMIT {
            return Err(ProgramError::Nesting(format!(
                "more than {CHECK_JUMP_LIMIT} jumps: the check stops here (endless loop?)"
            )));
        }
        let target = self.find_label(key)?;
        if let Some(u) = self.units.last_mut() {
            u.reader
                .seek(target)
                .map_err(|e| ProgramError::Io(e.to_string()))?;
        }
        Ok(())
    }

    /// Acts on the control flow a block asked for.
    pub(super) fn follow(&mut self, flow: Flow, mode: Mode) -> Result<(), ProgramError> {
        match flow {
            Flow::Continue | Flow::End => Ok(()),
            Flow::Goto(key) => self.jump(&key, mode),
            Flow::Call { label, rep: None } => {
                let depth: usize = self.units.iter().map(|u| u.calls.len()).sum();
                if depth >= MAX_SUBPROGRAM_DEPTH {
                    return Err(ProgramError::Nesting(format!(
                        "CALL {label}: subprograms nested deeper than {MAX_SUBPROGRAM_DEPTH} levels"
                    )));
                }
                let ret = match self.units.last() {
                    Some(u) => u.reader.next_start(),
                    None => return Ok(()),
                };
                self.jump(&label, mode)?;
                if let Some(u) = self.units.last_mut() {
                    u.calls.push(ret);
                }
                Ok(())
            }
            Flow::Call {
                label,
                rep: Some(count),
            } => {
                let at = self.current.offset;
                let Some(u) = self.units.last_mut() else {
                    return Ok(());
                };
                let left = u.repeats.entry(at).or_insert(count);
                if *left == 0 {
                    u.repeats.remove(&at);
                    return Ok(());
                }
                *left -= 1;
                self.jump(&label, mode)
            }
            Flow::CallPgm(written) => self.call_program(&written),
            Flow::ProbeWait => {
                // the block runs again once the machine has measured the probing move; the
                // ops before it and the move itself leave now
                self.blocks = self.blocks.saturating_sub(1);
                self.machine.release();
                let at = self.current;
                match self.units.last_mut() {
                    Some(u) => u
                        .reader
                        .seek(at)
                        .map_err(|e| ProgramError::Io(e.to_string())),
                    None => Ok(()),
                }
            }
            Flow::Contours(labels) => {
                let collected = self.collect_contours(&labels);
                self.machine.finish_contours(collected, &mut self.queue)
            }
        }
    }

    /// SL cycles: runs the contour subprograms of cycle 14 with the machine collecting their
    /// lines and arcs instead of emitting them, then returns to the calling block.
    fn collect_contours(&mut self, labels: &[LabelKey]) -> Result<(), ProgramError> {
        let Some(resume) = self.units.last().map(|u| u.reader.next_start()) else {
            return Ok(());
        };
        self.machine.begin_contours();
        let mut result = Ok(());
        for key in labels {
            result = self.collect_contour(key);
            if result.is_err() {
                break;
            }
        }
        if let Some(u) = self.units.last_mut() {
            u.reader
                .seek(resume)
                .map_err(|e| ProgramError::Io(e.to_string()))?;
        }
        result
    }

    /// Runs one contour subprogram (from its LBL to LBL 0) into the machine's collector.
    fn collect_contour(&mut self, key: &LabelKey) -> Result<(), ProgramError> {
        let start = self.find_label(key)?;
        let io = |e: std::io::Error| ProgramError::Io(e.to_string());
        let mut scratch = VecDeque::new();
        let Some(u) = self.units.last_mut() else {
            return Ok(());
        };
        u.reader.seek(start).map_err(io)?;
        let wrap = |line: u32, e: ProgramError| ProgramError::Contour {
            label: key.to_string(),
            line,
            error: Box::new(e),
        };
        loop {
            let Some(u) = self.units.last_mut() else {
                return Ok(());
            };
            let Some(s) = u.reader.next_block().map_err(io)? else {
                return Err(wrap(start.line, ProgramError::Missing("LBL 0 missing")));
            };
            let block = self
                .parser
                .parse(u.reader.text())
                .map_err(|e| wrap(s.line, e.error))?;
            match block.stmt {
                Stmt::Label(LabelRef::Num(0)) | Stmt::EndPgm => break,
                Stmt::Empty | Stmt::Label(_) => continue,
                _ => {}
            }
            let (line, col) = u.reader.position(block.start);
            let loc = SourceLoc {
                file: u.file_id,
                line,
                col,
                block: block.number,
            };
            let flow = self
                .machine
                .exec(
                    &block.stmt,
                    &self.parser,
                    u.reader.text(),
                    loc,
                    &mut scratch,
                )
                .map_err(|(_, e)| wrap(line, e))?;
            if flow != Flow::Continue {
                return Err(wrap(
                    line,
                    ProgramError::Missing("no jumps, calls or program end in a contour subprogram"),
                ));
            }
        }
        self.machine
            .end_contour(&key.to_string(), &mut scratch)
            .map_err(|e| wrap(start.line, e))
    }

    /// CALL PGM: opens the called file and runs it until its END PGM.
    fn call_program(&mut self, written: &str) -> Result<(), ProgramError> {
        let Some(caller) = self.unit().map(|u| u.path.clone()) else {
            return Ok(());
        };
        let path = called_path(&caller, written);
        if self.units.len() > MAX_PROGRAM_DEPTH {
            return Err(ProgramError::Nesting(format!(
                "CALL PGM {written}: program calls nested deeper than {MAX_PROGRAM_DEPTH} levels"
            )));
        }
        let canon = std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone());
        if self
            .units
            .iter()
            .any(|u| std::fs::canonicalize(&u.path).unwrap_or_else(|_| u.path.clone()) == canon)
        {
            return Err(ProgramError::Nesting(format!(
                "CALL PGM {written}: the program is already running (recursive call)"
            )));
        }
        let input = open_klartext(&path).map_err(|d| {
            ProgramError::CallPgm(format!("CALL PGM {}: {}", path.display(), d.message))
        })?;
        let id = match self.files.iter().position(|f| *f == path) {
            Some(i) => i,
            None => {
                self.files.push(path.clone());
                self.files.len() - 1
            }
        };
        let id = u16::try_from(id)
            .map_err(|_| ProgramError::Nesting("too many program files".into()))?;
        tracing::debug!(file = %path.display(), "CALL PGM");
        self.units.push(Unit::new(path, id, input));
        self.machine.params.enter_program();
        Ok(())
    }
}
