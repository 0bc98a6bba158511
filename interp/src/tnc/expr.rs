//! Q parameters and formulas: storage, compiled (postfix) expressions and their evaluation.
//!
//! A formula is compiled once per block into a reused postfix buffer, so evaluating it needs
//! no allocation. Grammar (usual precedence, all binary operators left-associative except `^`):
//!
//! ```text
//! sum     := product (('+' | '-') product)*
//! product := unary (('*' | '/' | '%') unary)*
//! unary   := ('+' | '-') unary | power
//! power   := atom ('^' unary)?
//! atom    := number | Q n | QL n | QR n | PI | '(' sum ')' | FUNCTION unary
//! ```
//! Functions take their argument in degrees where angles are involved (SIN, COS, TAN; ASIN,
//! ACOS, ATAN return degrees), as on the TNC. `%` is the remainder of the division. The string
//! functions that give numbers (STRLEN, INSTR, STRCOMP, TONUMB) are atoms of this grammar; see
//! [`super::strings`].
//!
//! Parameters used before assignment: Q, QL and QR parameters read as 0 until a block assigns
//! them (the TNC starts its parameters at 0 and never refuses to read one). QS string
//! parameters are undefined until assigned: STRLEN of an undefined QS gives -1, every other
//! use of it stops the program with "QSn is not defined".

use crate::diag::ProgramError;

/// Which parameter family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ParamKind {
    /// Global Q parameters.
    Q,
    /// Local QL parameters.
    QL,
    /// Remanent QR parameters.
    QR,
}

/// Highest accepted parameter index (per family).
pub(crate) const MAX_PARAM: u32 = 65_535;

/// A parameter reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ParamRef {
    /// Family.
    pub kind: ParamKind,
    /// Number.
    pub index: u32,
}

/// A numeric word value: a literal or a signed parameter reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Value {
    /// A number as written (sign applied).
    Num(f64),
    /// A parameter, negated when written `-Qn`.
    Param {
        /// Which parameter.
        param: ParamRef,
        /// True for `-Qn`.
        negate: bool,
    },
}

/// A one-argument function.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Func {
    /// SIN (degrees).
    Sin,
    /// COS (degrees).
    Cos,
    /// TAN (degrees).
    Tan,
    /// ASIN (result in degrees).
    Asin,
    /// ACOS (result in degrees).
    Acos,
    /// ATAN (result in degrees).
    Atan,
    /// SQ: square.
    Sq,
    /// SQRT: square root.
    Sqrt,
    /// LN: natural logarithm.
    Ln,
    /// LOG: decimal logarithm.
    Log,
    /// EXP: e to the power.
    Exp,
    /// NEG: negation.
    Neg,
    /// INT: integer part.
    Int,
    /// ABS: absolute value.
    Abs,
    /// FRAC: fractional part.
    Frac,
    /// SGN: sign (-1, 0, 1).
    Sgn,
}

impl Func {
    /// The function named by an upper-case identifier.
    pub fn from_name(name: &[u8]) -> Option<Func> {
        Some(match name {
            b"SIN" => Func::Sin,
            b"COS" => Func::Cos,
            b"TAN" => Func::Tan,
            b"ASIN" => Func::Asin,
            b"ACOS" => Func::Acos,
            b"ATAN" => Func::Atan,
            b"SQ" => Func::Sq,
            b"SQRT" => Func::Sqrt,
            b"LN" => Func::Ln,
            b"LOG" => Func::Log,
            b"EXP" => Func::Exp,
            b"NEG" => Func::Neg,
            b"INT" => Func::Int,
            b"ABS" => Func::Abs,
            b"FRAC" => Func::Frac,
            b"SGN" => Func::Sgn,
            _ => return None,
        })
    }

