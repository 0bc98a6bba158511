//! Klartext lexer: a hand-written byte scanner over one block's text.
//!
//! Tokens borrow nothing and allocate nothing: identifiers are byte ranges into the block,
//! numbers are converted on the spot. Whitespace (also inside words, `L Z + Q13`) separates
//! tokens and is otherwise ignored; `;` starts a comment that runs to the end of the physical
//! line, or further when the line ends in `~` (the block reader keeps a `~` that ends a comment:
//! the comment goes on over the next line; a `~` elsewhere in a comment is text). Numbers accept `.` or `,` as decimal separator (old exports write `X+49,000`).

/// What a token is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TokKind {
    /// A run of ASCII letters (and `_`), as the byte range `start..end` of the block text.
    Ident,
    /// An unsigned number; its value comes from [`Lexer::num`].
    Num,
    /// `+`
    Plus,
    /// `-`
    Minus,
    /// `*`
    Star,
    /// `/`
    Slash,
    /// `^`
    Caret,
    /// `%`
    Percent,
    /// `(`
    LParen,
    /// `)`
    RParen,
    /// `:`
    Colon,
    /// `=`
    Eq,
    /// A double-quoted string; the range excludes the quotes.
    Str,
    /// A `{...}` template placeholder.
    Placeholder,
    /// Any other byte (see [`Token::byte`]).
    Other,
    /// End of the block.
    End,
}

/// One token with its byte range in the block text (small enough to travel in registers).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Token {
    /// Kind.
    pub kind: TokKind,
    /// The byte itself for [`TokKind::Other`].
    pub byte: u8,
    /// First byte.
    start: u32,
    /// One past the last byte (for `Str`: of the contents).
    end: u32,
}

impl Token {
    /// A token of `kind` over `start..end`.
    pub fn new(kind: TokKind, start: usize, end: usize) -> Token {
        Token {
            kind,
            byte: 0,
            start: start as u32,
            end: end as u32,
        }
    }

    /// First byte of the token in the block text.
    pub fn start(self) -> usize {
        self.start as usize
    }

    /// One past the last byte.
    pub fn end(self) -> usize {
        self.end as usize
    }
}

/// Scanner over one block.
pub(crate) struct Lexer<'a> {
    text: &'a [u8],
    pos: usize,
    peeked: Option<Token>,
}

impl<'a> Lexer<'a> {
    /// Starts scanning `text` at byte `pos`. Blocks longer than 4 GiB are cut there.
    pub fn new(text: &'a [u8], pos: usize) -> Self {
        let text = text
            .get(..text.len().min(u32::MAX as usize))
            .unwrap_or(text);
        Lexer {
            text,
            pos,
            peeked: None,
        }
    }

