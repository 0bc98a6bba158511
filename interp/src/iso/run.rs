//! The streaming TNC ISO program runner: program structure, labels, calls and jumps.
//!
//! A program is `%NAME G71 *` (G70: inch), numbered blocks ending in `*`, and the closing
//! `N… %NAME G71 *`. Labels are `G98 L n`; `L n,0` calls the subprogram at label n, which
//! runs to `G98 L0` and returns after the call; `L n,k` (k ≥ 1) jumps back to label n k
//! more times (a program section repeat); D09–D12 jump to a label. Label positions are
//! recorded as blocks are read; a label further down is found by reading ahead without
//! executing, so memory stays bounded by the number of labels. M02/M30 end the run; the
//! rest is only read for labels (subprograms live there).

use std::collections::{HashMap, VecDeque};
use std::path::PathBuf;

use super::block::{Addr, IsoBlock, IsoKind};
use super::exec::{IsoFlow, IsoState};
use crate::diag::{Diagnostic, ProgramError};
use crate::dialect::DialectRun;
use crate::klartext::parser::Stmt;
use crate::op::{Op, Pose, SourceLoc};
use crate::source::{BlockReader, BlockStart, ProgramInput};
use crate::tnc::exec::Machine;
use crate::tnc::expr::Value;

/// Deepest subprogram nesting accepted.
pub const MAX_CALL_DEPTH: usize = 64;

/// Most jumps (calls, repeats, D09–D12) in a row without an op in between: a guard against
/// endless loops that compute without moving.
pub const MAX_IDLE_JUMPS: u64 = 100_000;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    BeforeHeader,
    Running,
    Stopped,
    Ended,
    Done,
}

/// How much of each block is processed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Run,
    Check,
    Syntax,
}

/// A TNC ISO program being run block by block.
pub(crate) struct IsoProgram {
    file: PathBuf,
    reader: BlockReader,
    block: IsoBlock,
    state: IsoState,
    queue: VecDeque<Op>,
    phase: Phase,
    finished: bool,
    blocks: u64,
    block_skip: bool,
    labels: HashMap<u32, BlockStart>,
    calls: Vec<BlockStart>,
    repeats: HashMap<u64, u32>,
    jumps: u64,
    current: BlockStart,
    /// A diagnostic handed out after the ops that precede it.
    pending_error: Option<Diagnostic>,
}

fn label_of(block: &IsoBlock) -> Option<u32> {
    let is_g98 = block
        .words
        .iter()
        .any(|w| w.addr == Addr::Letter(b'G') && w.value == Value::Num(98.0));
    if !is_g98 {
        return None;
    }
    block.words.iter().find_map(|w| match (w.addr, w.value) {
        (Addr::Letter(b'L'), Value::Num(v)) if v >= 0.0 && v.fract() == 0.0 && v <= 65_535.0 => {
            Some(v as u32)
        }
        _ => None,
    })
}

impl IsoProgram {
    /// A runner over `input`; `start` is where the machine stands.
    pub fn new(file: PathBuf, input: Box<dyn ProgramInput>, start: Pose) -> Self {
        IsoProgram {
            file,
            reader: BlockReader::new(input),
            block: IsoBlock::default(),
            state: IsoState::new(Machine::new(start)),
            queue: VecDeque::with_capacity(8),
            phase: Phase::BeforeHeader,
            finished: false,
            blocks: 0,
            block_skip: true,
            labels: HashMap::new(),
            calls: Vec::new(),
            repeats: HashMap::new(),
            jumps: 0,
            current: BlockStart { offset: 0, line: 1 },
            pending_error: None,
        }
    }

    fn diag(&self, pos: usize, error: &ProgramError) -> Diagnostic {
        let (line, col) = self.reader.position(pos);
        Diagnostic::new(self.file.clone(), line, col, self.block.number, error)
    }

    /// The diagnostic of an error raised by a block starting at `start`: at the head block of
    /// a cycle definition when that definition failed, else at `pos` (or `start`).
    fn block_diag(&mut self, pos: Option<u32>, start: usize, error: &ProgramError) -> Diagnostic {
        match self.state.failed_head.take() {
            Some(at) => Diagnostic::new(self.file.clone(), at.line, at.col, at.block, error),
            None => self.diag(pos.map_or(start, |p| p as usize), error),
        }
    }

    fn end_diag(&self, error: &ProgramError) -> Diagnostic {
        let (line, col) = self.reader.end_position();
        Diagnostic::new(self.file.clone(), line, col, None, error)
    }

