//! Running DIN PLUS statements: variable assignments, IF/WHILE/REPEAT/SWITCH structures and
//! local subprogram calls, on the streaming reader.
//!
//! The program is never held in memory: a structure that skips blocks (a false IF, the
//! branches of a SWITCH, a finished WHILE) reads ahead without running them, counting
//! nested structures of the same kind; a loop seeks back to its WHILE (which tests its
//! condition again) or to the block after its REPEAT. A structure must close inside the
//! section (or subprogram) that opens it.
//!
//! Guards: one loop runs at most [`MAX_LOOP_PASSES`] passes and the whole program at most
//! [`MAX_TOTAL_PASSES`] loop passes and subprogram runs together, so a loop whose condition never changes ends in a diagnostic at its
//! WHILE or UNTIL, in a check run too. Subprogram calls nest at most [`MAX_CALL_DEPTH`]
//! deep, and Q repeats a call at most [`MAX_REPEAT`] times.
//!
//! Subprograms are `SUBPROGRAM "name"` sections after END, each closed by RETURN. A call
//! `L"name"` looks the name up among the sections seen so far, else reads ahead to find it.
//! The called subprogram gets its own local variables (`#l…`) and the call's transfer values
//! (`#__la` … from `LA` …); global and channel variables are shared. With Q the subprogram
//! runs Q times in a row, each time with fresh locals and the same transfer values.

use std::collections::HashMap;

use super::block::{DinLine, parse_line};
use super::expr::Vars;
use super::flow::{Kind, Stmt};
use super::run::{DinProgram, Mode, Phase, Section};
use crate::diag::{Diagnostic, ProgramError};
use crate::source::BlockStart;

/// Most passes of one loop.
pub const MAX_LOOP_PASSES: u64 = 10_000;
/// Most loop passes of a whole program run.
pub const MAX_TOTAL_PASSES: u64 = 100_000;
/// Deepest subprogram nesting.
pub const MAX_CALL_DEPTH: usize = 32;
/// Most repetitions Q of one call.
pub const MAX_REPEAT: f64 = 10_000.0;

/// A place in the program for a later diagnostic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Where {
    line: u32,
    col: u32,
    block: Option<u64>,
}

/// An open structure while running.
#[derive(Debug, Clone, Copy)]
struct Open {
    kind: Kind,
    at: Where,
    /// The opening block (WHILE: where a pass starts again).
    start: BlockStart,
    /// The block after the opening one (REPEAT: where a pass starts again).
    body: BlockStart,
    passes: u64,
}

/// An active subprogram call.
#[derive(Debug, Clone)]
struct Frame {
    name: String,
    ret: BlockStart,
    body: BlockStart,
    left: u64,
    section: Option<Section>,
    base: usize,
}

/// The statement state of a running program.
#[derive(Debug)]
pub(crate) struct Control {
    vars: Vars,
    open: Vec<Open>,
    calls: Vec<Frame>,
    subs: HashMap<String, BlockStart>,
    /// Structures opened in blocks that are only read (syntax check, uncalled subprograms).
    read_only: Vec<(Kind, Where)>,
    passes: u64,
}

impl Control {
    /// No variables, nothing open.
    pub fn new() -> Self {
        Control {
            vars: Vars::new(),
            open: Vec::new(),
            calls: Vec::new(),
            subs: HashMap::new(),
            read_only: Vec::new(),
            passes: 0,
        }
    }

    /// Number of active subprogram calls.
    pub fn depth(&self) -> usize {
        self.calls.len()
    }

    /// The variables.
    pub fn vars(&self) -> &Vars {
        &self.vars
    }

    /// True while a subprogram runs.
    pub fn in_call(&self) -> bool {
        !self.calls.is_empty()
    }

    fn base(&self) -> usize {
        self.calls.last().map_or(0, |f| f.base)
    }

    /// The innermost structure of the current program level.
    fn top(&self) -> Option<Open> {
        if self.open.len() > self.base() {
            self.open.last().copied()
        } else {
            None
        }
    }
}

fn unclosed(kind: Kind) -> ProgramError {
    ProgramError::Unexpected(format!(
        "{} without {}: the structure is not closed",
        kind.opener(),
        kind.closer()
    ))
}

