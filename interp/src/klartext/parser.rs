//! Klartext parser: one block's text → a [`Block`] with its words resolved to typed fields.
//!
//! Parsing checks syntax only (which words a block type takes, that values are present); it
//! does not look at Q parameter values or geometry, so a whole file can be checked without
//! running it. Formulas are compiled into the parser's reused postfix buffer ([`Parser::code`]).
//!
//! Tolerated forms seen in real files: optional block number (also `N12`), `/` block skip
//! before or after the number, spaces inside words, `R`/`F`/`M`/`REP` without a value (old
//! exports: `R` alone is R0, an empty `F`, `M` or `REP` is ignored), `F MAX`, decimal commas,
//! `* - text` headlines, `;` comments and `( … )` comment headers, `CYCL DEF9 .0` (number
//! glued to DEF, blank before the sub-block: [`super::cycle`]). Continuations are joined by
//! the block reader (`crate::source`): `~` also before a trailing comment, a comment ending in
//! `~` goes on over the next line, and SPL coefficient lines join their SPL block; a K line
//! anywhere else is an error here. Text before BEGIN PGM and an END PGM name that differs
//! from BEGIN PGM are warnings of the interpreter, not parse errors. Block types this version
//! does not run (the keyword `FK` alone, other FN numbers, …) are recognised by their keyword
//! and reported as not supported when executed.

use super::lexer::{Lexer, TokKind, Token};
use crate::diag::ProgramError;
use crate::op::AxisLetter;
use crate::tnc::expr::{MAX_PARAM, ParamKind, ParamRef, Value};
pub(crate) use crate::tnc::stmt::*;

pub(super) type PResult<T> = Result<T, (usize, ProgramError)>;

// Word classes a block type accepts.
pub(super) const W_AXES: u16 = 1;
pub(super) const W_POLAR: u16 = 2;
pub(super) const W_DR: u16 = 4;
pub(super) const W_RADIUS: u16 = 8;
pub(super) const W_COMP: u16 = 16;
pub(super) const W_FEED: u16 = 32;
pub(super) const W_M: u16 = 64;
pub(super) const W_APPR: u16 = 128;
pub(super) const PATH: u16 = W_COMP | W_FEED | W_M;

/// Deepest parenthesis/function nesting accepted in a formula.
pub(super) const MAX_DEPTH: u32 = 64;

/// The Klartext parser: reads a block's text into its [`Stmt`] and the block's words
/// ([`crate::tnc::stmt::Parsed`], which the TNC core executes; the parsing methods live in
/// this front-end).
pub(crate) use crate::tnc::stmt::Parsed as Parser;

/// Upper-cases an identifier into a small stack buffer (longer ones are cut, which makes them
/// unknown words).
pub(super) fn upper(bytes: &[u8]) -> ([u8; 16], usize) {
    let mut out = [0u8; 16];
    let n = bytes.len().min(16);
    for (o, b) in out.iter_mut().zip(bytes.iter()) {
        *o = b.to_ascii_uppercase();
    }
    (out, if bytes.len() > 16 { 16 } else { n })
}

pub(super) fn describe(lx: &Lexer<'_>, t: Token) -> String {
    match t.kind {
        TokKind::End => "end of block".into(),
        TokKind::Num => format!("number '{}'", text_of(lx.slice(t))),
        TokKind::Ident => format!("word '{}'", text_of(lx.slice(t))),
        TokKind::Str => format!("text \"{}\"", text_of(lx.slice(t))),
        TokKind::Other => format!("character '{}'", char::from(t.byte)),
        _ => format!("'{}'", text_of(lx.slice(t))),
    }
}

pub(super) fn unexpected(lx: &Lexer<'_>, t: Token) -> (usize, ProgramError) {
    if t.kind == TokKind::Placeholder {
        return (t.start(), ProgramError::Placeholder(text_of(lx.slice(t))));
    }
    (t.start(), ProgramError::Unexpected(describe(lx, t)))
}

pub(super) fn axis_of(c: u8) -> Option<AxisLetter> {
    Some(match c {
        b'X' => AxisLetter::X,
        b'Y' => AxisLetter::Y,
        b'Z' => AxisLetter::Z,
        b'A' => AxisLetter::A,
        b'B' => AxisLetter::B,
        b'C' => AxisLetter::C,
        b'U' => AxisLetter::U,
        b'V' => AxisLetter::V,
        b'W' => AxisLetter::W,
        _ => return None,
    })
}

