//! DIN PLUS statements that are not address words: variable assignments, the control
//! structures, subprogram calls and RETURN.
//!
//! Each statement stands in a block of its own (after an optional block number):
//!
//! ```text
//! N10 #l1 = 5                      assignment: a formula (see `expr`) into a variable
//! N20 IF (#l1 > 2) [THEN]          branch: THEN may follow on the IF line or in its own block
//! N30 THEN
//! N40 ELSE                         optional
//! N50 ENDIF
//! N60 WHILE (#l1 < 10)             loop while the condition holds (checked before each pass)
//! N70 ENDWHILE
//! N80 REPEAT                       loop until the condition holds (checked after each pass)
//! N90 UNTIL (#l1 >= 10)
//! N100 SWITCH #l2                  the branch whose CASE value equals the value runs,
//! N110 CASE 1                      DEFAULT when none does; a branch ends at BREAK or at the
//! N120 BREAK                       next CASE/DEFAULT (there is no fall-through)
//! N130 DEFAULT
//! N140 ENDSWITCH
//! N150 L"name" LA10 LB#l1 Q2       call of the local subprogram `SUBPROGRAM "name"` with
//!                                  transfer values LA … LZ (read there as #__la … #__lz),
//!                                  Q repetitions (default 1); V is accepted and ignored
//! N160 RETURN                      end of a subprogram
//! ```

use super::block::{DinValue, DinWord, SyntaxError, words};
use super::expr::{self, Expr, VarRef};
use crate::diag::ProgramError;

/// A statement.
#[derive(Debug, Clone, PartialEq)]
pub enum Stmt {
    /// `#v = formula`.
    Assign(VarRef, Expr),
    /// `IF condition`.
    If(Expr),
    /// `THEN`.
    Then,
    /// `ELSE`.
    Else,
    /// `ENDIF`.
    EndIf,
    /// `WHILE condition`.
    While(Expr),
    /// `ENDWHILE`.
    EndWhile,
    /// `REPEAT`.
    Repeat,
    /// `UNTIL condition`.
    Until(Expr),
    /// `SWITCH value`.
    Switch(Expr),
    /// `CASE value[, value…]`.
    Case(Vec<Expr>),
    /// `DEFAULT`.
    Default,
    /// `BREAK`.
    Break,
    /// `ENDSWITCH`.
    EndSwitch,
    /// `RETURN`.
    Return,
    /// `L"name" LA… Q… V…`.
    Call {
        /// The subprogram name.
        name: String,
        /// Transfer values, letter (`b'a'` for LA) and formula.
        transfer: Vec<(u8, Expr)>,
        /// Q: repetitions.
        repeat: Option<Expr>,
    },
}

/// The kind of structure a statement opens or closes (for matching).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// IF … ENDIF.
    If,
    /// WHILE … ENDWHILE.
    While,
    /// REPEAT … UNTIL.
    Repeat,
    /// SWITCH … ENDSWITCH.
    Switch,
}

impl Kind {
    /// The keyword that opens the structure.
    pub fn opener(self) -> &'static str {
        match self {
            Kind::If => "IF",
            Kind::While => "WHILE",
            Kind::Repeat => "REPEAT",
            Kind::Switch => "SWITCH",
        }
    }

    /// The keyword that closes it.
    pub fn closer(self) -> &'static str {
        match self {
            Kind::If => "ENDIF",
            Kind::While => "ENDWHILE",
            Kind::Repeat => "UNTIL",
            Kind::Switch => "ENDSWITCH",
        }
    }
}

impl Stmt {
    /// The structure this statement opens.
    pub fn opens(&self) -> Option<Kind> {
        match self {
            Stmt::If(_) => Some(Kind::If),
            Stmt::While(_) => Some(Kind::While),
            Stmt::Repeat => Some(Kind::Repeat),
            Stmt::Switch(_) => Some(Kind::Switch),
            _ => None,
        }
    }

    /// The structure this statement closes.
    pub fn closes(&self) -> Option<Kind> {
        match self {
            Stmt::EndIf => Some(Kind::If),
            Stmt::EndWhile => Some(Kind::While),
            Stmt::Until(_) => Some(Kind::Repeat),
            Stmt::EndSwitch => Some(Kind::Switch),
            _ => None,
        }
    }