impl DinProgram {
    fn here(&self, pos: usize) -> Where {
        let (line, col) = self.reader.position(pos);
        Where {
            line,
            col,
            block: self.number,
        }
    }

    fn diag_at(&self, w: Where, e: &ProgramError) -> Diagnostic {
        Diagnostic::new(self.file.clone(), w.line, w.col, w.block, e)
    }

    fn seek_to(&mut self, to: BlockStart, at: Where) -> Result<(), Diagnostic> {
        self.reader
            .seek(to)
            .map_err(|e| self.diag_at(at, &ProgramError::Io(e.to_string())))
    }

    /// Records where the body of a `SUBPROGRAM "name"` section starts.
    pub(super) fn subprogram_start(&mut self, name: &str, start: usize) -> Result<(), Diagnostic> {
        let body = self.reader.next_start();
        let first = *self.control.subs.entry(name.to_string()).or_insert(body);
        if first != body {
            return Err(self.diag(
                start,
                &ProgramError::Unexpected(format!(
                    "second SUBPROGRAM \"{name}\" (line {}): names must differ",
                    first.line.saturating_sub(1)
                )),
            ));
        }
        Ok(())
    }

    /// At a section code: every structure and call must be closed.
    pub(super) fn section_boundary(&mut self, start: usize) -> Result<(), Diagnostic> {
        if let Some(f) = self.control.calls.first().cloned() {
            self.control.calls.clear();
            self.control.open.clear();
            while self.control.vars.frames() > 1 {
                self.control.vars.pop_frame();
            }
            self.section = f.section;
            return Err(self.diag(
                start,
                &ProgramError::Missing("the subprogram ends without RETURN before this section"),
            ));
        }
        self.close_all()
    }

    /// At the end of the text: the same checks as at a section code.
    pub(super) fn end_of_text(&mut self) -> Result<(), Diagnostic> {
        if let Some(f) = self.control.calls.first().cloned() {
            self.control.calls.clear();
            self.control.open.clear();
            let (line, col) = self.reader.end_position();
            return Err(Diagnostic::new(
                self.file.clone(),
                line,
                col,
                None,
                &ProgramError::Unexpected(format!(
                    "end of file in subprogram \"{}\": RETURN is missing",
                    f.name
                )),
            ));
        }
        self.close_all()
    }

    fn close_all(&mut self) -> Result<(), Diagnostic> {
        let first_run = self.control.open.first().map(|o| (o.kind, o.at));
        let first_read = self.control.read_only.first().copied();
        self.control.open.clear();
        self.control.read_only.clear();
        match first_run.or(first_read) {
            Some((kind, at)) => Err(self.diag_at(at, &unclosed(kind))),
            None => Ok(()),
        }
    }

    /// A statement block.
    pub(super) fn statement(
        &mut self,
        stmt: Stmt,
        pos: usize,
        mode: Mode,
    ) -> Result<(), Diagnostic> {
        let section = *self.section.get_or_insert(Section::Machining);
        if !matches!(section, Section::Machining | Section::Subprogram) {
            return Err(self.diag(
                pos,
                &ProgramError::Unexpected(format!(
                    "{} outside a MACHINING section or subprogram",
                    stmt.keyword()
                )),
            ));
        }
        let runs = mode != Mode::Syntax
            && self.phase == Phase::Running
            && (section == Section::Machining || self.control.in_call());
        if !runs {
            if self.phase == Phase::Stopped && mode != Mode::Syntax {
                return Ok(());
            }
            return self.read_only(&stmt, pos);
        }
        self.blocks += 1;
        self.run_statement(stmt, pos, mode)
    }

    /// Structure checks of a statement that is read but not run.
    fn read_only(&mut self, stmt: &Stmt, pos: usize) -> Result<(), Diagnostic> {
        let at = self.here(pos);
        if let Some(k) = stmt.opens() {
            self.control.read_only.push((k, at));
            return Ok(());
        }
        let top = self.control.read_only.last().map(|t| t.0);
        let need = match stmt {
            Stmt::Then | Stmt::Else => Some(Kind::If),
            Stmt::Case(_) | Stmt::Default | Stmt::Break => Some(Kind::Switch),
            Stmt::Return => {
                return match self.control.read_only.first().copied() {
                    Some((k, w)) => {
                        self.control.read_only.clear();
                        Err(self.diag_at(w, &unclosed(k)))
                    }
                    None => Ok(()),
                };
            }
            _ => stmt.closes(),
        };
        let Some(need) = need else {
            return Ok(());
        };
        if top != Some(need) {
            return Err(self.diag(pos, &stray(stmt, need, top)));
        }
        if stmt.closes().is_some() {
            self.control.read_only.pop();
        }
        Ok(())
    }