    fn step(&mut self, mode: Mode) -> Result<(), Diagnostic> {
        match self.reader.next_block() {
            Ok(Some(s)) => self.current = s,
            Ok(None) => {
                let was = self.phase;
                self.phase = Phase::Done;
                return match was {
                    Phase::Ended => Ok(()),
                    Phase::BeforeHeader => Err(self.end_diag(&ProgramError::Missing(
                        "a TNC ISO program starts with `%NAME G71 *`",
                    ))),
                    _ => Err(self.end_diag(&ProgramError::Missing(
                        "the closing `N… %NAME G71 *` block is missing at end of file",
                    ))),
                };
            }
            Err(e) => {
                self.phase = Phase::Done;
                return Err(self.end_diag(&ProgramError::Io(e.to_string())));
            }
        }
        if let Err((pos, e)) = self.block.parse(self.reader.text()) {
            if self.phase == Phase::BeforeHeader {
                self.phase = Phase::Running;
            }
            return Err(self.diag(pos, &e));
        }
        let start = self.block.start;
        match (self.phase, self.block.kind) {
            (_, IsoKind::Empty) => return Ok(()),
            (Phase::BeforeHeader, IsoKind::Header { inch }) => {
                self.state.machine.set_inch(inch);
                self.phase = Phase::Running;
                self.blocks += 1;
                return Ok(());
            }
            (Phase::BeforeHeader, _) => {
                self.phase = Phase::Running;
                return Err(self.diag(
                    start,
                    &ProgramError::Missing("a TNC ISO program starts with `%NAME G71 *`"),
                ));
            }
            (Phase::Ended | Phase::Done, _) => {
                return Err(self.diag(
                    start,
                    &ProgramError::Unexpected("block after the closing `%NAME` block".into()),
                ));
            }
            (Phase::Stopped, IsoKind::Header { .. }) => {
                self.phase = Phase::Ended;
                return Ok(());
            }
            (Phase::Stopped, _) => {
                self.note_label();
                return Ok(());
            }
            (Phase::Running, _) => {}
        }
        if mode == Mode::Syntax {
            self.note_label();
            if let IsoKind::Header { .. } = self.block.kind {
                self.phase = Phase::Ended;
            }
            return Ok(());
        }
        if self.block.skip && self.block_skip {
            return Ok(());
        }
        let (line, col) = self.reader.position(start);
        let loc = SourceLoc {
            file: 0,
            line,
            col,
            block: self.block.number,
        };
        self.blocks += 1;
        let text = self.reader.text();
        let numbered = self.block.number.is_some();
        if numbered || !matches!(self.block.kind, IsoKind::Formula) {
            // a numbered block or one that is no `Q…=` line completes a cycle definition
            // written over several lines
            if let Err((p, e)) = self.state.close_cycle(text, &mut self.queue) {
                return Err(self.block_diag(p, start, &e));
            }
        }
        let flow = match self.block.kind {
            IsoKind::Header { .. } => {
                // the closing block: END PGM
                let parser = crate::klartext::parser::Parser::default();
                self.state
                    .machine
                    .exec(&Stmt::EndPgm, &parser, text, loc, &mut self.queue)
                    .map_err(|(p, e)| self.diag(p.map_or(start, |p| p as usize), &e))?;
                self.phase = Phase::Ended;
                if mode == Mode::Run {
                    self.finished = true;
                }
                return Ok(());
            }
            IsoKind::Formula if numbered => {
                let r = self.state.formula(text, loc, &mut self.queue);
                r.map(|()| IsoFlow::Continue)
            }
            IsoKind::Formula => match self.state.cycle_more(text, &mut self.queue) {
                Ok(true) => Ok(IsoFlow::Continue),
                Ok(false) => {
                    let r = self.state.formula(text, loc, &mut self.queue);
                    r.map(|()| IsoFlow::Continue)
                }
                Err(e) => Err(e),
            },
            IsoKind::CycleDef { number, after } => self
                .state
                .cycle_head(number, after, text, loc, &mut self.queue)
                .map(|()| IsoFlow::Continue),
            IsoKind::Words => self.state.words(&self.block, text, loc, &mut self.queue),
            IsoKind::Empty => Ok(IsoFlow::Continue),
        };
        let flow = match flow {
            Ok(f) => f,
            Err((p, e)) => return Err(self.block_diag(p, start, &e)),
        };
        if !self.queue.is_empty() {
            self.jumps = 0;
        }
        self.follow(flow, mode, start)
    }

    /// Records a `G98 L n` label at the current block.
    fn note_label(&mut self) {
        if let Some(n) = label_of(&self.block)
            && n != 0
        {
            self.labels.entry(n).or_insert(self.current);
        }
    }

