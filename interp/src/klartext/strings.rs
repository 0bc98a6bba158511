//! QS string syntax in Klartext: assignment blocks, `DECLARE STRING`, `STRING FORMULA` and
//! the string functions inside formulas, compiled into the block's postfix code (the TNC
//! core evaluates it: [`crate::tnc::strings`]).

use super::lexer::{Lexer, TokKind};
use super::parser::{
    LabelRef, MAX_DEPTH, PResult, Parser, Stmt, describe, param_index, param_kind, required,
    text_of, unexpected, upper,
};
use crate::diag::ProgramError;
use crate::tnc::expr::{Rpn, Value};
use crate::tnc::strings::*;

/// Reads the number after `QS` (the `QS` word itself already consumed).
fn qs_index(lx: &mut Lexer<'_>, at: usize) -> PResult<u32> {
    let t = lx.peek();
    if t.kind != TokKind::Num {
        return Err((at, ProgramError::MissingValue("QS".into())));
    }
    let n = lx.num(t);
    if n.fract() != 0.0 || !(0.0..=f64::from(MAX_QS)).contains(&n) {
        return Err((
            t.start(),
            ProgramError::OutOfRange(format!(
                "string parameter number {n} is not an integer from 0 to {MAX_QS}"
            )),
        ));
    }
    lx.next_token();
    Ok(n as u32)
}

/// Expects a token of `kind`; `what` names it in the error.
fn expect(lx: &mut Lexer<'_>, kind: TokKind, what: &'static str) -> PResult<()> {
    let t = lx.next_token();
    if t.kind == kind {
        Ok(())
    } else {
        Err((t.start(), ProgramError::Missing(what)))
    }
}

/// Reads `prefixQSn` (e.g. `SRC_QS1`, also `SRC_ QS1`) and returns n.
fn qs_word(lx: &mut Lexer<'_>, prefix: &'static [u8]) -> PResult<u32> {
    let t = lx.next_token();
    let (u, n) = upper(lx.slice(t));
    let word = &u[..n];
    let what = match prefix {
        b"SRC_" => "expected SRC_QSn (the string parameter to read)",
        _ => "expected SEA_QSn (the string parameter to search for)",
    };
    if t.kind != TokKind::Ident || !word.starts_with(prefix) {
        return Err((t.start(), ProgramError::Missing(what)));
    }
    let rest = &word[prefix.len()..];
    if rest == b"QS" {
        return qs_index(lx, t.start());
    }
    if rest.is_empty() {
        let q = lx.next_token();
        if q.kind == TokKind::Ident && lx.slice(q).eq_ignore_ascii_case(b"QS") {
            return qs_index(lx, q.start());
        }
        return Err((q.start(), ProgramError::Missing(what)));
    }
    Err((t.start(), ProgramError::Missing(what)))
}

impl Parser {
    /// `QSn = string formula` (the `QS` keyword consumed; `at` is its position).
    pub(super) fn string_assignment(&mut self, lx: &mut Lexer<'_>, at: usize) -> PResult<Stmt> {
        let target = qs_index(lx, at)?;
        expect(lx, TokKind::Eq, "expected '=' after the string parameter")?;
        self.code.clear();
        self.string_expr(lx, 0)?;
        let end = lx.next_token();
        if end.kind != TokKind::End {
            return Err(unexpected(lx, end));
        }
        Ok(Stmt::AssignString { target })
    }

    /// `DECLARE STRING QSn = …` (other DECLARE forms are not supported).
    pub(super) fn declare(&mut self, lx: &mut Lexer<'_>) -> PResult<Stmt> {
        let t = lx.next_token();
        if t.kind == TokKind::Ident && lx.slice(t).eq_ignore_ascii_case(b"STRING") {
            let q = lx.next_token();
            if !(q.kind == TokKind::Ident && lx.slice(q).eq_ignore_ascii_case(b"QS")) {
                return Err((
                    q.start(),
                    ProgramError::Missing("expected QSn after DECLARE STRING"),
                ));
            }
            return self.string_assignment(lx, q.start());
        }
        Ok(Stmt::Unsupported {
            what: "DECLARE",
            number: None,
        })
    }