    fn run_statement(&mut self, stmt: Stmt, pos: usize, mode: Mode) -> Result<(), Diagnostic> {
        let at = self.here(pos);
        let eval =
            |p: &Self, e: &super::expr::Expr| e.eval(&p.control.vars).map_err(|e| p.diag(pos, &e));
        let top = self.control.top();
        let need = |k: Kind| -> Result<Open, Diagnostic> {
            match top {
                Some(o) if o.kind == k => Ok(o),
                _ => Err(self.diag(pos, &stray(&stmt, k, top.map(|o| o.kind)))),
            }
        };
        match &stmt {
            Stmt::Assign(v, e) => {
                let x = eval(self, e)?;
                self.control
                    .vars
                    .set(*v, x)
                    .map_err(|e| self.diag(pos, &e))?;
            }
            Stmt::If(c) => {
                // a false condition runs the ELSE branch, if there is one
                let taken = eval(self, c)? != 0.0
                    || self.skip(Kind::If, at, mode, |s| {
                        matches!(s, Stmt::Else | Stmt::EndIf)
                    })? == Stmt::Else;
                if taken {
                    self.open(Kind::If, at);
                }
            }
            Stmt::Then => {
                need(Kind::If)?;
            }
            Stmt::Else => {
                let o = need(Kind::If)?;
                self.control.open.pop();
                self.skip(Kind::If, o.at, mode, |s| matches!(s, Stmt::EndIf))?;
            }
            Stmt::EndIf | Stmt::EndSwitch => {
                need(stmt.closes().unwrap_or(Kind::If))?;
                self.control.open.pop();
            }
            Stmt::While(c) => {
                let again = top.filter(|o| o.kind == Kind::While && o.start == self.current);
                if eval(self, c)? != 0.0 {
                    match again {
                        Some(_) => {
                            if let Err(d) = self.pass(pos) {
                                // go on after the loop (a check run reports the rest)
                                let _ = self
                                    .skip(Kind::While, at, mode, |s| matches!(s, Stmt::EndWhile));
                                return Err(d);
                            }
                        }
                        None => self.open(Kind::While, at),
                    }
                } else {
                    let opened = again.map_or(at, |o| o.at);
                    if again.is_some() {
                        self.control.open.pop();
                    }
                    self.skip(Kind::While, opened, mode, |s| matches!(s, Stmt::EndWhile))?;
                }
            }
            Stmt::EndWhile => {
                let o = need(Kind::While)?;
                self.seek_to(o.start, at)?;
            }
            Stmt::Repeat => self.open(Kind::Repeat, at),
            Stmt::Until(c) => {
                let o = need(Kind::Repeat)?;
                if eval(self, c)? != 0.0 {
                    self.control.open.pop();
                } else {
                    self.pass(pos)?;
                    self.seek_to(o.body, at)?;
                }
            }
            Stmt::Switch(v) => {
                let v = eval(self, v)?;
                self.switch(v, at, mode)?;
            }
            Stmt::Case(_) | Stmt::Default | Stmt::Break => {
                let o = need(Kind::Switch)?;
                self.control.open.pop();
                self.skip(Kind::Switch, o.at, mode, |s| matches!(s, Stmt::EndSwitch))?;
            }
            Stmt::Return => self.ret(pos, at)?,
            Stmt::Call {
                name,
                transfer,
                repeat,
            } => {
                let q = match repeat {
                    None => 1.0,
                    Some(e) => eval(self, e)?,
                };
                if !(q >= 1.0 && q.fract() == 0.0 && q <= MAX_REPEAT) {
                    return Err(self.diag(
                        pos,
                        &ProgramError::OutOfRange(format!(
                            "Q{q}: the repeat count must be a whole number from 1 to {MAX_REPEAT}"
                        )),
                    ));
                }
                let mut values = Vec::with_capacity(transfer.len());
                for (letter, e) in transfer {
                    values.push((*letter, eval(self, e)?));
                }
                self.call(name, &values, q as u64, pos, at)?;
            }
        }
        Ok(())
    }

