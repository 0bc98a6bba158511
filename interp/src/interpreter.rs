//! The streaming interpreter and the whole-program checks built on it.

use std::collections::VecDeque;
use std::fs::File;
use std::io::{BufRead, BufReader, Cursor};
use std::path::{Path, PathBuf};

use crate::diag::{Diagnostic, ProgramError};
use crate::dialect::{Dialect, detect_dialect};
use crate::klartext::exec::{Blank, Flow, Machine};
use crate::klartext::parser::{Parser, Stmt};
use crate::op::{Op, Pose, SourceLoc};
use crate::source::{BlockReader, BlockStart, ProgramInput};

/// How much of each block is processed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Execute and stop at the first error (the iterator).
    Run,
    /// Execute, report every error and go on.
    Check,
    /// Parse only.
    Syntax,
}

/// Where the program is in its structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// No BEGIN PGM yet.
    BeforeBegin,
    /// Between BEGIN PGM and the end.
    Running,
    /// M2/M30 reached: the rest is only checked for syntax (subprograms live there).
    Stopped,
    /// END PGM read.
    Ended,
    /// Nothing more to read.
    Done,
}

/// Streaming Klartext interpreter: an iterator of ops, one block at a time.
///
/// Yields `Ok(op)` for every op in program order; after a diagnostic, the end of the program
/// (END PGM, M2, M30) or the end of the text it yields `None`.
pub struct Interpreter {
    file: PathBuf,
    reader: BlockReader,
    parser: Parser,
    machine: Machine,
    queue: VecDeque<Op>,
    phase: Phase,
    blocks: u64,
    block_skip: bool,
    finished: bool,
    /// Where the current block starts in the file: what a label table will record so that
    /// jumps can seek back without holding the program in memory.
    current: BlockStart,
}

impl std::fmt::Debug for Interpreter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Interpreter")
            .field("file", &self.file)
            .field("blocks", &self.blocks)
            .finish_non_exhaustive()
    }
}

fn whole_file_error(file: &Path, error: &ProgramError) -> Diagnostic {
    Diagnostic::new(file.to_path_buf(), 1, 1, None, error)
}

impl Interpreter {
    /// Opens a program file; `start` is where the machine stands before the first block.
    ///
    /// Fails when the file cannot be read or is not in a dialect this version runs.
    pub fn open(path: &Path, start: Pose) -> Result<Self, Diagnostic> {
        let file = File::open(path)
            .map_err(|e| whole_file_error(path, &ProgramError::Io(e.to_string())))?;
        let mut reader = BufReader::with_capacity(64 * 1024, file);
        let head = reader
            .fill_buf()
            .map_err(|e| whole_file_error(path, &ProgramError::Io(e.to_string())))?;
        let head = &head[..head.len().min(4096)];
        match detect_dialect(path, head) {
            Some(Dialect::Klartext) => {}
            Some(other) => {
                return Err(whole_file_error(
                    path,
                    &ProgramError::DialectNotSupported(other.name()),
                ));
            }
            None => return Err(whole_file_error(path, &ProgramError::UnknownDialect)),
        }
        tracing::debug!(file = %path.display(), "opened Klartext program");
        Ok(Self::with_input(
            path.to_path_buf(),
            Box::new(reader),
            start,
        ))
    }

    /// Interprets Klartext held in memory (tests, benches); `name` is used in diagnostics.
    pub fn from_source(name: &str, text: &str, start: Pose) -> Self {
        Self::with_input(
            PathBuf::from(name),
            Box::new(Cursor::new(text.as_bytes().to_vec())),
            start,
        )
    }

    fn with_input(file: PathBuf, input: Box<dyn ProgramInput>, start: Pose) -> Self {
        Interpreter {
            file,
            reader: BlockReader::new(input),
            parser: Parser::default(),
            machine: Machine::new(start),
            queue: VecDeque::with_capacity(8),
            phase: Phase::BeforeBegin,
            blocks: 0,
            block_skip: true,
            finished: false,
            current: BlockStart { offset: 0, line: 1 },
        }
    }

    /// Number of blocks executed so far (empty and comment lines not counted).
    pub fn blocks_executed(&self) -> u64 {
        self.blocks
    }

    /// Switches block skip: when on (the default) blocks marked `/` are not executed.
    pub fn set_block_skip(&mut self, on: bool) {
        self.block_skip = on;
    }

    /// The blank recorded from BLK FORM, if any.
    pub fn blank(&self) -> Option<Blank> {
        self.machine.blank
    }

    /// Byte offset and line where the block read last starts.
    pub fn block_offset(&self) -> (u64, u32) {
        (self.current.offset, self.current.line)
    }

    /// The last programmed position (mm, degrees).
    pub fn position(&self) -> Pose {
        self.machine.pos
    }

    fn diag_at(&self, pos: usize, block: Option<u64>, error: &ProgramError) -> Diagnostic {
        let (line, col) = self.reader.position(pos);
        Diagnostic::new(self.file.clone(), line, col, block, error)
    }

