//! Q parameter assignments: `FN 0..8, 13` and `Qn = formula`, compiled to postfix code.

use super::lexer::{Lexer, TokKind};
use super::parser::{
    MAX_DEPTH, PResult, Parser, Stmt, describe, param_index, param_kind, required, text_of,
    unexpected, upper,
};
use crate::diag::ProgramError;
use crate::tnc::expr::Value;
use crate::tnc::expr::{BinOp, Func, ParamRef, Rpn};

impl Parser {
    /// `FN n: target = operands`.
    pub(super) fn function(&mut self, lx: &mut Lexer<'_>) -> PResult<Stmt> {
        let t = lx.next_token();
        if t.kind != TokKind::Num {
            return Err((t.start(), ProgramError::MissingValue("FN".into())));
        }
        let n = lx.num(t);
        if n.fract() != 0.0 || !(0.0..100.0).contains(&n) {
            return Err((
                t.start(),
                ProgramError::OutOfRange(format!("FN {n} is not a Q parameter function")),
            ));
        }
        let n = n as u32;
        if !matches!(n, 0..=8 | 13) {
            return self.fn_other(lx, n);
        }
        let c = lx.next_token();
        if c.kind != TokKind::Colon {
            return Err((
                c.start(),
                ProgramError::Missing("expected ':' after FN number"),
            ));
        }
        let q = lx.next_token();
        let (u, len) = upper(lx.slice(q));
        let kind = match (q.kind, param_kind(&u[..len])) {
            (TokKind::Ident, Some(k)) => k,
            _ => {
                return Err((
                    q.start(),
                    ProgramError::Missing("expected the Q parameter to assign"),
                ));
            }
        };
        let target = param_index(lx, kind, q.start())?;
        let e = lx.next_token();
        if e.kind != TokKind::Eq {
            return Err((
                e.start(),
                ProgramError::Missing("expected '=' after the parameter"),
            ));
        }
        self.code.clear();
        let operand = |lx: &mut Lexer<'_>, code: &mut Vec<Rpn>| -> PResult<()> {
            let p = lx.peek().start();
            let v = required(lx, "operand", p)?;
            code.push(Rpn::Push(v));
            Ok(())
        };
        let func_word = |lx: &mut Lexer<'_>, word: &[u8]| -> PResult<()> {
            let t = lx.next_token();
            if t.kind == TokKind::Ident && lx.slice(t).eq_ignore_ascii_case(word) {
                Ok(())
            } else {
                Err((t.start(), ProgramError::Unexpected(describe(lx, t))))
            }
        };
        match n {
            0 => operand(lx, &mut self.code)?,
            5..=7 => {
                let (word, f) = match n {
                    5 => (&b"SQRT"[..], Func::Sqrt),
                    6 => (&b"SIN"[..], Func::Sin),
                    _ => (&b"COS"[..], Func::Cos),
                };
                func_word(lx, word)?;
                operand(lx, &mut self.code)?;
                self.code.push(Rpn::Unary(f));
            }
            _ => {
                operand(lx, &mut self.code)?;
                let op = lx.next_token();
                let ok = match (n, op.kind) {
                    (1, TokKind::Plus) => Some(BinOp::Add),
                    (2, TokKind::Minus) => Some(BinOp::Sub),
                    (3, TokKind::Star) => Some(BinOp::Mul),
                    (4, TokKind::Ident) if lx.slice(op).eq_ignore_ascii_case(b"DIV") => {
                        Some(BinOp::Div)
                    }
                    (8, TokKind::Ident) if lx.slice(op).eq_ignore_ascii_case(b"LEN") => {
                        Some(BinOp::Len)
                    }
                    (13, TokKind::Ident) if lx.slice(op).eq_ignore_ascii_case(b"ANG") => {
                        Some(BinOp::Ang)
                    }
                    _ => None,
                };
                let Some(bin) = ok else {
                    return Err((
                        op.start(),
                        ProgramError::Unexpected(format!("{} in FN {n}", describe(lx, op))),
                    ));
                };
                operand(lx, &mut self.code)?;
                self.code.push(Rpn::Binary(bin));
            }
        }
        let end = lx.next_token();
        if end.kind != TokKind::End {
            return Err(unexpected(lx, end));
        }
        Ok(Stmt::Assign { target })
    }

    /// `Qn = formula`.
    pub(super) fn assignment(&mut self, lx: &mut Lexer<'_>, target: ParamRef) -> PResult<Stmt> {
        let e = lx.next_token();
        if e.kind != TokKind::Eq {
            return Err((
                e.start(),
                ProgramError::Missing("expected '=' after the parameter"),
            ));
        }
        self.code.clear();
        self.sum(lx, 0)?;
        let end = lx.next_token();
        if end.kind != TokKind::End {
            return Err(unexpected(lx, end));
        }
        Ok(Stmt::Assign { target })
    }

    fn sum(&mut self, lx: &mut Lexer<'_>, depth: u32) -> PResult<()> {
        self.product(lx, depth)?;
        loop {
            let op = match lx.peek().kind {
                TokKind::Plus => BinOp::Add,
                TokKind::Minus => BinOp::Sub,
                _ => return Ok(()),
            };
            lx.next_token();
            self.product(lx, depth)?;
            self.code.push(Rpn::Binary(op));
        }
    }

    fn product(&mut self, lx: &mut Lexer<'_>, depth: u32) -> PResult<()> {
        self.unary(lx, depth)?;
        loop {
            let op = match lx.peek().kind {
                TokKind::Star => BinOp::Mul,
                TokKind::Slash => BinOp::Div,
                TokKind::Percent => BinOp::Rem,
                _ => return Ok(()),
            };
            lx.next_token();
            self.unary(lx, depth)?;
            self.code.push(Rpn::Binary(op));
        }
    }

    fn unary(&mut self, lx: &mut Lexer<'_>, depth: u32) -> PResult<()> {
        let t = lx.peek();
        if depth > MAX_DEPTH {
            return Err((
                t.start(),
                ProgramError::OutOfRange(format!("formula nested deeper than {MAX_DEPTH}")),
            ));
        }
        match t.kind {
            TokKind::Plus => {
                lx.next_token();
                self.unary(lx, depth + 1)
            }
            TokKind::Minus => {
                lx.next_token();
                self.unary(lx, depth + 1)?;
                self.code.push(Rpn::Unary(Func::Neg));
                Ok(())
            }
            _ => {
                self.atom(lx, depth)?;
                if lx.peek().kind == TokKind::Caret {
                    lx.next_token();
                    self.unary(lx, depth + 1)?;
                    self.code.push(Rpn::Binary(BinOp::Pow));
                }
                Ok(())
            }
        }
    }

    fn atom(&mut self, lx: &mut Lexer<'_>, depth: u32) -> PResult<()> {
        let t = lx.next_token();
        match t.kind {
            TokKind::Num => {
                self.code.push(Rpn::Push(Value::Num(lx.num(t))));
                Ok(())
            }
            TokKind::LParen => {
                self.sum(lx, depth + 1)?;
                let c = lx.next_token();
                if c.kind == TokKind::RParen {
                    Ok(())
                } else {
                    Err((c.start(), ProgramError::Missing("expected ')'")))
                }
            }
            TokKind::Ident => {
                let (u, n) = upper(lx.slice(t));
                let name = &u[..n];
                if let Some(kind) = param_kind(name) {
                    let param = param_index(lx, kind, t.start())?;
                    self.code.push(Rpn::Push(Value::Param {
                        param,
                        negate: false,
                    }));
                    Ok(())
                } else if name == b"PI" {
                    self.code.push(Rpn::Push(Value::Num(std::f64::consts::PI)));
                    Ok(())
                } else if let Some(f) = Func::from_name(name) {
                    self.unary(lx, depth + 1)?;
                    self.code.push(Rpn::Unary(f));
                    Ok(())
                } else if matches!(name, b"STRLEN" | b"STRCOMP" | b"INSTR" | b"TONUMB") {
                    self.string_number(lx, name, t.start())
                } else if name == b"QS" {
                    Err((
                        t.start(),
                        ProgramError::Unexpected(
                            "string parameter QS in a number formula (convert it with TONUMB( SRC_QSn ))"
                                .into(),
                        ),
                    ))
                } else if matches!(name, b"SUBSTR" | b"TOCHAR") {
                    Err((
                        t.start(),
                        ProgramError::Unexpected(format!(
                            "{} in a number formula: it gives a text (assign it to a QS parameter)",
                            text_of(name)
                        )),
                    ))
                } else if name == b"CFGREAD" {
                    Err((
                        t.start(),
                        ProgramError::NotSupported("CFGREAD (machine configuration data)".into()),
                    ))
                } else {
                    Err(unexpected(lx, t))
                }
            }
            TokKind::End => Err((t.start(), ProgramError::Missing("formula ends too early"))),
            _ => Err(unexpected(lx, t)),
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::interpreter::Interpreter;
    use crate::op::{OpKind, Pose};

    /// X of the single line each program moves to (`L X+Q1`).
    fn x_of(body: &str) -> Result<f64, String> {
        let src = format!("BEGIN PGM F MM\n{body}\nL X+Q1 F100\nEND PGM F MM\n");
        let mut x = None;
        for r in Interpreter::from_source("f.h", &src, Pose::ZERO) {
            if let OpKind::Line { to, .. } = r.map_err(|d| d.to_string())?.kind {
                x = Some(to.0[0]);
            }
        }
        x.ok_or_else(|| "no motion".into())
    }

    #[test]
    fn precedence_and_associativity() {
        let cases: [(&str, f64); 8] = [
            ("Q1 = 10 - 4 - 3", 3.0),
            ("Q1 = 2 ^ 3 ^ 2", 512.0),
            ("Q1 = -2 ^ 2", -4.0),
            ("Q1 = 7 % 4 * 2", 6.0),
            ("Q1 = 2 + 3 * 4 ^ 2 / 8", 8.0),
            ("Q1 = SQRT 16 + 1", 5.0),
            ("QS1 = \"abc\"\nQ1 = 1 + STRLEN( SRC_QS1 ) ^ 2", 10.0),
            ("QS1 = \"abc\"\nQ1 = -STRLEN( SRC_QS1 ) * 2", -6.0),
        ];
        for (body, want) in cases {
            let got = x_of(body).unwrap();
            assert!((got - want).abs() < 1e-12, "{body}: {got} != {want}");
        }
    }

    #[test]
    fn continued_formula_lines() {
        // a formula continued with `~` on the next line (as in real exports)
        let x =
            x_of("Q4 = 0,5\nQ1 = COS ( Q4 * 120 ) * 4 + ( 5 * ~\n    SIN ( 30 ) ) + 1").unwrap();
        assert!((x - (0.5 * 4.0 + 2.5 + 1.0)).abs() < 1e-12, "{x}");
        let e = x_of("Q1 = 1 + ~\n   FOO").unwrap_err();
        assert!(e.starts_with("f.h:3:4: unexpected word 'FOO'"), "{e}");
        let e = x_of("Q1 = 1 + NOSUCH( 2 )").unwrap_err();
        assert!(e.starts_with("f.h:2:10:"), "{e}");
    }
}
