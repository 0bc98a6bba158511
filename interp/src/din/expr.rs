//! DIN PLUS variables and formulas: variable references, expressions and their evaluation.
//!
//! Variables (the kinds this version supports):
//! - `#l1` … `#l99`: local variables. Each main program and each subprogram call has its own
//!   set; a subprogram does not see the caller's locals.
//! - `#g1` … `#g999`: global variables, shared by the main program and all subprograms.
//! - `#c1` … `#c99`: channel variables; with one channel they behave like globals.
//! - `#__la` … `#__lz`: the transfer values of a subprogram call (`LA` … `LZ` in the call),
//!   read-only inside the called subprogram.
//!
//! Reading a variable that was never assigned is an error (no silent 0).
//!
//! Formulas (usual precedence, binary operators left-associative except `^`):
//!
//! ```text
//! or      := and ('OR' and)*
//! and     := not ('AND' not)*
//! not     := 'NOT' not | compare
//! compare := sum (('==' | '<>' | '!=' | '<' | '<=' | '>' | '>=') sum)?
//! sum     := product (('+' | '-') product)*
//! product := unary (('*' | '/') unary)*
//! unary   := ('+' | '-') unary | power
//! power   := atom ('^' unary)?
//! atom    := number | variable | PI | '(' or ')' | FUNCTION '(' or ')'
//! ```
//! A comparison or logical operator gives 1 (true) or 0 (false); a condition holds when its
//! value is not 0. Functions: SIN, COS, TAN (argument in degrees), ASIN, ACOS, ATAN (result
//! in degrees), SQRT, ABS, INT (toward zero), FRAC, ROUND (half away from zero), EXP, LN,
//! LOG (base 10). `[ … ]` is a comment in DIN PLUS, so formulas group with `( … )`.

use std::collections::HashMap;

use crate::diag::ProgramError;

/// Highest local / channel variable number.
pub const MAX_LOCAL: u32 = 99;
/// Highest global variable number.
pub const MAX_GLOBAL: u32 = 999;

/// A variable reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum VarRef {
    /// `#l n`.
    Local(u32),
    /// `#g n`.
    Global(u32),
    /// `#c n`.
    Channel(u32),
    /// `#__l<letter>`: a transfer value (`b'a'` for LA).
    Transfer(u8),
}

impl std::fmt::Display for VarRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            VarRef::Local(n) => write!(f, "#l{n}"),
            VarRef::Global(n) => write!(f, "#g{n}"),
            VarRef::Channel(n) => write!(f, "#c{n}"),
            VarRef::Transfer(c) => write!(f, "#__l{}", char::from(*c)),
        }
    }
}

/// A one-argument function.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Func {
    /// Sine of degrees.
    Sin,
    /// Cosine of degrees.
    Cos,
    /// Tangent of degrees.
    Tan,
    /// Arc sine in degrees.
    Asin,
    /// Arc cosine in degrees.
    Acos,
    /// Arc tangent in degrees.
    Atan,
    /// Square root.
    Sqrt,
    /// Absolute value.
    Abs,
    /// Integer part (toward zero).
    Int,
    /// Fractional part.
    Frac,
    /// Rounded to the nearest whole number.
    Round,
    /// e to the power.
    Exp,
    /// Natural logarithm.
    Ln,
    /// Logarithm to base 10.
    Log,
}

const FUNCS: [(&str, Func); 14] = [
    ("SIN", Func::Sin),
    ("COS", Func::Cos),
    ("TAN", Func::Tan),
    ("ASIN", Func::Asin),
    ("ACOS", Func::Acos),
    ("ATAN", Func::Atan),
    ("SQRT", Func::Sqrt),
    ("ABS", Func::Abs),
    ("INT", Func::Int),
    ("FRAC", Func::Frac),
    ("ROUND", Func::Round),
    ("EXP", Func::Exp),
    ("LN", Func::Ln),
    ("LOG", Func::Log),
];

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    /// `+`.
    Add,
    /// `-`.
    Sub,
    /// `*`.
    Mul,
    /// `/`.
    Div,
    /// `^`.
    Pow,
    /// `==`.
    Eq,
    /// `<>` or `!=`.
    Ne,
    /// `<`.
    Lt,
    /// `<=`.
    Le,
    /// `>`.
    Gt,
    /// `>=`.
    Ge,
    /// `AND`.
    And,
    /// `OR`.
    Or,
}