    /// The bytes of a token.
    pub fn slice(&self, t: Token) -> &'a [u8] {
        self.text.get(t.start()..t.end()).unwrap_or(&[])
    }

    /// The whole block text.
    pub fn text(&self) -> &'a [u8] {
        self.text
    }

    /// Bytes `start..end` of the block text.
    pub fn slice_range(&self, start: usize, end: usize) -> &'a [u8] {
        self.text.get(start..end).unwrap_or(&[])
    }

    /// The value of a [`TokKind::Num`] token.
    pub fn num(&self, t: Token) -> f64 {
        scan_number(self.text, t.start()).0
    }

    /// The next token without consuming it.
    pub fn peek(&mut self) -> Token {
        match self.peeked {
            Some(t) => t,
            None => {
                let t = self.scan();
                self.peeked = Some(t);
                t
            }
        }
    }

    /// Consumes and returns the next token.
    pub fn next_token(&mut self) -> Token {
        match self.peeked.take() {
            Some(t) => t,
            None => self.scan(),
        }
    }

    /// Looks at a plain word at the current position without consuming it: up to four
    /// upper-case letters, an optional sign, an optional number or `Q`+digits, ending at a
    /// blank or the end of the block (`X+10`, `IY-Q2`, `F500`, `M8`, `DR+`, `RL`, `FMAX`,
    /// `PA+270`). Returns `None` for anything else, or when a token is peeked. The caller
    /// consumes the word with [`Lexer::set_pos`]`(word.end)` once it has used it.
    #[inline]
    pub fn plain_word(&self) -> Option<PlainWord> {
        if self.peeked.is_some() {
            return None;
        }
        let t = self.text;
        let mut i = self.pos;
        while t.get(i) == Some(&b' ') {
            i += 1;
        }
        let start = i;
        while t.get(i).is_some_and(u8::is_ascii_uppercase) {
            i += 1;
        }
        let mut name_end = i;
        let mut param = false;
        if name_end - start >= 2
            && t.get(name_end - 1) == Some(&b'Q')
            && t.get(name_end).is_some_and(u8::is_ascii_digit)
        {
            // `FQ58`, `XQ3`: the word, then the parameter without a sign
            name_end -= 1;
            param = true;
        }
        if name_end == start || name_end - start > 4 {
            return None;
        }
        let mut sign = 0i8;
        if !param {
            match t.get(i) {
                Some(b'+') => {
                    sign = 1;
                    i += 1;
                }
                Some(b'-') => {
                    sign = -1;
                    i += 1;
                }
                _ => {}
            }
            param = t.get(i) == Some(&b'Q');
            if param {
                i += 1;
            }
        }
        let mut value = None;
        if t.get(i).is_some_and(u8::is_ascii_digit) {
            let (v, end) = scan_number(t, i);
            if param && end != number_end_digits(t, i) {
                return None; // a parameter number with a fraction: the token path reports it
            }
            value = Some(v);
            i = end;
        } else if param {
            return None;
        }
        match t.get(i) {
            None | Some(b' ' | b'\n' | b'\r' | b'\t') => {}
            _ => return None,
        }
        Some(PlainWord {
            start,
            name_end,
            sign,
            value,
            param,
            end: i,
        })
    }

    /// True when nothing but blanks is left and no token is peeked (cheap end-of-block test).
    pub fn at_plain_end(&self) -> bool {
        self.peeked.is_none()
            && self
                .text
                .get(self.pos..)
                .is_none_or(|rest| rest.iter().all(|&b| matches!(b, b' ' | b'\t' | b'\r')))
    }

    /// Continues scanning at byte `pos` (drops a peeked token).
    pub fn set_pos(&mut self, pos: usize) {
        self.peeked = None;
        self.pos = pos;
    }

    /// The byte at `i`, if any.
    pub fn byte_at(&self, i: usize) -> Option<u8> {
        self.text.get(i).copied()
    }

    /// Skips whitespace and comments, returns the position of the next token.
    fn skip_blank(&mut self) {
        while let Some(&b) = self.text.get(self.pos) {
            if b == b';' {
                self.pos = comment_end(self.text, self.pos);
            } else if b.is_ascii_whitespace() || b == 0 {
                self.pos += 1;
            } else {
                break;
            }
        }
    }

    fn scan(&mut self) -> Token {
        self.skip_blank();
        let start = self.pos;
        let Some(&b) = self.text.get(start) else {
            return Token::new(TokKind::End, start, start);
        };
        let single = |kind| (kind, start + 1);
        let (kind, end) = match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'_' => {
                let mut i = start + 1;
                while let Some(&c) = self.text.get(i) {
                    if c.is_ascii_alphabetic() || c == b'_' {
                        i += 1;
                    } else {
                        break;
                    }
                }
                (TokKind::Ident, i)
            }
            b'0'..=b'9' => (TokKind::Num, number_end(self.text, start)),
            b'.' | b',' if self.text.get(start + 1).is_some_and(u8::is_ascii_digit) => {
                (TokKind::Num, number_end(self.text, start))
            }
            b'+' => single(TokKind::Plus),
            b'-' => single(TokKind::Minus),
            b'*' => single(TokKind::Star),
            b'/' => single(TokKind::Slash),
            b'^' => single(TokKind::Caret),
            b'%' => single(TokKind::Percent),
            b'(' => single(TokKind::LParen),
            b')' => single(TokKind::RParen),
            b':' => single(TokKind::Colon),
            b'=' => single(TokKind::Eq),
            b'"' => {
                let mut i = start + 1;
                while let Some(&c) = self.text.get(i) {
                    if c == b'"' || c == b'\n' {
                        break;
                    }
                    i += 1;
                }
                self.pos = (i + 1).min(self.text.len());
                return Token::new(TokKind::Str, start + 1, i);
            }
            b'{' => {
                let mut i = start + 1;
                while let Some(&c) = self.text.get(i) {
                    i += 1;
                    if c == b'}' || c == b'\n' {
                        break;
                    }
                }
                (TokKind::Placeholder, i)
            }
            other => {
                self.pos = start + 1;
                let mut t = Token::new(TokKind::Other, start, start + 1);
                t.byte = other;
                return t;
            }
        };
        self.pos = end;
        Token::new(kind, start, end)
    }
}