    fn apply(self, x: f64) -> Result<f64, ProgramError> {
        let bad = |what: &str| Err(ProgramError::Arithmetic(format!("{what} of {x}")));
        Ok(match self {
            Func::Sin => x.to_radians().sin(),
            Func::Cos => x.to_radians().cos(),
            Func::Tan => x.to_radians().tan(),
            Func::Asin if (-1.0..=1.0).contains(&x) => x.asin().to_degrees(),
            Func::Asin => return bad("ASIN"),
            Func::Acos if (-1.0..=1.0).contains(&x) => x.acos().to_degrees(),
            Func::Acos => return bad("ACOS"),
            Func::Atan => x.atan().to_degrees(),
            Func::Sq => x * x,
            Func::Sqrt if x >= 0.0 => x.sqrt(),
            Func::Sqrt => return bad("square root"),
            Func::Ln if x > 0.0 => x.ln(),
            Func::Ln => return bad("LN"),
            Func::Log if x > 0.0 => x.log10(),
            Func::Log => return bad("LOG"),
            Func::Exp => x.exp(),
            Func::Neg => -x,
            Func::Int => x.trunc(),
            Func::Abs => x.abs(),
            Func::Frac => x.fract(),
            Func::Sgn => {
                if x > 0.0 {
                    1.0
                } else if x < 0.0 {
                    -1.0
                } else {
                    0.0
                }
            }
        })
    }
}

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum BinOp {
    /// `+`.
    Add,
    /// `-`.
    Sub,
    /// `*`.
    Mul,
    /// `/` (FN 4 DIV).
    Div,
    /// `%`: remainder.
    Rem,
    /// `^`: power.
    Pow,
    /// FN 8: √(a² + b²)
    Len,
    /// FN 13: angle of the vector (a, b) in degrees, atan2(b, a)
    Ang,
}

/// One postfix instruction.
///
/// Numeric formulas use the number stack only; string formulas (see
/// [`super::strings`]) also use a string stack: `PushText`, `PushQs`, `Concat`, `ToChar` and
/// `SubStr` produce strings, the other string functions produce numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Rpn {
    /// Push a value.
    Push(Value),
    /// Replace the top value by a function of it.
    Unary(Func),
    /// Replace the two top values by an operation on them.
    Binary(BinOp),
    /// Push the text literal at bytes `start..end` of the block text (string stack).
    PushText(u32, u32),
    /// Push the contents of QS n (string stack).
    PushQs(u32),
    /// Replace the two top strings by their concatenation (`||`).
    Concat,
    /// TOCHAR: pop a number (and before it the decimals when `true`), push its text.
    ToChar(bool),
    /// SUBSTR of QS n: pop LEN and BEG, push the substring.
    SubStr(u32),
    /// STRLEN of QS n: push its number of characters (-1 when QS n is undefined).
    StrLen(u32),
    /// STRCOMP of QS a with QS b: push -1, 0 or +1.
    StrComp(u32, u32),
    /// INSTR: pop BEG, push where QS b first occurs in QS a from BEG on.
    InStr(u32, u32),
    /// TONUMB of QS n: push the number it spells.
    ToNumb(u32),
}

/// Parameter storage: Q, QL and QR families, zero until assigned, and the QS strings,
/// undefined until assigned.
#[derive(Debug, Default)]
pub(crate) struct Params {
    q: Vec<f64>,
    ql: Vec<f64>,
    qr: Vec<f64>,
    /// QS strings by index; `None` = never assigned.
    pub(super) qs: Vec<Option<String>>,
    /// QL parameters of the calling programs while a called program runs.
    saved_ql: Vec<Vec<f64>>,
}

impl Params {
    fn family(&self, kind: ParamKind) -> &Vec<f64> {
        match kind {
            ParamKind::Q => &self.q,
            ParamKind::QL => &self.ql,
            ParamKind::QR => &self.qr,
        }
    }

    /// Value of a parameter (0 when never assigned).
    pub fn get(&self, p: ParamRef) -> f64 {
        self.family(p.kind)
            .get(p.index as usize)
            .copied()
            .unwrap_or(0.0)
    }

    /// Assigns a parameter.
    pub fn set(&mut self, p: ParamRef, v: f64) {
        let fam = match p.kind {
            ParamKind::Q => &mut self.q,
            ParamKind::QL => &mut self.ql,
            ParamKind::QR => &mut self.qr,
        };
        let i = p.index.min(MAX_PARAM) as usize;
        if fam.len() <= i {
            fam.resize(i + 1, 0.0);
        }
        if let Some(slot) = fam.get_mut(i) {
            *slot = v;
        }
    }

    /// CALL PGM: QL parameters are local to a program, so the called program starts with
    /// its own (all 0) and the caller's are kept aside.
    pub fn enter_program(&mut self) {
        let caller = std::mem::take(&mut self.ql);
        self.saved_ql.push(caller);
    }

    /// End of a called program: the caller's QL parameters come back.
    pub fn leave_program(&mut self) {
        if let Some(caller) = self.saved_ql.pop() {
            self.ql = caller;
        }
    }