/// A parsed formula.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    /// A number.
    Num(f64),
    /// A variable.
    Var(VarRef),
    /// `-x`.
    Neg(Box<Expr>),
    /// `NOT x`.
    Not(Box<Expr>),
    /// A binary operation.
    Bin(BinOp, Box<Expr>, Box<Expr>),
    /// A function call.
    Call(Func, Box<Expr>),
}

/// Variables of a running program: globals and channel variables, and a stack of local
/// frames (one per active subprogram call, the main program at the bottom).
#[derive(Debug, Default)]
pub struct Vars {
    shared: HashMap<VarRef, f64>,
    frames: Vec<Frame>,
}

/// The locals and transfer values of one program level.
#[derive(Debug, Default)]
struct Frame {
    locals: HashMap<u32, f64>,
    transfer: HashMap<u8, f64>,
}

impl Vars {
    /// An empty store with the main program's frame.
    pub fn new() -> Self {
        Vars {
            shared: HashMap::new(),
            frames: vec![Frame::default()],
        }
    }

    /// Opens the frame of a subprogram call with its transfer values (letter → value).
    pub fn push_frame(&mut self, transfer: &[(u8, f64)]) {
        self.frames.push(Frame {
            locals: HashMap::new(),
            transfer: transfer.iter().copied().collect(),
        });
    }

    /// Forgets the locals of the current subprogram repetition, keeping its transfer values.
    pub fn clear_locals(&mut self) {
        if let Some(f) = self.frames.last_mut() {
            f.locals.clear();
        }
    }

    /// How many frames are open (1: the main program only).
    pub fn frames(&self) -> usize {
        self.frames.len()
    }

    /// Closes the innermost subprogram frame.
    pub fn pop_frame(&mut self) {
        if self.frames.len() > 1 {
            self.frames.pop();
        }
    }

    /// The value of a variable.
    pub fn get(&self, v: VarRef) -> Result<f64, ProgramError> {
        let found = match v {
            VarRef::Local(n) => self.frames.last().and_then(|f| f.locals.get(&n)).copied(),
            VarRef::Transfer(c) => self.frames.last().and_then(|f| f.transfer.get(&c)).copied(),
            _ => self.shared.get(&v).copied(),
        };
        found.ok_or_else(|| match v {
            VarRef::Transfer(c) => ProgramError::Arithmetic(format!(
                "{v}: the subprogram call gives no transfer value L{}",
                char::from(c.to_ascii_uppercase())
            )),
            _ => ProgramError::Arithmetic(format!("variable {v} has no value yet")),
        })
    }

    /// Assigns a variable (transfer values are read-only).
    pub fn set(&mut self, v: VarRef, value: f64) -> Result<(), ProgramError> {
        if !value.is_finite() {
            return Err(ProgramError::Arithmetic(format!(
                "{v} = {value}: not a finite number"
            )));
        }
        match v {
            VarRef::Local(n) => {
                if let Some(f) = self.frames.last_mut() {
                    f.locals.insert(n, value);
                }
            }
            VarRef::Transfer(_) => {
                return Err(ProgramError::Unexpected(format!(
                    "assignment to {v}: transfer values are read-only"
                )));
            }
            _ => {
                self.shared.insert(v, value);
            }
        }
        Ok(())
    }
}