    /// The keyword, for messages.
    pub fn keyword(&self) -> &'static str {
        match self {
            Stmt::Assign(..) => "assignment",
            Stmt::If(_) => "IF",
            Stmt::Then => "THEN",
            Stmt::Else => "ELSE",
            Stmt::EndIf => "ENDIF",
            Stmt::While(_) => "WHILE",
            Stmt::EndWhile => "ENDWHILE",
            Stmt::Repeat => "REPEAT",
            Stmt::Until(_) => "UNTIL",
            Stmt::Switch(_) => "SWITCH",
            Stmt::Case(_) => "CASE",
            Stmt::Default => "DEFAULT",
            Stmt::Break => "BREAK",
            Stmt::EndSwitch => "ENDSWITCH",
            Stmt::Return => "RETURN",
            Stmt::Call { .. } => "subprogram call",
        }
    }
}

/// True when `rest` starts with a variable (`#l…`, `#g…`, `#c…`, `#__…`), not a header line.
pub fn is_variable(rest: &[u8]) -> bool {
    match rest {
        [b'#', b'_', b'_', ..] => true,
        [b'#', k, d, ..] => b"lgcLGC".contains(k) && d.is_ascii_digit(),
        _ => false,
    }
}

fn blank(text: &[u8], i: &mut usize) {
    while text.get(*i).is_some_and(|b| b.is_ascii_whitespace()) {
        *i += 1;
    }
}

fn at_end(text: &[u8], mut i: usize) -> Result<(), SyntaxError> {
    blank(text, &mut i);
    match text.get(i) {
        None => Ok(()),
        Some(c) => Err((
            i,
            ProgramError::Unexpected(format!("'{}' after the statement", char::from(*c))),
        )),
    }
}

fn formula(text: &[u8], i: &mut usize, what: &'static str) -> Result<Expr, SyntaxError> {
    blank(text, i);
    if text.get(*i).is_none() {
        return Err((*i, ProgramError::Missing(what)));
    }
    expr::parse(text, i)
}

const KEYWORDS: [&str; 14] = [
    "IF",
    "THEN",
    "ELSE",
    "ENDIF",
    "WHILE",
    "ENDWHILE",
    "REPEAT",
    "UNTIL",
    "SWITCH",
    "CASE",
    "DEFAULT",
    "BREAK",
    "ENDSWITCH",
    "RETURN",
];

/// Reads a statement at `i`, or None when the line is an ordinary block of words.
pub fn statement(text: &[u8], i: usize) -> Result<Option<Stmt>, SyntaxError> {
    let rest = text.get(i..).unwrap_or(&[]);
    if is_variable(rest) {
        let mut j = i;
        let var = expr::parse_var(text, &mut j)?;
        blank(text, &mut j);
        if text.get(j) != Some(&b'=') || text.get(j + 1) == Some(&b'=') {
            return Err((j, ProgramError::Missing("`=` after the variable")));
        }
        j += 1;
        let e = formula(text, &mut j, "a formula after `=`")?;
        at_end(text, j)?;
        return Ok(Some(Stmt::Assign(var, e)));
    }
    if matches!(rest, [b'L' | b'l', b'"', ..]) {
        return call(text, i).map(Some);
    }
    let len = rest
        .iter()
        .position(|b| !b.is_ascii_alphabetic())
        .unwrap_or(rest.len());
    let word = String::from_utf8_lossy(rest.get(..len).unwrap_or(&[])).to_ascii_uppercase();
    let Some(kw) = KEYWORDS.iter().find(|k| **k == word) else {
        return Ok(None);
    };
    let mut j = i + len;
    let stmt = match *kw {
        "IF" => {
            let e = formula(text, &mut j, "a condition after IF")?;
            blank(text, &mut j);
            let tail = text.get(j..).unwrap_or(&[]);
            if tail.len() >= 4
                && tail
                    .get(..4)
                    .is_some_and(|t| t.eq_ignore_ascii_case(b"THEN"))
            {
                j += 4;
            }
            Stmt::If(e)
        }
        "WHILE" => Stmt::While(formula(text, &mut j, "a condition after WHILE")?),
        "UNTIL" => Stmt::Until(formula(text, &mut j, "a condition after UNTIL")?),
        "SWITCH" => Stmt::Switch(formula(text, &mut j, "a value after SWITCH")?),
        "CASE" => {
            let mut values = vec![formula(text, &mut j, "a value after CASE")?];
            loop {
                blank(text, &mut j);
                if text.get(j) != Some(&b',') {
                    break;
                }
                j += 1;
                values.push(formula(text, &mut j, "a value after `,`")?);
            }
            Stmt::Case(values)
        }
        "THEN" => Stmt::Then,
        "ELSE" => Stmt::Else,
        "ENDIF" => Stmt::EndIf,
        "ENDWHILE" => Stmt::EndWhile,
        "REPEAT" => Stmt::Repeat,
        "DEFAULT" => Stmt::Default,
        "BREAK" => Stmt::Break,
        "ENDSWITCH" => Stmt::EndSwitch,
        _ => Stmt::Return,
    };
    at_end(text, j)?;
    Ok(Some(stmt))
}

