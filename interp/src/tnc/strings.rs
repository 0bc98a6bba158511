//! QS string parameters: assignment blocks, string formulas and the string functions.
//!
//! Blocks (TNC syntax):
//!
//! ```text
//! QS10 = "text"                         assignment of a literal, a QS or a string formula
//! DECLARE STRING QS10 = "text"          the same, in the form the TNC dialog writes
//! STRING FORMULA QS10 = QS1 || "x" || TOCHAR( DAT+Q1 DECIMALS3 )
//! QS2 = SUBSTR( SRC_QS1 BEG2 LEN4 )
//! Q1 = STRLEN( SRC_QS1 )                numeric functions of strings, inside any formula:
//! Q2 = INSTR( SRC_QS1 SEA_QS2 BEG0 )    STRLEN, INSTR, STRCOMP, TONUMB
//! Q3 = STRCOMP( SRC_QS1 SEA_QS2 )
//! Q4 = TONUMB( SRC_QS11 )
//! CALL LBL QS2 / FN 9: IF … GOTO LBL QS5   jump to the label named by the contents of QS n
//! ```
//!
//! Rules this interpreter applies (TNC manuals; where they are silent, the choice is noted):
//! - a QS parameter holds at most 255 characters; longer results are an error.
//! - a QS parameter is *undefined* until assigned. STRLEN of an undefined QS gives -1 (as on
//!   the TNC); every other use of an undefined QS (copy, `||`, SUBSTR, INSTR, STRCOMP,
//!   TONUMB, a QS label) stops with "QSn is not defined".
//! - character positions count from 0 (BEG0 is the first character).
//! - SUBSTR copies LEN characters from position BEG; a range outside the text is an error.
//! - INSTR gives the position of the first occurrence of the search text at or after BEG; when
//!   there is none it gives the length of the searched text (so `INSTR(…) EQU STRLEN(…)`
//!   means "not found", the idiom of real programs).
//! - STRCOMP gives 0 for equal texts, -1 when the first sorts before the second (character
//!   codes, a prefix sorts first), +1 otherwise.
//! - TONUMB accepts an optional sign, digits and one `.` or `,` (blanks around are ignored);
//!   any other text is an error.
//! - TOCHAR writes the value with DECIMALS places (0 to 16); without DECIMALS it writes the
//!   shortest text that reads back as the same number (project choice).
//! - CFGREAD and SYSSTR read control configuration that this machine does not have: they are
//!   refused as not supported.
//! - Numeric parameters (Q, QL, QR) read as 0 until assigned: the TNC keeps parameter
//!   values and starts them at 0, so reading one never fails.

use super::exec::{ExecError, LabelKey, Machine, here};
use super::expr::{Params, Rpn, malformed};
use super::stmt::LabelRef;
use crate::diag::ProgramError;

/// Longest text a QS parameter holds (TNC limit).
pub const MAX_STRING: usize = 255;

/// Highest QS index accepted.
pub const MAX_QS: u32 = 65_535;

/// Most decimals TOCHAR writes.
pub const MAX_DECIMALS: f64 = 16.0;

fn undefined(n: u32) -> ProgramError {
    ProgramError::Arithmetic(format!("QS{n} is not defined (assign it before use)"))
}

fn whole(x: f64, what: &str) -> Result<usize, ProgramError> {
    if x.fract() == 0.0 && (0.0..=1e6).contains(&x) {
        Ok(x as usize)
    } else {
        Err(ProgramError::OutOfRange(format!(
            "{what} {x} is not a whole number from 0"
        )))
    }
}

impl Params {
    /// The text of QS n, `None` while undefined.
    pub fn get_str(&self, n: u32) -> Option<&str> {
        self.qs.get(n as usize).and_then(|s| s.as_deref())
    }

    fn defined_str(&self, n: u32) -> Result<&str, ProgramError> {
        self.get_str(n).ok_or_else(|| undefined(n))
    }

    /// Assigns QS n (at most [`MAX_STRING`] characters).
    pub fn set_str(&mut self, n: u32, s: String) -> Result<(), ProgramError> {
        let len = s.chars().count();
        if len > MAX_STRING {
            return Err(ProgramError::OutOfRange(format!(
                "text of {len} characters is longer than the {MAX_STRING} a QS parameter holds"
            )));
        }
        let i = n.min(MAX_QS) as usize;
        if self.qs.len() <= i {
            self.qs.resize(i + 1, None);
        }
        if let Some(slot) = self.qs.get_mut(i) {
            *slot = Some(s);
        }
        Ok(())
    }