pub(super) fn param_kind(name: &[u8]) -> Option<ParamKind> {
    match name {
        b"Q" => Some(ParamKind::Q),
        b"QL" => Some(ParamKind::QL),
        b"QR" => Some(ParamKind::QR),
        _ => None,
    }
}

/// Result of reading a word's value.
pub(super) enum Val {
    /// Nothing follows the word.
    None,
    /// Only a sign follows (`DR+`); true for minus.
    Sign(bool),
    /// A value.
    Some(Value),
}

/// Reads the parameter number after `Q`/`QL`/`QR`.
pub(super) fn param_index(lx: &mut Lexer<'_>, kind: ParamKind, at: usize) -> PResult<ParamRef> {
    let t = lx.peek();
    let n = if t.kind == TokKind::Num {
        lx.num(t)
    } else {
        -1.0
    };
    match t.kind {
        TokKind::Num if n.fract() == 0.0 && n <= f64::from(MAX_PARAM) => {
            lx.next_token();
            Ok(ParamRef {
                kind,
                index: n as u32,
            })
        }
        TokKind::Num => Err((
            t.start(),
            ProgramError::OutOfRange(format!(
                "parameter number {n} is not an integer from 0 to {MAX_PARAM}"
            )),
        )),
        _ => Err((at, ProgramError::MissingValue("Q".into()))),
    }
}

/// Reads an optional signed number or parameter reference.
pub(super) fn value(lx: &mut Lexer<'_>) -> PResult<Val> {
    let mut neg = false;
    let mut signed = false;
    loop {
        match lx.peek().kind {
            TokKind::Plus => {
                lx.next_token();
                signed = true;
            }
            TokKind::Minus => {
                lx.next_token();
                signed = true;
                neg = !neg;
            }
            _ => break,
        }
    }
    let t = lx.peek();
    match t.kind {
        TokKind::Num => {
            lx.next_token();
            let v = lx.num(t);
            Ok(Val::Some(Value::Num(if neg { -v } else { v })))
        }
        TokKind::Ident => {
            let (u, n) = upper(lx.slice(t));
            match param_kind(&u[..n]) {
                Some(kind) => {
                    lx.next_token();
                    let param = param_index(lx, kind, t.start())?;
                    Ok(Val::Some(Value::Param { param, negate: neg }))
                }
                None if signed => Ok(Val::Sign(neg)),
                None => Ok(Val::None),
            }
        }
        _ if signed => Ok(Val::Sign(neg)),
        _ => Ok(Val::None),
    }
}

/// Reads a value that must be present.
pub(super) fn required(lx: &mut Lexer<'_>, word: &str, at: usize) -> PResult<Value> {
    match value(lx)? {
        Val::Some(v) => Ok(v),
        _ => Err((at, ProgramError::MissingValue(word.into()))),
    }
}

impl Parser {
    /// Parses one block's text.
    pub fn parse(&mut self, text: &[u8]) -> Result<Block, ParseError> {
        let mut lx = Lexer::new(text, 0);
        let mut number = None;
        let mut skip = false;
        let res;
        let start;
        if let Some(p) = plain_prefix(text) {
            // common form `12 L …`: no need for the token machinery to find the keyword
            // (a keyword followed by a blank is never a comment block)
            start = p.start;
            number = p.number;
            let kw = Token::new(TokKind::Ident, p.keyword.0, p.keyword.1);
            res = self.dispatch(&mut lx, kw);
        } else if is_comment_block(text) {
            start = lx.peek().start();
            res = Ok(Stmt::Empty);
        } else {
            start = lx.peek().start();
            res = self.parse_inner(&mut lx, &mut number, &mut skip);
        }
        match res {
            Ok(stmt) => Ok(Block {
                number,
                skip,
                start,
                stmt,
            }),
            Err((pos, error)) => match template_placeholder(text) {
                // a file generated from a template whose fields were never filled in
                Some((at, field)) => Err(ParseError {
                    pos: at,
                    number,
                    error: ProgramError::Placeholder(field),
                }),
                None => Err(ParseError { pos, number, error }),
            },
        }
    }

