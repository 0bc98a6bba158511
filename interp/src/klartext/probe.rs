//! Parsing of touch-probe blocks: `TCH PROBE n NAME` with `Qn=value` assignments (current
//! format, cycles 400 and up) and the old sub-block format of cycles 0 and 1
//! (`TCH PROBE 0.0 REF. PLANE Q10 Z-`, `TCH PROBE 0.1 X+5 Y+0 Z-5`). The words are kept as
//! for `CYCL DEF` (see [`super::cycle`]) and interpreted by the TNC machine.

use super::cycle::{cycle_number, keyword, old_items, q_entries};
use super::lexer::Lexer;
use super::parser::{PResult, Parser, Stmt};
use crate::diag::ProgramError;

impl Parser {
    /// `TCH PROBE …`; `after` is the byte after the keyword `TCH`.
    pub(super) fn tch_probe(&mut self, lx: &mut Lexer<'_>, after: usize) -> PResult<Stmt> {
        let text = lx.text();
        let mut i = after;
        if !keyword(text, &mut i, b"PROBE") {
            return Err((after, ProgramError::Missing("expected PROBE after TCH")));
        }
        let at = i;
        let (number, sub) = cycle_number(text, &mut i).map_err(|_| {
            (
                at,
                ProgramError::Missing("TCH PROBE needs a touch-probe cycle number"),
            )
        })?;
        self.cycle.items.clear();
        self.cycle.q.clear();
        match sub {
            Some(0) => {
                // `0.0 REF. PLANE Q10 Z-` / `1.0 POLAR DATUM`: the result parameter and the
                // direction follow the name, whose words (`REF.`) are skipped
                let end = text.iter().position(|&b| b == b';').unwrap_or(text.len());
                let q = (i..end).find(|&k| {
                    text.get(k).is_some_and(|c| c.eq_ignore_ascii_case(&b'Q'))
                        && text.get(k + 1).is_some_and(u8::is_ascii_digit)
                        && !text
                            .get(k.wrapping_sub(1))
                            .is_some_and(u8::is_ascii_alphanumeric)
                });
                if let Some(q) = q {
                    old_items(text, q, &mut self.cycle.items)?;
                }
            }
            Some(_) => old_items(text, i, &mut self.cycle.items)?,
            None => q_entries(text, i, &mut self.cycle.q)?,
        }
        Ok(Stmt::TouchProbe { number, sub })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tnc::expr::{ParamKind, ParamRef, Value};

    fn parse(text: &str) -> Result<(Stmt, Parser), ProgramError> {
        let mut p = Parser::default();
        let b = p.parse(text.as_bytes()).map_err(|e| e.error)?;
        Ok((b.stmt, p))
    }

    #[test]
    fn current_format_keeps_the_q_assignments() {
        let (s, p) =
            parse("7 TCH PROBE 412 PRESET INSIDE CIRCLE ~\n  Q321=+50 ;CENTER ~\n  Q262=-Q5 ;DIA")
                .expect("parses");
        assert_eq!(
            s,
            Stmt::TouchProbe {
                number: 412,
                sub: None
            }
        );
        assert_eq!(p.cycle.q.len(), 2);
        assert_eq!(p.cycle.q[0].q, 321);
        assert_eq!(p.cycle.q[1].q, 262);
    }

    #[test]
    fn old_format_head_keeps_the_result_parameter_and_direction() {
        let (s, p) = parse("5 TCH PROBE 0.0 REF. PLANE Q10 Z-").expect("parses");
        assert_eq!(
            s,
            Stmt::TouchProbe {
                number: 0,
                sub: Some(0)
            }
        );
        let q10 = ParamRef {
            kind: ParamKind::Q,
            index: 10,
        };
        assert_eq!(
            p.cycle.items.first().and_then(|i| i.value),
            Some(Value::Param {
                param: q10,
                negate: false
            })
        );
        let z = p.cycle.items.get(1).expect("direction");
        assert_eq!((z.word(), z.sign_only), (&b"Z"[..], Some(true)));
        let (_, p) = parse("6 TCH PROBE 1.1 X WINKEL: +30").expect("parses");
        assert_eq!(p.cycle.items.len(), 2);
    }

    #[test]
    fn tch_without_probe_or_number_is_an_error() {
        assert!(parse("5 TCH 412").is_err());
        assert!(parse("5 TCH PROBE ABC").is_err());
    }
}
