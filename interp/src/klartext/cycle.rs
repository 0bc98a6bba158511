//! Parsing of cycle blocks: `CYCL DEF`, `CYCL CALL` and `PATTERN DEF`.
//!
//! Cycles are keyed on their number only; the name after the number depends on the language
//! the program was written in (`7.0 NULLPUNKT`, `7.0 DATUM SHIFT`, `7.0 PONTO ZERO`) and is
//! skipped. Two formats exist:
//!
//! - old format: a head block `CYCL DEF n.0 NAME` and sub-blocks `CYCL DEF n.1 …`,
//!   `n.2 …`, each a block of its own. A sub-block holds words with values
//!   (`X+10`, `ROT+45`, `SCL 0.5`, `TIEFE-20`, `V.ZEIT 1.5`, `HSC-MODE:0`), words without a
//!   value (`8.1 X Y`), plain values and datum table rows (`7.1 #5`). The words are kept
//!   as [`OldItem`]s and interpreted by the executor per cycle;
//! - current format: `CYCL DEF n NAME` followed (on `~` continuation lines) by
//!   `Qnnn=value ;comment` assignments. A value is a number, a signed parameter
//!   (`+Q99`, `-Q5`, `QL3`), or one of the words `AUTO`/`FAUTO` (the feed of TOOL CALL),
//!   `MAX`/`FMAX` (rapid traverse, entered as 99999 on the control) or `PREDEF` (the
//!   value of a global default, which this interpreter does not have: the parameter counts
//!   as not given).
//!
//! Decimal commas and empty words of old exports are accepted.

use super::lexer::scan_number;
use super::parser::{PResult, Parser, Stmt, W_AXES, W_FEED, W_M, describe, upper};
use crate::diag::ProgramError;
use crate::tnc::cycle_words::*;
use crate::tnc::expr::{ParamKind, ParamRef, Value};

/// Upper-case letter or one of the characters that may continue a word (`V.ZEIT`,
/// `HSC-MODE`) when a letter follows.
fn word_byte(text: &[u8], i: usize) -> bool {
    match text.get(i) {
        Some(c) if c.is_ascii_alphabetic() || *c == b'_' => true,
        Some(b'.' | b'-') => {
            text.get(i + 1).is_some_and(u8::is_ascii_alphabetic)
                && !matches!(param_at(text, &mut (i + 1)), Ok(Some(_)))
        }
        _ => false,
    }
}

fn skip_blanks(text: &[u8], i: &mut usize) {
    while matches!(text.get(*i), Some(b' ' | b'\t' | b'\r' | b'\n' | b'~')) {
        *i += 1;
    }
}

/// Reads `[Q|QL|QR]n` at `i` (after any sign); returns the parameter and moves `i` past it.
fn param_at(text: &[u8], i: &mut usize) -> PResult<Option<ParamRef>> {
    let start = *i;
    if !text
        .get(start)
        .is_some_and(|c| c.eq_ignore_ascii_case(&b'Q'))
    {
        return Ok(None);
    }
    let mut j = start + 1;
    let kind = match text.get(j).map(u8::to_ascii_uppercase) {
        Some(b'L') => {
            j += 1;
            ParamKind::QL
        }
        Some(b'R') => {
            j += 1;
            ParamKind::QR
        }
        _ => ParamKind::Q,
    };
    if !text.get(j).is_some_and(u8::is_ascii_digit) {
        return Ok(None);
    }
    let (n, end) = scan_number(text, j);
    if n.fract() != 0.0 || n > f64::from(crate::tnc::expr::MAX_PARAM) {
        return Err((
            start,
            ProgramError::OutOfRange(format!("parameter number {n} is not a whole number")),
        ));
    }
    *i = end;
    Ok(Some(ParamRef {
        kind,
        index: n as u32,
    }))
}

/// Reads an optional value at `i`: signs (blanks allowed between sign and number, as in
/// `X + 0`), then a number or a parameter. Returns the value, or the sign alone when no
/// number follows it.
fn value_at(text: &[u8], i: &mut usize) -> PResult<(Option<Value>, Option<bool>)> {
    let mut j = *i;
    skip_blanks(text, &mut j);
    let mut neg = false;
    let mut signed = false;
    while let Some(&c @ (b'+' | b'-')) = text.get(j) {
        signed = true;
        if c == b'-' {
            neg = !neg;
        }
        j += 1;
        skip_blanks(text, &mut j);
    }
    if let Some(param) = param_at(text, &mut j)? {
        *i = j;
        return Ok((Some(Value::Param { param, negate: neg }), None));
    }
    let digit = |k: usize| text.get(k).is_some_and(u8::is_ascii_digit);
    if digit(j) || (text.get(j) == Some(&b'.') && digit(j + 1)) {
        let (v, end) = if text.get(j) == Some(&b'.') {
            let (f, e) = scan_number(text, j + 1);
            let digits = e - (j + 1);
            (f / 10f64.powi(digits as i32), e)
        } else {
            scan_number(text, j)
        };
        *i = end;
        return Ok((Some(Value::Num(if neg { -v } else { v })), None));
    }
    if signed {
        *i = j;
        return Ok((None, Some(neg)));
    }
    Ok((None, None))
}

