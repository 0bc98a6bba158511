//! Splitting one lathe DIN PLUS line into a section code or address words.
//!
//! A line is a section code (`MACHINING`, `BEARBEITUNG`, `LATERAL_Y X118 C0 B130 …`), a
//! program name (`%name.nc`), a `#` header line, or a block `[/][N<nr>] words`. Comments are
//! `[ … ]` anywhere in a line. A word is an address — a run of letters such as `X`, `Xi`,
//! `XK`, `ZS`, `Wi`, `BR`, `ID` — followed by a signed number, `?` (unknown coordinate, solved
//! from the neighbouring contour elements) or a quoted text (`ID"342-300.1"`). Addresses are
//! matched case-sensitively where the manual distinguishes them (`Xi` incremental, `XK`
//! Cartesian), else upper-cased.

use super::expr::{self, Expr};
use super::flow::{self, Stmt};
use crate::diag::ProgramError;

/// Most words one block may carry.
pub const MAX_WORDS: usize = 32;

/// A word value.
#[derive(Debug, Clone, PartialEq)]
pub enum DinValue {
    /// A number.
    Num(f64),
    /// `?`: unknown, to be solved from the neighbouring elements.
    Unknown,
    /// A quoted text.
    Text(String),
    /// A variable or a formula in parentheses (`X#l1`, `Z-#g2`, `X(#l1*2+5)`), evaluated when
    /// the block runs.
    Expr(Expr),
}

/// One address word.
#[derive(Debug, Clone, PartialEq)]
pub struct DinWord {
    /// The address as written, with `i` kept lower-case (`Xi`, `Wi`) and the rest upper-cased.
    pub addr: String,
    /// The value.
    pub value: DinValue,
    /// Byte position of the word in the line.
    pub pos: usize,
}

/// What a line is.
#[derive(Debug, Clone, PartialEq)]
pub enum DinLine {
    /// Empty, comment only, or a `#` header line.
    Empty,
    /// `%name`: the program name.
    Name,
    /// A section code with its parameters (`LATERAL_Y X118 …`).
    Section {
        /// The section code, upper-cased, words joined by one space.
        code: String,
        /// The parameter words after the code.
        words: Vec<DinWord>,
    },
    /// `SUBPROGRAM "name"`: the start of a local subprogram.
    Subprogram {
        /// The name between the quotes.
        name: String,
    },
    /// A variable assignment, a control structure keyword, RETURN or a subprogram call.
    Control {
        /// The block number `N…`.
        number: Option<u64>,
        /// The statement.
        stmt: Stmt,
        /// Byte position of the statement in the line.
        pos: usize,
    },
    /// A block of address words.
    Block {
        /// The block number `N…`.
        number: Option<u64>,
        /// The words.
        words: Vec<DinWord>,
    },
}

/// A syntax error at a byte position.
pub type SyntaxError = (usize, ProgramError);

/// The section codes this version knows: English, German, and END as the Russian edition of
/// the DIN manual writes it in its G745 example (`КОНЕЦ`).
pub const SECTION_CODES: [&str; 36] = [
    "HEADER",
    "PROGRAM HEAD",
    "PROGRAMMKOPF",
    "CHUCKING EQUIPMENT",
    "SPANNMITTEL",
    "TURRET",
    "REVOLVER",
    "BLANK",
    "ROHTEIL",
    "AUXIL_BLANK",
    "HILFSROHTEIL",
    "FINISHED PART",
    "FINISHED",
    "FERTIGTEIL",
    "AUXIL_CONTOUR",
    "HILFSKONTUR",
    "FRONT",
    "FACE_C",
    "STIRN_C",
    "REAR_C",
    "RUECKSEITE_C",
    "LATERAL",
    "LATERAL_C",
    "MANTEL_C",
    "FACE_Y",
    "STIRN_Y",
    "LATERAL_Y",
    "MANTEL_Y",
    "SURFACE_Y",
    "MACHINING",
    "BEARBEITUNG",
    "END",
    "ENDE",
    "КОНЕЦ",
    "SUBPROGRAM",
    "UNTERPROGRAMM",
];

