//! Parsing of the program-structure and special path blocks: labels, calls, the FN functions
//! beyond arithmetic (jumps, error, output, system data), TOOL CALL, TOOL DEF, BLK FORM,
//! CHF, SPL and APPR/DEP.

use super::lexer::{Lexer, TokKind};
use super::parser::{
    ApprKind, Cond, LabelRef, PResult, Parser, SplineWords, Stmt, ToolCall, ToolId, Val, W_APPR,
    W_AXES, W_COMP, W_FEED, W_M, W_POLAR, W_RADIUS, axis_of, describe, param_index, param_kind,
    required, set_once, text_of, unexpected, upper, value,
};
use super::words::split_q;
use crate::diag::ProgramError;
use crate::tnc::expr::Value;
use crate::tnc::table::TableOp;

/// Largest spline exponent the TNC accepts (`E±255`).
const MAX_SPLINE_EXP: i32 = 255;

impl Parser {
    /// The label after `LBL` or `CALL LBL` / `GOTO LBL`: a whole number or a quoted name.
    pub(super) fn label_ref(&mut self, lx: &mut Lexer<'_>, at: usize) -> PResult<LabelRef> {
        let t = lx.next_token();
        match t.kind {
            TokKind::Num => {
                let n = lx.num(t);
                if n.fract() != 0.0 || !(0.0..=f64::from(u32::MAX)).contains(&n) {
                    return Err((
                        t.start(),
                        ProgramError::OutOfRange(format!("label {n} is not a whole number")),
                    ));
                }
                Ok(LabelRef::Num(n as u32))
            }
            TokKind::Str => Ok(LabelRef::Name(t.start() as u32, t.end() as u32)),
            TokKind::Ident if upper(lx.slice(t)).0.starts_with(b"QS") => Err((
                t.start(),
                ProgramError::Unexpected(
                    "QS label in LBL: a label is defined by a number or a quoted name".into(),
                ),
            )),
            TokKind::End => Err((at, ProgramError::Missing("label number or name missing"))),
            _ => Err(unexpected(lx, t)),
        }
    }

    /// Expects the end of the block.
    fn end_of_block(lx: &mut Lexer<'_>) -> PResult<()> {
        let t = lx.next_token();
        if t.kind == TokKind::End {
            Ok(())
        } else {
            Err(unexpected(lx, t))
        }
    }

    /// Expects the keyword `word` (case-insensitive).
    fn keyword(lx: &mut Lexer<'_>, word: &[u8]) -> PResult<()> {
        let t = lx.next_token();
        if t.kind == TokKind::Ident && lx.slice(t).eq_ignore_ascii_case(word) {
            Ok(())
        } else {
            Err((
                t.start(),
                ProgramError::Unexpected(format!(
                    "{} (expected {})",
                    describe(lx, t),
                    text_of(word)
                )),
            ))
        }
    }

    /// `CALL LBL label [REP k[/k]]` or `CALL PGM path`.
    pub(super) fn call(&mut self, lx: &mut Lexer<'_>, at: usize) -> PResult<Stmt> {
        let t = lx.next_token();
        let (u, n) = upper(lx.slice(t));
        match (t.kind, &u[..n]) {
            (TokKind::Ident, b"LBL") => {
                let label = self.label_target(lx, t.start())?;
                let mut rep = None;
                let r = lx.next_token();
                if r.kind == TokKind::Ident {
                    let (ru, rn) = upper(lx.slice(r));
                    let name = &ru[..rn];
                    rep = match name {
                        // an empty REP (old exports) is a plain subprogram call
                        b"REP" => match value(lx)? {
                            Val::Some(v) => Some(v),
                            Val::None => None,
                            Val::Sign(_) => {
                                return Err((r.start(), ProgramError::MissingValue("REP".into())));
                            }
                        },
                        _ => match name.strip_prefix(b"REP").and_then(param_kind) {
                            Some(kind) => Some(Value::Param {
                                param: param_index(lx, kind, r.start())?,
                                negate: false,
                            }),
                            None => return Err(unexpected(lx, r)),
                        },
                    };
                    // the file form `REP 25/25` shows the count left after the slash
                    if lx.peek().kind == TokKind::Slash {
                        lx.next_token();
                        required(lx, "REP", r.start())?;
                    }
                } else if r.kind != TokKind::End {
                    return Err(unexpected(lx, r));
                }
                Self::end_of_block(lx)?;
                Ok(Stmt::CallLbl { label, rep })
            }
            (TokKind::Ident, b"PGM") => {
                let (start, end) = path_range(lx, t.end());
                if start == end {
                    return Err((at, ProgramError::Missing("CALL PGM needs a program name")));
                }
                Ok(Stmt::CallPgm {
                    start: start as u32,
                    end: end as u32,
                })
            }
            _ => Err((
                t.start(),
                ProgramError::Missing("expected LBL or PGM after CALL"),
            )),
        }
    }