/// A word seen by [`Lexer::plain_word`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PlainWord {
    /// First byte of the word (its letters).
    pub start: usize,
    /// One past the last letter.
    pub name_end: usize,
    /// +1, -1, or 0 when no sign is written.
    pub sign: i8,
    /// The number after the sign (the parameter number when `param`).
    pub value: Option<f64>,
    /// True for `Qn`.
    pub param: bool,
    /// One past the word.
    pub end: usize,
}

/// End of the `;` comment that starts at `from`: the end of its physical line, or of a later
/// one while the comment's line ends in `~` (its last non-blank byte).
pub(crate) fn comment_end(text: &[u8], from: usize) -> usize {
    let mut i = from;
    loop {
        let rest = text.get(i..).unwrap_or(&[]);
        let line_end = rest
            .iter()
            .position(|&b| b == b'\n')
            .map_or(text.len(), |p| i + p);
        let wrapped = text
            .get(i..line_end)
            .and_then(|l| l.iter().rev().find(|b| !b.is_ascii_whitespace()))
            == Some(&b'~');
        if !wrapped || line_end >= text.len() {
            return line_end;
        }
        i = line_end + 1;
    }
}

/// End of the run of digits at `start`.
fn number_end_digits(text: &[u8], start: usize) -> usize {
    let mut i = start;
    while text.get(i).is_some_and(u8::is_ascii_digit) {
        i += 1;
    }
    i
}

/// End of the number starting at `start`: the same extent [`scan_number`] reads.
fn number_end(text: &[u8], start: usize) -> usize {
    let mut i = start;
    let mut seen_point = false;
    while let Some(&c) = text.get(i) {
        if c.is_ascii_digit() {
            i += 1;
        } else if (c == b'.' || (c == b',' && text.get(i + 1).is_some_and(u8::is_ascii_digit)))
            && !seen_point
        {
            seen_point = true;
            i += 1;
        } else {
            break;
        }
    }
    i
}