/// Removes `[ … ]` comments (replaced by blanks so positions stay), returns the cleaned line.
fn strip_comments(text: &[u8]) -> Result<Vec<u8>, SyntaxError> {
    let mut out = text.to_vec();
    let mut open = None;
    for (i, b) in text.iter().enumerate() {
        match (*b, open) {
            (b'[', None) => open = Some(i),
            (b']', Some(_)) => {
                if let Some(s) = open.take() {
                    for o in out.iter_mut().take(i + 1).skip(s) {
                        *o = b' ';
                    }
                }
            }
            _ => {}
        }
    }
    if let Some(s) = open {
        return Err((s, ProgramError::Missing("comment `[` without closing `]`")));
    }
    Ok(out)
}

fn is_blank(b: u8) -> bool {
    b == b' ' || b == b'\t' || b == b'\r' || b == b'\n'
}

/// Reads an unsigned decimal number (digits, `.` or `,` as decimal mark).
fn number(text: &[u8], i: &mut usize) -> Option<f64> {
    let s = *i;
    while text
        .get(*i)
        .is_some_and(|b| b.is_ascii_digit() || *b == b'.')
    {
        *i += 1;
    }
    let raw = std::str::from_utf8(text.get(s..*i)?).ok()?;
    if raw.is_empty() {
        return None;
    }
    raw.parse::<f64>().ok()
}

/// Parses one line.
pub fn parse_line(raw: &[u8]) -> Result<DinLine, SyntaxError> {
    let text = strip_comments(raw)?;
    let mut i = 0;
    while text.get(i).copied().is_some_and(is_blank) {
        i += 1;
    }
    let Some(&first) = text.get(i) else {
        return Ok(DinLine::Empty);
    };
    if first == b'#' && !flow::is_variable(text.get(i..).unwrap_or(&[])) {
        return Ok(DinLine::Empty);
    }
    if first == b'%' {
        return Ok(DinLine::Name);
    }
    let numbered =
        (first == b'N' || first == b'n') && text.get(i + 1).is_some_and(u8::is_ascii_digit);
    if !numbered && let Some(section) = section_code(&text, i)? {
        return Ok(section);
    }
    if !numbered && let Some(stmt) = flow::statement(&text, i)? {
        return Ok(DinLine::Control {
            number: None,
            stmt,
            pos: i,
        });
    }
    if !numbered && looks_like_section(text.get(i..).unwrap_or(&[])) {
        let code: String = String::from_utf8_lossy(text.get(i..).unwrap_or(&[]))
            .trim_end()
            .to_string();
        return Err((
            i,
            ProgramError::Unexpected(format!("section code '{code}' (not a known section)")),
        ));
    }
    let mut number_word = None;
    if first == b'/' {
        return Err((
            i,
            ProgramError::NotSupported("block skip `/` in lathe DIN".into()),
        ));
    }
    if (first == b'N' || first == b'n') && text.get(i + 1).is_some_and(u8::is_ascii_digit) {
        let at = i;
        i += 1;
        let n = number(&text, &mut i).unwrap_or(-1.0);
        if n.fract() != 0.0 || !(0.0..1e15).contains(&n) {
            return Err((
                at,
                ProgramError::OutOfRange("block number is not a whole number".into()),
            ));
        }
        number_word = Some(n as u64);
    }
    while text.get(i).copied().is_some_and(is_blank) {
        i += 1;
    }
    if let Some(stmt) = flow::statement(&text, i)? {
        return Ok(DinLine::Control {
            number: number_word,
            stmt,
            pos: i,
        });
    }
    let words = words(&text, i)?;
    if words.is_empty() && number_word.is_none() {
        return Ok(DinLine::Empty);
    }
    Ok(DinLine::Block {
        number: number_word,
        words,
    })
}