/// The text of the block up to a `;` comment (old sub-blocks are one line).
fn code_end(text: &[u8], from: usize) -> usize {
    let mut i = from;
    while let Some(&c) = text.get(i) {
        if c == b';' {
            return i;
        }
        i += 1;
    }
    i
}

/// Splits an old-format sub-block into items.
pub(super) fn old_items(text: &[u8], from: usize, out: &mut Vec<OldItem>) -> PResult<()> {
    out.clear();
    let end = code_end(text, from);
    let body = text.get(..end).unwrap_or(text);
    let mut i = from;
    loop {
        skip_blanks(body, &mut i);
        let Some(&c) = body.get(i) else {
            return Ok(());
        };
        let start = i;
        let mut item = OldItem {
            word: [0; OLD_WORD_LEN],
            len: 0,
            value: None,
            sign_only: None,
            pos: start as u32,
        };
        if c == b'#' {
            item.word[0] = b'#';
            item.len = 1;
            i += 1;
        } else if c.is_ascii_alphabetic() && param_at(body, &mut i.clone())?.is_none() {
            let ws = i;
            while word_byte(body, i) {
                // `FQ5`: a parameter directly after a word
                if i > ws && param_at(body, &mut i.clone())?.is_some() {
                    break;
                }
                i += 1;
            }
            let (u, n) = upper(body.get(ws..i).unwrap_or(&[]));
            let n = n.min(OLD_WORD_LEN);
            item.word[..n].copy_from_slice(&u[..n]);
            item.len = n as u8;
            if body.get(i) == Some(&b':') {
                i += 1;
            }
        } else if matches!(c, b'/' | b':' | b',' | b'(' | b')') {
            i += 1;
            continue;
        }
        let (v, sign) = value_at(body, &mut i)?;
        item.value = v;
        item.sign_only = sign;
        if item.len == 0 && v.is_none() && sign.is_none() {
            return Err((
                start,
                ProgramError::Unexpected(format!("character '{}'", char::from(c))),
            ));
        }
        out.push(item);
    }
}

/// Reads the `Qn=value` assignments of a current-format definition (after the name).
pub(crate) fn q_entries(text: &[u8], from: usize, out: &mut Vec<QEntry>) -> PResult<()> {
    out.clear();
    let mut i = from;
    // skip the cycle name: everything up to the first `Qn` followed by `=`
    while i < text.len() {
        let c = text.get(i).copied().unwrap_or(0);
        if c == b';' {
            while text.get(i).is_some_and(|&b| b != b'\n') {
                i += 1;
            }
            continue;
        }
        let word_start = i == 0 || !text.get(i - 1).is_some_and(u8::is_ascii_alphanumeric);
        if word_start && c.eq_ignore_ascii_case(&b'Q') {
            let at = i;
            let mut j = i;
            if let Some(p) = param_at(text, &mut j)? {
                skip_blanks(text, &mut j);
                if text.get(j) == Some(&b'=') && p.kind == ParamKind::Q {
                    j += 1;
                    let value = q_value(text, &mut j, p.index, at)?;
                    out.push(QEntry {
                        q: p.index,
                        value,
                        pos: at as u32,
                    });
                    i = j;
                    continue;
                }
                if !out.is_empty() {
                    return Err((at, ProgramError::MissingValue(format!("Q{}", p.index))));
                }
            }
        } else if !out.is_empty() && !matches!(c, b' ' | b'\t' | b'\r' | b'\n' | b'~') {
            return Err((
                i,
                ProgramError::Unexpected(format!(
                    "character '{}' in cycle parameters",
                    char::from(c)
                )),
            ));
        }
        i += 1;
    }
    Ok(())
}

