//! The tool table: reading HEIDENHAIN `TOOL.T` files and looking tools up for TOOL CALL.
//!
//! A `TOOL.T` file is a fixed-column text table: a `BEGIN TOOL.T MM|INCH` line, a header
//! line naming the columns, one line per tool and an `[END]` line. Each column starts where
//! its name starts in the header and ends where the next name starts. The columns used here
//! are T (number), NAME, L (length), R (radius), R2 (corner radius), DL, DR and DR2 (deltas);
//! other columns are skipped. Lengths of an INCH table are converted to mm. Values may be
//! written with a sign and a decimal comma; an empty cell reads as 0.

use std::collections::BTreeMap;

use thiserror::Error;

/// One tool of the table (mm).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Tool {
    /// Tool number (T).
    pub number: u32,
    /// Tool name (NAME), may be empty.
    pub name: String,
    /// Length L.
    pub length: f64,
    /// Radius R.
    pub radius: f64,
    /// Corner radius R2.
    pub r2: f64,
    /// Length delta DL.
    pub dl: f64,
    /// Radius delta DR.
    pub dr: f64,
    /// Corner radius delta DR2.
    pub dr2: f64,
}

/// A problem in a tool table file.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ToolTableError {
    /// The file could not be read.
    #[error("cannot read tool table: {0}")]
    Io(String),
    /// The file has no header line with a T column.
    #[error("tool table: no header line with a T column")]
    NoHeader,
    /// A cell that should hold a number does not.
    #[error("tool table line {line}: column {column}: '{text}' is not a number")]
    BadNumber {
        /// 1-based line in the file.
        line: usize,
        /// Column name.
        column: String,
        /// The cell text.
        text: String,
    },
    /// The same tool number twice.
    #[error("tool table line {line}: tool {number} defined twice")]
    Duplicate {
        /// 1-based line.
        line: usize,
        /// Tool number.
        number: u32,
    },
}

/// The tools known to the interpreter, by number.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ToolTable {
    tools: BTreeMap<u32, Tool>,
}

impl ToolTable {
    /// An empty table.
    pub fn new() -> Self {
        Self::default()
    }

    /// True when no tool is defined.
    pub fn is_empty(&self) -> bool {
        self.tools.is_empty()
    }

    /// Number of tools.
    pub fn len(&self) -> usize {
        self.tools.len()
    }

    /// Adds or replaces a tool.
    pub fn insert(&mut self, tool: Tool) {
        self.tools.insert(tool.number, tool);
    }

    /// The tool with this number.
    pub fn get(&self, number: u32) -> Option<&Tool> {
        self.tools.get(&number)
    }

    /// The tools in order of their numbers.
    pub fn iter(&self) -> impl Iterator<Item = &Tool> {
        self.tools.values()
    }

    /// The number of the first tool with this name (names compare case-insensitively).
    pub fn number_of(&self, name: &str) -> Option<u32> {
        self.tools
            .values()
            .find(|t| t.name.eq_ignore_ascii_case(name))
            .map(|t| t.number)
    }

    /// Looks a tool up by name when given, else by number.
    pub fn lookup(&self, number: Option<u32>, name: Option<&str>) -> Option<&Tool> {
        match name {
            Some(n) => self.number_of(n).and_then(|k| self.get(k)),
            None => number.and_then(|k| self.get(k)),
        }
    }

    /// Reads a `TOOL.T` file.
    pub fn load(path: &std::path::Path) -> Result<Self, ToolTableError> {
        let bytes = crate::files::read_bounded(path, super::table::MAX_TABLE_FILE)
            .map_err(|e| ToolTableError::Io(e.to_string()))?;
        // latin-1 decoding: every byte is one character, so columns stay aligned
        let text: String = bytes.iter().map(|&b| char::from(b)).collect();
        Self::parse(&text)
    }

