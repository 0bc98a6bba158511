//! What the measuring cycles (420 … 427, 430) do with their results beyond the Q parameters:
//! the tolerance check, the workpiece status, the program stop on a tolerance error and the
//! measuring log.
//!
//! Rules, as klar applies them from the TNC 640 touch-probe manual:
//! - a cycle compares each measured size or position with the limits its parameters give
//!   (a maximum and minimum size, or a tolerance ± about the nominal position); a limit that is
//!   not programmed is not checked;
//! - the workpiece status goes to Q180 (good), Q181 (rework) or Q182 (scrap), the one that
//!   applies set to 1 and the others to 0, when the cycle checked at least one limit. Rework
//!   is material left over: a bore, slot or pocket too small, a boss, ridge or outline too
//!   large; the other way round is scrap, and so is a position off its tolerance;
//! - Q309=1 stops the program with a tolerance error after the results are written (Q309=0
//!   or no Q309: the program goes on and the status tells);
//! - Q281=1 (or 2) writes a measuring log: the text file `TCHPR<cycle>.TXT` in the program's
//!   folder, one block per run of the cycle (the first block of a program run replaces the
//!   file, later ones append, as for FN 16 output); a check run writes nothing. The block
//!   lists the cycle, program and line, then per result its nominal value, the value
//!   measured, the deviation and the limits with "ok" or what they exceed, and last the
//!   workpiece status. Q281=2 also shows the log in klar's program log (the TNC also
//!   interrupts the program to show it; klar does not stop).

use super::exec::{ExecError, Machine, here};
use crate::diag::ProgramError;
use crate::op::SourceLoc;

/// A measuring cycle's result out of its tolerance with Q309=1.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ToleranceError {
    /// A measured value outside its limits.
    #[error(
        "tolerance exceeded: TCH PROBE {cycle}, {what} measured {actual:.4} lies outside {allowed} ({status})"
    )]
    Exceeded {
        /// Cycle number.
        cycle: u32,
        /// The result, e.g. `Q156 width`.
        what: String,
        /// The value measured, program units.
        actual: f64,
        /// The values allowed, e.g. `9.9500 … 10.0500` or `at most 10.0500`.
        allowed: String,
        /// `rework` or `scrap`.
        status: &'static str,
    },
}

/// How a result that exceeds its limits leaves the workpiece.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Status {
    /// Within all limits.
    Good,
    /// Material left to cut.
    Rework,
    /// Too much material gone, or a position off.
    Scrap,
}

impl Status {
    fn word(self) -> &'static str {
        match self {
            Status::Good => "good",
            Status::Rework => "rework",
            Status::Scrap => "scrap",
        }
    }
}

/// One result of a measuring cycle, program units.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Item {
    /// Result parameter and what it is, e.g. `Q156 width`.
    pub what: String,
    /// Nominal value.
    pub nominal: f64,
    /// Measured value.
    pub actual: f64,
    /// Lowest value allowed (`None`: not checked).
    pub min: Option<f64>,
    /// Highest value allowed (`None`: not checked).
    pub max: Option<f64>,
    /// What a value below `min` means.
    pub below: Status,
    /// What a value above `max` means.
    pub above: Status,
}

impl Item {
    /// A size with limits `max`/`min`; `inner`: a bore, slot or pocket (too small is rework).
    pub fn size(
        what: &str,
        nominal: f64,
        actual: f64,
        max: Option<f64>,
        min: Option<f64>,
        inner: bool,
    ) -> Self {
        Item {
            what: what.into(),
            nominal,
            actual,
            min,
            max,
            below: if inner { Status::Rework } else { Status::Scrap },
            above: if inner { Status::Scrap } else { Status::Rework },
        }
    }

    /// A position that may lie `tol` either side of `nominal` (`None`: not checked).
    pub fn position(what: &str, nominal: f64, actual: f64, tol: Option<f64>) -> Self {
        Item {
            what: what.into(),
            nominal,
            actual,
            min: tol.map(|t| nominal - t.abs()),
            max: tol.map(|t| nominal + t.abs()),
            below: Status::Scrap,
            above: Status::Scrap,
        }
    }

    /// The status of this item alone.
    fn status(&self) -> Status {
        match (self.min, self.max) {
            (Some(lo), _) if self.actual < lo => self.below,
            (_, Some(hi)) if self.actual > hi => self.above,
            _ => Status::Good,
        }
    }

    fn checked(&self) -> bool {
        self.min.is_some() || self.max.is_some()
    }
}