    /// Resolves a word value.
    pub fn value(&self, v: Value) -> f64 {
        match v {
            Value::Num(x) => x,
            Value::Param { param, negate } => {
                let x = self.get(param);
                if negate { -x } else { x }
            }
        }
    }

    /// Runs a postfix program on a number and a string stack; `text` is the block text the
    /// string literals point into.
    pub(super) fn run_code(
        &self,
        code: &[Rpn],
        stack: &mut Vec<f64>,
        strings: &mut Vec<String>,
        text: &[u8],
    ) -> Result<(), ProgramError> {
        for ins in code {
            match *ins {
                Rpn::Push(v) => stack.push(self.value(v)),
                Rpn::Unary(f) => {
                    let x = stack.pop().ok_or_else(malformed)?;
                    stack.push(f.apply(x)?);
                }
                Rpn::Binary(op) => {
                    let b = stack.pop().ok_or_else(malformed)?;
                    let a = stack.pop().ok_or_else(malformed)?;
                    stack.push(binary(op, a, b)?);
                }
                other => self.string_step(other, stack, strings, text)?,
            }
        }
        Ok(())
    }

    /// Evaluates a postfix program, using `stack` as scratch space.
    pub fn eval(&self, code: &[Rpn], stack: &mut Vec<f64>) -> Result<f64, ProgramError> {
        stack.clear();
        let mut strings = Vec::new();
        self.run_code(code, stack, &mut strings, &[])?;
        if !strings.is_empty() {
            return Err(malformed());
        }
        let v = stack.pop().ok_or_else(malformed)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(ProgramError::Arithmetic(format!(
                "result {v} is not a finite number"
            )))
        }
    }
}

pub(super) fn malformed() -> ProgramError {
    ProgramError::Arithmetic("malformed formula".into())
}

fn binary(op: BinOp, a: f64, b: f64) -> Result<f64, ProgramError> {
    Ok(match op {
        BinOp::Add => a + b,
        BinOp::Sub => a - b,
        BinOp::Mul => a * b,
        BinOp::Div | BinOp::Rem if b == 0.0 => {
            return Err(ProgramError::Arithmetic("division by zero".into()));
        }
        BinOp::Div => a / b,
        BinOp::Rem => a % b,
        BinOp::Pow => a.powf(b),
        BinOp::Len => a.hypot(b),
        BinOp::Ang => b.atan2(a).to_degrees(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn postfix_evaluation_against_direct_arithmetic() {
        let mut p = Params::default();
        let q1 = ParamRef {
            kind: ParamKind::Q,
            index: 1,
        };
        p.set(q1, 3.0);
        // (Q1 + 2) * -Q1 ^ 2  ->  postfix: Q1 2 + Q1(neg) 2 ^ *
        let code = [
            Rpn::Push(Value::Param {
                param: q1,
                negate: false,
            }),
            Rpn::Push(Value::Num(2.0)),
            Rpn::Binary(BinOp::Add),
            Rpn::Push(Value::Param {
                param: q1,
                negate: true,
            }),
            Rpn::Push(Value::Num(2.0)),
            Rpn::Binary(BinOp::Pow),
            Rpn::Binary(BinOp::Mul),
        ];
        let mut stack = Vec::new();
        assert_eq!(p.eval(&code, &mut stack).unwrap(), 5.0 * 9.0);
        let div0 = [
            Rpn::Push(Value::Num(1.0)),
            Rpn::Push(Value::Num(0.0)),
            Rpn::Binary(BinOp::Div),
        ];
        assert!(p.eval(&div0, &mut stack).is_err());
    }

    #[test]
    fn ql_parameters_are_local_to_a_called_program() {
        let mut p = Params::default();
        let ql = |index| ParamRef {
            kind: ParamKind::QL,
            index,
        };
        let q = ParamRef {
            kind: ParamKind::Q,
            index: 1,
        };
        p.set(ql(5), 2.5);
        p.set(q, 7.0);
        p.enter_program();
        assert_eq!(p.get(ql(5)), 0.0);
        assert_eq!(p.get(q), 7.0);
        p.set(ql(5), 9.0);
        p.set(q, 8.0);
        p.leave_program();
        assert_eq!(p.get(ql(5)), 2.5);
        assert_eq!(p.get(q), 8.0);
    }
}