/// Powers of ten exactly representable as f64.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Scans an unsigned decimal number starting at `start` (digits, optional `.`/`,` fraction).
///
/// With at most 15 significant digits the result is correctly rounded (an exact integer
/// divided by an exact power of ten); longer numbers go through the standard parser.
#[inline]
pub(crate) fn scan_number(text: &[u8], start: usize) -> (f64, usize) {
    // Up to 15 significant digits always stay below 2^53, so the common case needs no
    // overflow checks.
    let mut i = start;
    let mut mant: u64 = 0;
    let mut digits = 0usize;
    while let Some(&c) = text.get(i) {
        let d = c.wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        mant = mant.wrapping_mul(10).wrapping_add(u64::from(d));
        digits += 1;
        i += 1;
    }
    let mut frac = 0usize;
    if let Some(&c) = text.get(i)
        && (c == b'.' || (c == b',' && text.get(i + 1).is_some_and(u8::is_ascii_digit)))
    {
        i += 1;
        while let Some(&c) = text.get(i) {
            let d = c.wrapping_sub(b'0');
            if d > 9 {
                break;
            }
            mant = mant.wrapping_mul(10).wrapping_add(u64::from(d));
            frac += 1;
            i += 1;
        }
    }
    if digits + frac <= 15
        && let Some(p) = POW10.get(frac)
    {
        // mant < 10^15 < 2^53 fits i64 exactly; the signed conversion is a single instruction
        let v = (mant as i64) as f64;
        return (if frac == 0 { v } else { v / p }, i);
    }
    // Slow path: copy with '.' as separator and use the standard parser.
    let mut s = String::with_capacity(i - start);
    for &c in text.get(start..i).unwrap_or(&[]) {
        s.push(if c == b',' { '.' } else { char::from(c) });
    }
    (s.parse::<f64>().unwrap_or(f64::NAN), i)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Kinds, with numbers as their values.
    fn kinds(text: &str) -> Vec<(TokKind, f64)> {
        let mut l = Lexer::new(text.as_bytes(), 0);
        let mut v = Vec::new();
        loop {
            let t = l.next_token();
            if t.kind == TokKind::End {
                break;
            }
            let n = if t.kind == TokKind::Num {
                l.num(t)
            } else {
                0.0
            };
            v.push((t.kind, n));
        }
        v
    }

    #[test]
    fn numbers_match_the_standard_parser() {
        for s in [
            "0",
            "12",
            "12.5",
            "0.001",
            "99999.9999",
            "3.14159265358979",
            "5.",
        ] {
            let (v, e) = scan_number(s.as_bytes(), 0);
            assert_eq!(e, s.len());
            assert_eq!(v, s.parse::<f64>().unwrap(), "{s}");
        }
        let (v, _) = scan_number(b"49,000", 0);
        assert_eq!(v, 49.0);
        let long = "1234567890.12345678901";
        let (v, _) = scan_number(long.as_bytes(), 0);
        assert_eq!(v, long.parse::<f64>().unwrap());
    }

    #[test]
    fn spaced_words_and_comments() {
        use TokKind::*;
        assert_eq!(
            kinds("L Z + Q13 ; move"),
            vec![
                (Ident, 0.0),
                (Ident, 0.0),
                (Plus, 0.0),
                (Ident, 0.0),
                (Num, 13.0)
            ]
        );
        assert_eq!(
            kinds("FN0 : Q1 =+2,5"),
            vec![
                (Ident, 0.0),
                (Num, 0.0),
                (Colon, 0.0),
                (Ident, 0.0),
                (Num, 1.0),
                (Eq, 0.0),
                (Plus, 0.0),
                (Num, 2.5)
            ]
        );
    }
}

#[cfg(test)]
mod plain_word_tests {
    use super::*;

    /// The fast path reads the common word forms completely (name, sign, value, parameter).
    #[test]
    fn plain_words_of_common_forms() {
        let cases: [(&str, &str, i8, Option<f64>, bool); 6] = [
            ("X+Q1", "X", 1, Some(1.0), true),
            ("Y-Q2", "Y", -1, Some(2.0), true),
            ("FQ4", "F", 0, Some(4.0), true),
            ("R+10", "R", 1, Some(10.0), false),
            ("DR+", "DR", 1, None, false),
            ("IX-0.5", "IX", -1, Some(0.5), false),
        ];
        for (text, name, sign, value, param) in cases {
            let l = Lexer::new(text.as_bytes(), 0);
            let w = l.plain_word().unwrap_or_else(|| panic!("{text}"));
            assert_eq!(
                &text.as_bytes()[w.start..w.name_end],
                name.as_bytes(),
                "{text}"
            );
            assert_eq!(
                (w.sign, w.value, w.param, w.end),
                (sign, value, param, text.len())
            );
        }
    }
}
