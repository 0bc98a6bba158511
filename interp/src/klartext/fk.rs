//! FK free contour programming: the words of FPOL, FL, FLT, FC, FCT and FSELECT blocks.
//!
//! An FK block describes a line (FL, FLT) or an arc (FC, FCT) by whatever is known about it;
//! the geometry is solved in [`crate::tnc::fk_solve`]. Words taken here (axis letters are those of
//! the working plane):
//! - end point `X Y` (`IX IY`: relative to the element's start point), polar `PR PA`
//!   (`IPR IPA`: relative to the polar coordinates of the start point) about the FPOL pole;
//! - `AN` the direction of travel of a line, or the entry tangent of an arc (degrees from the
//!   first plane axis); `LEN` the length of a line, or the chord (the straight distance
//!   from start to end) of an arc; `CCA` the angle at which the end point of an arc lies,
//!   seen from its centre;
//! - arcs: `DR+`/`DR-`, radius `R`, centre `CCX CCY` (`ICCX ICCY`: relative to the start
//!   point) or `CCPR CCPA` about the FPOL pole;
//! - `CLSD+` marks the first element of a closed contour, `CLSD-` the last one (its end is
//!   the start of the `CLSD+` element);
//! - auxiliary points `P1X P1Y`, `P2X P2Y`, `P3X P3Y` lying on the element (for lines also on
//!   its extension); `PDX PDY` with `D`: a point at distance D from the element;
//! - relative data `RX n`, `RY n`, `RPR n`, `RPA n`, `RAN n`, `RCCX n`, `RCCY n`, `RCCPR n`,
//!   `RCCPA n`: the matching incremental word (`IX`, `IPR`, `AN`, `ICCX`, …) is then taken
//!   relative to the end point (for RAN: the end direction) of the FK element of block `n`;
//! - `F`, `FMAX`, `FAUTO`, `M`, `RL`, `RR`, `R0` as in L blocks.
//!
//! `FPOL X Y` sets the pole of FK polar data in the working plane (`IX IY`: relative to the
//! current position); it stays until the next FPOL and is independent of CC.
//! `FSELECT n` picks solution `n` when the data leave several (see [`crate::tnc::fk_solve`]).

use super::lexer::{Lexer, TokKind};
use super::parser::{
    Coord, FeedWord, MAX_M, PResult, Parser, Stmt, Val, text_of, unexpected, upper, value,
};
use crate::diag::ProgramError;
use crate::op::CompSide;
use crate::tnc::expr::Value;
use crate::tnc::fk_words::*;

/// Index 0..3 of the axis letter `X`, `Y`, `Z` ending `name`, when `name` is `prefix` + letter.
fn axis_suffix(name: &[u8], prefix: &[u8]) -> Option<usize> {
    let rest = name.strip_prefix(prefix)?;
    match rest {
        b"X" => Some(0),
        b"Y" => Some(1),
        b"Z" => Some(2),
        _ => None,
    }
}