    fn open(&mut self, kind: Kind, at: Where) {
        self.control.open.push(Open {
            kind,
            at,
            start: self.current,
            body: self.reader.next_start(),
            passes: 1,
        });
    }

    /// Counts a subprogram run against the program's pass budget (calls nested in repeated
    /// calls could otherwise multiply without end).
    fn budget(&mut self, pos: usize) -> Result<(), Diagnostic> {
        self.control.passes += 1;
        if self.control.passes > MAX_TOTAL_PASSES {
            let d = self.diag(
                pos,
                &ProgramError::OutOfRange(format!(
                    "more than {MAX_TOTAL_PASSES} loop passes and subprogram runs: \
                     the program does not end"
                )),
            );
            let at = self.here(pos);
            self.unwind(at);
            return Err(d);
        }
        Ok(())
    }

    /// Leaves every active subprogram call: back to the main program after its outermost
    /// call, as if that call had returned (a check run goes on from there).
    fn unwind(&mut self, at: Where) {
        let Some(first) = self.control.calls.first().cloned() else {
            return;
        };
        self.control.calls.clear();
        self.control.open.truncate(first.base);
        while self.control.vars.frames() > 1 {
            self.control.vars.pop_frame();
        }
        self.section = first.section;
        let _ = self.seek_to(first.ret, at);
    }

    /// Counts one more pass of the innermost loop.
    fn pass(&mut self, pos: usize) -> Result<(), Diagnostic> {
        self.control.passes += 1;
        let Some(o) = self.control.open.last_mut() else {
            return Ok(());
        };
        o.passes += 1;
        let (n, kind) = (o.passes, o.kind);
        if n > MAX_LOOP_PASSES || self.control.passes > MAX_TOTAL_PASSES {
            let limit = if n > MAX_LOOP_PASSES {
                format!("ran more than {MAX_LOOP_PASSES} passes")
            } else {
                format!("went past the program's {MAX_TOTAL_PASSES} loop passes")
            };
            self.control.open.pop();
            return Err(self.diag(
                pos,
                &ProgramError::OutOfRange(format!(
                    "{}…{} loop {limit}: it does not end",
                    kind.opener(),
                    kind.closer()
                )),
            ));
        }
        Ok(())
    }

    /// Reads ahead without running to the statement of this structure for which `stop`
    /// holds (nested structures of the same kind are passed over); returns it.
    fn skip(
        &mut self,
        kind: Kind,
        opened: Where,
        mode: Mode,
        stop: fn(&Stmt) -> bool,
    ) -> Result<Stmt, Diagnostic> {
        let mut depth = 0usize;
        loop {
            let at = match self.reader.next_block() {
                Ok(Some(at)) => at,
                Ok(None) => return Err(self.diag_at(opened, &unclosed(kind))),
                Err(e) => return Err(self.diag_at(opened, &ProgramError::Io(e.to_string()))),
            };
            self.current = at;
            match parse_line(self.reader.text()) {
                Err((p, e)) => {
                    self.number = None;
                    if mode == Mode::Check {
                        let d = self.diag(p, &e);
                        self.deferred.push(d);
                    }
                }
                Ok(DinLine::Section { .. } | DinLine::Subprogram { .. }) => {
                    // the section is read normally after the diagnostic
                    self.seek_to(at, opened)?;
                    return Err(self.diag_at(opened, &unclosed(kind)));
                }
                Ok(DinLine::Control { stmt, number, .. }) => {
                    if stmt.opens() == Some(kind) {
                        depth += 1;
                    } else if depth > 0 && stmt.closes() == Some(kind) {
                        depth -= 1;
                    } else if depth == 0 && stop(&stmt) {
                        self.number = number;
                        return Ok(stmt);
                    }
                }
                Ok(_) => {}
            }
        }
    }

