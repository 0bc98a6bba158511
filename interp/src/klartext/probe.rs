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
