//! Splitting one TNC ISO block into its address words.
//!
//! A block is `[/][N<nr>] word word … *` with an optional `;` comment. A word is an address
//! (one letter, or `DL`/`DR` for tool deltas) followed by a signed number or a signed Q/QL/QR
//! parameter (`X+10`, `H-Q3`, `G01`). `L1,0` (label call with a repeat count) is read as the
//! word `L` with value 1 and a comma count; a D-function operand `P01 +Q5` as the word `P`
//! with count 1 and value Q5. The `%NAME G71 *` header and footer and Q
//! parameter formulas (`Q1 = …`) are recognised here and handed on as such.

use crate::diag::ProgramError;
use crate::tnc::expr::{MAX_PARAM, ParamKind, ParamRef, Value};

/// Most words one block may carry.
pub(crate) const MAX_WORDS: usize = 32;

/// An address letter (or two-letter address) of an ISO word.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Addr {
    /// A single letter `A`..`Z`.
    Letter(u8),
    /// `DL`: tool length delta.
    Dl,
    /// `DR`: tool radius delta.
    Dr,
}

/// One address word.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct IsoWord {
    /// The address.
    pub addr: Addr,
    /// The value.
    pub value: Value,
    /// The number after a comma (`L1,3`), if any.
    pub count: Option<f64>,
    /// An axis letter written without a value (`G28 X Y`: the mirrored axes); `value` is 0.
    pub bare: bool,
    /// Byte position of the word in the block text.
    pub pos: u32,
}

/// What kind of block the text is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum IsoKind {
    /// Nothing to execute (empty line, comment).
    Empty,
    /// `%NAME G70|G71`: program begin or end; true for inch.
    Header {
        /// True for G70 (inch).
        inch: bool,
    },
    /// Address words (in [`IsoBlock::words`]).
    Words,
    /// A `Q… = formula` assignment: the Klartext parser reads it.
    Formula,
    /// `G2nn NAME Q…=… ;comment …`: a cycle definition; the `Q…=` assignments follow
    /// the number from byte `after` on, on this line or on the next lines.
    CycleDef {
        /// The cycle number.
        number: u32,
        /// Byte position just after the number.
        after: usize,
    },
}

/// One parsed ISO block.
#[derive(Debug, Clone)]
pub(crate) struct IsoBlock {
    /// Block number `N…`.
    pub number: Option<u64>,
    /// True when the block starts with `/`.
    pub skip: bool,
    /// Byte position of the first character of the block.
    pub start: usize,
    /// The block kind.
    pub kind: IsoKind,
    /// The words, in the order written.
    pub words: Vec<IsoWord>,
}

impl Default for IsoBlock {
    fn default() -> Self {
        IsoBlock {
            number: None,
            skip: false,
            start: 0,
            kind: IsoKind::Empty,
            words: Vec::with_capacity(MAX_WORDS),
        }
    }
}

/// A syntax error at a byte position.
pub(crate) type SyntaxError = (usize, ProgramError);

fn skip_blank(text: &[u8], i: &mut usize) {
    while text.get(*i).is_some_and(|b| *b == b' ' || *b == b'\t') {
        *i += 1;
    }
}

/// Reads an unsigned decimal number at `i` (digits with an optional `.` part).
fn number(text: &[u8], i: &mut usize) -> Option<f64> {
    let s = *i;
    while text
        .get(*i)
        .is_some_and(|b| b.is_ascii_digit() || *b == b'.')
    {
        *i += 1;
    }
    let raw = text.get(s..*i)?;
    if raw.is_empty() {
        return None;
    }
    std::str::from_utf8(raw).ok()?.parse::<f64>().ok()
}

/// The end of the block's words: the position of the block-ending `*`, or of a `;` comment,
/// or the end of the text.
pub(crate) fn words_end(text: &[u8]) -> usize {
    let end = text.iter().position(|&b| b == b';').unwrap_or(text.len());
    let body = text.get(..end).unwrap_or(&[]);
    match body.iter().rposition(|b| !b.is_ascii_whitespace()) {
        Some(p) if body.get(p) == Some(&b'*') => p,
        _ => end,
    }
}