impl Parser {
    /// Parses the words of an FK block after its keyword.
    pub(super) fn fk_block(&mut self, lx: &mut Lexer<'_>, kind: FkKind) -> PResult<Stmt> {
        let block = match kind {
            FkKind::Pole => "FPOL",
            FkKind::Line => "FL",
            FkKind::LineTangent => "FLT",
            FkKind::Arc => "FC",
            FkKind::ArcTangent => "FCT",
            FkKind::Select => "FSELECT",
        };
        let mut f = FkWords::default();
        if kind == FkKind::Select {
            let t = lx.next_token();
            let n = if t.kind == TokKind::Num {
                lx.num(t)
            } else {
                0.0
            };
            if !((1.0..=99.0).contains(&n) && n.fract() == 0.0) {
                return Err((
                    t.start(),
                    ProgramError::Missing("FSELECT needs the solution number (1, 2, …)"),
                ));
            }
            f.select = Some((n as u32, t.start() as u32));
            let t = lx.next_token();
            if t.kind != TokKind::End {
                return Err(unexpected(lx, t));
            }
            self.fk = f;
            return Ok(Stmt::Fk(kind));
        }
        let arc = matches!(kind, FkKind::Arc | FkKind::ArcTangent);
        loop {
            let t = lx.next_token();
            match t.kind {
                TokKind::End => break,
                TokKind::Ident => {}
                _ => return Err(unexpected(lx, t)),
            }
            let raw = lx.slice(t);
            let (u, n) = upper(raw);
            let name = &u[..n];
            let pos = t.start() as u32;
            let misplaced = || {
                Err((
                    t.start(),
                    ProgramError::MisplacedWord {
                        word: text_of(name),
                        block,
                    },
                ))
            };
            let dup = || Err((t.start(), ProgramError::DuplicateWord(text_of(name))));
            if kind == FkKind::Pole && !matches!(name, b"X" | b"Y" | b"Z") {
                return misplaced();
            }
            // P1X … P3Y: the lexer splits them into `P`, `1`, `X`
            if name == b"P" {
                let nt = lx.next_token();
                let k = if nt.kind == TokKind::Num {
                    lx.num(nt)
                } else {
                    0.0
                };
                let at = lx.next_token();
                let ax = if at.kind == TokKind::Ident && at.start() == nt.end() {
                    axis_suffix(&upper(lx.slice(at)).0[..1], b"")
                } else {
                    None
                };
                let (Some(ax), true) = (ax, (k == 1.0 || k == 2.0 || k == 3.0)) else {
                    return Err((
                        t.start(),
                        ProgramError::UnknownWord {
                            word: text_of(raw),
                            block,
                        },
                    ));
                };
                let i = k as usize - 1;
                let v = need(lx, name, t.start())?;
                let Some(slot) = f.aux.get_mut(i).and_then(|p| p.get_mut(ax)) else {
                    return misplaced();
                };
                if slot.is_some() {
                    return dup();
                }
                if f.aux[i].iter().all(Option::is_none) {
                    f.aux_pos[i] = pos;
                }
                f.aux[i][ax] = Some(v);
                continue;
            }
            let coord = |lx: &mut Lexer<'_>, inc: bool| -> PResult<Coord> {
                Ok(Coord {
                    value: need(lx, name, t.start())?,
                    incremental: inc,
                    pos,
                })
            };
            let block_ref = |lx: &mut Lexer<'_>| -> PResult<(u64, u32)> {
                let nt = lx.next_token();
                let v = if nt.kind == TokKind::Num {
                    lx.num(nt)
                } else {
                    -1.0
                };
                if v < 0.0 || v.fract() != 0.0 || v > 1e15 {
                    return Err((
                        t.start(),
                        ProgramError::Missing("relative FK data need a block number"),
                    ));
                }
                Ok((v as u64, pos))
            };
            let set = |slot: &mut Option<Coord>, c: Coord| -> PResult<()> {
                if slot.is_some() {
                    return Err((c.pos as usize, ProgramError::DuplicateWord(text_of(name))));
                }
                *slot = Some(c);
                Ok(())
            };
            let set_ref = |slot: &mut RelRef, r: (u64, u32)| -> PResult<()> {
                if slot.is_some() {
                    return Err((r.1 as usize, ProgramError::DuplicateWord(text_of(name))));
                }
                *slot = Some(r);
                Ok(())
            };
            if let Some(ax) = axis_suffix(name, b"") {
                let c = coord(lx, false)?;
                set(&mut f.end[ax], c)?;
                continue;
            }
            if let Some(ax) = axis_suffix(name, b"I") {
                let c = coord(lx, true)?;
                set(&mut f.end[ax], c)?;
                continue;
            }
            if let Some(ax) = axis_suffix(name, b"CC").or(axis_suffix(name, b"ICC")) {
                if !arc {
                    return misplaced();
                }
                let c = coord(lx, name[0] == b'I')?;
                set(&mut f.cc[ax], c)?;
                continue;
            }
            if let Some(ax) = axis_suffix(name, b"PD") {
                let v = need(lx, name, t.start())?;
                if f.pd[ax].replace(v).is_some() {
                    return dup();
                }
                continue;
            }
            if let Some(ax) = axis_suffix(name, b"RCC") {
                if !arc {
                    return misplaced();
                }
                let r = block_ref(lx)?;
                set_ref(&mut f.rel_cc[ax], r)?;
                continue;
            }
            if let Some(ax) = axis_suffix(name, b"R") {
                let r = block_ref(lx)?;
                set_ref(&mut f.rel_end[ax], r)?;
                continue;
            }
            match name {
                b"PR" | b"IPR" => {
                    let c = coord(lx, name[0] == b'I')?;
                    set(&mut f.pr, c)?;
                }
                b"PA" | b"IPA" => {
                    let c = coord(lx, name[0] == b'I')?;
                    set(&mut f.pa, c)?;
                }
                b"CCPR" | b"ICCPR" | b"CCPA" | b"ICCPA" if arc => {
                    let c = coord(lx, name[0] == b'I')?;
                    if name.ends_with(b"PR") {
                        set(&mut f.ccpr, c)?;
                    } else {
                        set(&mut f.ccpa, c)?;
                    }
                }
                b"AN" => {
                    let c = coord(lx, false)?;
                    set(&mut f.an, c)?;
                }
                b"CCA" if arc => {
                    let c = coord(lx, false)?;
                    set(&mut f.cca, c)?;
                }
                b"LEN" => {
                    let v = need(lx, name, t.start())?;
                    if f.len.replace((v, pos)).is_some() {
                        return dup();
                    }
                }
                b"D" => {
                    let v = need(lx, name, t.start())?;
                    if f.dist.replace((v, pos)).is_some() {
                        return dup();
                    }
                }
                b"DR" if arc => match value(lx)? {
                    Val::Sign(neg) => {
                        if f.dr.replace((!neg, pos)).is_some() {
                            return dup();
                        }
                    }
                    _ => {
                        return Err((
                            t.start(),
                            ProgramError::Missing("DR needs a sign: DR+ or DR-"),
                        ));
                    }
                },
                b"CLSD" => match value(lx)? {
                    Val::Sign(neg) => {
                        if f.clsd.replace((!neg, pos)).is_some() {
                            return dup();
                        }
                    }
                    _ => {
                        return Err((
                            t.start(),
                            ProgramError::Missing("CLSD needs a sign: CLSD+ or CLSD-"),
                        ));
                    }
                },
                b"R" => match value(lx)? {
                    Val::Some(Value::Num(0.0)) => {
                        if f.base.comp.replace(CompSide::Off).is_some() {
                            return dup();
                        }
                    }
                    Val::Some(v) if arc => {
                        if f.radius.replace((v, pos)).is_some() {
                            return dup();
                        }
                    }
                    Val::None => {
                        if f.base.comp.replace(CompSide::Off).is_some() {
                            return dup();
                        }
                    }
                    _ => return misplaced(),
                },
                b"RL" | b"RR" => {
                    let side = if name == b"RL" {
                        CompSide::Left
                    } else {
                        CompSide::Right
                    };
                    if f.base.comp.replace(side).is_some() {
                        return dup();
                    }
                }
                b"RPR" => set_ref(&mut f.rel_pr, block_ref(lx)?)?,
                b"RPA" => set_ref(&mut f.rel_pa, block_ref(lx)?)?,
                b"RAN" => set_ref(&mut f.rel_an, block_ref(lx)?)?,
                b"RCCPR" if arc => set_ref(&mut f.rel_ccpr, block_ref(lx)?)?,
                b"RCCPA" if arc => set_ref(&mut f.rel_ccpa, block_ref(lx)?)?,
                b"F" | b"FMAX" | b"FAUTO" => {
                    let fw = match (name, value(lx)?) {
                        (b"FMAX", Val::None) => FeedWord::Max,
                        (b"FAUTO", Val::None) => FeedWord::Auto,
                        (b"F", Val::Some(v)) => FeedWord::Value(v),
                        _ => return Err((t.start(), ProgramError::MissingValue("F".into()))),
                    };
                    if f.base.feed.replace(fw).is_some() {
                        return dup();
                    }
                }
                b"M" => match value(lx)? {
                    Val::Some(Value::Num(m)) if m >= 0.0 && m.fract() == 0.0 && m < 1e6 => {
                        let i = usize::from(f.base.m_count);
                        if i >= MAX_M {
                            return Err((
                                t.start(),
                                ProgramError::OutOfRange(format!(
                                    "more than {MAX_M} M words in one block"
                                )),
                            ));
                        }
                        f.base.m[i] = m as u32;
                        f.base.m_pos[i] = pos;
                        f.base.m_count += 1;
                    }
                    _ => {
                        return Err((
                            t.start(),
                            ProgramError::OutOfRange(
                                "M needs a whole number from 0 to 999999".into(),
                            ),
                        ));
                    }
                },
                b"CCPR" | b"CCPA" | b"ICCPR" | b"ICCPA" | b"CCA" | b"DR" | b"RCCPR" | b"RCCPA" => {
                    return misplaced();
                }
                _ => {
                    return Err((
                        t.start(),
                        ProgramError::UnknownWord {
                            word: text_of(raw),
                            block,
                        },
                    ));
                }
            }
        }
        self.fk = f;
        Ok(Stmt::Fk(kind))
    }
}

/// Reads the value of a word that needs one.
fn need(lx: &mut Lexer<'_>, name: &[u8], at: usize) -> PResult<Value> {
    match value(lx)? {
        Val::Some(v) => Ok(v),
        _ => Err((at, ProgramError::MissingValue(text_of(name)))),
    }
}