    /// `STRING FORMULA QSn = …`.
    pub(super) fn string_formula(&mut self, lx: &mut Lexer<'_>) -> PResult<Stmt> {
        let f = lx.next_token();
        if !(f.kind == TokKind::Ident && lx.slice(f).eq_ignore_ascii_case(b"FORMULA")) {
            return Err((
                f.start(),
                ProgramError::Missing("expected FORMULA after STRING"),
            ));
        }
        let q = lx.next_token();
        if !(q.kind == TokKind::Ident && lx.slice(q).eq_ignore_ascii_case(b"QS")) {
            return Err((
                q.start(),
                ProgramError::Missing("expected QSn after STRING FORMULA"),
            ));
        }
        self.string_assignment(lx, q.start())
    }

    /// `term ('||' term)*`.
    fn string_expr(&mut self, lx: &mut Lexer<'_>, depth: u32) -> PResult<()> {
        self.string_term(lx, depth)?;
        loop {
            let t = lx.peek();
            if !(t.kind == TokKind::Other && t.byte == b'|') {
                return Ok(());
            }
            lx.next_token();
            let second = lx.next_token();
            if !(second.kind == TokKind::Other && second.byte == b'|') {
                return Err((
                    t.start(),
                    ProgramError::Missing("expected '||' to join texts"),
                ));
            }
            self.string_term(lx, depth)?;
            self.code.push(Rpn::Concat);
        }
    }

    /// A literal, `QSn`, `( … )`, SUBSTR(…) or TOCHAR(…).
    fn string_term(&mut self, lx: &mut Lexer<'_>, depth: u32) -> PResult<()> {
        let t = lx.next_token();
        if depth > MAX_DEPTH {
            return Err((
                t.start(),
                ProgramError::OutOfRange(format!("formula nested deeper than {MAX_DEPTH}")),
            ));
        }
        match t.kind {
            TokKind::Str => {
                if lx.byte_at(t.end()) != Some(b'"') {
                    return Err((
                        t.start().saturating_sub(1),
                        ProgramError::Missing("text without its closing '\"'"),
                    ));
                }
                if t.end() - t.start() > MAX_STRING {
                    return Err((
                        t.start(),
                        ProgramError::OutOfRange(format!(
                            "text longer than the {MAX_STRING} characters a QS parameter holds"
                        )),
                    ));
                }
                self.code
                    .push(Rpn::PushText(t.start() as u32, t.end() as u32));
                Ok(())
            }
            TokKind::LParen => {
                self.string_expr(lx, depth + 1)?;
                expect(lx, TokKind::RParen, "expected ')'")
            }
            TokKind::Ident => {
                let (u, n) = upper(lx.slice(t));
                match &u[..n] {
                    b"QS" => {
                        let i = qs_index(lx, t.start())?;
                        self.code.push(Rpn::PushQs(i));
                        Ok(())
                    }
                    b"SUBSTR" => {
                        expect(lx, TokKind::LParen, "expected '(' after SUBSTR")?;
                        let src = qs_word(lx, b"SRC_")?;
                        self.numeric_arg(lx, b"BEG")?;
                        self.numeric_arg(lx, b"LEN")?;
                        expect(
                            lx,
                            TokKind::RParen,
                            "expected ')' after SUBSTR( SRC_QSn BEG.. LEN..",
                        )?;
                        self.code.push(Rpn::SubStr(src));
                        Ok(())
                    }
                    b"TOCHAR" => {
                        expect(lx, TokKind::LParen, "expected '(' after TOCHAR")?;
                        // DECIMALS comes after DAT in the text but is popped second: compile
                        // DAT into a scratch copy and append it after DECIMALS
                        let mark = self.code.len();
                        self.numeric_arg(lx, b"DAT")?;
                        let dat: Vec<Rpn> = self.code.split_off(mark);
                        let p = lx.peek();
                        let with = p.kind == TokKind::Ident
                            && upper(lx.slice(p)).0.starts_with(b"DECIMALS");
                        if with {
                            self.numeric_arg(lx, b"DECIMALS")?;
                        }
                        self.code.extend(dat);
                        expect(
                            lx,
                            TokKind::RParen,
                            "expected ')' after TOCHAR( DAT.. DECIMALS..",
                        )?;
                        self.code.push(Rpn::ToChar(with));
                        Ok(())
                    }
                    b"CFGREAD" | b"SYSSTR" => Err((
                        t.start(),
                        ProgramError::NotSupported(format!(
                            "{} (control configuration and system texts)",
                            text_of(&u[..n])
                        )),
                    )),
                    b"STRLEN" | b"INSTR" | b"STRCOMP" | b"TONUMB" => Err((
                        t.start(),
                        ProgramError::Unexpected(format!(
                            "{} in a string formula: it gives a number (assign it to a Q parameter)",
                            text_of(&u[..n])
                        )),
                    )),
                    _ if param_kind(&u[..n]).is_some() => Err((
                        t.start(),
                        ProgramError::Unexpected(format!(
                            "number parameter {} in a string formula (use TOCHAR( DAT+{}.. ))",
                            text_of(&u[..n]),
                            text_of(&u[..n])
                        )),
                    )),
                    _ => Err((
                        t.start(),
                        ProgramError::Unexpected(format!(
                            "unknown string function '{}'",
                            text_of(lx.slice(t))
                        )),
                    )),
                }
            }
            TokKind::End => Err((
                t.start(),
                ProgramError::Missing("string formula ends too early"),
            )),
            _ => Err(unexpected(lx, t)),
        }
    }