impl IsoBlock {
    /// Parses one block's text into `self` (reusing the word buffer).
    pub fn parse(&mut self, text: &[u8]) -> Result<(), SyntaxError> {
        self.words.clear();
        self.number = None;
        self.skip = false;
        self.kind = IsoKind::Empty;
        let end = words_end(text);
        let body = text.get(..end).unwrap_or(&[]);
        let mut i = 0;
        skip_blank(body, &mut i);
        self.start = i;
        if body.get(i) == Some(&b'/') {
            self.skip = true;
            i += 1;
            skip_blank(body, &mut i);
        }
        if body.get(i).is_some_and(|b| b.eq_ignore_ascii_case(&b'N'))
            && body.get(i + 1).is_some_and(u8::is_ascii_digit)
        {
            let at = i;
            i += 1;
            let n = number(body, &mut i).unwrap_or(-1.0);
            if n.fract() != 0.0 || !(0.0..1e15).contains(&n) {
                return Err((
                    at,
                    ProgramError::OutOfRange("block number is not a whole number".into()),
                ));
            }
            self.number = Some(n as u64);
            skip_blank(body, &mut i);
        }
        if i >= body.len() {
            return Ok(());
        }
        if body.get(i) == Some(&b'%') {
            return self.header(body, i);
        }
        if is_formula(body, i) {
            self.kind = IsoKind::Formula;
            return Ok(());
        }
        if let Some((number, after)) = cycle_head(body, i) {
            self.kind = IsoKind::CycleDef { number, after };
            return Ok(());
        }
        self.kind = IsoKind::Words;
        while i < body.len() {
            skip_blank(body, &mut i);
            let Some(&c) = body.get(i) else { break };
            if !c.is_ascii_alphabetic() {
                return Err((
                    i,
                    ProgramError::Unexpected(format!("character '{}'", char::from(c))),
                ));
            }
            let at = i;
            let up = c.to_ascii_uppercase();
            i += 1;
            let next = body.get(i).map(u8::to_ascii_uppercase);
            let addr = match (up, next) {
                (b'D', Some(b'L')) => {
                    i += 1;
                    Addr::Dl
                }
                (b'D', Some(b'R')) => {
                    i += 1;
                    Addr::Dr
                }
                _ => Addr::Letter(up),
            };
            if body.get(i).is_some_and(u8::is_ascii_alphabetic)
                && !body.get(i).is_some_and(|b| b.eq_ignore_ascii_case(&b'Q'))
            {
                let name: String = body
                    .get(at..)
                    .unwrap_or(&[])
                    .iter()
                    .take_while(|b| b.is_ascii_alphanumeric())
                    .map(|&b| char::from(b))
                    .collect();
                return Err((
                    at,
                    ProgramError::UnknownWord {
                        word: name,
                        block: "ISO",
                    },
                ));
            }
            if addr == Addr::Letter(b'P') {
                // D-function operand `P01 +Q5`: the operand number, then its value
                let index = number(body, &mut i)
                    .ok_or((at, ProgramError::MissingValue("P (operand number)".into())))?;
                skip_blank(body, &mut i);
                let value = signed_value(body, &mut i, at)?;
                self.push(IsoWord {
                    addr,
                    value,
                    count: Some(index),
                    bare: false,
                    pos: at as u32,
                })?;
                continue;
            }
            let bare = matches!(addr, Addr::Letter(b'X' | b'Y' | b'Z' | b'U' | b'V' | b'W'))
                && body
                    .get(i)
                    .is_none_or(|b| *b == b' ' || *b == b'\t' || *b == b'\r' || *b == b'\n');
            if bare {
                self.push(IsoWord {
                    addr,
                    value: Value::Num(0.0),
                    count: None,
                    bare: true,
                    pos: at as u32,
                })?;
                continue;
            }
            let value = signed_value(body, &mut i, at)?;
            let mut count = None;
            if body.get(i) == Some(&b',') {
                i += 1;
                count = Some(number(body, &mut i).ok_or((
                    i,
                    ProgramError::MissingValue("the repeat count after ','".into()),
                ))?);
            }
            self.push(IsoWord {
                addr,
                value,
                count,
                bare: false,
                pos: at as u32,
            })?;
        }
        Ok(())
    }