    /// The FN functions other than arithmetic: 9–12 jumps, 14 error, 15/16 output, 18 system
    /// data. Others are recognised and reported as not supported when executed.
    pub(super) fn fn_other(&mut self, lx: &mut Lexer<'_>, n: u32) -> PResult<Stmt> {
        let c = lx.next_token();
        if c.kind != TokKind::Colon {
            return Err((
                c.start(),
                ProgramError::Missing("expected ':' after FN number"),
            ));
        }
        match n {
            9..=12 => {
                Self::keyword(lx, b"IF")?;
                let p = lx.peek().start();
                let a = required(lx, "IF", p)?;
                let op = lx.next_token();
                let (ou, on) = upper(lx.slice(op));
                let cond = match &ou[..on] {
                    b"EQU" => Cond::Equ,
                    b"NE" => Cond::Ne,
                    b"GT" => Cond::Gt,
                    b"LT" => Cond::Lt,
                    b"IS" => {
                        return Err((
                            op.start(),
                            ProgramError::NotSupported("IS DEFINED / IS UNDEFINED".into()),
                        ));
                    }
                    _ => return Err(unexpected(lx, op)),
                };
                let expected = match n {
                    9 => Cond::Equ,
                    10 => Cond::Ne,
                    11 => Cond::Gt,
                    _ => Cond::Lt,
                };
                if cond != expected {
                    return Err((
                        op.start(),
                        ProgramError::Unexpected(format!(
                            "comparison {} in FN {n}",
                            text_of(&ou[..on])
                        )),
                    ));
                }
                let p = lx.peek().start();
                let b = required(lx, "comparison", p)?;
                Self::keyword(lx, b"GOTO")?;
                let l = lx.next_token();
                if !(l.kind == TokKind::Ident && lx.slice(l).eq_ignore_ascii_case(b"LBL")) {
                    return Err((l.start(), ProgramError::Missing("expected LBL after GOTO")));
                }
                let label = self.label_target(lx, l.start())?;
                Self::end_of_block(lx)?;
                Ok(Stmt::Jump { a, cond, b, label })
            }
            14 => {
                Self::keyword(lx, b"ERROR")?;
                let e = lx.next_token();
                if e.kind != TokKind::Eq {
                    return Err((e.start(), ProgramError::Missing("expected '=' after ERROR")));
                }
                let p = lx.peek().start();
                let code = required(lx, "ERROR", p)?;
                Ok(Stmt::FnError { code })
            }
            15 | 16 => {
                // FN 15: PRINT …, FN 16: F-PRINT … (`F`, `-`, `PRINT` as tokens)
                if n == 16 {
                    Self::keyword(lx, b"F")?;
                    let dash = lx.next_token();
                    if dash.kind != TokKind::Minus {
                        return Err((dash.start(), ProgramError::Missing("expected F-PRINT")));
                    }
                }
                Self::keyword(lx, b"PRINT")?;
                let kw = lx.peek();
                let (start, end) = path_range(lx, kw.start());
                Ok(Stmt::Print {
                    file: n == 16,
                    start: start as u32,
                    end: end as u32,
                })
            }
            18 => {
                Self::keyword(lx, b"SYSREAD")?;
                let q = lx.next_token();
                let (qu, qn) = upper(lx.slice(q));
                let Some(kind) = param_kind(&qu[..qn]) else {
                    return Err((
                        q.start(),
                        ProgramError::Missing("expected the Q parameter to assign"),
                    ));
                };
                let target = param_index(lx, kind, q.start())?;
                let e = lx.next_token();
                if e.kind != TokKind::Eq {
                    return Err((e.start(), ProgramError::Missing("expected '='")));
                }
                let mut id = None;
                let mut nr = None;
                let mut idx = None;
                loop {
                    let w = lx.next_token();
                    match w.kind {
                        TokKind::End => break,
                        TokKind::Ident => {}
                        _ => return Err(unexpected(lx, w)),
                    }
                    let (wu, wn) = upper(lx.slice(w));
                    let (name, q) = split_q(&wu[..wn], |n| matches!(n, b"ID" | b"NR" | b"IDX"));
                    let slot = match name {
                        b"ID" => &mut id,
                        b"NR" => &mut nr,
                        b"IDX" => &mut idx,
                        _ => return Err(unexpected(lx, w)),
                    };
                    *slot = Some(match q {
                        Some(kind) => Value::Param {
                            param: param_index(lx, kind, w.start())?,
                            negate: false,
                        },
                        None => required(lx, &text_of(name), w.start())?,
                    });
                }
                let at = lx.peek().start();
                let (Some(id), Some(nr)) = (id, nr) else {
                    return Err((at, ProgramError::Missing("SYSREAD needs ID and NR")));
                };
                Ok(Stmt::SysRead {
                    target,
                    id,
                    nr,
                    idx,
                })
            }
            26 => {
                Self::keyword(lx, b"TABOPEN")?;
                let at = lx.peek().start();
                let (start, end) = path_range(lx, at);
                if start == end {
                    return Err((at, ProgramError::Missing("TABOPEN needs the table file")));
                }
                Ok(Stmt::Table(TableOp::Open {
                    start: start as u32,
                    end: end as u32,
                }))
            }
            27 => {
                Self::keyword(lx, b"TABWRITE")?;
                let (line, cols) = table_address(lx)?;
                let e = lx.next_token();
                if e.kind != TokKind::Eq {
                    return Err((
                        e.start(),
                        ProgramError::Missing("expected '=' before the parameter"),
                    ));
                }
                let first = table_param(lx)?;
                Self::end_of_block(lx)?;
                Ok(Stmt::Table(TableOp::Write { line, cols, first }))
            }
            28 => {
                Self::keyword(lx, b"TABREAD")?;
                let target = table_param(lx)?;
                let e = lx.next_token();
                if e.kind != TokKind::Eq {
                    return Err((
                        e.start(),
                        ProgramError::Missing("expected '=' after the parameter"),
                    ));
                }
                let (line, cols) = table_address(lx)?;
                Self::end_of_block(lx)?;
                Ok(Stmt::Table(TableOp::Read { target, line, cols }))
            }
            _ => Ok(Stmt::Unsupported {
                what: "FN",
                number: Some(n),
            }),
        }
    }