/// True for a line of upper-case words and underscores only (at least three letters): the
/// shape of a section code, which no NC block has (its words carry values).
fn looks_like_section(rest: &[u8]) -> bool {
    let body = rest.trim_ascii_end();
    body.len() >= 3
        && body
            .iter()
            .all(|b| b.is_ascii_uppercase() || *b == b'_' || *b == b' ')
        && body.iter().filter(|b| b.is_ascii_uppercase()).count() >= 3
}

/// Recognises a section code at `i`: the whole line, or the code followed by words.
fn section_code(text: &[u8], i: usize) -> Result<Option<DinLine>, SyntaxError> {
    let rest = String::from_utf8_lossy(text.get(i..).unwrap_or(&[])).into_owned();
    let upper = rest.trim_end().to_uppercase();
    for code in SECTION_CODES {
        if let Some(after) = upper.strip_prefix(code) {
            let boundary = after.is_empty() || after.starts_with([' ', '\t']);
            if !boundary {
                continue;
            }
            // parameters of LATERAL_Y / SURFACE_Y / FACE_Y and CONTOUR-like sections
            let offset = i + rest.len() - rest.trim_start().len() + code.len();
            let byte_offset = offset.min(text.len());
            if matches!(code, "SUBPROGRAM" | "UNTERPROGRAMM") {
                return subprogram_name(text, byte_offset).map(Some);
            }
            let words = if after.trim().is_empty() {
                Vec::new()
            } else {
                words(text, byte_offset)?
            };
            return Ok(Some(DinLine::Section {
                code: code.to_string(),
                words,
            }));
        }
    }
    Ok(None)
}

/// `SUBPROGRAM "name"`: reads the quoted name after the code.
fn subprogram_name(text: &[u8], mut i: usize) -> Result<DinLine, SyntaxError> {
    while text.get(i).copied().is_some_and(is_blank) {
        i += 1;
    }
    let missing = (
        i,
        ProgramError::Missing("SUBPROGRAM needs its name in quotes: SUBPROGRAM \"name\""),
    );
    if text.get(i) != Some(&b'"') {
        return Err(missing);
    }
    let at = i;
    let DinValue::Text(name) = value(text, &mut i, at, "SUBPROGRAM")? else {
        return Err(missing);
    };
    let mut j = i;
    while text.get(j).copied().is_some_and(is_blank) {
        j += 1;
    }
    if name.trim().is_empty() {
        return Err(missing);
    }
    if let Some(c) = text.get(j) {
        return Err((
            j,
            ProgramError::Unexpected(format!("'{}' after the subprogram name", char::from(*c))),
        ));
    }
    Ok(DinLine::Subprogram { name })
}

/// Reads address words from `i` to the end of the line.
pub(crate) fn words(text: &[u8], mut i: usize) -> Result<Vec<DinWord>, SyntaxError> {
    let mut out = Vec::new();
    loop {
        while text.get(i).copied().is_some_and(is_blank) {
            i += 1;
        }
        let Some(&c) = text.get(i) else { break };
        if !c.is_ascii_alphabetic() {
            return Err((
                i,
                ProgramError::Unexpected(format!("character '{}'", char::from(c))),
            ));
        }
        let at = i;
        while text.get(i).is_some_and(u8::is_ascii_alphabetic) {
            i += 1;
        }
        let raw = text.get(at..i).unwrap_or(&[]);
        let addr = address(raw);
        let value = value(text, &mut i, at, &addr)?;
        if out.len() >= MAX_WORDS {
            return Err((
                at,
                ProgramError::OutOfRange(format!("more than {MAX_WORDS} words in one block")),
            ));
        }
        out.push(DinWord {
            addr,
            value,
            pos: at,
        });
    }
    Ok(out)
}

