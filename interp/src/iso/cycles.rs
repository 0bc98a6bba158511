//! TNC ISO coordinate transformations, cycle definitions and cycle calls.
//!
//! All of them run through the Klartext cycle machinery, so an ISO program and its Klartext
//! twin share one transform stack and one set of cycle generators:
//!
//! - `G54 X… Y… Z…` is the datum shift of cycle 7 (`7.1 X… Y… Z…`; under G91 the values
//!   add to the active shift like `IX…`). `G53 P01 n` takes row n of the datum table
//!   (`7.1 #n`).
//! - `G28 X Y` mirrors the listed axes (cycle 8; the axes are written without values);
//!   `G28` alone switches mirroring off.
//! - `G73 H…` rotates the working plane about the datum (cycle 10, `ROT`; under G91 the
//!   angle adds like `IROT`).
//! - `G72 F…` scales X, Y and Z about the datum by the factor F (cycle 11, `SCL`).
//! - `G62 T…` sets the path tolerance T (cycle 32); `G62` alone goes back to the
//!   machine's default.
//! - `G80 A… B… C…` tilts the working plane by spatial angles (cycle 19); `G80` alone
//!   resets it.
//! - A block starting `G2nn NAME` defines cycle nnn with the `Qnnn=value ;comment`
//!   assignments that follow, either joined with `~` or on lines of their own (without a
//!   block number); the definition is complete at the first line carrying the block end
//!   `*`, or when a numbered block or a line that is not a `Q…=` assignment follows.
//! - `G4nn NAME` with the same `Q…=` lines is touch-probe cycle 4nn (`TCH PROBE 4nn`),
//!   acting where it is defined like its Klartext twin: the same probing moves, results and
//!   presets (the cycles and their rules are in `crate::tnc::probe_cycles`).
//! - The old HEIDENHAIN cycles G83 (pecking, cycle 1) and G84 (tapping with a floating tap
//!   holder, cycle 2) take their values as operands `P01 … P05`, in the order of the
//!   sub-blocks of the Klartext cycle: G83 P01 set-up clearance, P02 total hole depth,
//!   P03 plunging depth, P04 dwell time, P05 feed rate; G84 P01 set-up clearance, P02
//!   total hole depth, P03 dwell time, P04 feed rate.
//! - `G79 [M…]` calls the last defined machining cycle at the current position
//!   (`CYCL CALL`); M99 and M89 act as in Klartext.

use std::collections::VecDeque;

use super::block::{Addr, IsoBlock, IsoWord};
use super::exec::{IsoFlow, IsoState, err, letter, m_words};
use crate::diag::ProgramError;
use crate::klartext::cycle::q_entries;
use crate::op::{AxisLetter, Op, SourceLoc};
use crate::tnc::cycle_words::{CallKind, OLD_WORD_LEN, OldItem, QEntry};
use crate::tnc::exec::{ExecError, Flow};
use crate::tnc::expr::Value;
use crate::tnc::stmt::{Stmt, Words};

/// A cycle definition whose `Q…=` lines are still being read.
#[derive(Debug)]
pub(crate) struct OpenCycle {
    number: u32,
    q: Vec<QEntry>,
    loc: SourceLoc,
}

/// An old-format cycle item `word value`.
fn item(word: &[u8], value: Option<Value>, pos: u32) -> OldItem {
    let mut w = [0u8; OLD_WORD_LEN];
    let n = word.len().min(OLD_WORD_LEN);
    if let (Some(dst), Some(src)) = (w.get_mut(..n), word.get(..n)) {
        dst.copy_from_slice(src);
    }
    OldItem {
        word: w,
        len: n as u8,
        value,
        sign_only: None,
        pos,
    }
}

fn misplaced(w: &IsoWord, g: &'static str) -> ExecError {
    let word = match w.addr {
        Addr::Letter(c) => char::from(c).to_string(),
        Addr::Dl => "DL".into(),
        Addr::Dr => "DR".into(),
    };
    err(w.pos, ProgramError::MisplacedWord { word, block: g })
}