    fn parse_inner(
        &mut self,
        lx: &mut Lexer<'_>,
        number: &mut Option<u64>,
        skip: &mut bool,
    ) -> PResult<Stmt> {
        if lx.peek().kind == TokKind::Slash {
            lx.next_token();
            *skip = true;
        }
        let t = lx.peek();
        let mut numbered = None;
        match t.kind {
            TokKind::Num => numbered = Some((lx.num(t), t)),
            TokKind::Ident
                if lx.slice(t).eq_ignore_ascii_case(b"N")
                    && lx.byte_at(t.end()).is_some_and(|b| b.is_ascii_digit()) =>
            {
                lx.next_token();
                let n = lx.peek();
                if n.kind == TokKind::Num {
                    numbered = Some((lx.num(n), n));
                }
            }
            _ => {}
        }
        if let Some((n, tok)) = numbered {
            lx.next_token();
            if n.fract() != 0.0 || n > 1e15 {
                return Err((
                    tok.start(),
                    ProgramError::OutOfRange(format!(
                        "block number '{}' is not a whole number",
                        text_of(lx.slice(tok))
                    )),
                ));
            }
            *number = Some(n as u64);
        }
        if lx.peek().kind == TokKind::Slash {
            lx.next_token();
            *skip = true;
        }
        let t = lx.peek();
        match t.kind {
            TokKind::End => return Ok(Stmt::Empty),
            TokKind::Star | TokKind::LParen => return Ok(Stmt::Empty),
            TokKind::Ident => {}
            _ => return Err(unexpected(lx, t)),
        }
        self.dispatch(lx, t)
    }

    /// Parses the rest of a block from its keyword token `t` (not consumed yet).
    fn dispatch(&mut self, lx: &mut Lexer<'_>, t: Token) -> PResult<Stmt> {
        let (u, n) = upper(lx.slice(t));
        let kw = &u[..n];
        if kw == b"M" {
            lx.set_pos(t.start());
            self.words(lx, W_M, "M")?;
            return Ok(Stmt::Misc);
        }
        lx.set_pos(t.end());
        let unsupported = |what| Ok(Stmt::Unsupported { what, number: None });
        match kw {
            b"BEGIN" => {
                self.expect_word(lx, b"PGM", "BEGIN PGM")?;
                Ok(Stmt::BeginPgm {
                    inch: self.program_unit(lx, t.start(), true)?,
                })
            }
            b"END" => {
                self.expect_word(lx, b"PGM", "END PGM")?;
                self.program_unit(lx, t.start(), false)?;
                Ok(Stmt::EndPgm)
            }
            b"BLK" => {
                self.expect_word(lx, b"FORM", "BLK FORM")?;
                self.blk_form(lx)
            }
            b"TOOL" => {
                let w = lx.next_token();
                let (u2, n2) = upper(lx.slice(w));
                match (w.kind, &u2[..n2]) {
                    (TokKind::Ident, b"CALL") => {
                        self.tool = self.tool_call(lx)?;
                        Ok(Stmt::ToolCall)
                    }
                    (TokKind::Ident, b"DEF") => self.tool_def(lx),
                    _ => Err((
                        w.start(),
                        ProgramError::Missing("expected CALL or DEF after TOOL"),
                    )),
                }
            }
            b"L" => {
                self.words(lx, W_AXES | PATH, "L")?;
                Ok(Stmt::Line)
            }
            b"LP" => {
                self.words(lx, W_AXES | W_POLAR | PATH, "LP")?;
                Ok(Stmt::LinePolar)
            }
            b"C" => {
                self.words(lx, W_AXES | W_DR | PATH, "C")?;
                Ok(Stmt::Circle)
            }
            b"CC" => {
                self.words(lx, W_AXES, "CC")?;
                Ok(Stmt::Centre)
            }
            b"CR" => {
                self.words(lx, W_AXES | W_DR | W_RADIUS | PATH, "CR")?;
                Ok(Stmt::CircleRadius)
            }
            b"CT" => {
                self.words(lx, W_AXES | PATH, "CT")?;
                Ok(Stmt::CircleTangent)
            }
            b"CP" => {
                self.words(lx, W_AXES | W_POLAR | W_DR | PATH, "CP")?;
                if let Some(pr) = self.words.pr {
                    return Err((
                        pr.pos as usize,
                        ProgramError::MisplacedWord {
                            word: "PR".into(),
                            block: "CP",
                        },
                    ));
                }
                Ok(Stmt::CirclePolar)
            }
            b"STOP" => {
                self.words(lx, W_M, "STOP")?;
                Ok(Stmt::Stop)
            }
            b"LBL" => Ok(Stmt::Label(self.label_ref(lx, t.start())?)),
            b"FN" => self.function(lx),
            b"Q" | b"QL" | b"QR" => {
                let kind = param_kind(kw).unwrap_or(ParamKind::Q);
                let target = param_index(lx, kind, t.start())?;
                self.assignment(lx, target)
            }
            b"QS" => self.string_assignment(lx, t.start()),
            b"STRING" => self.string_formula(lx),
            b"CALL" => self.call(lx, t.start()),
            b"CYCL" => self.cycl(lx, t.end()),
            b"APPR" => self.approach(lx, true),
            b"DEP" => self.approach(lx, false),
            b"RND" => {
                self.words(lx, W_RADIUS | W_FEED, "RND")?;
                if self.words.radius.is_none() {
                    return Err((t.start(), ProgramError::Missing("RND needs the radius R")));
                }
                Ok(Stmt::Round)
            }
            b"CHF" => self.chamfer(lx, t.start()),
            b"SPL" => self.spline(lx),
            b"CTP" => {
                self.words(lx, W_AXES | W_POLAR | PATH, "CTP")?;
                Ok(Stmt::CircleTangentPolar)
            }
            b"FPOL" => self.fk_block(lx, crate::tnc::fk_words::FkKind::Pole),
            b"FL" => self.fk_block(lx, crate::tnc::fk_words::FkKind::Line),
            b"FLT" => self.fk_block(lx, crate::tnc::fk_words::FkKind::LineTangent),
            b"FC" => self.fk_block(lx, crate::tnc::fk_words::FkKind::Arc),
            b"FCT" => self.fk_block(lx, crate::tnc::fk_words::FkKind::ArcTangent),
            b"FSELECT" => self.fk_block(lx, crate::tnc::fk_words::FkKind::Select),
            b"FK" => unsupported("FK free contour programming"),
            b"PLANE" => super::plane::parse_plane(self, lx, t.start()),
            b"FUNCTION" => super::tcpm::parse_function(lx),
            b"TCH" => self.tch_probe(lx, t.end()),
            b"DECLARE" => self.declare(lx),
            b"SEL" => unsupported("SEL"),
            b"PATTERN" => self.pattern_def(lx.text(), t.end()),
            b"LN" => unsupported("LN"),
            b"TRANS" => unsupported("TRANS"),
            b"SYSCALL" => unsupported("SYSCALL"),
            b"K" if lx.byte_at(t.end()).is_some_and(|b| b.is_ascii_digit()) => Err((
                t.start(),
                ProgramError::Unexpected(
                    "spline coefficients outside an SPL block (a line of K3/K2/K1 words continues \
                     the SPL block right before it)"
                        .into(),
                ),
            )),
            _ => Err((t.start(), ProgramError::UnknownBlock(text_of(lx.slice(t))))),
        }
    }