    /// `TOOL DEF n|"name"|Qn [L±l] [R±r] …`.
    pub(super) fn tool_def(&mut self, lx: &mut Lexer<'_>) -> PResult<Stmt> {
        let mut number = None;
        let t = lx.peek();
        match t.kind {
            TokKind::Num => {
                lx.next_token();
                number = Some(Value::Num(lx.num(t)));
            }
            TokKind::Str => {
                lx.next_token();
            }
            TokKind::Ident => {
                let (u, n) = upper(lx.slice(t));
                if let Some(kind) = param_kind(&u[..n]) {
                    lx.next_token();
                    number = Some(Value::Param {
                        param: param_index(lx, kind, t.start())?,
                        negate: false,
                    });
                }
            }
            _ => {}
        }
        let mut length = None;
        let mut radius = None;
        loop {
            let w = lx.next_token();
            match w.kind {
                TokKind::End => break,
                TokKind::Ident => {}
                _ => return Err(unexpected(lx, w)),
            }
            let (u, n) = upper(lx.slice(w));
            let slot = match &u[..n] {
                b"L" => &mut length,
                b"R" => &mut radius,
                // DR2 and other newer TOOL DEF words carry no geometry used here
                b"DL" | b"DR" | b"DR2" | b"S" => {
                    required(lx, "TOOL DEF", w.start())?;
                    continue;
                }
                _ => return Err(unexpected(lx, w)),
            };
            *slot = Some(required(lx, &text_of(&u[..n]), w.start())?);
        }
        Ok(Stmt::ToolDef {
            number,
            length,
            radius,
        })
    }

