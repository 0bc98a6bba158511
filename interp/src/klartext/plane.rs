//! PLANE blocks in Klartext: reads the form, its angles or vectors and the positioning word
//! into the block's [`PlaneWords`] (the TNC core executes them: [`crate::tnc::plane`]).

use super::lexer::{Lexer, TokKind};
use super::parser::{PResult, Parser, Stmt, required, unexpected, upper};
use crate::diag::ProgramError;
use crate::tnc::plane::*;

/// Slots a form accepts besides DIST, F and MB.
fn accepts(kind: PlaneKind, slot: usize) -> bool {
    match kind {
        PlaneKind::Reset => false,
        PlaneKind::Spatial | PlaneKind::Relativ => (SPA..SPA + 3).contains(&slot),
        PlaneKind::Projected => (PROPR..PROPR + 3).contains(&slot),
        PlaneKind::Euler => (EULPR..EULPR + 3).contains(&slot),
        PlaneKind::Vector => (BX..NX + 3).contains(&slot),
        PlaneKind::Points => (P1X..P1X + 9).contains(&slot),
        PlaneKind::Axial => (AXA..AXA + 3).contains(&slot),
    }
}

/// Reads the rest of a PLANE block into `p.plane`.
pub(super) fn parse_plane(p: &mut Parser, lx: &mut Lexer<'_>, at: usize) -> PResult<Stmt> {
    let mut w = PlaneWords::default();
    let t = lx.next_token();
    let (u, n) = upper(lx.slice(t));
    w.kind = match (t.kind, &u[..n]) {
        (TokKind::Ident, b"SPATIAL") => PlaneKind::Spatial,
        (TokKind::Ident, b"PROJECTED") => PlaneKind::Projected,
        (TokKind::Ident, b"EULER") => PlaneKind::Euler,
        (TokKind::Ident, b"VECTOR") => PlaneKind::Vector,
        (TokKind::Ident, b"POINTS") => PlaneKind::Points,
        (TokKind::Ident, b"RELATIV" | b"RELATIVE") => PlaneKind::Relativ,
        (TokKind::Ident, b"AXIAL") => PlaneKind::Axial,
        (TokKind::Ident, b"RESET") => PlaneKind::Reset,
        _ => {
            return Err((
                t.start(),
                ProgramError::Missing(
                    "PLANE needs SPATIAL, PROJECTED, EULER, VECTOR, POINTS, RELATIV, AXIAL or RESET",
                ),
            ));
        }
    };
    loop {
        let t = lx.next_token();
        if t.kind == TokKind::End {
            break;
        }
        if t.kind != TokKind::Ident {
            return Err(unexpected(lx, t));
        }
        let (u, n) = upper(lx.slice(t));
        let word = &u[..n];
        let pos = t.start();
        let set_pos = |slot: &mut Option<Positioning>, v| match slot {
            Some(_) => Err((pos, ProgramError::DuplicateWord("MOVE/TURN/STAY".into()))),
            None => {
                *slot = Some(v);
                Ok(())
            }
        };
        match word {
            b"MOVE" => set_pos(&mut w.positioning, Positioning::Move)?,
            b"TURN" => set_pos(&mut w.positioning, Positioning::Turn)?,
            b"STAY" => set_pos(&mut w.positioning, Positioning::Stay)?,
            b"FMAX" => w.rapid = true,
            // SYM± (newer controls) chooses between the same two solutions as SEQ±.
            b"SEQ" | b"SYM" => {
                let s = lx.next_token();
                w.seq = Some(match s.kind {
                    TokKind::Plus => true,
                    TokKind::Minus => false,
                    _ => return Err((pos, ProgramError::MissingValue("SEQ (+ or -)".into()))),
                });
            }
            b"TABLE" | b"COORD" => {
                let r = lx.next_token();
                if r.kind != TokKind::Ident || !lx.slice(r).eq_ignore_ascii_case(b"ROT") {
                    return Err((pos, ProgramError::Missing("expected ROT after TABLE/COORD")));
                }
                w.table_rot = Some(word == b"TABLE");
            }
            b"F" | b"MB" if is_max(lx) => {
                lx.next_token();
                w.rapid |= word == b"F";
            }
            b"P" => {
                let num = lx.next_token();
                let k = if num.kind == TokKind::Num {
                    lx.num(num)
                } else {
                    0.0
                };
                let axis = lx.next_token();
                let (ua, na) = upper(lx.slice(axis));
                let col = match (axis.kind, &ua[..na]) {
                    (TokKind::Ident, b"X") => 0,
                    (TokKind::Ident, b"Y") => 1,
                    (TokKind::Ident, b"Z") => 2,
                    _ => return Err(unexpected(lx, axis)),
                };
                if !(k == 1.0 || k == 2.0 || k == 3.0) {
                    return Err(unexpected(lx, num));
                }
                let slot = P1X + 3 * (k as usize - 1) + col;
                store(&mut w, lx, slot, pos)?;
            }
            _ => match NAMES.iter().position(|name| *name == word) {
                Some(slot) => store(&mut w, lx, slot, pos)?,
                None => return Err(unexpected(lx, t)),
            },
        }
    }
    check_words(&w, at)?;
    p.plane = w;
    Ok(Stmt::Plane)
}

/// True when the next token is the word MAX.
fn is_max(lx: &mut Lexer<'_>) -> bool {
    let t = lx.peek();
    t.kind == TokKind::Ident && lx.slice(t).eq_ignore_ascii_case(b"MAX")
}

/// Reads the value of the word in `slot`.
fn store(w: &mut PlaneWords, lx: &mut Lexer<'_>, slot: usize, pos: usize) -> PResult<()> {
    let name = NAMES
        .get(slot)
        .map_or(String::new(), |n| super::parser::text_of(n));
    if slot < DIST && !accepts(w.kind, slot) {
        return Err((
            pos,
            ProgramError::Unexpected(format!("word {name} in this PLANE form")),
        ));
    }
    let v = required(lx, &name, pos)?;
    let cell = w
        .vals
        .get_mut(slot)
        .ok_or((pos, ProgramError::Unexpected(name.clone())))?;
    if cell.is_some() {
        return Err((pos, ProgramError::DuplicateWord(name)));
    }
    *cell = Some((v, pos as u32));
    Ok(())
}

/// Block-level rules: SPATIAL needs all three angles, RELATIV exactly one, every form a
/// positioning word.
fn check_words(w: &PlaneWords, at: usize) -> PResult<()> {
    let given = |range: std::ops::Range<usize>| range.filter(|s| w.vals[*s].is_some()).count();
    match w.kind {
        PlaneKind::Spatial if given(SPA..SPA + 3) != 3 => {
            return Err((
                at,
                ProgramError::Missing("PLANE SPATIAL needs SPA, SPB and SPC"),
            ));
        }
        PlaneKind::Relativ if given(SPA..SPA + 3) != 1 => {
            return Err((
                at,
                ProgramError::Missing("PLANE RELATIV needs exactly one of SPA, SPB, SPC"),
            ));
        }
        PlaneKind::Vector if given(BX..NX + 3) == 0 => {
            return Err((
                at,
                ProgramError::Missing("PLANE VECTOR needs BX BY BZ NX NY NZ"),
            ));
        }
        PlaneKind::Points if given(P1X..P1X + 9) == 0 => {
            return Err((at, ProgramError::Missing("PLANE POINTS needs P1 P2 P3")));
        }
        _ => {}
    }
    if w.positioning.is_none() {
        return Err((at, ProgramError::Missing("PLANE needs MOVE, TURN or STAY")));
    }
    Ok(())
}
