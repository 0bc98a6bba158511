//! The streaming lathe DIN runner: program sections, their order, and which blocks run.
//!
//! Sections follow the manual's order: HEADER, CHUCKING EQUIPMENT, TURRET, BLANK,
//! AUXIL_BLANK, FINISHED PART, AUXIL_CONTOUR, the C/Y contour sections (FACE_C, REAR_C,
//! LATERAL_C, FACE_Y, LATERAL_Y/SURFACE_Y, in any order), MACHINING, END, then SUBPROGRAM
//! sections (German names accepted). A section out of order, or one of the single sections
//! twice, is an error. Only MACHINING blocks move the machine: tool calls, M functions or
//! motion in the other sections are errors (the contour sections describe geometry with
//! G0–G13, which is read but not run; the FINISHED PART contour is kept for G890). TURRET blocks (`T1 ID"…"`) name the tools. A program
//! whose first NC block comes before any section code is a bare machining program (the form
//! of the manual's short examples): its blocks run as a MACHINING section. END (also the
//! Russian edition's `КОНЕЦ`) ends the run; M30/M2 end it early, and the rest is only checked
//! for syntax.
//!
//! Variable assignments, control structures, subprogram calls and RETURN (see `flow`) run
//! in MACHINING and in called subprograms (see `control`); in the other sections they are
//! errors, and where blocks are only read (a syntax check, subprograms nobody calls) their
//! structures are still checked for nesting. Variables and formulas in address words are
//! evaluated when the block runs.

use std::collections::VecDeque;
use std::path::PathBuf;

use super::block::{DinLine, DinValue, DinWord, parse_line};
use super::contour::ContourError;
use super::control::Control;
use super::exec::{DinExec, DinFlow};
use super::flow;
use super::lathe::groups;
use super::roughing;
use super::tilt::LateralPlane;
use crate::diag::{Diagnostic, ProgramError};
use crate::dialect::DialectRun;
use crate::op::{Op, Pose, SourceLoc};
use crate::source::{BlockReader, BlockStart, ProgramInput};

/// Program sections in their required order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Section {
    /// HEADER / PROGRAMMKOPF.
    Header,
    /// CHUCKING EQUIPMENT / SPANNMITTEL.
    Chucking,
    /// TURRET / REVOLVER.
    Turret,
    /// BLANK / ROHTEIL.
    Blank,
    /// AUXIL_BLANK.
    AuxBlank,
    /// FINISHED PART / FERTIGTEIL.
    Finished,
    /// AUXIL_CONTOUR.
    AuxContour,
    /// FACE_C, REAR_C, LATERAL_C, FACE_Y, LATERAL_Y, SURFACE_Y.
    AxisContour,
    /// MACHINING / BEARBEITUNG.
    Machining,
    /// END / ENDE.
    End,
    /// SUBPROGRAM / UNTERPROGRAMM.
    Subprogram,
}

impl Section {
    /// The section a code names.
    pub fn from_code(code: &str) -> Option<Section> {
        Some(match code {
            "HEADER" | "PROGRAM HEAD" | "PROGRAMMKOPF" => Section::Header,
            "CHUCKING EQUIPMENT" | "SPANNMITTEL" => Section::Chucking,
            "TURRET" | "REVOLVER" => Section::Turret,
            "BLANK" | "ROHTEIL" => Section::Blank,
            "AUXIL_BLANK" | "HILFSROHTEIL" => Section::AuxBlank,
            "FINISHED PART" | "FINISHED" | "FERTIGTEIL" => Section::Finished,
            "AUXIL_CONTOUR" | "HILFSKONTUR" => Section::AuxContour,
            "FRONT" | "FACE_C" | "STIRN_C" | "REAR_C" | "RUECKSEITE_C" | "LATERAL"
            | "LATERAL_C" | "MANTEL_C" | "FACE_Y" | "STIRN_Y" | "LATERAL_Y" | "MANTEL_Y"
            | "SURFACE_Y" => Section::AxisContour,
            "MACHINING" | "BEARBEITUNG" => Section::Machining,
            "END" | "ENDE" | "КОНЕЦ" => Section::End,
            "SUBPROGRAM" | "UNTERPROGRAMM" => Section::Subprogram,
            _ => return None,
        })
    }