    /// `CHF len [F..]` (also `CHF5`): the length goes to [`super::parser::Words::radius`].
    pub(super) fn chamfer(&mut self, lx: &mut Lexer<'_>, at: usize) -> PResult<Stmt> {
        let p = lx.peek().start();
        let len = required(lx, "CHF", p.max(at))?;
        self.words(lx, W_FEED | W_M, "CHF")?;
        self.words.radius = Some((len, p as u32));
        Ok(Stmt::Chamfer)
    }

    /// `SPL X.. Y.. … K3X.. K2X.. K1X.. … [F..] [M..]`, coefficients with optional exponent
    /// (`K3X+1.275 E+2`, `K2X2.459E-002`).
    pub(super) fn spline(&mut self, lx: &mut Lexer<'_>) -> PResult<Stmt> {
        self.spline = SplineWords::default();
        // First pass: pull the coefficient words out; everything else is an ordinary word.
        // The words are parsed from a copy of the block where coefficients are blanked.
        let start = lx.peek().start();
        let mut rest: Vec<u8> = lx.text().to_vec();
        let mut sub = Lexer::new(lx.text(), start);
        loop {
            let t = sub.next_token();
            match t.kind {
                TokKind::End => break,
                TokKind::Ident => {}
                _ => continue,
            }
            let raw = sub.slice(t);
            if !(raw.len() == 1 && raw[0].eq_ignore_ascii_case(&b'K')) {
                continue;
            }
            let order = sub.next_token();
            let o = if order.kind == TokKind::Num {
                sub.num(order)
            } else {
                -1.0
            };
            let slot_index = match o {
                3.0 => 0,
                2.0 => 1,
                1.0 => 2,
                _ => {
                    return Err((
                        t.start(),
                        ProgramError::Unexpected("spline word: expected K3, K2 or K1".into()),
                    ));
                }
            };
            let a = sub.next_token();
            let letter = sub.slice(a);
            let axis = match (a.kind, letter) {
                (TokKind::Ident, [c]) => axis_of(c.to_ascii_uppercase()),
                _ => None,
            };
            let Some(axis) = axis else {
                return Err((
                    a.start(),
                    ProgramError::Missing("spline coefficient needs an axis letter (K3X…)"),
                ));
            };
            let v = required(&mut sub, "K", t.start())?;
            let mut exp = 0i32;
            let e = sub.peek();
            if e.kind == TokKind::Ident && sub.slice(e).eq_ignore_ascii_case(b"E") {
                sub.next_token();
                let ev = required(&mut sub, "E", e.start())?;
                match ev {
                    Value::Num(x) if x.fract() == 0.0 && x.abs() <= f64::from(MAX_SPLINE_EXP) => {
                        exp = x as i32;
                    }
                    _ => {
                        return Err((
                            e.start(),
                            ProgramError::OutOfRange(format!(
                                "spline exponent must be a whole number from -{MAX_SPLINE_EXP} to {MAX_SPLINE_EXP}"
                            )),
                        ));
                    }
                }
            }
            let triple = &mut self.spline.k[axis.index()];
            if triple[slot_index].is_some() {
                return Err((
                    t.start(),
                    ProgramError::DuplicateWord(format!("K{}{axis}", 3 - slot_index)),
                ));
            }
            if triple.iter().skip(slot_index + 1).any(Option::is_some) {
                return Err((
                    t.start(),
                    ProgramError::Unexpected(format!(
                        "K{}{axis} after a lower coefficient: write K3, K2, K1 in that order",
                        3 - slot_index
                    )),
                ));
            }
            triple[slot_index] = Some((v, exp));
            let end = sub.peek().start();
            for b in rest.get_mut(t.start()..end).into_iter().flatten() {
                if *b != b'\n' {
                    *b = b' ';
                }
            }
        }
        let mut words_lx = Lexer::new(&rest, start);
        self.words(&mut words_lx, W_AXES | W_FEED | W_M, "SPL")?;
        Ok(Stmt::Spline)
    }