    fn push(&mut self, w: IsoWord) -> Result<(), SyntaxError> {
        if self.words.len() >= MAX_WORDS {
            return Err((
                w.pos as usize,
                ProgramError::OutOfRange(format!("more than {MAX_WORDS} words in one block")),
            ));
        }
        self.words.push(w);
        Ok(())
    }

    fn header(&mut self, body: &[u8], at: usize) -> Result<(), SyntaxError> {
        let rest: String = body
            .get(at + 1..)
            .unwrap_or(&[])
            .iter()
            .map(|&b| char::from(b))
            .collect();
        let mut parts = rest.split_whitespace();
        let _name = parts.next().ok_or((
            at,
            ProgramError::Missing("a `%` block needs the program name"),
        ))?;
        let unit = parts.next().map(str::to_ascii_uppercase);
        let inch = match unit.as_deref() {
            Some("G70") => true,
            Some("G71") => false,
            _ => {
                return Err((
                    at,
                    ProgramError::Missing("a `%NAME` block needs the unit G71 (mm) or G70 (inch)"),
                ));
            }
        };
        self.kind = IsoKind::Header { inch };
        Ok(())
    }
}

/// `G<n>` with n ≥ 200 at `i`, followed by a blank, a name or the end: the head of a cycle
/// definition. Returns the number and the position after it.
fn cycle_head(body: &[u8], i: usize) -> Option<(u32, usize)> {
    if !body.get(i)?.eq_ignore_ascii_case(&b'G') {
        return None;
    }
    let mut j = i + 1;
    let mut n: u32 = 0;
    while let Some(d) = body.get(j).filter(|b| b.is_ascii_digit()) {
        n = n.checked_mul(10)?.checked_add(u32::from(d - b'0'))?;
        j += 1;
    }
    let ends = body
        .get(j)
        .is_none_or(|b| b.is_ascii_whitespace() || b.is_ascii_alphabetic());
    (j > i + 1 && n >= 200 && ends).then_some((n, j))
}

/// True when the text at `i` reads `Q…n =` / `QL…n =` / `QR…n =`.
fn is_formula(body: &[u8], mut i: usize) -> bool {
    if !body.get(i).is_some_and(|b| b.eq_ignore_ascii_case(&b'Q')) {
        return false;
    }
    i += 1;
    if body
        .get(i)
        .is_some_and(|b| b.eq_ignore_ascii_case(&b'L') || b.eq_ignore_ascii_case(&b'R'))
    {
        i += 1;
    }
    let digits = i;
    while body.get(i).is_some_and(u8::is_ascii_digit) {
        i += 1;
    }
    if i == digits {
        return false;
    }
    skip_blank(body, &mut i);
    body.get(i) == Some(&b'=')
}