    fn repeatable(self) -> bool {
        matches!(self, Section::AxisContour | Section::Subprogram)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Phase {
    Running,
    Stopped,
    Ended,
    Done,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Mode {
    Run,
    Check,
    Syntax,
}

/// A lathe DIN program being run line by line.
pub(crate) struct DinProgram {
    pub(super) file: PathBuf,
    pub(super) reader: BlockReader,
    pub(super) exec: DinExec,
    pub(super) queue: VecDeque<Op>,
    pub(super) section: Option<Section>,
    pub(super) phase: Phase,
    pub(super) finished: bool,
    pub(super) blocks: u64,
    pub(super) number: Option<u64>,
    /// Variables, control structures and subprogram calls.
    pub(super) control: Control,
    /// Where the current block starts in the file.
    pub(super) current: BlockStart,
    /// Diagnostics found while reading ahead (skipped branches) in a check run.
    pub(super) deferred: Vec<Diagnostic>,
    /// The calling files while an external subprogram runs (see `external`).
    pub(super) outer: Vec<super::external::Outer>,
}

/// Reads the parameters of a LATERAL_Y / SURFACE_Y section code.
pub(crate) fn lateral_plane(words: &[DinWord]) -> Result<LateralPlane, (usize, ProgramError)> {
    let mut plane = LateralPlane {
        reference_diameter: 0.0,
        c: 0.0,
        b: None,
        i: 0.0,
        k: 0.0,
        no_back_shift: false,
    };
    for w in words {
        let DinValue::Num(v) = w.value else {
            return Err((w.pos, ProgramError::MissingValue(w.addr.clone())));
        };
        match w.addr.as_str() {
            "X" => plane.reference_diameter = v,
            "C" => plane.c = v,
            "B" => plane.b = Some(v),
            "I" => plane.i = v,
            "K" => plane.k = v,
            "H" if v == 0.0 || v == 1.0 => plane.no_back_shift = v == 1.0,
            "H" => {
                return Err((
                    w.pos,
                    ProgramError::OutOfRange(format!("H{v}: expected 0 or 1")),
                ));
            }
            _ => {
                return Err((
                    w.pos,
                    ProgramError::UnknownWord {
                        word: w.addr.clone(),
                        block: "LATERAL_Y",
                    },
                ));
            }
        }
    }
    Ok(plane)
}

fn moves_or_calls(words: &[DinWord]) -> Option<&DinWord> {
    words
        .iter()
        .find(|w| matches!(w.addr.as_str(), "T" | "M" | "G"))
}

impl DinProgram {
    /// A runner over `input`; `start` is where the machine stands.
    pub fn new(file: PathBuf, input: Box<dyn ProgramInput>, start: Pose) -> Self {
        DinProgram {
            file,
            reader: BlockReader::new(input),
            exec: DinExec::new(start),
            queue: VecDeque::with_capacity(16),
            section: None,
            phase: Phase::Running,
            finished: false,
            blocks: 0,
            number: None,
            control: Control::new(),
            current: BlockStart { offset: 0, line: 1 },
            deferred: Vec::new(),
            outer: Vec::new(),
        }
    }

    pub(super) fn diag(&self, pos: usize, error: &ProgramError) -> Diagnostic {
        let (line, col) = self.reader.position(pos);
        Diagnostic::new(self.file.clone(), line, col, self.number, error)
    }

    pub(super) fn step(&mut self, mode: Mode) -> Result<(), Diagnostic> {
        match self.reader.next_block() {
            Ok(Some(at)) => self.current = at,
            Ok(None) => {
                let was = self.phase;
                self.phase = Phase::Done;
                self.end_of_text()?;
                if was == Phase::Ended {
                    return Ok(());
                }
                let (line, col) = self.reader.end_position();
                return Err(Diagnostic::new(
                    self.file.clone(),
                    line,
                    col,
                    None,
                    &ProgramError::Missing("the section code END is missing at end of file"),
                ));
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
        }
        self.number = None;
        let line = parse_line(self.reader.text()).map_err(|(p, e)| self.diag(p, &e))?;
        let start = self
            .reader
            .text()
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(0);
        match line {
            DinLine::Empty | DinLine::Name => Ok(()),
            DinLine::Section { code, words } => self.section(&code, &words, start, mode),
            DinLine::Subprogram { name } => {
                let first = self.subprogram_start(&name, start);
                self.section("SUBPROGRAM", &[], start, mode).and(first)
            }
            DinLine::Control { number, stmt, pos } => {
                self.number = number;
                self.statement(stmt, pos, mode)
            }
            DinLine::Block { number, words } => {
                self.number = number;
                self.nc_block(words, start, mode)
            }
        }
    }

    fn section(
        &mut self,
        code: &str,
        words: &[DinWord],
        start: usize,
        mode: Mode,
    ) -> Result<(), Diagnostic> {
        let Some(next) = Section::from_code(code) else {
            return Err(self.diag(start, &ProgramError::UnknownBlock(code.to_string())));
        };
        // what the previous section left open is reported, and this section still begins
        let mut left_open = self.section_boundary(start);
        if self.section == Some(Section::Finished) && next != Section::Finished {
            let r = self.exec.contour.close();
            left_open = left_open.and(r.map_err(|e| self.contour_diag(e, start)));
        }
        if let Some(cur) = self.section
            && (next < cur || (next == cur && !next.repeatable()))
        {
            return Err(self.diag(
                start,
                &ProgramError::Unexpected(format!(
                    "section {code} here: sections go HEADER, TURRET, BLANK, FINISHED PART, \
                     contour sections, MACHINING, END, each once"
                )),
            ));
        }
        if !words.is_empty() {
            if matches!(code, "LATERAL_Y" | "MANTEL_Y" | "SURFACE_Y") {
                // validated here; the plane serves the contour-milling cycles (not run yet)
                lateral_plane(words).map_err(|(p, e)| self.diag(p, &e))?;
            } else if let Some(w) = words.first() {
                return Err(self.diag(
                    w.pos,
                    &ProgramError::UnknownWord {
                        word: w.addr.clone(),
                        block: "section code",
                    },
                ));
            }
        }
        self.section = Some(next);
        if next == Section::End {
            if self.phase == Phase::Running && mode != Mode::Syntax {
                let (line, col) = self.reader.position(start);
                let loc = SourceLoc {
                    file: 0,
                    line,
                    col,
                    block: None,
                };
                self.exec.end_ops(loc, &mut self.queue);
            }
            self.phase = Phase::Ended;
            if mode == Mode::Run {
                self.finished = true;
            }
        }
        left_open
    }

    fn nc_block(
        &mut self,
        mut words: Vec<DinWord>,
        start: usize,
        mode: Mode,
    ) -> Result<(), Diagnostic> {
        let section = match self.section {
            Some(s) => s,
            None => {
                // a bare machining program
                self.section = Some(Section::Machining);
                Section::Machining
            }
        };
        match section {
            Section::Turret => {
                self.turret(&words);
                return Ok(());
            }
            Section::Subprogram if self.control.in_call() => {}
            Section::Subprogram => return Ok(()),
            Section::Machining => {}
            Section::Finished => {
                if let Some(w) = words.iter().find(|w| w.addr == "T" || w.addr == "M") {
                    return Err(self.diag(
                        w.pos,
                        &ProgramError::Unexpected(
                            "tool call or M function outside a MACHINING section".into(),
                        ),
                    ));
                }
                if mode != Mode::Syntax {
                    let number = self.number;
                    flow::resolve(&mut words, self.control.vars())
                        .map_err(|(p, e)| self.diag(p, &e))?;
                    let reader = &self.reader;
                    let r = self
                        .exec
                        .contour
                        .add(&words, number, &|p| reader.position(p));
                    r.map_err(|e| self.contour_diag(e, start))?;
                }
                return Ok(());
            }
            Section::Blank if mode != Mode::Syntax => {
                if let Some(w) = words.iter().find(|w| w.addr == "T" || w.addr == "M") {
                    return Err(self.diag(
                        w.pos,
                        &ProgramError::Unexpected(
                            "tool call or M function outside a MACHINING section".into(),
                        ),
                    ));
                }
                flow::resolve(&mut words, self.control.vars())
                    .map_err(|(p, e)| self.diag(p, &e))?;
                let gs = groups(&words)
                    .map_err(|(p, e)| self.diag(p.map_or(start, |p| p as usize), &e))?;
                for g in gs.iter().filter(|g| g.g == Some(20)) {
                    let bar = roughing::bar(g)
                        .map_err(|(p, e)| self.diag(p.map_or(start, |p| p as usize), &e))?;
                    self.exec.blank = Some(bar);
                }
                return Ok(());
            }
            Section::Blank | Section::AuxBlank | Section::AuxContour | Section::AxisContour => {
                if let Some(w) = words.iter().find(|w| w.addr == "T" || w.addr == "M") {
                    return Err(self.diag(
                        w.pos,
                        &ProgramError::Unexpected(
                            "tool call or M function outside a MACHINING section".into(),
                        ),
                    ));
                }
                return Ok(());
            }
            _ => {
                if let Some(w) = moves_or_calls(&words) {
                    return Err(self.diag(
                        w.pos,
                        &ProgramError::Unexpected(
                            "motion, tool call or M function outside a MACHINING section".into(),
                        ),
                    ));
                }
                return Ok(());
            }
        }
        if self.phase == Phase::Stopped || mode == Mode::Syntax {
            return Ok(());
        }
        if self.phase == Phase::Ended {
            return Err(self.diag(start, &ProgramError::AfterEnd));
        }
        let (line, col) = self.reader.position(start);
        let loc = SourceLoc {
            file: 0,
            line,
            col,
            block: self.number,
        };
        self.blocks += 1;
        flow::resolve(&mut words, self.control.vars()).map_err(|(p, e)| self.diag(p, &e))?;
        let flow = self
            .exec
            .block(&words, self.number, loc, &mut self.queue)
            .map_err(|(p, e)| self.diag(p.map_or(start, |p| p as usize), &e))?;
        if flow == DinFlow::End {
            self.phase = Phase::Stopped;
            if mode == Mode::Run {
                self.finished = true;
            }
        }
        Ok(())
    }

    fn contour_diag(&self, e: ContourError, start: usize) -> Diagnostic {
        match e {
            ContourError::Here((p, e)) => self.diag(p.map_or(start, |p| p as usize), &e),
            ContourError::Earlier {
                line,
                col,
                block,
                error,
            } => Diagnostic::new(self.file.clone(), line, col, block, &error),
        }
    }

    fn turret(&mut self, words: &[DinWord]) {
        let t = words
            .iter()
            .find_map(|w| match (w.addr.as_str(), &w.value) {
                ("T", DinValue::Num(v)) if *v >= 0.0 && v.fract() == 0.0 && *v < 1e9 => {
                    Some(*v as u32)
                }
                _ => None,
            });
        let id = words
            .iter()
            .find_map(|w| match (w.addr.as_str(), &w.value) {
                ("ID", DinValue::Text(s)) => Some(s.clone()),
                _ => None,
            });
        if let (Some(t), Some(id)) = (t, id) {
            self.exec.tools.insert(t, id);
        }
    }

    fn run_all(&mut self, mode: Mode) -> Vec<Diagnostic> {
        let mut diags = Vec::new();
        while self.phase != Phase::Done {
            if let Err(d) = self.step(mode) {
                diags.push(d);
            }
            diags.append(&mut self.deferred);
            self.queue.clear();
        }
        diags
    }
}

impl Iterator for DinProgram {
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

impl DialectRun for DinProgram {
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
        self.exec.lathe.pos
    }

    fn set_block_skip(&mut self, _on: bool) {}
}