    /// Executes one string instruction (anything but Push, Unary, Binary).
    pub(super) fn string_step(
        &self,
        ins: Rpn,
        nums: &mut Vec<f64>,
        strs: &mut Vec<String>,
        text: &[u8],
    ) -> Result<(), ProgramError> {
        let mut pop = || nums.pop().ok_or_else(malformed);
        match ins {
            Rpn::PushText(s, e) => strs.push(
                text.get(s as usize..e as usize)
                    .ok_or_else(malformed)?
                    .iter()
                    .map(|&b| char::from(b))
                    .collect(),
            ),
            Rpn::PushQs(n) => strs.push(self.defined_str(n)?.to_string()),
            Rpn::Concat => {
                let b = strs.pop().ok_or_else(malformed)?;
                let a = strs.last_mut().ok_or_else(malformed)?;
                a.push_str(&b);
            }
            Rpn::ToChar(with_decimals) => {
                let v = pop()?;
                let decimals = if with_decimals {
                    let d = pop()?;
                    if !(d.fract() == 0.0 && (0.0..=MAX_DECIMALS).contains(&d)) {
                        return Err(ProgramError::OutOfRange(format!(
                            "TOCHAR DECIMALS{d} is not a whole number from 0 to {MAX_DECIMALS}"
                        )));
                    }
                    Some(d as usize)
                } else {
                    None
                };
                strs.push(match decimals {
                    Some(d) => format!("{v:.d$}"),
                    None => format!("{v}"),
                });
            }
            Rpn::SubStr(n) => {
                let len = whole(pop()?, "SUBSTR LEN")?;
                let beg = whole(pop()?, "SUBSTR BEG")?;
                let src = self.defined_str(n)?;
                let count = src.chars().count();
                if beg + len > count {
                    return Err(ProgramError::OutOfRange(format!(
                        "SUBSTR BEG{beg} LEN{len} reaches past the end of QS{n} ({count} characters; the first is BEG0)"
                    )));
                }
                strs.push(src.chars().skip(beg).take(len).collect());
            }
            Rpn::StrLen(n) => nums.push(match self.get_str(n) {
                Some(s) => s.chars().count() as f64,
                None => -1.0,
            }),
            Rpn::StrComp(a, b) => {
                let (a, b) = (self.defined_str(a)?, self.defined_str(b)?);
                nums.push(match a.chars().cmp(b.chars()) {
                    std::cmp::Ordering::Less => -1.0,
                    std::cmp::Ordering::Equal => 0.0,
                    std::cmp::Ordering::Greater => 1.0,
                });
            }
            Rpn::InStr(a, b) => {
                let beg = whole(pop()?, "INSTR BEG")?;
                let (src, sea) = (self.defined_str(a)?, self.defined_str(b)?);
                nums.push(instr(src, sea, beg) as f64);
            }
            Rpn::ToNumb(n) => nums.push(to_number(self.defined_str(n)?)?),
            Rpn::Push(_) | Rpn::Unary(_) | Rpn::Binary(_) => return Err(malformed()),
        }
        Ok(())
    }

    /// Evaluates a string formula; `text` is the block text its literals point into.
    pub fn eval_string(
        &self,
        code: &[Rpn],
        nums: &mut Vec<f64>,
        text: &[u8],
    ) -> Result<String, ProgramError> {
        nums.clear();
        let mut strs: Vec<String> = Vec::new();
        self.run_code(code, nums, &mut strs, text)?;
        let s = strs.pop().ok_or_else(malformed)?;
        if !strs.is_empty() || !nums.is_empty() {
            return Err(malformed());
        }
        let len = s.chars().count();
        if len > MAX_STRING {
            return Err(ProgramError::OutOfRange(format!(
                "text of {len} characters is longer than the {MAX_STRING} a QS parameter holds"
            )));
        }
        Ok(s)
    }
}