    fn follow(&mut self, flow: IsoFlow, mode: Mode, start: usize) -> Result<(), Diagnostic> {
        match flow {
            IsoFlow::Continue => Ok(()),
            IsoFlow::End => {
                self.phase = Phase::Stopped;
                if mode == Mode::Run {
                    self.finished = true;
                }
                Ok(())
            }
            IsoFlow::Label(0) => {
                if let Some(ret) = self.calls.pop() {
                    self.seek(ret, start)?;
                }
                Ok(())
            }
            IsoFlow::Label(_) => {
                self.note_label();
                Ok(())
            }
            IsoFlow::Call(n) => {
                if self.calls.len() >= MAX_CALL_DEPTH {
                    return Err(self.diag(
                        start,
                        &ProgramError::OutOfRange(format!(
                            "subprogram calls nested deeper than {MAX_CALL_DEPTH}"
                        )),
                    ));
                }
                let ret = self.reader.next_start();
                let target = self.find_label(n, start)?;
                self.calls.push(ret);
                self.seek(target, start)
            }
            IsoFlow::Repeat(n, k) => {
                let key = self.current.offset;
                let left = self.repeats.entry(key).or_insert(k);
                if *left == 0 {
                    self.repeats.remove(&key);
                    return Ok(());
                }
                *left -= 1;
                let target = self.find_label(n, start)?;
                self.seek(target, start)
            }
            IsoFlow::Goto(n) => {
                let target = self.find_label(n, start)?;
                self.seek(target, start)
            }
        }
    }

    fn seek(&mut self, to: BlockStart, start: usize) -> Result<(), Diagnostic> {
        self.jumps += 1;
        if self.jumps > MAX_IDLE_JUMPS {
            return Err(self.diag(
                start,
                &ProgramError::OutOfRange(format!(
                    "more than {MAX_IDLE_JUMPS} jumps without motion: the program loops endlessly"
                )),
            ));
        }
        self.reader
            .seek(to)
            .map_err(|e| self.diag(start, &ProgramError::Io(e.to_string())))
    }

    /// The position of label `n`, reading ahead when it was not seen yet.
    fn find_label(&mut self, n: u32, start: usize) -> Result<BlockStart, Diagnostic> {
        if let Some(&at) = self.labels.get(&n) {
            return Ok(at);
        }
        let resume = self.reader.next_start();
        let here = self.diag(
            start,
            &ProgramError::Missing("the called label is not defined (G98 L…)"),
        );
        let mut scratch = IsoBlock::default();
        while let Ok(Some(at)) = self.reader.next_block() {
            if scratch.parse(self.reader.text()).is_ok()
                && let Some(l) = label_of(&scratch)
                && l != 0
            {
                self.labels.entry(l).or_insert(at);
                if l == n {
                    return Ok(at);
                }
            }
        }
        // not found: go back so that a check run goes on after the call
        let _ = self.reader.seek(resume);
        Err(Diagnostic {
            message: match here.block {
                Some(b) => format!("block {b}: label {n} is not defined (G98 L{n})"),
                None => format!("label {n} is not defined (G98 L{n})"),
            },
            ..here
        })
    }

    /// Hands out the front op when nothing can change it any more, in machine coordinates:
    /// the cycle transforms (datum shift, mirror, rotation, scaling) first, then the tilted
    /// working plane, as for Klartext programs.
    fn pop_ready(&mut self) -> Option<Op> {
        if let Some(op) = self.state.machine.tilt_pending() {
            return Some(op);
        }
        if !self.state.machine.front_ready() {
            return None;
        }
        let op = self.queue.pop_front()?;
        let op = self.state.machine.output(op);
        let op = self.state.machine.tilt_output(op);
        self.state.machine.popped();
        Some(op)
    }

    fn run_all(&mut self, mode: Mode) -> Vec<Diagnostic> {
        let mut diags = Vec::new();
        while self.phase != Phase::Done {
            if let Err(d) = self.step(mode) {
                diags.push(d);
            }
            // hand out what is ready; a held contour element stays for a G24/G25
            while self.pop_ready().is_some() {}
        }
        diags
    }
}

impl Iterator for IsoProgram {
    type Item = Result<Op, Diagnostic>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            // the last contour element waits while a G24/G25 in the next block may shorten it
            if let Some(op) = self.pop_ready() {
                return Some(Ok(op));
            }
            if let Some(d) = self.pending_error.take() {
                self.queue.clear();
                return Some(Err(d));
            }
            if self.finished || self.phase == Phase::Done {
                self.state.machine.release();
                return self.pop_ready().map(Ok);
            }
            if let Err(d) = self.step(Mode::Run) {
                self.finished = true;
                self.state.machine.release();
                self.pending_error = Some(d);
            }
        }
    }
}

impl DialectRun for IsoProgram {
    fn check_all(&mut self, syntax_only: bool) -> Vec<Diagnostic> {
        self.run_all(if syntax_only {
            Mode::Syntax
        } else {
            Mode::Check
        })
    }

    fn blocks_executed(&self) -> u64 {
        self.blocks
    }

    fn last_position(&self) -> Pose {
        self.state.machine.pos
    }

    fn set_block_skip(&mut self, on: bool) {
        self.block_skip = on;
    }

    fn klartext_machine(&mut self) -> Option<&mut Machine> {
        Some(&mut self.state.machine)
    }

    fn klartext_machine_ref(&self) -> Option<&Machine> {
        Some(&self.state.machine)
    }
}
