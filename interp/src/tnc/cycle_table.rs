//! Datum tables (`.D`, read by `CYCL DEF 7.1 #n`) and preset tables (`.PR`, read by
//! cycle 247) in the HEIDENHAIN table text format:
//!
//! ```text
//! BEGIN NULLTAB.D MM
//! NR    X          Y          Z
//! 0     +0         +0         +0
//! 1     +25.5      -10        +0
//! [END]
//! ```
//!
//! The first line names the table and its unit (`MM` or `INCH`; INCH values are converted to
//! mm). The second line names the columns; `NR` is the row number, the axis columns are
//! `X Y Z A B C U V W`; a preset table's `ROT` column is the basic rotation about the tool
//! axis (degrees); other columns (`DOC`, …) are ignored. A row whose fields split at
//! blanks into as many fields as the header has columns is read field by field; otherwise the
//! fields are cut at the header's column positions (tables written by the control are
//! aligned, and a blank field means "not set"). `[END]` ends the table.

use std::collections::BTreeMap;

use crate::op::AxisLetter;

/// Why a table text cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DatumTableError {
    /// The `BEGIN name MM|INCH` line is missing.
    #[error("line 1: a table starts with `BEGIN name.D MM` (or INCH)")]
    NoBegin,
    /// The column header line is missing or has no `NR` column.
    #[error("line 2: the column header needs an NR column")]
    NoHeader,
    /// A field that is not a number.
    #[error("line {line}: column {column}: '{text}' is not a number")]
    BadNumber {
        /// 1-based line.
        line: usize,
        /// Column name.
        column: String,
        /// The field.
        text: String,
    },
}

/// A parsed datum or preset table: axis values (mm, degrees) per row number.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DatumTable {
    rows: BTreeMap<i64, [Option<f64>; 9]>,
    /// The `ROT` column (basic rotation, degrees) where it has a value.
    rot: BTreeMap<i64, f64>,
}

fn number(s: &str) -> Option<f64> {
    let s = s.trim().replace(',', ".");
    let s = s.strip_prefix('+').unwrap_or(&s);
    s.parse::<f64>().ok().filter(|v| v.is_finite())
}