/// Reads `[+|-](number | Q n | QL n | QR n)` after an address at `at`.
fn signed_value(body: &[u8], i: &mut usize, at: usize) -> Result<Value, SyntaxError> {
    let mut neg = false;
    while let Some(&c) = body.get(*i) {
        match c {
            b'+' => {}
            b'-' => neg = !neg,
            _ => break,
        }
        *i += 1;
    }
    let missing = |end: usize| {
        let word: String = body
            .get(at..end)
            .unwrap_or(&[])
            .iter()
            .map(|&b| char::from(b))
            .collect();
        (at, ProgramError::MissingValue(word))
    };
    match body.get(*i) {
        Some(b) if b.is_ascii_digit() || *b == b'.' => {
            let v = number(body, i).ok_or_else(|| missing(*i))?;
            Ok(Value::Num(if neg { -v } else { v }))
        }
        Some(b) if b.eq_ignore_ascii_case(&b'Q') => {
            *i += 1;
            let kind = match body.get(*i).map(u8::to_ascii_uppercase) {
                Some(b'L') => {
                    *i += 1;
                    ParamKind::QL
                }
                Some(b'R') => {
                    *i += 1;
                    ParamKind::QR
                }
                _ => ParamKind::Q,
            };
            let p = *i;
            let n = number(body, i).ok_or_else(|| missing(*i))?;
            if n.fract() != 0.0 || n > f64::from(MAX_PARAM) {
                return Err((
                    p,
                    ProgramError::OutOfRange(format!(
                        "parameter number {n} is not an integer from 0 to {MAX_PARAM}"
                    )),
                ));
            }
            Ok(Value::Param {
                param: ParamRef {
                    kind,
                    index: n as u32,
                },
                negate: neg,
            })
        }
        _ => Err(missing(*i)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> IsoBlock {
        let mut b = IsoBlock::default();
        b.parse(text.as_bytes()).unwrap();
        b
    }

    #[test]
    fn words_numbers_and_parameters() {
        let b = parse("N20 G01 X+10.5 Y-Q3 F200 M03 * ; comment");
        assert_eq!(b.number, Some(20));
        assert_eq!(b.kind, IsoKind::Words);
        let addrs: Vec<Addr> = b.words.iter().map(|w| w.addr).collect();
        assert_eq!(
            addrs,
            [b'G', b'X', b'Y', b'F', b'M'].map(Addr::Letter).to_vec()
        );
        assert_eq!(b.words[1].value, Value::Num(10.5));
        assert_eq!(
            b.words[2].value,
            Value::Param {
                param: ParamRef {
                    kind: ParamKind::Q,
                    index: 3
                },
                negate: true
            }
        );
        assert_eq!(b.words[1].pos, 8);
    }

    #[test]
    fn header_call_count_and_formula() {
        assert_eq!(parse("%PART G71 *").kind, IsoKind::Header { inch: false });
        assert_eq!(
            parse("N9999 %PART G70 *").kind,
            IsoKind::Header { inch: true }
        );
        let b = parse("N50 L1,2 *");
        assert_eq!(b.words[0].count, Some(2.0));
        assert_eq!(parse("N60 Q1 = Q2 * 3 *").kind, IsoKind::Formula);
        assert_eq!(parse("N61 T1 G17 S100 DR-0.5 *").words[3].addr, Addr::Dr);
    }

    #[test]
    fn cycle_definition_heads() {
        assert_eq!(
            parse("N70 G200 BOHREN").kind,
            IsoKind::CycleDef {
                number: 200,
                after: 8
            }
        );
        assert_eq!(
            parse("G221 Q225=+10 *").kind,
            IsoKind::CycleDef {
                number: 221,
                after: 4
            }
        );
        // below 200 and G words further on are ordinary words
        assert_eq!(parse("N10 G01 X+5 *").kind, IsoKind::Words);
        assert_eq!(parse("N10 G79 M99 *").kind, IsoKind::Words);
        assert_eq!(parse("N10 X+1 G200 *").kind, IsoKind::Words);
    }

    #[test]
    fn bad_words_are_located() {
        let mut b = IsoBlock::default();
        // an axis without a value is kept as a bare word (G28 X Y); the executor refuses
        // it elsewhere
        b.parse(b"N10 G28 X Y *").unwrap();
        assert!(b.words[1].bare && b.words[2].bare && !b.words[0].bare);
        assert_eq!(b.words[1].pos, 8);
        let e = b.parse(b"N10 G01 F *").unwrap_err();
        assert_eq!(e.0, 8);
        let e = b.parse(b"N10 G01 XX5 *").unwrap_err();
        assert_eq!(e.0, 8);
        assert!(b.parse(b"%PART *").is_err());
        assert!(b.parse(b"N10 G01 #5 *").is_err());
    }
}