impl Expr {
    /// Evaluates the formula.
    pub fn eval(&self, vars: &Vars) -> Result<f64, ProgramError> {
        let v = match self {
            Expr::Num(v) => *v,
            Expr::Var(r) => vars.get(*r)?,
            Expr::Neg(e) => -e.eval(vars)?,
            Expr::Not(e) => f64::from(u8::from(e.eval(vars)? == 0.0)),
            Expr::Bin(op, a, b) => {
                let (x, y) = (a.eval(vars)?, b.eval(vars)?);
                let t = |c: bool| f64::from(u8::from(c));
                match op {
                    BinOp::Add => x + y,
                    BinOp::Sub => x - y,
                    BinOp::Mul => x * y,
                    BinOp::Div => {
                        if y == 0.0 {
                            return Err(ProgramError::Arithmetic(format!("division of {x} by 0")));
                        }
                        x / y
                    }
                    BinOp::Pow => x.powf(y),
                    BinOp::Eq => t(x == y),
                    BinOp::Ne => t(x != y),
                    BinOp::Lt => t(x < y),
                    BinOp::Le => t(x <= y),
                    BinOp::Gt => t(x > y),
                    BinOp::Ge => t(x >= y),
                    BinOp::And => t(x != 0.0 && y != 0.0),
                    BinOp::Or => t(x != 0.0 || y != 0.0),
                }
            }
            Expr::Call(f, e) => {
                let x = e.eval(vars)?;
                let bad = |what: &str| Err(ProgramError::Arithmetic(format!("{what} of {x}")));
                match f {
                    Func::Sin => x.to_radians().sin(),
                    Func::Cos => x.to_radians().cos(),
                    Func::Tan => x.to_radians().tan(),
                    Func::Asin | Func::Acos if !(-1.0..=1.0).contains(&x) => {
                        return bad("arc sine/cosine");
                    }
                    Func::Asin => x.asin().to_degrees(),
                    Func::Acos => x.acos().to_degrees(),
                    Func::Atan => x.atan().to_degrees(),
                    Func::Sqrt if x < 0.0 => return bad("square root"),
                    Func::Sqrt => x.sqrt(),
                    Func::Abs => x.abs(),
                    Func::Int => x.trunc(),
                    Func::Frac => x.fract(),
                    Func::Round => x.round(),
                    Func::Exp => x.exp(),
                    Func::Ln | Func::Log if x <= 0.0 => return bad("logarithm"),
                    Func::Ln => x.ln(),
                    Func::Log => x.log10(),
                }
            }
        };
        if v.is_finite() {
            Ok(v)
        } else {
            Err(ProgramError::Arithmetic(
                "the formula has no finite value".into(),
            ))
        }
    }
}

/// A parse error at a byte position.
pub type ExprError = (usize, ProgramError);

/// Reads a formula from `text` at `*i`; stops before the first byte that cannot continue it.
pub fn parse(text: &[u8], i: &mut usize) -> Result<Expr, ExprError> {
    let mut p = Parser { text, i: *i };
    let e = p.or()?;
    *i = p.i;
    Ok(e)
}

/// Reads a parenthesised formula `( … )` at `*i` (which points at `(`).
pub fn parse_paren(text: &[u8], i: &mut usize) -> Result<Expr, ExprError> {
    let mut p = Parser { text, i: *i };
    let e = p.paren(0)?;
    *i = p.i;
    Ok(e)
}

/// Reads a variable reference at `*i` (which points at `#`).
pub fn parse_var(text: &[u8], i: &mut usize) -> Result<VarRef, ExprError> {
    let at = *i;
    let bad = |what: String| (at, ProgramError::Unexpected(what));
    if text.get(at) != Some(&b'#') {
        return Err(bad("text where a variable #… belongs".into()));
    }
    if text
        .get(at + 1..at + 4)
        .is_some_and(|t| t.eq_ignore_ascii_case(b"__l"))
    {
        let Some(c) = text.get(at + 4).filter(|c| c.is_ascii_alphabetic()) else {
            return Err(bad(
                "transfer variable without its letter (#__la … #__lz)".into()
            ));
        };
        *i = at + 5;
        return Ok(VarRef::Transfer(c.to_ascii_lowercase()));
    }
    let kind = text.get(at + 1).map(u8::to_ascii_lowercase);
    let mut j = at + 2;
    while text.get(j).is_some_and(u8::is_ascii_digit) {
        j += 1;
    }
    let digits = std::str::from_utf8(text.get(at + 2..j).unwrap_or(&[])).unwrap_or("");
    let n: u32 = digits.parse().map_err(|_| {
        bad("variable: expected #l, #g or #c followed by its number, or #__la … #__lz".into())
    })?;
    let (max, v) = match kind {
        Some(b'l') => (MAX_LOCAL, VarRef::Local(n)),
        Some(b'g') => (MAX_GLOBAL, VarRef::Global(n)),
        Some(b'c') => (MAX_LOCAL, VarRef::Channel(n)),
        _ => {
            return Err(bad(
                "variable kind: this version knows #l (local), #g (global), #c (channel) \
                 and #__l… (transfer values)"
                    .into(),
            ));
        }
    };
    if n == 0 || n > max {
        return Err((
            at,
            ProgramError::OutOfRange(format!("variable {v}: the number must be 1 to {max}")),
        ));
    }
    *i = j;
    Ok(v)
}