/// The value after `Qn=`.
fn q_value(text: &[u8], j: &mut usize, q: u32, at: usize) -> PResult<CycleValue> {
    skip_blanks(text, j);
    let ws = *j;
    let mut k = ws;
    while text.get(k).is_some_and(u8::is_ascii_alphabetic) {
        k += 1;
    }
    let (u, n) = upper(text.get(ws..k).unwrap_or(&[]));
    let word = match &u[..n] {
        b"AUTO" | b"FAUTO" => Some(CycleValue::Auto),
        b"MAX" | b"FMAX" => Some(CycleValue::Max),
        b"PREDEF" => Some(CycleValue::Predef),
        _ => None,
    };
    if let Some(w) = word {
        *j = k;
        return Ok(w);
    }
    match value_at(text, j)? {
        (Some(v), _) => Ok(CycleValue::Val(v)),
        _ => Err((at, ProgramError::MissingValue(format!("Q{q}=")))),
    }
}

/// The number after `CYCL DEF`: (number, sub-block) with `sub` for the old `n.s` form.
pub(super) fn cycle_number(text: &[u8], i: &mut usize) -> PResult<(u32, Option<u8>)> {
    skip_blanks(text, i);
    let start = *i;
    let mut n: u64 = 0;
    while let Some(&c) = text.get(*i) {
        if !c.is_ascii_digit() {
            break;
        }
        n = n.saturating_mul(10).saturating_add(u64::from(c - b'0'));
        *i += 1;
    }
    if *i == start {
        return Err((
            start,
            ProgramError::Missing("CYCL DEF needs a cycle number"),
        ));
    }
    let number = u32::try_from(n).map_err(|_| {
        (
            start,
            ProgramError::OutOfRange(format!("cycle number {n} is too large")),
        )
    })?;
    // `7.1`, `7,1`, and `7 .1` with a blank before the point (hyperMILL writes `DEF9 .0`)
    let mut p = *i;
    while matches!(text.get(p), Some(b' ' | b'\t')) {
        p += 1;
    }
    let point = match text.get(p) {
        Some(b'.') => true,
        Some(b',') => p == *i,
        _ => false,
    };
    if point && text.get(p + 1).is_some_and(u8::is_ascii_digit) {
        *i = p + 1;
        let s0 = *i;
        let mut s: u32 = 0;
        while let Some(&c) = text.get(*i) {
            if !c.is_ascii_digit() {
                break;
            }
            s = s.saturating_mul(10).saturating_add(u32::from(c - b'0'));
            *i += 1;
        }
        let sub = u8::try_from(s).map_err(|_| {
            (
                s0,
                ProgramError::OutOfRange(format!("sub-block {number}.{s} is too large")),
            )
        })?;
        return Ok((number, Some(sub)));
    }
    Ok((number, None))
}

/// Skips a keyword (case-insensitive) at `i` when it is there, also when a digit follows it
/// directly (`DEF9`).
fn keyword_before_number(text: &[u8], i: &mut usize, word: &[u8]) -> bool {
    skip_word(text, i, word, |c| c.is_ascii_alphabetic() || c == b'_')
}

/// Skips a keyword (case-insensitive) at `i` when it is there.
pub(super) fn keyword(text: &[u8], i: &mut usize, word: &[u8]) -> bool {
    skip_word(text, i, word, |c| c.is_ascii_alphanumeric())
}

/// Skips `word` (case-insensitive, after blanks) at `i` when it is there and the byte after it
/// does not continue it (`continues`).
fn skip_word(text: &[u8], i: &mut usize, word: &[u8], continues: impl Fn(u8) -> bool) -> bool {
    let mut j = *i;
    skip_blanks(text, &mut j);
    let end = j + word.len();
    let hit = text
        .get(j..end)
        .is_some_and(|s| s.eq_ignore_ascii_case(word))
        && !text.get(end).is_some_and(|c| continues(*c));
    if hit {
        *i = end;
    }
    hit
}

impl Parser {
    /// `CYCL DEF …` / `CYCL CALL …`; `after` is the byte after the keyword `CYCL`.
    pub(super) fn cycl(&mut self, lx: &mut super::lexer::Lexer<'_>, after: usize) -> PResult<Stmt> {
        let text = lx.text();
        let mut i = after;
        // `DEF9` (no blank before the number) is how some posts write it
        if keyword_before_number(text, &mut i, b"DEF") {
            let (number, sub) = cycle_number(text, &mut i)?;
            self.cycle.items.clear();
            self.cycle.q.clear();
            match sub {
                Some(0) => {}
                Some(_) => old_items(text, i, &mut self.cycle.items)?,
                None => q_entries(text, i, &mut self.cycle.q)?,
            }
            return Ok(Stmt::CycleDef { number, sub });
        }
        if keyword(text, &mut i, b"CALL") {
            let kind = if keyword(text, &mut i, b"POS") {
                CallKind::Pos
            } else if keyword(text, &mut i, b"PAT") {
                CallKind::Pat
            } else {
                CallKind::Here
            };
            lx.set_pos(i);
            let allowed = match kind {
                CallKind::Pos => W_AXES | W_FEED | W_M,
                CallKind::Pat => W_FEED | W_M,
                CallKind::Here => W_M,
            };
            self.words(lx, allowed, "CYCL CALL")?;
            return Ok(Stmt::CycleCall { kind });
        }
        lx.set_pos(after);
        let t = lx.peek();
        Err((
            t.start(),
            ProgramError::Unexpected(format!(
                "{} after CYCL (expected DEF or CALL)",
                describe(lx, t)
            )),
        ))
    }