    /// `NAMEvalue` / `NAME Qn` / `NAMEQn`: a numeric argument of a string function, pushed.
    fn numeric_arg(&mut self, lx: &mut Lexer<'_>, name: &'static [u8]) -> PResult<()> {
        let t = lx.next_token();
        let (u, n) = upper(lx.slice(t));
        let word = &u[..n];
        if t.kind != TokKind::Ident || !word.starts_with(name) {
            return Err((
                t.start(),
                ProgramError::Unexpected(format!(
                    "{} (expected {}…)",
                    describe(lx, t),
                    text_of(name)
                )),
            ));
        }
        let v = match param_kind(&word[name.len()..]) {
            Some(kind) => Value::Param {
                param: param_index(lx, kind, t.start())?,
                negate: false,
            },
            None if word.len() == name.len() => required(lx, &text_of(name), t.start())?,
            None => return Err(unexpected(lx, t)),
        };
        self.code.push(Rpn::Push(v));
        Ok(())
    }

    /// The string functions that give numbers, inside a numeric formula: `name` is the
    /// upper-case function word at `at`; its `( … )` follows.
    pub(super) fn string_number(
        &mut self,
        lx: &mut Lexer<'_>,
        name: &[u8],
        at: usize,
    ) -> PResult<()> {
        let word = text_of(name);
        let open = lx.next_token();
        if open.kind != TokKind::LParen {
            return Err((
                open.start(),
                ProgramError::Missing("expected '(' after the string function"),
            ));
        }
        let ins = match name {
            b"STRLEN" => Rpn::StrLen(qs_word(lx, b"SRC_")?),
            b"TONUMB" => Rpn::ToNumb(qs_word(lx, b"SRC_")?),
            b"STRCOMP" => {
                let a = qs_word(lx, b"SRC_")?;
                Rpn::StrComp(a, qs_word(lx, b"SEA_")?)
            }
            b"INSTR" => {
                let a = qs_word(lx, b"SRC_")?;
                let b = qs_word(lx, b"SEA_")?;
                let p = lx.peek();
                if p.kind == TokKind::Ident && upper(lx.slice(p)).0.starts_with(b"BEG") {
                    self.numeric_arg(lx, b"BEG")?;
                } else {
                    self.code.push(Rpn::Push(Value::Num(0.0)));
                }
                Rpn::InStr(a, b)
            }
            _ => {
                return Err((
                    at,
                    ProgramError::NotSupported(format!("string function {word}")),
                ));
            }
        };
        let close = lx.next_token();
        if close.kind != TokKind::RParen {
            return Err((
                close.start(),
                ProgramError::Missing("expected ')' to close the string function"),
            ));
        }
        self.code.push(ins);
        Ok(())
    }

    /// The label after `CALL LBL` or `GOTO LBL`: a number, a quoted name or `QSn` (the label
    /// named by the text of QS n).
    pub(super) fn label_target(&mut self, lx: &mut Lexer<'_>, at: usize) -> PResult<LabelRef> {
        let t = lx.peek();
        if t.kind == TokKind::Ident && lx.slice(t).eq_ignore_ascii_case(b"QS") {
            lx.next_token();
            return Ok(LabelRef::Qs(qs_index(lx, t.start())?));
        }
        self.label_ref(lx, at)
    }
}