/// The text with every block end `*` blanked, so that the Klartext reader of `Q…=` lists
/// accepts it.
fn without_stars(text: &[u8]) -> Vec<u8> {
    text.iter()
        .map(|&b| if b == b'*' { b' ' } else { b })
        .collect()
}

impl IsoState {
    /// G28, G53, G54, G62, G72, G73, G80: the cycles 8, 7, 7, 32, 11, 10, 19.
    pub(super) fn transform(
        &mut self,
        g: u32,
        g_pos: u32,
        b: &IsoBlock,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let inc = self.incremental();
        let mut items = Vec::new();
        let (number, name): (u32, &'static str) = match g {
            28 => (8, "a G28 (mirror image)"),
            53 => (7, "a G53 (datum from the table)"),
            54 => (7, "a G54 (datum shift)"),
            62 => (32, "a G62 (tolerance)"),
            72 => (11, "a G72 (scaling)"),
            73 => (10, "a G73 (rotation)"),
            _ => (19, "a G80 (tilted working plane)"),
        };
        for w in &b.words {
            let Some(c) = letter(w) else {
                return Err(misplaced(w, name));
            };
            if c == b'G' {
                continue;
            }
            let axis = AxisLetter::from_char(char::from(c)).filter(|a| !a.is_rotary());
            let it = match (g, c) {
                (28, _) if axis.is_some() && w.bare => item(&[c], None, w.pos),
                (54, _) if axis.is_some() && !w.bare => {
                    if inc {
                        item(&[b'I', c], Some(w.value), w.pos)
                    } else {
                        item(&[c], Some(w.value), w.pos)
                    }
                }
                (53, b'P') if w.count == Some(1.0) => item(b"#", Some(w.value), w.pos),
                (72, b'F') => item(b"SCL", Some(w.value), w.pos),
                (62, b'T') => item(b"T", Some(w.value), w.pos),
                (73, b'H') => item(if inc { b"IROT" } else { b"ROT" }, Some(w.value), w.pos),
                (80, b'A' | b'B' | b'C') if !w.bare => item(&[c], Some(w.value), w.pos),
                _ => return Err(misplaced(w, name)),
            };
            items.push(it);
        }
        let needs = match g {
            53 => Some("G53 needs the datum table row: G53 P01 n"),
            54 => Some("G54 needs the shift of at least one axis"),
            72 => Some("G72 needs the scaling factor F"),
            73 => Some("G73 needs the rotation angle H"),
            _ => None,
        };
        if let Some(msg) = needs
            && items.is_empty()
        {
            return Err(err(g_pos, ProgramError::Missing(msg)));
        }
        self.parser.cycle.items.clear();
        self.exec(
            &Stmt::CycleDef {
                number,
                sub: Some(0),
            },
            text,
            loc,
            out,
        )?;
        self.parser.cycle.items = items;
        self.exec(
            &Stmt::CycleDef {
                number,
                sub: Some(1),
            },
            text,
            loc,
            out,
        )?;
        Ok(())
    }

    /// G83 / G84 `P01 …`: the old cycles 1 and 2, one sub-block per operand.
    pub(super) fn old_cycle(
        &mut self,
        g: u32,
        b: &IsoBlock,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let (number, feed_line, name) = if g == 83 {
            (1, 5u8, "a G83 (pecking)")
        } else {
            (2, 4u8, "a G84 (tapping)")
        };
        let mut subs: Vec<(u8, OldItem)> = Vec::new();
        for w in &b.words {
            match (letter(w), w.count) {
                (Some(b'G'), _) => {}
                (Some(b'P'), Some(n))
                    if n >= 1.0 && n <= f64::from(feed_line) && n.fract() == 0.0 =>
                {
                    let line = n as u8;
                    if subs.iter().any(|(l, _)| *l == line) {
                        return Err(err(
                            w.pos,
                            ProgramError::DuplicateWord(format!("P{line:02}")),
                        ));
                    }
                    let word: &[u8] = if line == feed_line { b"F" } else { b"" };
                    subs.push((line, item(word, Some(w.value), w.pos)));
                }
                _ => return Err(misplaced(w, name)),
            }
        }
        subs.sort_by_key(|(l, _)| *l);
        self.parser.cycle.items.clear();
        self.exec(
            &Stmt::CycleDef {
                number,
                sub: Some(0),
            },
            text,
            loc,
            out,
        )?;
        for (line, it) in subs {
            self.parser.cycle.items = vec![it];
            self.exec(
                &Stmt::CycleDef {
                    number,
                    sub: Some(line),
                },
                text,
                loc,
                out,
            )?;
        }
        Ok(())
    }