    /// `APPR|DEP LT|LN|CT|LCT|PLT|PLN|PCT|PLCT …`.
    pub(super) fn approach(&mut self, lx: &mut Lexer<'_>, approach: bool) -> PResult<Stmt> {
        let block = if approach { "APPR" } else { "DEP" };
        let t = lx.next_token();
        let (u, n) = upper(lx.slice(t));
        let (kind, polar) = match (t.kind, &u[..n]) {
            (TokKind::Ident, b"LT") => (ApprKind::Lt, false),
            (TokKind::Ident, b"LN") => (ApprKind::Ln, false),
            (TokKind::Ident, b"CT") => (ApprKind::Ct, false),
            (TokKind::Ident, b"LCT") => (ApprKind::Lct, false),
            (TokKind::Ident, b"PLT") => (ApprKind::Lt, true),
            (TokKind::Ident, b"PLN") => (ApprKind::Ln, true),
            (TokKind::Ident, b"PCT") => (ApprKind::Ct, true),
            (TokKind::Ident, b"PLCT") => (ApprKind::Lct, true),
            _ => {
                return Err((
                    t.start(),
                    ProgramError::Missing("expected LT, LN, CT, LCT, PLT, PLN, PCT or PLCT"),
                ));
            }
        };
        let coords = if polar { W_AXES | W_POLAR } else { W_AXES };
        self.words(
            lx,
            coords | W_APPR | W_RADIUS | W_COMP | W_FEED | W_M,
            block,
        )?;
        Ok(Stmt::ApproachDepart {
            approach,
            kind,
            polar,
        })
    }
}

/// `line / "COL1,COL2"` of TABREAD and TABWRITE.
fn table_address(lx: &mut Lexer<'_>) -> PResult<(Value, (u32, u32))> {
    let p = lx.peek().start();
    let line = required(lx, "the table line", p)?;
    let slash = lx.next_token();
    if slash.kind != TokKind::Slash {
        return Err((
            slash.start(),
            ProgramError::Missing("expected '/' before the column names"),
        ));
    }
    let c = lx.next_token();
    if c.kind != TokKind::Str || c.start() == c.end() {
        return Err((
            c.start(),
            ProgramError::Missing("expected the column names in quotes"),
        ));
    }
    Ok((line, (c.start() as u32, c.end() as u32)))
}

/// The Q, QL or QR parameter of TABREAD and TABWRITE.
fn table_param(lx: &mut Lexer<'_>) -> PResult<crate::tnc::expr::ParamRef> {
    let q = lx.next_token();
    let (u, n) = upper(lx.slice(q));
    match (q.kind, param_kind(&u[..n])) {
        (TokKind::Ident, Some(kind)) => param_index(lx, kind, q.start()),
        _ => Err((
            q.start(),
            ProgramError::Missing("expected a Q, QL or QR parameter"),
        )),
    }
}

/// The rest of the block from `from`, without surrounding blanks, a trailing `;` comment or
/// quotes: the argument of CALL PGM and FN 15/16.
fn path_range(lx: &Lexer<'_>, from: usize) -> (usize, usize) {
    let text = lx.text();
    let mut s = from.min(text.len());
    let mut e = text
        .iter()
        .skip(s)
        .position(|&b| b == b';' || b == b'\n')
        .map_or(text.len(), |p| p + s);
    while s < e && text.get(s).is_some_and(|b| b.is_ascii_whitespace()) {
        s += 1;
    }
    while e > s && text.get(e - 1).is_some_and(|b| b.is_ascii_whitespace()) {
        e -= 1;
    }
    if e >= s + 2 && text.get(s) == Some(&b'"') && text.get(e - 1) == Some(&b'"') {
        s += 1;
        e -= 1;
    }
    (s, e)
}