    /// SWITCH: runs on after the first CASE whose value equals `v`, else after DEFAULT, else
    /// after ENDSWITCH.
    fn switch(&mut self, v: f64, opened: Where, mode: Mode) -> Result<(), Diagnostic> {
        let mut default: Option<(BlockStart, BlockStart)> = None;
        loop {
            let stmt = self.skip(Kind::Switch, opened, mode, |s| {
                matches!(s, Stmt::Case(_) | Stmt::Default | Stmt::EndSwitch)
            })?;
            match stmt {
                Stmt::Case(values) => {
                    for e in &values {
                        let x = e.eval(&self.control.vars).map_err(|e| self.diag(0, &e))?;
                        if x == v {
                            self.open_switch(opened);
                            return Ok(());
                        }
                    }
                }
                Stmt::Default => {
                    default.get_or_insert((self.current, self.reader.next_start()));
                }
                _ => {
                    if let Some((start, body)) = default {
                        self.seek_to(body, opened)?;
                        self.current = start;
                        self.open_switch(opened);
                    }
                    return Ok(());
                }
            }
        }
    }

    fn open_switch(&mut self, at: Where) {
        self.control.open.push(Open {
            kind: Kind::Switch,
            at,
            start: self.current,
            body: self.reader.next_start(),
            passes: 1,
        });
    }

    fn call(
        &mut self,
        name: &str,
        transfer: &[(u8, f64)],
        repeat: u64,
        pos: usize,
        at: Where,
    ) -> Result<(), Diagnostic> {
        if self.control.calls.len() >= MAX_CALL_DEPTH {
            let d = self.diag(
                pos,
                &ProgramError::Nesting(format!(
                    "subprogram calls nested deeper than {MAX_CALL_DEPTH}"
                )),
            );
            self.unwind(at);
            return Err(d);
        }
        self.budget(pos)?;
        let ret = self.reader.next_start();
        let spot = self.reader.position(pos);
        let body = match self.control.subs.get(name) {
            _ if self.in_external() => self.enter_external(name, spot)?,
            Some(b) => *b,
            None => match self.find_subprogram(name, ret, pos) {
                Ok(b) => b,
                Err(_) => self.enter_external(name, spot)?,
            },
        };
        self.control.calls.push(Frame {
            name: name.to_string(),
            ret,
            body,
            left: repeat - 1,
            section: self.section,
            base: self.control.open.len(),
        });
        self.control.vars.push_frame(transfer);
        self.section = Some(Section::Subprogram);
        self.seek_to(body, at)
    }

    /// Reads ahead for `SUBPROGRAM "name"`, noting every subprogram on the way.
    fn find_subprogram(
        &mut self,
        name: &str,
        resume: BlockStart,
        pos: usize,
    ) -> Result<BlockStart, Diagnostic> {
        let missing = self.diag(
            pos,
            &ProgramError::NoLabel(format!("SUBPROGRAM \"{name}\"")),
        );
        while let Ok(Some(_)) = self.reader.next_block() {
            if let Ok(DinLine::Subprogram { name: n }) = parse_line(self.reader.text()) {
                let body = self.reader.next_start();
                self.control.subs.entry(n.clone()).or_insert(body);
                if n == name {
                    return Ok(body);
                }
            }
        }
        let _ = self.reader.seek(resume);
        Err(missing)
    }

    fn ret(&mut self, pos: usize, at: Where) -> Result<(), Diagnostic> {
        let Some(frame) = self.control.calls.last().cloned() else {
            return Err(self.diag(
                pos,
                &ProgramError::Unexpected("RETURN outside a called subprogram".into()),
            ));
        };
        if let Some(o) = self.control.open.get(frame.base).copied() {
            self.control.open.truncate(frame.base);
            return Err(self.diag_at(o.at, &unclosed(o.kind)));
        }
        if frame.left > 0 {
            self.budget(pos)?;
            if let Some(f) = self.control.calls.last_mut() {
                f.left -= 1;
            }
            self.control.vars.clear_locals();
            return self.seek_to(frame.body, at);
        }
        self.control.calls.pop();
        self.control.vars.pop_frame();
        self.leave_external(self.control.calls.len());
        self.section = frame.section;
        self.seek_to(frame.ret, at)
    }
}

/// A closing or middle keyword without its structure; `top` is the innermost open one.
fn stray(stmt: &Stmt, need: Kind, top: Option<Kind>) -> ProgramError {
    match top {
        Some(t) if t != need => ProgramError::Unexpected(format!(
            "{} inside {}…{}: {} is missing before it",
            stmt.keyword(),
            t.opener(),
            t.closer(),
            t.closer()
        )),
        _ => ProgramError::Unexpected(format!("{} without {}", stmt.keyword(), need.opener())),
    }
}