/// The canonical spelling of an address: upper case, but a trailing `i` of a two-letter
/// address (`Xi`, `Zi`, `Wi`, `Ci`, `Yi`) stays lower case (incremental).
fn address(raw: &[u8]) -> String {
    let mut s: String = raw.iter().map(|&b| char::from(b)).collect();
    if s.len() == 2 && s.ends_with('i') {
        let head = s[..1].to_ascii_uppercase();
        s = format!("{head}i");
        return s;
    }
    s.make_ascii_uppercase();
    s
}

fn value(text: &[u8], i: &mut usize, at: usize, addr: &str) -> Result<DinValue, SyntaxError> {
    match text.get(*i) {
        Some(b'?') => {
            *i += 1;
            return Ok(DinValue::Unknown);
        }
        Some(b'"') => {
            let s = *i + 1;
            let end = text
                .get(s..)
                .and_then(|t| t.iter().position(|&b| b == b'"'))
                .ok_or((*i, ProgramError::Missing("text without closing `\"`")))?;
            *i = s + end + 1;
            let t = text.get(s..s + end).unwrap_or(&[]);
            return Ok(DinValue::Text(t.iter().map(|&b| char::from(b)).collect()));
        }
        _ => {}
    }
    let mut neg = false;
    while let Some(&c) = text.get(*i) {
        match c {
            b'+' => {}
            b'-' => neg = !neg,
            _ => break,
        }
        *i += 1;
    }
    let formula = match text.get(*i) {
        Some(b'#') => Some(Expr::Var(expr::parse_var(text, i)?)),
        Some(b'(') => Some(expr::parse_paren(text, i)?),
        _ => None,
    };
    if let Some(e) = formula {
        return Ok(DinValue::Expr(if neg { Expr::Neg(Box::new(e)) } else { e }));
    }
    let v = number(text, i).ok_or((at, ProgramError::MissingValue(addr.to_string())))?;
    Ok(DinValue::Num(if neg { -v } else { v }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_words_and_comments() {
        let l = parse_line(b"N5 G745 XK0 YK-2.5 K50 Wi-30 [pattern] Q3").unwrap();
        let DinLine::Block { number, words } = l else {
            panic!("not a block")
        };
        assert_eq!(number, Some(5));
        let addrs: Vec<&str> = words.iter().map(|w| w.addr.as_str()).collect();
        assert_eq!(addrs, ["G", "XK", "YK", "K", "Wi", "Q"]);
        assert_eq!(words[2].value, DinValue::Num(-2.5));
        assert_eq!(words[4].value, DinValue::Num(-30.0));
        assert_eq!(words[5].pos, 39);
    }

    #[test]
    fn sections_names_unknowns_and_texts() {
        assert_eq!(
            parse_line(b"FINISHED PART").unwrap(),
            DinLine::Section {
                code: "FINISHED PART".into(),
                words: vec![]
            }
        );
        let DinLine::Section { code, words } =
            parse_line(b"SURFACE_Y X118 C0 B130 I59 K0").unwrap()
        else {
            panic!("not a section")
        };
        assert_eq!(code, "SURFACE_Y");
        assert_eq!(words.len(), 5);
        assert_eq!(parse_line(b"%745.nc").unwrap(), DinLine::Name);
        assert_eq!(
            parse_line("КОНЕЦ".as_bytes()).unwrap(),
            DinLine::Section {
                code: "КОНЕЦ".into(),
                words: vec![]
            }
        );
        let DinLine::Block { words, .. } = parse_line(b"N8 G12 X? Z? R15").unwrap() else {
            panic!()
        };
        assert_eq!(words[1].value, DinValue::Unknown);
        let DinLine::Block { words, .. } = parse_line(b"T1 ID\"342-300.1\"").unwrap() else {
            panic!()
        };
        assert_eq!(words[1].value, DinValue::Text("342-300.1".into()));
    }

    #[test]
    fn errors_are_located() {
        assert_eq!(parse_line(b"N1 G0 X").unwrap_err().0, 6);
        assert_eq!(parse_line(b"N1 G0 [open").unwrap_err().0, 6);
        assert_eq!(parse_line(b"N1 G0 X1 $").unwrap_err().0, 9);
    }
}