/// Position (from 0) of the first `sea` in `src` at or after character `beg`; the length of
/// `src` when there is none.
fn instr(src: &str, sea: &str, beg: usize) -> usize {
    let hay: Vec<char> = src.chars().collect();
    let needle: Vec<char> = sea.chars().collect();
    let n = hay.len();
    if needle.len() > n {
        return n;
    }
    (beg..=n - needle.len())
        .find(|&i| hay.get(i..i + needle.len()) == Some(&needle[..]))
        .unwrap_or(n)
}

/// The number a text spells: optional sign, digits, one decimal point or comma.
fn to_number(s: &str) -> Result<f64, ProgramError> {
    let t = s.trim();
    let body = t.strip_prefix(['+', '-']).unwrap_or(t);
    let digits = body.chars().filter(char::is_ascii_digit).count();
    let points = body.chars().filter(|c| matches!(c, '.' | ',')).count();
    if digits == 0 || points > 1 || digits + points != body.chars().count() {
        return Err(ProgramError::Arithmetic(format!(
            "TONUMB: \"{s}\" is not a number"
        )));
    }
    t.replace(',', ".")
        .parse::<f64>()
        .map_err(|_| ProgramError::Arithmetic(format!("TONUMB: \"{s}\" is not a number")))
}

impl Machine {
    /// `QSn = …`: evaluates the string formula in `code` and assigns it.
    pub(super) fn assign_string(
        &mut self,
        target: u32,
        code: &[Rpn],
        text: &[u8],
    ) -> Result<(), ExecError> {
        let s = self
            .params
            .eval_string(code, &mut self.stack, text)
            .map_err(here)?;
        self.params.set_str(target, s).map_err(here)
    }

