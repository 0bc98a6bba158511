//! ISO D-functions: D00–D08 and D13 compute a Q parameter (FN 0–8, 13 of Klartext), D09–D12
//! are the conditional jumps (FN 9–12) to a `G98` label.
//!
//! Form: `D01 Q6 P01 +Q5 P02 +Q108`: the target Q, then the operands P01, P02 (and for jumps
//! P03, the label number).

use std::collections::VecDeque;

use super::block::IsoBlock;
use super::block::IsoWord;
use super::exec::{IsoFlow, IsoState, code, err, letter};
use crate::diag::ProgramError;
use crate::klartext::parser::Stmt;
use crate::op::{Op, SourceLoc};
use crate::tnc::exec::ExecError;
use crate::tnc::expr::{BinOp, Func, ParamKind, ParamRef, Rpn, Value};

impl IsoState {
    /// D00–D13: parameter functions; D09–D12 conditional jumps.
    pub(super) fn d_function(
        &mut self,
        b: &IsoBlock,
        d: &IsoWord,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<IsoFlow, ExecError> {
        let n = code(d, "D")?;
        let operand = |i: u32| -> Result<Value, ExecError> {
            b.words
                .iter()
                .find(|w| letter(w) == Some(b'P') && w.count == Some(f64::from(i)))
                .map(|w| w.value)
                .ok_or((
                    Some(d.pos),
                    ProgramError::Missing("D function operand P01/P02 missing"),
                ))
        };
        if (9..=12).contains(&n) {
            let a = self.machine.params.value(operand(1)?);
            let c = self.machine.params.value(operand(2)?);
            let target = operand(3)?;
            let label = match target {
                Value::Num(v) if v >= 0.0 && v.fract() == 0.0 && v <= 65_535.0 => v as u32,
                _ => {
                    return Err((
                        Some(d.pos),
                        ProgramError::OutOfRange("jump target P03 must be a label number".into()),
                    ));
                }
            };
            let jump = match n {
                9 => a == c,
                10 => a != c,
                11 => a > c,
                _ => a < c,
            };
            return Ok(if jump {
                IsoFlow::Goto(label)
            } else {
                IsoFlow::Continue
            });
        }
        let q = b
            .words
            .iter()
            .find(|w| letter(w) == Some(b'Q'))
            .ok_or((Some(d.pos), ProgramError::Missing("D function needs a Q")))?;
        let index = match q.value {
            Value::Num(v) if v >= 0.0 && v.fract() == 0.0 && v <= 65_535.0 => v as u32,
            _ => {
                return Err(err(
                    q.pos,
                    ProgramError::OutOfRange("the Q to assign needs a number".into()),
                ));
            }
        };
        let target = ParamRef {
            kind: ParamKind::Q,
            index,
        };
        let code_buf = &mut self.parser.code;
        code_buf.clear();
        code_buf.push(Rpn::Push(operand(1)?));
        match n {
            0 => {}
            1..=4 | 8 | 13 => {
                code_buf.push(Rpn::Push(operand(2)?));
                code_buf.push(Rpn::Binary(match n {
                    1 => BinOp::Add,
                    2 => BinOp::Sub,
                    3 => BinOp::Mul,
                    4 => BinOp::Div,
                    8 => BinOp::Len,
                    _ => BinOp::Ang,
                }));
            }
            5 => code_buf.push(Rpn::Unary(Func::Sqrt)),
            6 => code_buf.push(Rpn::Unary(Func::Sin)),
            7 => code_buf.push(Rpn::Unary(Func::Cos)),
            other => {
                return Err(err(
                    d.pos,
                    ProgramError::NotSupported(format!("D{other:02}")),
                ));
            }
        }
        self.exec(&Stmt::Assign { target }, &[], loc, out)?;
        Ok(IsoFlow::Continue)
    }
}