    fn expect_word(&self, lx: &mut Lexer<'_>, word: &[u8], what: &'static str) -> PResult<()> {
        let t = lx.next_token();
        if t.kind == TokKind::Ident && lx.slice(t).eq_ignore_ascii_case(word) {
            Ok(())
        } else {
            Err((t.start(), ProgramError::Missing(what_expected(what))))
        }
    }

    /// Reads `name MM|INCH` after BEGIN/END PGM; returns true for INCH. The name's byte range
    /// goes to [`Parser::program_name`].
    fn program_unit(&mut self, lx: &mut Lexer<'_>, at: usize, strict: bool) -> PResult<bool> {
        let mut count = 0usize;
        let mut last: Option<Token> = None;
        let mut first = None;
        let mut before_last = None;
        loop {
            let t = lx.next_token();
            if t.kind == TokKind::End {
                break;
            }
            count += 1;
            first.get_or_insert(t.start());
            before_last = last.map(|l| l.end());
            last = Some(t);
        }
        let unit = last.and_then(|t| {
            if t.kind != TokKind::Ident {
                return None;
            }
            let s = lx.slice(t);
            if s.eq_ignore_ascii_case(b"MM") {
                Some(false)
            } else if s.eq_ignore_ascii_case(b"INCH") {
                Some(true)
            } else {
                None
            }
        });
        let name_start = first.unwrap_or(at);
        let name_end = match unit {
            Some(_) => before_last.unwrap_or(name_start),
            None => last.map_or(name_start, |t| t.end()),
        };
        self.program_name = (name_start, name_end.max(name_start));
        match unit {
            Some(inch) if count >= 2 || !strict => Ok(inch),
            Some(_) => Err((at, ProgramError::Missing("BEGIN PGM needs a program name"))),
            None if strict => Err((
                last.map_or(at, |t| t.start()),
                ProgramError::Missing("BEGIN PGM needs the unit MM or INCH after the name"),
            )),
            None => Ok(false),
        }
    }
}