impl DatumTable {
    /// Reads a table from its text.
    pub fn parse(text: &str) -> Result<DatumTable, DatumTableError> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let (_, begin) = lines.next().ok_or(DatumTableError::NoBegin)?;
        let mut head = begin.split_whitespace();
        if !head.next().is_some_and(|w| w.eq_ignore_ascii_case("BEGIN")) {
            return Err(DatumTableError::NoBegin);
        }
        let factor = if head.any(|w| w.eq_ignore_ascii_case("INCH")) {
            25.4
        } else {
            1.0
        };
        let (_, header) = lines.next().ok_or(DatumTableError::NoHeader)?;
        // column names with their start positions
        let mut cols: Vec<(usize, String)> = Vec::new();
        let mut prev_blank = true;
        for (i, c) in header.char_indices() {
            let blank = c.is_whitespace();
            if !blank && prev_blank {
                cols.push((i, String::new()));
            }
            if !blank && let Some(last) = cols.last_mut() {
                last.1.push(c.to_ascii_uppercase());
            }
            prev_blank = blank;
        }
        let nr_col = cols
            .iter()
            .position(|(_, n)| n == "NR")
            .ok_or(DatumTableError::NoHeader)?;
        let mut rows = BTreeMap::new();
        let mut rot = BTreeMap::new();
        for (ln, line) in lines {
            let t = line.trim();
            if t.eq_ignore_ascii_case("[END]") || t.eq_ignore_ascii_case("END") {
                break;
            }
            let split: Vec<&str> = line.split_whitespace().collect();
            let fields: Vec<String> = if split.len() == cols.len() {
                split.iter().map(|s| s.to_string()).collect()
            } else {
                cols.iter()
                    .enumerate()
                    .map(|(k, (start, _))| {
                        let end = cols.get(k + 1).map_or(line.len(), |c| c.0);
                        line.get((*start).min(line.len())..end.min(line.len()))
                            .unwrap_or("")
                            .trim()
                            .to_string()
                    })
                    .collect()
            };
            let bad = |k: usize, f: &str| DatumTableError::BadNumber {
                line: ln + 1,
                column: cols.get(k).map(|c| c.1.clone()).unwrap_or_default(),
                text: f.to_string(),
            };
            let nr_text = fields.get(nr_col).map(String::as_str).unwrap_or("");
            let nr = number(nr_text)
                .filter(|v| v.fract() == 0.0)
                .ok_or_else(|| bad(nr_col, nr_text))? as i64;
            let mut row = [None; 9];
            for (k, (_, name)) in cols.iter().enumerate() {
                if name == "ROT" {
                    let f = fields.get(k).map(String::as_str).unwrap_or("").trim();
                    if !f.is_empty() {
                        rot.insert(nr, number(f).ok_or_else(|| bad(k, f))?);
                    }
                    continue;
                }
                let mut ch = name.chars();
                let (Some(c), None) = (ch.next(), ch.next()) else {
                    continue;
                };
                let Some(axis) = AxisLetter::from_char(c) else {
                    continue;
                };
                let f = fields.get(k).map(String::as_str).unwrap_or("").trim();
                if f.is_empty() {
                    continue;
                }
                let v = number(f).ok_or_else(|| bad(k, f))?;
                row[axis.index()] = Some(if axis.is_rotary() { v } else { v * factor });
            }
            rows.insert(nr, row);
        }
        Ok(DatumTable { rows, rot })
    }

    /// The values of row `nr` (axes without a value are `None`), if the row exists.
    pub fn row(&self, nr: i64) -> Option<&[Option<f64>; 9]> {
        self.rows.get(&nr)
    }

    /// The basic rotation (`ROT` column, degrees) of row `nr`; 0 when not set.
    pub fn rot(&self, nr: i64) -> f64 {
        self.rot.get(&nr).copied().unwrap_or(0.0)
    }

    /// Writes row `nr` (created when missing): the axis values given replace the row's,
    /// the others stay; `rot` replaces the basic rotation when given.
    pub fn write(&mut self, nr: i64, values: &[Option<f64>; 9], rot: Option<f64>) {
        let row = self.rows.entry(nr).or_insert([None; 9]);
        for (slot, v) in row.iter_mut().zip(values) {
            if v.is_some() {
                *slot = *v;
            }
        }
        if let Some(r) = rot {
            self.rot.insert(nr, r);
        }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True when the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_aligned_and_blank_separated_tables() {
        let t = DatumTable::parse(
            "BEGIN NULLTAB.D MM\nNR    X          Y          Z        DOC\n0     +0         +0         +0\n1     +25,5      -10                 clamp\n2 1 2 3 x\n[END]\n",
        )
        .expect("parses");
        assert_eq!(t.len(), 3);
        assert_eq!(t.row(1).map(|r| r[0]), Some(Some(25.5)));
        assert_eq!(t.row(1).map(|r| r[1]), Some(Some(-10.0)));
        assert_eq!(t.row(1).map(|r| r[2]), Some(None));
        assert_eq!(t.row(2).map(|r| r[2]), Some(Some(3.0)));
        assert!(t.row(7).is_none());
    }

    #[test]
    fn inch_tables_are_converted_and_errors_reported() {
        let t = DatumTable::parse("BEGIN P.D INCH\nNR X C\n5 1 90\n").expect("parses");
        assert_eq!(
            t.row(5).map(|r| (r[0], r[5])),
            Some((Some(25.4), Some(90.0)))
        );
        assert_eq!(DatumTable::parse("NR X\n"), Err(DatumTableError::NoBegin));
        assert_eq!(
            DatumTable::parse("BEGIN T.D MM\nX Y\n"),
            Err(DatumTableError::NoHeader)
        );
        assert!(matches!(
            DatumTable::parse("BEGIN T.D MM\nNR X\n1 abc\n"),
            Err(DatumTableError::BadNumber { line: 3, .. })
        ));
    }
}