    /// `PATTERN DEF` with its elements `POS1 (X.. Y.. Z..)`, `ROW1 (…)`, … ; `after` is the
    /// byte after the keyword `PATTERN`.
    pub(super) fn pattern_def(&mut self, text: &[u8], after: usize) -> PResult<Stmt> {
        let mut i = after;
        if !keyword(text, &mut i, b"DEF") {
            return Err((after, ProgramError::Missing("expected DEF after PATTERN")));
        }
        self.cycle.pattern.clear();
        loop {
            skip_blanks(text, &mut i);
            let Some(&c) = text.get(i) else { break };
            if c == b';' {
                while text.get(i).is_some_and(|&b| b != b'\n') {
                    i += 1;
                }
                continue;
            }
            let start = i;
            while text.get(i).is_some_and(u8::is_ascii_alphabetic) {
                i += 1;
            }
            let (u, n) = upper(text.get(start..i).unwrap_or(&[]));
            let kind = match &u[..n] {
                b"POS" => PatternKind::Pos,
                b"ROW" => PatternKind::Row,
                b"PAT" => PatternKind::Pat,
                b"FRAME" => PatternKind::Frame,
                b"CIRC" => PatternKind::Circ,
                b"PITCHCIRC" => PatternKind::PitchCirc,
                _ => {
                    return Err((
                        start,
                        ProgramError::Unexpected(format!(
                            "'{}' in PATTERN DEF (POS, ROW, PAT, FRAME, CIRC or PITCHCIRC)",
                            String::from_utf8_lossy(
                                text.get(start..i.max(start + 1)).unwrap_or(&[])
                            )
                        )),
                    ));
                }
            };
            while text.get(i).is_some_and(u8::is_ascii_digit) {
                i += 1;
            }
            skip_blanks(text, &mut i);
            if text.get(i) != Some(&b'(') {
                return Err((
                    i,
                    ProgramError::Missing("expected ( after the pattern element"),
                ));
            }
            i += 1;
            let mut item = PatternItem {
                kind,
                words: [([0; 8], 0, Value::Num(0.0)); PATTERN_WORDS],
                count: 0,
                pos: start as u32,
            };
            loop {
                skip_blanks(text, &mut i);
                match text.get(i) {
                    Some(b')') => {
                        i += 1;
                        break;
                    }
                    None => {
                        return Err((start, ProgramError::Missing("missing ) in PATTERN DEF")));
                    }
                    _ => {}
                }
                let ws = i;
                while text.get(i).is_some_and(u8::is_ascii_alphabetic) {
                    if i > ws && param_at(text, &mut i.clone())?.is_some() {
                        break;
                    }
                    i += 1;
                }
                if i == ws {
                    return Err((
                        ws,
                        ProgramError::Unexpected("value without a word in PATTERN DEF".into()),
                    ));
                }
                let (u, n) = upper(text.get(ws..i).unwrap_or(&[]));
                let (v, _) = value_at(text, &mut i)?;
                let Some(v) = v else {
                    return Err((
                        ws,
                        ProgramError::MissingValue(String::from_utf8_lossy(&u[..n]).into()),
                    ));
                };
                let slot = item.words.get_mut(usize::from(item.count)).ok_or((
                    ws,
                    ProgramError::OutOfRange("too many words in a PATTERN DEF element".into()),
                ))?;
                let mut name = [0u8; 8];
                let nn = n.min(8);
                name[..nn].copy_from_slice(&u[..nn]);
                *slot = (name, nn as u8, v);
                item.count += 1;
            }
            self.cycle.pattern.push(item);
        }
        if self.cycle.pattern.is_empty() {
            return Err((after, ProgramError::Missing("PATTERN DEF without elements")));
        }
        Ok(Stmt::PatternDef)
    }
}

#[cfg(test)]
#[path = "cycle_parse_tests.rs"]
mod tests;