    /// The label a call or jump goes to; a QS label is the label named by the text of QS n.
    pub(super) fn label_key(&self, r: LabelRef, text: &[u8]) -> Result<LabelKey, ExecError> {
        match r {
            LabelRef::Qs(n) => match self.params.get_str(n) {
                Some(s) => Ok(LabelKey::Name(s.to_string())),
                None => Err(here(undefined(n))),
            },
            other => Ok(LabelKey::from_ref(other, text)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interpreter::Interpreter;
    use crate::klartext::parser::Parser;
    use crate::op::{OpKind, Pose};

    /// Parses and runs `blocks` (one per line) on fresh parameters; returns them.
    fn run(blocks: &str) -> Result<Params, (usize, ProgramError)> {
        let mut p = Parser::default();
        let mut m = Machine::new(Pose::ZERO);
        for (i, line) in blocks.lines().enumerate() {
            let b = p.parse(line.as_bytes()).map_err(|e| (i, e.error))?;
            let loc = crate::op::SourceLoc {
                file: 0,
                line: i as u32 + 1,
                col: 1,
                block: None,
            };
            let mut out = std::collections::VecDeque::new();
            m.exec(&b.stmt, &p, line.as_bytes(), loc, &mut out)
                .map_err(|e| (i, e.1))?;
        }
        Ok(m.params)
    }

    fn q(p: &Params, n: u32) -> f64 {
        p.get(crate::tnc::expr::ParamRef {
            kind: crate::tnc::expr::ParamKind::Q,
            index: n,
        })
    }

    #[test]
    fn literal_copy_and_concatenation() {
        let p = run("QS1 = \"AB\"\n\
             DECLARE STRING QS2 = \"c;d\"\n\
             STRING FORMULA QS3 = QS1 || \"-\" || QS2\n\
             QS4 = QS3")
        .unwrap();
        assert_eq!(p.get_str(1), Some("AB"));
        assert_eq!(p.get_str(2), Some("c;d"));
        assert_eq!(p.get_str(3), Some("AB-c;d"));
        assert_eq!(p.get_str(4), Some("AB-c;d"));
    }

    #[test]
    fn substr_counts_from_zero() {
        // "HEIDENHAIN": BEG2 LEN4 = characters 2..5 = "IDEN"
        let p = run(
            "QS10 = \"HEIDENHAIN\"\nQ1 = 2\nQS11 = SUBSTR( SRC_QS10 BEGQ1 LEN4 )\n\
             QS12 = SUBSTR( SRC_QS10 BEG0 LEN1 )\nQS13 = SUBSTR(SRC_QS10 BEG10 LEN0)",
        )
        .unwrap();
        assert_eq!(p.get_str(11), Some("IDEN"));
        assert_eq!(p.get_str(12), Some("H"));
        assert_eq!(p.get_str(13), Some(""));
        let e = run("QS10 = \"ABC\"\nQS11 = SUBSTR( SRC_QS10 BEG2 LEN2 )").unwrap_err();
        assert_eq!(e.0, 1);
        assert!(e.1.to_string().contains("past the end"), "{}", e.1);
    }

    #[test]
    fn numeric_string_functions() {
        let p = run(
            "QS1 = \"abcabc\"\nQS2 = \"ca\"\nQS3 = \"zz\"\nQS4 = \" -12,5 \"\n\
             Q1 = STRLEN( SRC_QS1 )\n\
             Q2 = INSTR( SRC_QS1 SEA_QS2 BEG0 )\n\
             Q3 = INSTR( SRC_QS1 SEA_QS3 BEG0 )\n\
             Q4 = STRCOMP( SRC_QS2 SEA_QS3 )\n\
             Q5 = STRCOMP( SRC_QS3 SEA_QS2 )\n\
             Q6 = STRCOMP( SRC_QS1 SEA_QS1 )\n\
             Q7 = TONUMB( SRC_QS4 ) * 2\n\
             Q8 = STRLEN( SRC_QS99 )\n\
             Q9 = 1 + STRLEN( SRC_QS2 ) * 3\n\
             Q10 = INSTR( SRC_QS1 SEA_QS2 BEG3 )\n\
             QS5 = \"ab\"\nQ11 = STRCOMP( SRC_QS5 SEA_QS1 )",
        )
        .unwrap();
        assert_eq!(q(&p, 1), 6.0);
        assert_eq!(q(&p, 2), 2.0); // "ca" starts at index 2 of "abcabc"
        assert_eq!(q(&p, 3), 6.0); // not found: the length of the searched text
        assert_eq!(q(&p, 4), -1.0); // "ca" < "zz"
        assert_eq!(q(&p, 5), 1.0);
        assert_eq!(q(&p, 6), 0.0);
        assert_eq!(q(&p, 7), -25.0);
        assert_eq!(q(&p, 8), -1.0); // undefined QS
        assert_eq!(q(&p, 9), 7.0); // precedence: 1 + (2 * 3)
        assert_eq!(q(&p, 10), 6.0); // no "ca" at or after index 3 of "abcabc"
        assert_eq!(q(&p, 11), -1.0); // a prefix sorts first
    }

    #[test]
    fn tochar_with_and_without_decimals() {
        let p = run("Q1 = 3.14159\nQS1 = TOCHAR( DAT+Q1 DECIMALS3 )\n\
             QS2 = TOCHAR( DAT2.5 )\nQS3 = \"X\" || TOCHAR( DAT-7 DECIMALS0 ) || \"mm\"\n\
             Q2 = 2\nQS4 = TOCHAR( DATQ2 DECIMALSQ2 )")
        .unwrap();
        assert_eq!(p.get_str(1), Some("3.142"));
        assert_eq!(p.get_str(2), Some("2.5"));
        assert_eq!(p.get_str(3), Some("X-7mm"));
        assert_eq!(p.get_str(4), Some("2.00"));
    }

    #[test]
    fn undefined_and_bad_values_are_errors() {
        let e = run("QS1 = QS2").unwrap_err();
        assert!(e.1.to_string().contains("QS2 is not defined"), "{}", e.1);
        let e = run("QS1 = \"1x\"\nQ1 = TONUMB( SRC_QS1 )").unwrap_err();
        assert_eq!(e.0, 1);
        assert!(e.1.to_string().contains("not a number"));
        let long = format!("QS1 = \"{}\"\nQS2 = QS1 || QS1", "a".repeat(200));
        let e = run(&long).unwrap_err();
        assert_eq!(e.0, 1);
        assert!(e.1.to_string().contains("255"));
    }

    #[test]
    fn syntax_errors_point_at_the_word() {
        let cases: [(&str, usize, &str); 7] = [
            ("QS1 = \"abc", 6, "closing"),
            ("QS1 = FOO( SRC_QS2 )", 6, "unknown string function"),
            ("Q1 = STRLEN( QS2 )", 13, "SRC_QS"),
            ("QS1 = SUBSTR( SRC_QS2 LEN2 BEG1 )", 22, "BEG"),
            ("QS1 = \"a\" | \"b\"", 10, "||"),
            ("QS1 = CFGREAD( KEY_QS2 )", 6, "not supported"),
            ("QS1 = Q2", 6, "TOCHAR"),
        ];
        for (text, col, msg) in cases {
            let e = Parser::default().parse(text.as_bytes()).unwrap_err();
            assert_eq!(e.pos, col, "{text}: {}", e.error);
            assert!(e.error.to_string().contains(msg), "{text}: {}", e.error);
        }
    }

    fn ops(src: &str) -> Result<Vec<OpKind>, String> {
        Interpreter::from_source("s.h", src, Pose::ZERO)
            .map(|r| r.map(|o| o.kind).map_err(|d| d.to_string()))
            .collect()
    }

    fn xs(ops: &[OpKind]) -> Vec<f64> {
        ops.iter()
            .filter_map(|o| match o {
                OpKind::Line { to, .. } => Some(to.0[0]),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn jump_and_call_through_qs_labels() {
        let src = "BEGIN PGM S MM\n\
             QS5 = \"two\"\n\
             FN 9: IF +0 EQU +0 GOTO LBL QS5\n\
             L X+1 F100\n\
             LBL \"two\"\n\
             L X+2 F100\n\
             QS2 = \"sub\"\n\
             CALL LBL QS2\n\
             L X+4\n\
             M30\n\
             LBL \"sub\"\n\
             L X+3\n\
             LBL 0\n\
             END PGM S MM\n";
        let o = ops(src).unwrap();
        assert_eq!(xs(&o), vec![2.0, 3.0, 4.0]);
        let e = ops("BEGIN PGM S MM\nQS1 = SUBSTR( SRC_QS2 BEG1 )\nEND PGM S MM\n").unwrap_err();
        assert_eq!(e, "s.h:2:28: unexpected ')' (expected LEN…)");
        let bad = "BEGIN PGM S MM\nCALL LBL QS7\nEND PGM S MM\n";
        let e = ops(bad).unwrap_err();
        assert!(e.starts_with("s.h:2:1: QS7 is not defined"), "{e}");
        let missing = "BEGIN PGM S MM\nQS1 = \"nowhere\"\nCALL LBL QS1\nEND PGM S MM\n";
        let e = ops(missing).unwrap_err();
        assert!(e.contains("LBL \"nowhere\" not found"), "{e}");
    }

    #[test]
    fn character_loop_in_the_style_of_engraving_macros() {
        // the string blocks of real engraving macros: walk a text character by character,
        // map special characters to label names and call the label of each character
        let src = r#"BEGIN PGM T MM
QS500 = "ab c!"
QS1 = QS500 ; copy of the text
QL10 = 0
QL11 = STRLEN( SRC_QS1 )
LBL "start"
QS2 = SUBSTR( SRC_QS1 BEGQL10 LEN1 )
QS3 = "1 1"
QS3 = SUBSTR( SRC_QS3 BEG1 LEN1 )
QL21 = STRCOMP( SRC_QS3 SEA_QS2 )
FN 10: IF +QL21 NE +0 GOTO LBL "not_space"
QS2 = "space"
LBL "not_space"
QS3 = ";'\/.,][`!@#$%^&*()_+:?><"
QL24 = STRLEN( SRC_QS3 )
QL25 = INSTR( SRC_QS3 SEA_QS2 BEG0 )
FN 9: IF +QL25 EQU +QL24 GOTO LBL "cont"
QS2 = "mark"
LBL "cont"
CALL LBL QS2
QL10 = QL10 + 1
FN 12: IF +QL10 LT +QL11 GOTO LBL "start"
M30
LBL "a"
L X+1 F100
LBL 0
LBL "b"
L X+2
LBL 0
LBL "space"
L X+3
LBL 0
LBL "c"
L X+4
LBL 0
LBL "mark"
L X+5
LBL 0
END PGM T MM
"#;
        let o = ops(src).unwrap();
        assert_eq!(xs(&o), vec![1.0, 2.0, 3.0, 4.0, 5.0]);
    }
}