/// `L"name"` followed by LA … LZ, Q and V words.
fn call(text: &[u8], i: usize) -> Result<Stmt, SyntaxError> {
    let s = i + 2;
    let end = text
        .get(s..)
        .and_then(|t| t.iter().position(|&b| b == b'"'))
        .ok_or((
            i + 1,
            ProgramError::Missing("subprogram name without closing `\"`"),
        ))?;
    let name: String = text
        .get(s..s + end)
        .unwrap_or(&[])
        .iter()
        .map(|&b| char::from(b))
        .collect();
    if name.trim().is_empty() {
        return Err((i, ProgramError::Missing("the subprogram name in L\"…\"")));
    }
    let params = words(text, s + end + 1)?;
    let mut transfer: Vec<(u8, Expr)> = Vec::new();
    let mut repeat = None;
    for w in params {
        let value = match w.value {
            DinValue::Num(v) => Expr::Num(v),
            DinValue::Expr(e) => e,
            _ => return Err((w.pos, ProgramError::MissingValue(w.addr.clone()))),
        };
        let addr = w.addr.to_ascii_uppercase();
        match addr.as_bytes() {
            [b'L', c] if c.is_ascii_uppercase() => {
                let letter = c.to_ascii_lowercase();
                if transfer.iter().any(|(l, _)| *l == letter) {
                    return Err((w.pos, ProgramError::DuplicateWord(addr)));
                }
                transfer.push((letter, value));
            }
            [b'Q'] => repeat = Some(value),
            [b'V'] => {}
            _ => {
                return Err((
                    w.pos,
                    ProgramError::UnknownWord {
                        word: w.addr.clone(),
                        block: "subprogram call",
                    },
                ));
            }
        }
    }
    Ok(Stmt::Call {
        name,
        transfer,
        repeat,
    })
}

/// Evaluates the words of a block: variables and formulas become numbers.
pub fn resolve(words: &mut [DinWord], vars: &expr::Vars) -> Result<(), SyntaxError> {
    for w in words.iter_mut() {
        if let DinValue::Expr(e) = &w.value {
            let v = e.eval(vars).map_err(|e| (w.pos, e))?;
            w.value = DinValue::Num(v);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stmt(s: &str) -> Stmt {
        statement(s.as_bytes(), 0).unwrap().unwrap()
    }

    #[test]
    fn statements_parse() {
        assert!(matches!(
            stmt("#l1 = 2 * #g3"),
            Stmt::Assign(VarRef::Local(1), _)
        ));
        assert!(matches!(stmt("IF (#l1 > 2) THEN"), Stmt::If(_)));
        assert!(matches!(stmt("IF #l1 == 2"), Stmt::If(_)));
        assert_eq!(stmt("endif"), Stmt::EndIf);
        assert!(matches!(stmt("CASE 1, 2"), Stmt::Case(v) if v.len() == 2));
        let Stmt::Call {
            name,
            transfer,
            repeat,
        } = stmt("L\"slot\" LA10 LB#l1 Q3 V1")
        else {
            panic!()
        };
        assert_eq!(name, "slot");
        assert_eq!(transfer.len(), 2);
        assert_eq!(transfer[1].0, b'b');
        assert_eq!(repeat, Some(Expr::Num(3.0)));
        assert!(statement(b"G1 X10", 0).unwrap().is_none());
        assert!(statement(b"IFX", 0).unwrap().is_none());
    }

    #[test]
    fn statement_errors_are_located() {
        assert_eq!(statement(b"#l1 == 2", 0).unwrap_err().0, 4);
        assert_eq!(statement(b"WHILE", 0).unwrap_err().0, 5);
        assert_eq!(statement(b"ENDIF X", 0).unwrap_err().0, 6);
        assert_eq!(statement(b"L\"a\" LA1 LA2", 0).unwrap_err().0, 9);
        assert!(statement(b"L\"a\" X1", 0).is_err());
    }
}