    /// Reads and processes one block. Ops go to the queue.
    fn step(&mut self, mode: Mode) -> Result<(), Diagnostic> {
        match self.reader.next_block() {
            Ok(Some(s)) => self.current = s,
            Ok(None) => {
                let was = self.phase;
                self.phase = Phase::Done;
                if was == Phase::Ended {
                    return Ok(());
                }
                let (line, col) = self.reader.end_position();
                let error = if was == Phase::BeforeBegin {
                    ProgramError::MissingBegin
                } else {
                    ProgramError::MissingEnd
                };
                return Err(Diagnostic::new(self.file.clone(), line, col, None, &error));
            }
            Err(e) => {
                self.phase = Phase::Done;
                let (line, col) = self.reader.end_position();
                return Err(Diagnostic::new(
                    self.file.clone(),
                    line,
                    col,
                    None,
                    &ProgramError::Io(e.to_string()),
                ));
            }
        };
        let block = match self.parser.parse(self.reader.text()) {
            Ok(b) => b,
            Err(pe) => {
                if self.phase == Phase::BeforeBegin {
                    self.phase = Phase::Running;
                }
                return Err(self.diag_at(pe.pos, pe.number, &pe.error));
            }
        };
        if block.stmt == Stmt::Empty {
            return Ok(());
        }
        match (self.phase, block.stmt) {
            (Phase::BeforeBegin, Stmt::BeginPgm { inch }) => {
                self.machine.set_inch(inch);
                self.phase = Phase::Running;
                self.blocks += 1;
                return Ok(());
            }
            (Phase::BeforeBegin, _) => {
                self.phase = Phase::Running;
                return Err(self.diag_at(block.start, block.number, &ProgramError::MissingBegin));
            }
            (Phase::Ended | Phase::Done, _) => {
                return Err(self.diag_at(block.start, block.number, &ProgramError::AfterEnd));
            }
            (_, Stmt::BeginPgm { .. }) => {
                return Err(self.diag_at(
                    block.start,
                    block.number,
                    &ProgramError::Unexpected("second BEGIN PGM".into()),
                ));
            }
            (Phase::Stopped, Stmt::EndPgm) => {
                self.phase = Phase::Ended;
                return Ok(());
            }
            (Phase::Stopped, _) => return Ok(()),
            (Phase::Running, _) => {}
        }
        if mode == Mode::Syntax {
            if block.stmt == Stmt::EndPgm {
                self.phase = Phase::Ended;
            }
            return Ok(());
        }
        if block.skip && self.block_skip {
            return Ok(());
        }
        let (line, col) = self.reader.position(block.start);
        let loc = SourceLoc {
            file: 0,
            line,
            col,
            block: block.number,
        };
        self.blocks += 1;
        match self.machine.exec(
            &block.stmt,
            &self.parser,
            self.reader.text(),
            loc,
            &mut self.queue,
        ) {
            Ok(Flow::Continue) => Ok(()),
            Ok(Flow::End) => {
                self.phase = if block.stmt == Stmt::EndPgm {
                    Phase::Ended
                } else {
                    Phase::Stopped
                };
                if mode == Mode::Run {
                    self.finished = true;
                }
                Ok(())
            }
            Err((pos, error)) => {
                let p = pos.map_or(block.start, |p| p as usize);
                Err(self.diag_at(p, block.number, &error))
            }
        }
    }

    /// Runs to the end in `mode`, collecting every diagnostic.
    fn run_all(&mut self, mode: Mode) -> Vec<Diagnostic> {
        let mut diags = Vec::new();
        while self.phase != Phase::Done {
            if let Err(d) = self.step(mode) {
                diags.push(d);
            }
            self.queue.clear();
        }
        diags
    }
}

impl Iterator for Interpreter {
    type Item = Result<Op, Diagnostic>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if let Some(op) = self.queue.pop_front() {
                return Some(Ok(op));
            }
            if self.finished || self.phase == Phase::Done {
                return None;
            }
            if let Err(d) = self.step(Mode::Run) {
                self.finished = true;
                self.queue.clear();
                return Some(Err(d));
            }
        }
    }
}

/// Checks a program's syntax in one streaming pass without executing it (constant memory).
///
/// Reports every syntax error: unknown or misplaced words, missing values, a missing BEGIN PGM
/// or END PGM, blocks after END PGM.
pub fn syntax_check(path: &Path) -> Result<(), Vec<Diagnostic>> {
    let mut it = Interpreter::open(path, Pose::ZERO).map_err(|d| vec![d])?;
    let diags = it.run_all(Mode::Syntax);
    if diags.is_empty() { Ok(()) } else { Err(diags) }
}

/// Checks syntax and runs the program without motion, reporting all errors (geometry and
/// runtime errors included); a block with an error is skipped and the run goes on.
pub fn check(path: &Path, start: Pose) -> Vec<Diagnostic> {
    match Interpreter::open(path, start) {
        Ok(mut it) => it.run_all(Mode::Check),
        Err(d) => vec![d],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn run_bytes(bytes: Vec<u8>, mode: Mode) -> usize {
        let mut it = Interpreter::with_input(
            PathBuf::from("fuzz.h"),
            Box::new(Cursor::new(bytes)),
            Pose::ZERO,
        );
        match mode {
            Mode::Run => it.by_ref().take(10_000).count(),
            other => it.run_all(other).len(),
        }
    }

    proptest! {
        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            run_bytes(bytes.clone(), Mode::Run);
            run_bytes(bytes.clone(), Mode::Check);
            run_bytes(bytes, Mode::Syntax);
        }

        #[test]
        fn random_blocks_after_begin_never_panic(
            body in proptest::collection::vec(any::<u8>(), 0..300)
        ) {
            let mut bytes = b"BEGIN PGM F MM\nCC X+0 Y+0\nL X+5 F100\n".to_vec();
            bytes.extend_from_slice(&body);
            run_bytes(bytes.clone(), Mode::Run);
            run_bytes(bytes, Mode::Check);
        }
    }
}