/// Most nested parentheses and operators in one formula.
const MAX_DEPTH: u32 = 64;

struct Parser<'a> {
    text: &'a [u8],
    i: usize,
}

impl Parser<'_> {
    fn blank(&mut self) {
        while self
            .text
            .get(self.i)
            .is_some_and(|b| *b == b' ' || *b == b'\t')
        {
            self.i += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.blank();
        self.text.get(self.i).copied()
    }

    /// Consumes `s` (ASCII, case-insensitive; a word must end at a non-letter).
    fn eat(&mut self, s: &str) -> bool {
        self.blank();
        let end = self.i + s.len();
        let Some(t) = self.text.get(self.i..end) else {
            return false;
        };
        if !t.eq_ignore_ascii_case(s.as_bytes()) {
            return false;
        }
        let word = s.bytes().all(|b| b.is_ascii_alphabetic());
        if word && self.text.get(end).is_some_and(u8::is_ascii_alphanumeric) {
            return false;
        }
        self.i = end;
        true
    }

    fn or(&mut self) -> Result<Expr, ExprError> {
        self.nested(0, Self::or_at)
    }

    fn nested(
        &mut self,
        depth: u32,
        f: fn(&mut Self, u32) -> Result<Expr, ExprError>,
    ) -> Result<Expr, ExprError> {
        if depth > MAX_DEPTH {
            return Err((
                self.i,
                ProgramError::OutOfRange(format!("formula nested deeper than {MAX_DEPTH}")),
            ));
        }
        f(self, depth)
    }

    fn or_at(&mut self, d: u32) -> Result<Expr, ExprError> {
        let mut a = self.and(d)?;
        while self.eat("OR") {
            let b = self.and(d)?;
            a = Expr::Bin(BinOp::Or, Box::new(a), Box::new(b));
        }
        Ok(a)
    }

    fn and(&mut self, d: u32) -> Result<Expr, ExprError> {
        let mut a = self.not(d)?;
        while self.eat("AND") {
            let b = self.not(d)?;
            a = Expr::Bin(BinOp::And, Box::new(a), Box::new(b));
        }
        Ok(a)
    }

    fn not(&mut self, d: u32) -> Result<Expr, ExprError> {
        if self.eat("NOT") {
            let e = self.nested(d + 1, Self::not)?;
            return Ok(Expr::Not(Box::new(e)));
        }
        self.compare(d)
    }

    fn compare(&mut self, d: u32) -> Result<Expr, ExprError> {
        let a = self.sum(d)?;
        const OPS: [(&str, BinOp); 7] = [
            ("==", BinOp::Eq),
            ("<>", BinOp::Ne),
            ("!=", BinOp::Ne),
            ("<=", BinOp::Le),
            (">=", BinOp::Ge),
            ("<", BinOp::Lt),
            (">", BinOp::Gt),
        ];
        for (s, op) in OPS {
            if self.eat(s) {
                let b = self.sum(d)?;
                return Ok(Expr::Bin(op, Box::new(a), Box::new(b)));
            }
        }
        Ok(a)
    }

    fn sum(&mut self, d: u32) -> Result<Expr, ExprError> {
        let mut a = self.product(d)?;
        loop {
            let op = match self.peek() {
                Some(b'+') => BinOp::Add,
                Some(b'-') => BinOp::Sub,
                _ => return Ok(a),
            };
            self.i += 1;
            let b = self.product(d)?;
            a = Expr::Bin(op, Box::new(a), Box::new(b));
        }
    }

    fn product(&mut self, d: u32) -> Result<Expr, ExprError> {
        let mut a = self.unary(d)?;
        loop {
            let op = match self.peek() {
                Some(b'*') => BinOp::Mul,
                Some(b'/') => BinOp::Div,
                _ => return Ok(a),
            };
            self.i += 1;
            let b = self.unary(d)?;
            a = Expr::Bin(op, Box::new(a), Box::new(b));
        }
    }

    fn unary(&mut self, d: u32) -> Result<Expr, ExprError> {
        match self.peek() {
            Some(b'-') => {
                self.i += 1;
                let e = self.nested(d + 1, Self::unary)?;
                Ok(Expr::Neg(Box::new(e)))
            }
            Some(b'+') => {
                self.i += 1;
                self.nested(d + 1, Self::unary)
            }
            _ => {
                let a = self.atom(d)?;
                if self.peek() == Some(b'^') {
                    self.i += 1;
                    let b = self.nested(d + 1, Self::unary)?;
                    return Ok(Expr::Bin(BinOp::Pow, Box::new(a), Box::new(b)));
                }
                Ok(a)
            }
        }
    }

    fn paren(&mut self, d: u32) -> Result<Expr, ExprError> {
        if !self.eat("(") {
            return Err((self.i, ProgramError::Missing("`(` after the function name")));
        }
        let e = self.nested(d + 1, Self::or_at)?;
        if !self.eat(")") {
            return Err((self.i, ProgramError::Missing("closing `)` in the formula")));
        }
        Ok(e)
    }

    fn atom(&mut self, d: u32) -> Result<Expr, ExprError> {
        let at = self.i;
        match self.peek() {
            Some(b'(') => self.paren(d),
            Some(b'#') => parse_var(self.text, &mut self.i).map(Expr::Var),
            Some(c) if c.is_ascii_digit() || c == b'.' => {
                let s = self.i;
                while self
                    .text
                    .get(self.i)
                    .is_some_and(|b| b.is_ascii_digit() || *b == b'.')
                {
                    self.i += 1;
                }
                let raw =
                    std::str::from_utf8(self.text.get(s..self.i).unwrap_or(&[])).unwrap_or("");
                raw.parse::<f64>()
                    .map(Expr::Num)
                    .map_err(|_| (s, ProgramError::Unexpected(format!("number '{raw}'"))))
            }
            Some(c) if c.is_ascii_alphabetic() => {
                if self.eat("PI") {
                    return Ok(Expr::Num(std::f64::consts::PI));
                }
                for (name, f) in FUNCS {
                    if self.eat(name) {
                        let e = self.paren(d)?;
                        return Ok(Expr::Call(f, Box::new(e)));
                    }
                }
                Err((
                    at,
                    ProgramError::Unexpected("word in a formula (not a function)".into()),
                ))
            }
            Some(c) => Err((
                self.i,
                ProgramError::Unexpected(format!("character '{}' in a formula", char::from(c))),
            )),
            None => Err((
                self.i,
                ProgramError::Missing("a value at the end of the formula"),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(s: &str, vars: &Vars) -> f64 {
        let mut i = 0;
        let e = parse(s.as_bytes(), &mut i).unwrap();
        assert_eq!(i, s.len(), "{s}");
        e.eval(vars).unwrap()
    }

    #[test]
    fn precedence_functions_and_comparisons() {
        let mut v = Vars::new();
        v.set(VarRef::Local(1), 3.0).unwrap();
        v.set(VarRef::Global(2), 4.0).unwrap();
        assert_eq!(eval("1 + 2 * 3", &v), 7.0);
        assert_eq!(eval("-2 ^ 2", &v), -4.0);
        assert_eq!(eval("2 ^ 3 ^ 2", &v), 512.0);
        assert_eq!(eval("SQRT(#l1*#l1 + #g2*#g2)", &v), 5.0);
        assert!((eval("SIN(30)", &v) - 0.5).abs() < 1e-12);
        assert_eq!(eval("#l1 < #g2 AND NOT #l1 == 4", &v), 1.0);
        assert_eq!(eval("#l1 <> 3 OR 0", &v), 0.0);
        assert_eq!(eval("(1 + 2) * 3", &v), 9.0);
    }

    #[test]
    fn errors() {
        let v = Vars::new();
        let mut i = 0;
        let e = parse(b"#l7 + 1", &mut i).unwrap();
        assert!(e.eval(&v).is_err());
        let mut i = 0;
        assert_eq!(parse(b"1 + (2", &mut i).unwrap_err().0, 6);
        let mut i = 0;
        assert!(parse(b"#x1", &mut i).is_err());
        let mut i = 0;
        assert!(parse(b"#l0", &mut i).is_err());
        let mut i = 0;
        let e = parse(b"1/(#g1-#g1)", &mut i).unwrap();
        let mut v = Vars::new();
        v.set(VarRef::Global(1), 2.0).unwrap();
        assert!(e.eval(&v).is_err());
        let deep = "(".repeat(200) + "1" + &")".repeat(200);
        let mut i = 0;
        assert!(parse(deep.as_bytes(), &mut i).is_err());
    }
}
