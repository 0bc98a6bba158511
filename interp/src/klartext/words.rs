//! Address words of path blocks (`X+10`, `IPA-Q3`, `DR+`, `RL`, `F MAX`, `M3`, …).

use super::lexer::{Lexer, PlainWord, TokKind};
use super::parser::{
    Coord, FeedWord, MAX_M, PResult, Parser, Val, W_APPR, W_AXES, W_COMP, W_DR, W_FEED, W_M,
    W_POLAR, W_RADIUS, Words, axis_of, param_index, text_of, unexpected, upper, value,
};
use crate::diag::ProgramError;
use crate::op::CompSide;
use crate::tnc::expr::MAX_PARAM;
use crate::tnc::expr::{ParamKind, ParamRef, Value};

impl Parser {
    /// Parses address words until the end of the block.
    pub(super) fn words(
        &mut self,
        lx: &mut Lexer<'_>,
        allowed: u16,
        block: &'static str,
    ) -> PResult<()> {
        let w = &mut self.words;
        w.clear();
        // the previous word was M128 (an F right after it is the compensating moves' feed)
        let mut after_m128 = false;
        loop {
            if lx.at_plain_end() {
                return Ok(());
            }
            let m_before = w.m_count;
            let m128_here = std::mem::take(&mut after_m128);
            // fast path for the common plain forms `X+10`, `IY-Q2`, `F500`
            if let Some(pw) = lx.plain_word()
                && !m128_here
                && plain(w, lx.slice_range(pw.start, pw.name_end), &pw, allowed)
            {
                lx.set_pos(pw.end);
                after_m128 = w.m_count > m_before && w.m.get(usize::from(m_before)) == Some(&128);
                continue;
            }
            let t = lx.next_token();
            match t.kind {
                TokKind::End => return Ok(()),
                TokKind::Ident => {}
                _ => return Err(unexpected(lx, t)),
            }
            let raw = lx.slice(t);
            let (u, n) = upper(raw);
            let (name, q) = split_q(&u[..n], is_word);
            let class = word_class(name);
            if class == 0 {
                return Err((
                    t.start(),
                    ProgramError::UnknownWord {
                        word: text_of(raw),
                        block,
                    },
                ));
            }
            if class & allowed == 0 {
                return Err((
                    t.start(),
                    ProgramError::MisplacedWord {
                        word: text_of(name),
                        block,
                    },
                ));
            }
            let val = match q {
                Some(kind) => Val::Some(Value::Param {
                    param: param_index(lx, kind, t.start())?,
                    negate: false,
                }),
                None => value(lx)?,
            };
            let pos = t.start() as u32;
            let dup = || Err((t.start(), ProgramError::DuplicateWord(text_of(name))));
            let need = |v: Val| match v {
                Val::Some(v) => Ok(v),
                _ => Err((t.start(), ProgramError::MissingValue(text_of(name)))),
            };
            match name {
                b"PR" | b"IPR" | b"PA" | b"IPA" => {
                    let c = Coord {
                        value: need(val)?,
                        incremental: name[0] == b'I',
                        pos,
                    };
                    let slot = if name.ends_with(b"PR") {
                        &mut w.pr
                    } else {
                        &mut w.pa
                    };
                    if slot.is_some() {
                        return dup();
                    }
                    *slot = Some(c);
                }
                b"DR" => {
                    if w.dr.is_some() {
                        return dup();
                    }
                    match val {
                        Val::Sign(neg) => w.dr = Some((!neg, pos)),
                        _ => {
                            return Err((
                                t.start(),
                                ProgramError::Missing("DR needs a sign: DR+ or DR-"),
                            ));
                        }
                    }
                }
                b"RL" | b"RR" => {
                    if w.comp.is_some() {
                        return dup();
                    }
                    if !matches!(val, Val::None) {
                        return Err((
                            t.start(),
                            ProgramError::Unexpected(format!("value after {}", text_of(name))),
                        ));
                    }
                    w.comp = Some(if name == b"RL" {
                        CompSide::Left
                    } else {
                        CompSide::Right
                    });
                }
                b"R" => Self::r_word(w, val, allowed, t.start())?,
                b"F" if m128_here && w.m128_feed.is_none() && matches!(val, Val::Some(_)) => {
                    if let Val::Some(v) = val {
                        w.m128_feed = Some((v, pos));
                    }
                }
                b"F" | b"FMAX" | b"FAUTO" => {
                    if w.feed.is_some() {
                        return dup();
                    }
                    w.feed = match (name, val) {
                        (b"FMAX", Val::None) => Some(FeedWord::Max),
                        (b"FAUTO", Val::None) => Some(FeedWord::Auto),
                        (b"F", Val::Some(v)) => Some(FeedWord::Value(v)),
                        (b"F", Val::None) => {
                            let t2 = lx.peek();
                            let s2 = lx.slice(t2);
                            if t2.kind == TokKind::Ident && s2.eq_ignore_ascii_case(b"MAX") {
                                lx.next_token();
                                Some(FeedWord::Max)
                            } else if t2.kind == TokKind::Ident && s2.eq_ignore_ascii_case(b"AUTO")
                            {
                                lx.next_token();
                                Some(FeedWord::Auto)
                            } else {
                                None // empty F of old exports
                            }
                        }
                        _ => {
                            return Err((
                                t.start(),
                                ProgramError::Unexpected(format!("sign after {}", text_of(name))),
                            ));
                        }
                    };
                }
                b"M" => match val {
                    Val::None => {} // empty M of old exports
                    Val::Some(Value::Num(m)) if m >= 0.0 && m.fract() == 0.0 && m < 1e6 => {
                        let i = usize::from(w.m_count);
                        if i >= MAX_M {
                            return Err((
                                t.start(),
                                ProgramError::OutOfRange(format!(
                                    "more than {MAX_M} M words in one block"
                                )),
                            ));
                        }
                        w.m[i] = m as u32;
                        w.m_pos[i] = pos;
                        w.m_count += 1;
                        after_m128 = m == 128.0;
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
                b"MB" => {
                    // M140 MB: the retract distance, or MB MAX
                    if w.mb.is_some() {
                        return dup();
                    }
                    w.mb = Some(match val {
                        Val::Some(v) => Some(v),
                        _ => {
                            let t2 = lx.peek();
                            if t2.kind == TokKind::Ident
                                && lx.slice(t2).eq_ignore_ascii_case(b"MAX")
                            {
                                lx.next_token();
                                None
                            } else {
                                return Err((t.start(), ProgramError::MissingValue("MB".into())));
                            }
                        }
                    });
                }
                b"LEN" | b"CCA" => {
                    let slot = if name == b"LEN" {
                        &mut w.len
                    } else {
                        &mut w.cca
                    };
                    if slot.is_some() {
                        return dup();
                    }
                    *slot = Some((need(val)?, pos));
                }
                _ => {
                    // axis words X..W, IX..IW
                    let (inc, letter) = if name.len() == 2 {
                        (true, name[1])
                    } else {
                        (false, name[0])
                    };
                    let Some(axis) = axis_of(letter) else {
                        return Err((
                            t.start(),
                            ProgramError::UnknownWord {
                                word: text_of(raw),
                                block,
                            },
                        ));
                    };
                    if w.axes[axis.index()].is_some() {
                        return dup();
                    }
                    let c = Coord {
                        value: need(val)?,
                        incremental: inc,
                        pos,
                    };
                    w.set_axis(axis, c);
                }
            }
        }
    }

    /// `R` word: CR radius, or radius compensation off.
    ///
    /// In CR, RND, CHF and APPR/DEP blocks a value or a parameter is the radius; `R0`
    /// (unsigned zero) and `R` alone switch compensation off. Elsewhere `R`/`R0` mean R0 and
    /// `R+`/`R-` (no value) select paraxial compensation: lengthen or shorten the move by the
    /// tool radius.
    fn r_word(w: &mut Words, val: Val, allowed: u16, at: usize) -> PResult<()> {
        let comp_off = |w: &mut Words| {
            if w.comp.is_some() {
                return Err((at, ProgramError::DuplicateWord("R0".into())));
            }
            w.comp = Some(CompSide::Off);
            Ok(())
        };
        match val {
            Val::None => comp_off(w),
            Val::Some(Value::Num(v)) if v == 0.0 && !v.is_sign_negative() => comp_off(w),
            Val::Some(v) if allowed & W_RADIUS != 0 => {
                if w.radius.is_some() {
                    return Err((at, ProgramError::DuplicateWord("R".into())));
                }
                w.radius = Some((v, at as u32));
                Ok(())
            }
            Val::Sign(neg) => {
                if w.paraxial.is_some() || w.comp.is_some() {
                    return Err((at, ProgramError::DuplicateWord("R".into())));
                }
                w.paraxial = Some((!neg, at as u32));
                Ok(())
            }
            Val::Some(_) => Err((
                at,
                ProgramError::Unexpected("value after R (only R0, RL or RR here)".into()),
            )),
        }
    }
}

/// Stores a word seen by the lexer's fast path when it is one of the common, valid forms;
/// returns false (nothing stored) otherwise, and the token path then reads the word and
/// reports any error, so both paths give the same results.
#[inline]
fn plain(w: &mut Words, name: &[u8], pw: &PlainWord, allowed: u16) -> bool {
    let value = || -> Option<Value> {
        let v = pw.value?;
        Some(if pw.param {
            if v > f64::from(MAX_PARAM) {
                return None;
            }
            Value::Param {
                param: ParamRef {
                    kind: ParamKind::Q,
                    index: v as u32,
                },
                negate: pw.sign < 0,
            }
        } else {
            Value::Num(if pw.sign < 0 { -v } else { v })
        })
    };
    let pos = pw.start as u32;
    match name {
        // (the guard checks the letter, so that F, M and R fall through to their own arms)
        [letter] | [b'I', letter] if allowed & W_AXES != 0 && axis_of(*letter).is_some() => {
            let Some(axis) = axis_of(*letter) else {
                return false;
            };
            let (Some(value), None) = (value(), w.axes[axis.index()]) else {
                return false;
            };
            w.set_axis(
                axis,
                Coord {
                    value,
                    incremental: name.len() == 2,
                    pos,
                },
            );
            true
        }
        b"F" if allowed & W_FEED != 0 && w.feed.is_none() => match value() {
            Some(v) => {
                w.feed = Some(FeedWord::Value(v));
                true
            }
            None => false,
        },
        b"FMAX" if allowed & W_FEED != 0 && w.feed.is_none() && pw.end == pw.name_end => {
            w.feed = Some(FeedWord::Max);
            true
        }
        b"M" if allowed & W_M != 0 && pw.sign == 0 && !pw.param => {
            let i = usize::from(w.m_count);
            match pw.value {
                Some(m) if m.fract() == 0.0 && m < 1e6 && i < MAX_M => {
                    w.m[i] = m as u32;
                    w.m_pos[i] = pos;
                    w.m_count += 1;
                    true
                }
                _ => false,
            }
        }
        b"R" if allowed & W_RADIUS != 0 && w.radius.is_none() && pw.sign != 0 => match value() {
            // `R+0` stays with the token path, which reads it as R0
            Some(v) if v != Value::Num(0.0) => {
                w.radius = Some((v, pos));
                true
            }
            _ => false,
        },
        b"DR" if allowed & W_DR != 0 && w.dr.is_none() && pw.sign != 0 && pw.value.is_none() => {
            w.dr = Some((pw.sign > 0, pos));
            true
        }
        b"RL" | b"RR" if allowed & W_COMP != 0 && w.comp.is_none() && pw.end == pw.name_end => {
            w.comp = Some(if name == b"RL" {
                CompSide::Left
            } else {
                CompSide::Right
            });
            true
        }
        b"PR" | b"PA" | b"IPR" | b"IPA" if allowed & W_POLAR != 0 => {
            let slot = if name.ends_with(b"PR") {
                &mut w.pr
            } else {
                &mut w.pa
            };
            match (slot.is_none(), value()) {
                (true, Some(value)) => {
                    *slot = Some(Coord {
                        value,
                        incremental: name[0] == b'I',
                        pos,
                    });
                    true
                }
                _ => false,
            }
        }
        _ => false,
    }
}

/// True for the address words of path blocks.
fn is_word(name: &[u8]) -> bool {
    word_class(name) != 0
}

/// Splits `FQ`, `XQL`, … into the word and the parameter family when the whole identifier is
/// not itself a word.
pub(super) fn split_q(name: &[u8], known: impl Fn(&[u8]) -> bool) -> (&[u8], Option<ParamKind>) {
    if known(name) {
        return (name, None);
    }
    for (suffix, kind) in [
        (&b"QL"[..], ParamKind::QL),
        (&b"QR"[..], ParamKind::QR),
        (&b"Q"[..], ParamKind::Q),
    ] {
        if let Some(prefix) = name.strip_suffix(suffix)
            && !prefix.is_empty()
            && known(prefix)
        {
            return (prefix, Some(kind));
        }
    }
    (name, None)
}

/// The class bit of a path-block word (0 = unknown).
fn word_class(name: &[u8]) -> u16 {
    match name {
        b"X" | b"Y" | b"Z" | b"A" | b"B" | b"C" | b"U" | b"V" | b"W" => W_AXES,
        b"IX" | b"IY" | b"IZ" | b"IA" | b"IB" | b"IC" | b"IU" | b"IV" | b"IW" => W_AXES,
        b"PR" | b"PA" | b"IPR" | b"IPA" => W_POLAR,
        b"DR" => W_DR,
        b"R" => W_COMP | W_RADIUS,
        b"RL" | b"RR" => W_COMP,
        b"F" | b"FMAX" | b"FAUTO" => W_FEED,
        b"M" | b"MB" => W_M,
        b"LEN" | b"CCA" => W_APPR,
        _ => 0,
    }
}