impl Machine {
    /// Finishes a measuring cycle: workpiece status (Q180 … Q182), the measuring log (Q281) and
    /// the stop on a tolerance error (Q309). `items` are in program units.
    pub(super) fn report(
        &mut self,
        cycle: u32,
        items: &[Item],
        log: f64,
        stop: bool,
        loc: SourceLoc,
    ) -> Result<(), ExecError> {
        let checked = items.iter().any(Item::checked);
        let worst = items.iter().map(Item::status).max().unwrap_or(Status::Good);
        if checked {
            for (q, s) in [
                (180, Status::Good),
                (181, Status::Rework),
                (182, Status::Scrap),
            ] {
                self.set_q(q, if worst == s { 1.0 } else { 0.0 });
            }
        }
        if log == 1.0 || log == 2.0 {
            let text = self.log_text(cycle, items, worst, checked, loc);
            self.write_log(cycle, &text, log == 2.0)?;
        }
        if stop && let Some(bad) = items.iter().find(|i| i.status() != Status::Good) {
            return Err(here(ProgramError::Tolerance(ToleranceError::Exceeded {
                cycle,
                what: bad.what.clone(),
                actual: bad.actual,
                allowed: match (bad.min, bad.max) {
                    (Some(lo), Some(hi)) => format!("{lo:.4} … {hi:.4}"),
                    (Some(lo), None) => format!("at least {lo:.4}"),
                    (None, Some(hi)) => format!("at most {hi:.4}"),
                    (None, None) => "its limits".into(),
                },
                status: bad.status().word(),
            })));
        }
        Ok(())
    }

    /// The log block of one run of a measuring cycle.
    fn log_text(
        &self,
        cycle: u32,
        items: &[Item],
        worst: Status,
        checked: bool,
        loc: SourceLoc,
    ) -> String {
        let program = self
            .io
            .program
            .as_deref()
            .and_then(|p| p.file_name())
            .map_or_else(
                || "(from memory)".to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
        let unit = if self.unit == 1.0 { "mm" } else { "inch" };
        let mut s = format!(
            "TCH PROBE {cycle} measuring log\nprogram {program}, line {}, unit {unit}\n",
            loc.line
        );
        s.push_str("result                  nominal      actual   deviation         min         max  check\n");
        let opt = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{v:.4}"));
        for it in items {
            let verdict = if !it.checked() {
                "-"
            } else {
                match it.status() {
                    Status::Good => "ok",
                    Status::Rework | Status::Scrap if it.min.is_some_and(|m| it.actual < m) => {
                        "below min"
                    }
                    _ => "above max",
                }
            };
            s.push_str(&format!(
                "{:<20} {:>11.4} {:>11.4} {:>11.4} {:>11} {:>11}  {verdict}\n",
                it.what,
                it.nominal,
                it.actual,
                it.actual - it.nominal,
                opt(it.min),
                opt(it.max),
            ));
        }
        let status = if checked {
            worst.word()
        } else {
            "not checked (no limits)"
        };
        s.push_str(&format!("workpiece status: {status}\n\n"));
        s
    }

    /// Writes the log block to `TCHPR<cycle>.TXT` next to the program.
    fn write_log(&mut self, cycle: u32, text: &str, show: bool) -> Result<(), ExecError> {
        if show {
            tracing::info!(target: "klar::program", "measuring log\n{text}");
        }
        let Some(dir) = self.io.dir.clone() else {
            tracing::info!(target: "klar::program", "measuring log (program run from memory: no file)\n{text}");
            return Ok(());
        };
        let path = dir.join(format!("TCHPR{cycle}.TXT"));
        if self.io.dry_run {
            tracing::debug!(target: "klar::program", file = %path.display(), "measuring log (check run, not written)");
            return Ok(());
        }
        super::table::write_output(&mut self.io, &path, text).map_err(here)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bore_too_small_is_rework_and_too_large_scrap() {
        let small = Item::size("Q153 diameter", 10.0, 9.9, Some(10.05), Some(9.95), true);
        assert_eq!(small.status(), Status::Rework);
        let large = Item::size("Q153 diameter", 10.0, 10.1, Some(10.05), Some(9.95), true);
        assert_eq!(large.status(), Status::Scrap);
        let boss = Item::size("Q153 diameter", 10.0, 10.1, Some(10.05), Some(9.95), false);
        assert_eq!(boss.status(), Status::Rework);
        let pos = Item::position("Q151 centre", 5.0, 5.2, Some(0.1));
        assert_eq!(pos.status(), Status::Scrap);
        let free = Item::position("Q151 centre", 5.0, 9.0, None);
        assert_eq!(free.status(), Status::Good);
        assert!(!free.checked());
    }
}
