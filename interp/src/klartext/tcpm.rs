//! `FUNCTION TCPM` and `FUNCTION RESET TCPM` in Klartext: reads the groups into a
//! [`TcpmMode`] (the TNC core applies it: [`crate::tnc::tcpm`]).

use super::lexer::{Lexer, TokKind};
use super::parser::{PResult, Stmt, text_of, unexpected, upper};
use crate::diag::ProgramError;
use crate::tnc::tcpm::TcpmMode;

/// The next token as an upper-case word, with its position; `None` for anything else.
fn next_word(lx: &mut Lexer<'_>) -> (Option<([u8; 16], usize)>, usize) {
    let t = lx.next_token();
    let at = t.start();
    if t.kind != TokKind::Ident {
        return (None, at);
    }
    (Some(upper(lx.slice(t))), at)
}

/// Reads the choice after a group word (`F` → `TCP`|`CONT`, …): true for `second`.
fn choice(lx: &mut Lexer<'_>, group: &'static str, first: &[u8], second: &[u8]) -> PResult<bool> {
    let (w, at) = next_word(lx);
    match w {
        Some((u, n)) if &u[..n] == first => Ok(false),
        Some((u, n)) if &u[..n] == second => Ok(true),
        _ => Err((
            at,
            ProgramError::Unexpected(format!(
                "word after {group} in FUNCTION TCPM (expected {} or {})",
                text_of(first),
                text_of(second)
            )),
        )),
    }
}

/// Reads `REFPNT TIP-TIP`; the forms with CENTER are refused (see the module notes).
fn refpnt(lx: &mut Lexer<'_>) -> PResult<()> {
    let (a, at) = next_word(lx);
    let dash = lx.next_token();
    let (b, _) = next_word(lx);
    let word = |w: Option<([u8; 16], usize)>| w.map(|(u, n)| text_of(&u[..n]));
    let (a, b) = (word(a), word(b));
    match (a.as_deref(), dash.kind, b.as_deref()) {
        (Some("TIP"), TokKind::Minus, Some("TIP")) => Ok(()),
        (Some(a @ ("TIP" | "CENTER")), TokKind::Minus, Some(b @ ("TIP" | "CENTER"))) => Err((
            at,
            ProgramError::NotSupported(format!(
                "FUNCTION TCPM REFPNT {a}-{b} (klar holds the tool tip: REFPNT TIP-TIP)"
            )),
        )),
        _ => Err((
            at,
            ProgramError::Unexpected(
                "word after REFPNT (expected TIP-TIP, TIP-CENTER or CENTER-CENTER)".into(),
            ),
        )),
    }
}

/// Reads `FUNCTION TCPM …` / `FUNCTION RESET TCPM`; other FUNCTION blocks are reported as not
/// supported.
pub(super) fn parse_function(lx: &mut Lexer<'_>) -> PResult<Stmt> {
    let t = lx.next_token();
    let (u, n) = upper(lx.slice(t));
    match &u[..n] {
        b"TCPM" => {}
        b"RESET" => {
            let t2 = lx.next_token();
            if !lx.slice(t2).eq_ignore_ascii_case(b"TCPM") {
                return Ok(Stmt::Unsupported {
                    what: "FUNCTION RESET",
                    number: None,
                });
            }
            return match lx.next_token() {
                t3 if t3.kind == TokKind::End => Ok(Stmt::Tcpm {
                    on: false,
                    mode: TcpmMode::default(),
                }),
                t3 => Err(unexpected(lx, t3)),
            };
        }
        _ => {
            return Ok(Stmt::Unsupported {
                what: "FUNCTION",
                number: None,
            });
        }
    }
    let mut mode = TcpmMode::default();
    let mut seen = [false; 4];
    loop {
        let t = lx.next_token();
        if t.kind == TokKind::End {
            return Ok(Stmt::Tcpm { on: true, mode });
        }
        if t.kind != TokKind::Ident {
            return Err(unexpected(lx, t));
        }
        let (u, n) = upper(lx.slice(t));
        let group = match &u[..n] {
            b"F" => 0,
            b"AXIS" => 1,
            b"PATHCTRL" => 2,
            b"REFPNT" => 3,
            _ => return Err(unexpected(lx, t)),
        };
        if std::mem::replace(&mut seen[group], true) {
            return Err((t.start(), ProgramError::DuplicateWord(text_of(&u[..n]))));
        }
        match group {
            0 => mode.cont = choice(lx, "F", b"TCP", b"CONT")?,
            1 => mode.spatial = choice(lx, "AXIS", b"POS", b"SPAT")?,
            2 => mode.vector = choice(lx, "PATHCTRL", b"AXIS", b"VECTOR")?,
            _ => refpnt(lx)?,
        }
    }
}