impl Parser {
    pub(super) fn blk_form(&mut self, lx: &mut Lexer<'_>) -> PResult<Stmt> {
        let t = lx.peek();
        let v = if t.kind == TokKind::Num {
            lx.num(t)
        } else {
            0.0
        };
        let corner = match t.kind {
            TokKind::Num if (v - 0.1).abs() < 1e-9 => 1,
            TokKind::Num if (v - 0.2).abs() < 1e-9 => 2,
            _ => {
                return Ok(Stmt::BlkForm {
                    corner: 0,
                    axis: None,
                });
            }
        };
        lx.next_token();
        let mut axis = None;
        if corner == 1 {
            let a = lx.peek();
            if a.kind == TokKind::Ident {
                let s = lx.slice(a);
                let next_is_value = matches!(
                    lx.byte_at(a.end()),
                    Some(b'+' | b'-' | b'0'..=b'9' | b'.' | b',')
                );
                if s.len() == 1 && !next_is_value {
                    axis = axis_of(s[0].to_ascii_uppercase());
                    if axis.is_some() {
                        lx.next_token();
                    }
                }
            }
        }
        self.words(lx, W_AXES, "BLK FORM")?;
        Ok(Stmt::BlkForm { corner, axis })
    }

    pub(super) fn tool_call(&mut self, lx: &mut Lexer<'_>) -> PResult<ToolCall> {
        let mut tc = ToolCall::default();
        let t = lx.peek();
        match t.kind {
            TokKind::Num => {
                lx.next_token();
                tc.tool = Some(ToolId::Number(Value::Num(lx.num(t))));
            }
            TokKind::Str => {
                lx.next_token();
                tc.tool = Some(ToolId::Name(t.start(), t.end()));
            }
            TokKind::Ident => {
                let (u, n) = upper(lx.slice(t));
                if let Some(kind) = param_kind(&u[..n]) {
                    lx.next_token();
                    let param = param_index(lx, kind, t.start())?;
                    tc.tool = Some(ToolId::Number(Value::Param {
                        param,
                        negate: false,
                    }));
                }
            }
            _ => {}
        }
        let a = lx.peek();
        if a.kind == TokKind::Ident {
            let s = lx.slice(a);
            if s.len() == 1 {
                let c = s[0].to_ascii_uppercase();
                if matches!(c, b'X' | b'Y' | b'Z' | b'U' | b'V' | b'W') {
                    lx.next_token();
                    tc.axis = axis_of(c);
                }
            }
        }
        loop {
            let t = lx.next_token();
            match t.kind {
                TokKind::End => break,
                TokKind::Ident => {}
                _ => return Err(unexpected(lx, t)),
            }
            let (u, n) = upper(lx.slice(t));
            let (name, q) = split_q(&u[..n], |w| matches!(w, b"S" | b"F" | b"DL" | b"DR"));
            let v = match q {
                Some(kind) => Value::Param {
                    param: param_index(lx, kind, t.start())?,
                    negate: false,
                },
                None if name == b"DR" && lx.byte_at(t.end()) == Some(b'2') => {
                    // DR2: the lexer split it into `DR` and the number; re-scan from after '2'
                    let _ = lx.next_token();
                    let v = required(lx, "DR2", t.start())?;
                    set_once(&mut tc.dr2, v, "DR2", t.start())?;
                    continue;
                }
                None => required(lx, &text_of(name), t.start())?,
            };
            let slot = match name {
                b"S" => &mut tc.speed,
                b"F" => &mut tc.feed,
                b"DL" => &mut tc.dl,
                b"DR" => &mut tc.dr,
                _ => {
                    return Err((
                        t.start(),
                        ProgramError::UnknownWord {
                            word: text_of(lx.slice(t)),
                            block: "TOOL CALL",
                        },
                    ));
                }
            };
            set_once(slot, v, &text_of(name), t.start())?;
        }
        Ok(tc)
    }
}