    /// G79 [M…]: CYCL CALL.
    pub(super) fn cycle_call(
        &mut self,
        b: &IsoBlock,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<IsoFlow, ExecError> {
        if let Some(w) = b
            .words
            .iter()
            .find(|w| !matches!(letter(w), Some(b'G' | b'M')))
        {
            return Err(misplaced(w, "a G79 (cycle call)"));
        }
        let mut words = Words::default();
        m_words(b, &mut words)?;
        self.parser.words = words;
        match self.exec(
            &Stmt::CycleCall {
                kind: CallKind::Here,
            },
            text,
            loc,
            out,
        )? {
            Flow::Continue => Ok(IsoFlow::Continue),
            Flow::End => Ok(IsoFlow::End),
            _ => Err((
                None,
                ProgramError::NotSupported("this cycle call in a TNC ISO program".into()),
            )),
        }
    }

    /// The head block `G2nn NAME …` of a cycle definition; `after` is the byte after the
    /// number. The definition runs at once when the block carries its end `*`.
    pub(super) fn cycle_head(
        &mut self,
        number: u32,
        after: usize,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        self.close_cycle(text, out)?;
        let copy = without_stars(text);
        let mut q = Vec::new();
        q_entries(&copy, after, &mut q).map_err(|(p, e)| (Some(p as u32), e))?;
        self.open_cycle = Some(OpenCycle { number, q, loc });
        if text.contains(&b'*') {
            self.close_cycle(text, out)?;
        }
        Ok(())
    }

    /// A `Q…=` line while a definition is open: adds its assignments. Returns false when
    /// no definition is open (the line is a Q formula).
    pub(super) fn cycle_more(
        &mut self,
        text: &[u8],
        out: &mut VecDeque<Op>,
    ) -> Result<bool, ExecError> {
        let Some(open) = self.open_cycle.as_mut() else {
            return Ok(false);
        };
        let copy = without_stars(text);
        let mut q = Vec::new();
        q_entries(&copy, 0, &mut q).map_err(|(p, e)| (Some(p as u32), e))?;
        if q.is_empty() {
            return Err((None, ProgramError::Missing("a `Qn=value` cycle parameter")));
        }
        // positions refer to this line; the definition reports errors at its head block
        for e in &mut q {
            e.pos = 0;
        }
        open.q.extend(q);
        if text.contains(&b'*') {
            self.close_cycle(text, out)?;
        }
        Ok(true)
    }

    /// Runs an open cycle definition (at its head block's location).
    pub(super) fn close_cycle(
        &mut self,
        text: &[u8],
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let Some(open) = self.open_cycle.take() else {
            return Ok(());
        };
        self.parser.cycle.q = open.q;
        // G400 … G499 are the touch-probe cycles, `TCH PROBE 4nn` in Klartext
        let stmt = if (400..500).contains(&open.number) {
            if self.machine.measured_probing() {
                // a cycle that waits for its probing moves runs again from its block, which
                // the cycle lines of TNC ISO do not allow: refused before any motion
                self.failed_head = Some(open.loc);
                return Err((
                    None,
                    ProgramError::NotSupported(format!(
                        "G{} on a machine that measures touch points with its drives (TCH PROBE in Klartext runs there)",
                        open.number
                    )),
                ));
            }
            Stmt::TouchProbe {
                number: open.number,
                sub: None,
            }
        } else {
            Stmt::CycleDef {
                number: open.number,
                sub: None,
            }
        };
        let loc = open.loc;
        self.exec(&stmt, text, loc, out)
            .map(|_| ())
            .map_err(|(_, e)| {
                self.failed_head = Some(loc);
                (None, e)
            })
    }
}