/// Where the block number and keyword of a block in the plain form `[nr ]KEYWORD[ …]` are.
struct PlainPrefix {
    /// First character of the block.
    start: usize,
    /// Block number.
    number: Option<u64>,
    /// Byte range of the upper-case keyword.
    keyword: (usize, usize),
}

/// Recognises the plain block start `  12 L …` (spaces, up to 15 digits, spaces, upper-case
/// letters followed by a blank or the end). Any other start (`N12`, `/`, `*`, `Q1=`, lower
/// case, …) gives `None` and goes through the token path.
fn plain_prefix(text: &[u8]) -> Option<PlainPrefix> {
    let mut i = 0;
    while matches!(text.get(i), Some(b' ' | b'\t')) {
        i += 1;
    }
    let start = i;
    let mut number = None;
    if text.get(i).is_some_and(u8::is_ascii_digit) {
        let mut n: u64 = 0;
        let mut digits = 0;
        while let Some(&c) = text.get(i) {
            if !c.is_ascii_digit() {
                break;
            }
            n = n * 10 + u64::from(c - b'0');
            digits += 1;
            i += 1;
            if digits > 15 {
                return None;
            }
        }
        if !matches!(text.get(i), Some(b' ' | b'\t')) {
            return None;
        }
        number = Some(n);
        while matches!(text.get(i), Some(b' ' | b'\t')) {
            i += 1;
        }
    }
    let ks = i;
    while text.get(i).is_some_and(u8::is_ascii_uppercase) {
        i += 1;
    }
    if i == ks || !matches!(text.get(i), None | Some(b' ' | b'\t' | b'\r' | b'\n')) {
        return None;
    }
    Some(PlainPrefix {
        start,
        number,
        keyword: (ks, i),
    })
}

/// The first `{…}` field of a text template in a block that failed to parse (Python-style
/// `{0:+d}`, `{1:s}`, `{name}`), with its byte position.
fn template_placeholder(text: &[u8]) -> Option<(usize, String)> {
    let open = text.iter().position(|&b| b == b'{')?;
    let len = text
        .get(open + 1..)?
        .iter()
        .take(40)
        .position(|&b| b == b'}')?;
    let inner = text.get(open + 1..open + 1 + len)?;
    let plausible = inner
        .iter()
        .all(|&b| b.is_ascii_alphanumeric() || b"_:+-.<>^=,#%".contains(&b));
    plausible.then(|| {
        let field = text
            .get(open..open + len + 2)
            .unwrap_or(&[])
            .iter()
            .map(|&b| char::from(b))
            .collect();
        (open, field)
    })
}

/// True when the block's keyword is BEGIN (`[nr] BEGIN …`), also when the rest of the block
/// is wrong: text before BEGIN PGM is passed over, a broken BEGIN PGM is not.
pub(crate) fn is_begin_block(text: &[u8]) -> bool {
    let mut i = 0;
    while text.get(i).is_some_and(|b| b.is_ascii_whitespace()) {
        i += 1;
    }
    while text.get(i).is_some_and(u8::is_ascii_digit) {
        i += 1;
    }
    while text.get(i).is_some_and(|b| b.is_ascii_whitespace()) {
        i += 1;
    }
    text.get(i..i + 5)
        .is_some_and(|w| w.eq_ignore_ascii_case(b"BEGIN"))
}

/// True when the block is only a comment (`[/][N]nr ; text`), which may run over several
/// `~`-continued lines.
fn is_comment_block(text: &[u8]) -> bool {
    let mut i = 0;
    let skip_ws = |i: &mut usize| {
        while text.get(*i).is_some_and(|b| b.is_ascii_whitespace()) {
            *i += 1;
        }
    };
    skip_ws(&mut i);
    if text.get(i) == Some(&b'/') {
        i += 1;
        skip_ws(&mut i);
    }
    if text.get(i).is_some_and(|b| b.eq_ignore_ascii_case(&b'N')) {
        i += 1;
    }
    while text.get(i).is_some_and(u8::is_ascii_digit) {
        i += 1;
    }
    skip_ws(&mut i);
    text.get(i) == Some(&b';')
}

fn what_expected(what: &'static str) -> &'static str {
    match what {
        "BEGIN PGM" => "expected PGM after BEGIN",
        "END PGM" => "expected PGM after END",
        "BLK FORM" => "expected FORM after BLK",
        _ => "unexpected word",
    }
}

pub(super) fn set_once(slot: &mut Option<Value>, v: Value, name: &str, at: usize) -> PResult<()> {
    if slot.is_some() {
        return Err((at, ProgramError::DuplicateWord(name.into())));
    }
    *slot = Some(v);
    Ok(())
}
