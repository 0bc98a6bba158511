//! The trace CSV: one row per servo cycle with the time, the commanded position of every
//! machine axis and the measured position the backend reported (`<letter>_act`). Numbers are
//! written in the shortest form that reads back to the same f64, so a trace is exact.
//!
//! On a machine with a spindle two columns follow: `S`, the commanded speed (rpm, signed:
//! positive M3), and `S_deg`, the measured spindle angle (degrees, unwrapped). A spindle that
//! measures no angle (a VFD) leaves `S_deg` empty; [`Trace::parse`] reads an empty field as
//! NaN.

use klar_interp::AxisLetter;
use std::io::{self, Write};

/// Writes trace rows to any writer.
pub struct TraceWriter<W: Write> {
    out: W,
    axes: usize,
    spindle: bool,
}

/// The spindle's part of a trace row: commanded speed (rpm, signed) and measured angle
/// (degrees, unwrapped; `None` when the spindle measures none).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SpindleRow {
    /// Commanded speed, rpm, signed.
    pub rpm: f64,
    /// Measured angle, degrees.
    pub angle: Option<f64>,
}

impl<W: Write> TraceWriter<W> {
    /// Writes the header row: `t`, the letters, then `<letter>_act`, then `S,S_deg` when
    /// the machine has a spindle.
    pub fn new(mut out: W, letters: &[AxisLetter], spindle: bool) -> io::Result<Self> {
        write!(out, "t")?;
        for l in letters {
            write!(out, ",{l}")?;
        }
        for l in letters {
            write!(out, ",{l}_act")?;
        }
        if spindle {
            write!(out, ",S,S_deg")?;
        }
        writeln!(out)?;
        Ok(Self {
            out,
            axes: letters.len(),
            spindle,
        })
    }

    /// Writes one row; `commanded` and `actual` hold one value per machine axis, `spindle`
    /// the spindle's columns (ignored on a machine without one).
    pub fn row(
        &mut self,
        t: f64,
        commanded: &[f64],
        actual: &[f64],
        spindle: SpindleRow,
    ) -> io::Result<()> {
        debug_assert_eq!(commanded.len(), self.axes);
        debug_assert_eq!(actual.len(), self.axes);
        write!(self.out, "{t}")?;
        for v in commanded.iter().chain(actual) {
            write!(self.out, ",{v}")?;
        }
        if self.spindle {
            write!(self.out, ",{}", spindle.rpm)?;
            match spindle.angle {
                Some(a) => write!(self.out, ",{a}")?,
                None => write!(self.out, ",")?,
            }
        }
        writeln!(self.out)
    }

    /// Flushes the writer.
    pub fn finish(mut self) -> io::Result<()> {
        self.out.flush()
    }
}

/// A trace read back from CSV (for tests and tools).
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// Column names after `t`.
    pub columns: Vec<String>,
    /// Time of each row.
    pub t: Vec<f64>,
    /// Values per row, in column order.
    pub rows: Vec<Vec<f64>>,
}

impl Trace {
    /// Parses trace CSV text.
    pub fn parse(text: &str) -> Result<Trace, String> {
        let mut lines = text.lines();
        let header = lines.next().ok_or("empty trace")?;
        let mut cols = header.split(',');
        if cols.next() != Some("t") {
            return Err("first column must be t".into());
        }
        let columns: Vec<String> = cols.map(str::to_string).collect();
        let mut t = Vec::new();
        let mut rows = Vec::new();
        for (i, line) in lines.enumerate() {
            // An empty field is a value the machine does not measure (S_deg of a VFD).
            let mut vals = line.split(',').map(|v| {
                if v.is_empty() {
                    Ok(f64::NAN)
                } else {
                    v.parse::<f64>()
                }
            });
            let time = vals
                .next()
                .ok_or_else(|| format!("row {}: empty", i + 2))?
                .map_err(|e| format!("row {}: {e}", i + 2))?;
            let row: Vec<f64> = vals
                .collect::<Result<_, _>>()
                .map_err(|e| format!("row {}: {e}", i + 2))?;
            if row.len() != columns.len() {
                return Err(format!(
                    "row {}: {} values for {} columns",
                    i + 2,
                    row.len(),
                    columns.len()
                ));
            }
            t.push(time);
            rows.push(row);
        }
        Ok(Trace { columns, t, rows })
    }

    /// The values of one column, by name.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let i = self.columns.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| r[i]).collect())
    }
}