    /// Parses the text of a `TOOL.T` file.
    pub fn parse(text: &str) -> Result<Self, ToolTableError> {
        let mut inch = false;
        let mut columns: Option<Vec<(String, usize)>> = None;
        let mut table = ToolTable::new();
        for (i, raw) in text.lines().enumerate() {
            let line_no = i + 1;
            let line = raw.trim_end_matches('\r');
            let trimmed = line.trim();
            let upper = trimmed.to_ascii_uppercase();
            if trimmed.is_empty() {
                continue;
            }
            if upper.starts_with("BEGIN") {
                inch = upper.split_whitespace().any(|w| w == "INCH");
                continue;
            }
            if upper.starts_with("[END]") || upper == "END" {
                break;
            }
            let Some(cols) = &columns else {
                let header = header_columns(line);
                if header.iter().any(|(n, _)| n == "T") {
                    columns = Some(header);
                }
                continue;
            };
            let chars: Vec<char> = line.chars().collect();
            let cell = |name: &str| -> Option<String> {
                let k = cols.iter().position(|(n, _)| n == name)?;
                let start = cols.get(k)?.1;
                let end = cols.get(k + 1).map_or(chars.len(), |c| c.1);
                let s: String = chars
                    .get(start.min(chars.len())..end.min(chars.len()))?
                    .iter()
                    .collect();
                Some(s.trim().to_string())
            };
            let num = |name: &str| -> Result<f64, ToolTableError> {
                let Some(s) = cell(name) else {
                    return Ok(0.0);
                };
                if s.is_empty() {
                    return Ok(0.0);
                }
                s.replace(',', ".")
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| ToolTableError::BadNumber {
                        line: line_no,
                        column: name.to_string(),
                        text: s.clone(),
                    })
            };
            let t = num("T")?;
            if !(t >= 0.0 && t.fract() == 0.0 && t <= f64::from(u32::MAX)) {
                return Err(ToolTableError::BadNumber {
                    line: line_no,
                    column: "T".into(),
                    text: cell("T").unwrap_or_default(),
                });
            }
            let scale = if inch { 25.4 } else { 1.0 };
            let tool = Tool {
                number: t as u32,
                name: cell("NAME").unwrap_or_default(),
                length: num("L")? * scale,
                radius: num("R")? * scale,
                r2: num("R2")? * scale,
                dl: num("DL")? * scale,
                dr: num("DR")? * scale,
                dr2: num("DR2")? * scale,
            };
            if table.tools.contains_key(&tool.number) {
                return Err(ToolTableError::Duplicate {
                    line: line_no,
                    number: tool.number,
                });
            }
            table.insert(tool);
        }
        if columns.is_none() {
            return Err(ToolTableError::NoHeader);
        }
        Ok(table)
    }
}

/// Column names of a header line with the character position where each starts.
fn header_columns(line: &str) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    let chars: Vec<char> = line.chars().collect();
    for (i, c) in chars.iter().enumerate() {
        match (c.is_whitespace(), start) {
            (false, None) => start = Some(i),
            (true, Some(s)) => {
                out.push((chars[s..i].iter().collect::<String>().to_uppercase(), s));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((chars[s..].iter().collect::<String>().to_uppercase(), s));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const TABLE: &str = "BEGIN TOOL.T MM\n\
T    NAME             L           R           R2          DL      DR      DR2     TL\n\
0    NULLTOOL         +0          +0          +0          +0      +0      +0\n\
1    MILL_D10         +42.5       +5          +0          -0.1    +0.02   +0\n\
7    BALL_6           +60,25      +3          +3          +0      -0,01   +0      L\n\
[END]\n";

    #[test]
    fn reads_columns_by_header_position() {
        let t = ToolTable::parse(TABLE).unwrap();
        assert_eq!(t.len(), 3);
        let m = t.get(1).unwrap();
        assert_eq!(m.name, "MILL_D10");
        assert_eq!((m.length, m.radius, m.dl, m.dr), (42.5, 5.0, -0.1, 0.02));
        let b = t.get(7).unwrap();
        assert_eq!((b.length, b.r2, b.dr), (60.25, 3.0, -0.01));
        assert_eq!(t.number_of("ball_6"), Some(7));
    }

    #[test]
    fn inch_tables_are_converted_and_bad_cells_reported() {
        let t =
            ToolTable::parse("BEGIN TOOL.T INCH\nT  NAME  L    R\n2  X     1    0.5\n").unwrap();
        assert_eq!(t.get(2).unwrap().radius, 12.7);
        let e = ToolTable::parse("BEGIN TOOL.T MM\nT  NAME  L    R\n2  X     abc  1\n");
        assert!(
            matches!(e, Err(ToolTableError::BadNumber { line: 3, .. })),
            "{e:?}"
        );
        assert_eq!(
            ToolTable::parse("no header here\n"),
            Err(ToolTableError::NoHeader)
        );
    }
}
