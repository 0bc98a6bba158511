//! Program data files next to the program: where FN 16 F-PRINT output goes and the freely
//! definable tables of FN 26 TABOPEN, FN 27 TABWRITE and FN 28 TABREAD.
//!
//! **Paths.** A path written in the program is relative to the folder of the main program.
//! A TNC drive prefix (`TNC:\`) and backslashes are accepted; the TNC folders named in the
//! path are used when they exist next to the program, otherwise the file name alone is taken
//! in the program folder. Paths are program data, so they are bounded (255 characters) and
//! may not leave the program folder: `..`, other drives (`PLC:`) and absolute paths are
//! refused with an error.
//!
//! **Tables** (`.TAB`): a `BEGIN name.TAB MM` line, a header line naming the columns (each
//! column starts where its name starts and ends where the next one starts; the first column
//! is NR, the line number), one line per row and `[END]`. FN 26 TABOPEN opens a table (one
//! at a time); FN 28 TABREAD `Qn = line / "COL1,COL2"` reads the cells of the row whose NR is
//! `line` into Qn, Qn+1, …; FN 27 TABWRITE `line / "COL1,COL2" = Qn` writes Qn, Qn+1, … into
//! them and saves the file at once. A check run reads the table from disk and keeps its
//! writes in memory.

use std::path::{Component, Path, PathBuf};

use super::exec::{ExecError, Machine, here};
use super::expr::{ParamRef, Value};
use super::system::ProgramIo;
use crate::diag::ProgramError;

/// Longest path accepted in FN 16 / FN 26.
pub const MAX_PATH: usize = 255;

/// Largest FN 16 format file read (bytes).
pub const MAX_FORMAT_FILE: u64 = 64 * 1024;

/// Most bytes FN 16 writes to one output file in a run.
pub const MAX_OUTPUT: usize = 1024 * 1024;

/// Largest table file read (bytes).
pub const MAX_TABLE_FILE: u64 = 4 * 1024 * 1024;

/// The file a program names, inside the program folder `dir`.
pub(crate) fn program_relative(
    dir: &Path,
    written: &str,
    what: &str,
) -> Result<PathBuf, ProgramError> {
    let bad = |why: &str| ProgramError::FileData(format!("{what} '{written}': {why}"));
    let w = written.trim().trim_matches('"').trim();
    if w.is_empty() {
        return Err(bad("no file name"));
    }
    if w.chars().count() > MAX_PATH {
        return Err(bad(&format!("path longer than {MAX_PATH} characters")));
    }
    let mut name = w.replace('\\', "/");
    if name.len() >= 4
        && name
            .get(..4)
            .is_some_and(|p| p.eq_ignore_ascii_case("TNC:"))
    {
        name = name.get(4..).unwrap_or("").to_string();
    } else if name.starts_with('/') {
        return Err(bad(
            "absolute paths are not allowed (paths are relative to the program)",
        ));
    }
    if name.contains(':') {
        return Err(bad("only the TNC: drive (the program folder) is available"));
    }
    let rel = PathBuf::from(name.trim_start_matches('/'));
    let mut parts = Vec::new();
    for c in rel.components() {
        match c {
            Component::Normal(p) => parts.push(p.to_os_string()),
            Component::CurDir => {}
            _ => return Err(bad("the path may not leave the program folder")),
        }
    }
    let Some(file) = parts.last().cloned() else {
        return Err(bad("no file name"));
    };
    let full: PathBuf = parts.iter().fold(dir.to_path_buf(), |p, c| p.join(c));
    if full.parent().is_some_and(Path::is_dir) {
        Ok(full)
    } else {
        // TNC folders that do not exist here: the file name in the program folder
        Ok(dir.join(file))
    }
}

/// Reads a text file of at most `limit` bytes (latin-1: one character per byte).
pub(crate) fn read_bounded(path: &Path, limit: u64) -> Result<String, ProgramError> {
    let io = |e: std::io::Error| {
        let text = format!("{}: {e}", path.display());
        if e.kind() == std::io::ErrorKind::NotFound {
            ProgramError::MissingFile(text)
        } else {
            ProgramError::FileData(text)
        }
    };
    let bytes = crate::files::read_bounded(path, limit).map_err(io)?;
    Ok(bytes.iter().map(|&b| char::from(b)).collect())
}

/// Latin-1 bytes of a text (characters beyond U+00FF become `?`).
fn latin1(s: &str) -> Vec<u8> {
    s.chars()
        .map(|c| u8::try_from(u32::from(c)).unwrap_or(b'?'))
        .collect()
}

/// Writes FN 16 output: replaces the file on its first use in the run, appends afterwards.
pub(crate) fn write_output(
    io: &mut ProgramIo,
    path: &Path,
    text: &str,
) -> Result<(), ProgramError> {
    use std::io::Write;
    let bytes = latin1(text);
    let err = |e: std::io::Error| ProgramError::FileData(format!("FN 16 {}: {e}", path.display()));
    let known = io.written.iter().position(|(p, _)| p == path);
    let before = known.and_then(|i| io.written.get(i)).map_or(0, |(_, n)| *n);
    if before + bytes.len() > MAX_OUTPUT {
        return Err(ProgramError::FileData(format!(
            "FN 16 {}: more than {MAX_OUTPUT} bytes of output in one run",
            path.display()
        )));
    }
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .write(true)
        .append(known.is_some())
        .truncate(known.is_none())
        .open(path)
        .map_err(err)?;
    f.write_all(&bytes).map_err(err)?;
    match known.and_then(|i| io.written.get_mut(i)) {
        Some(entry) => entry.1 += bytes.len(),
        None => io.written.push((path.to_path_buf(), bytes.len())),
    }
    Ok(())
}

/// What an FN 26/27/28 block asks for (paths and column lists as byte ranges of the block).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum TableOp {
    /// FN 26 TABOPEN path.
    Open {
        /// First byte of the path.
        start: u32,
        /// One past its last byte.
        end: u32,
    },
    /// FN 27 TABWRITE line / "cols" = Qn.
    Write {
        /// Row number (NR).
        line: Value,
        /// Column list: byte range of the quoted text.
        cols: (u32, u32),
        /// First parameter written.
        first: ParamRef,
    },
    /// FN 28 TABREAD Qn = line / "cols".
    Read {
        /// First parameter read into.
        target: ParamRef,
        /// Row number (NR).
        line: Value,
        /// Column list: byte range of the quoted text.
        cols: (u32, u32),
    },
}

/// An open freely definable table: its lines as read, with the column layout.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Table {
    /// The file.
    path: PathBuf,
    /// All lines of the file.
    lines: Vec<String>,
    /// Column names (upper case) and the character where each starts.
    columns: Vec<(String, usize)>,
    /// Index of the first data line.
    data_from: usize,
}

impl Table {
    /// Reads a table file.
    pub fn load(path: &Path) -> Result<Table, ProgramError> {
        let text = read_bounded(path, MAX_TABLE_FILE)?;
        Table::parse(path, &text)
    }

    fn parse(path: &Path, text: &str) -> Result<Table, ProgramError> {
        let bad = |why: String| ProgramError::FileData(format!("table {}: {why}", path.display()));
        let lines: Vec<String> = text
            .lines()
            .map(|l| l.trim_end_matches('\r').to_string())
            .collect();
        let mut idx = 0;
        let next_content = |from: usize| {
            (from..lines.len()).find(|&i| lines.get(i).is_some_and(|l| !l.trim().is_empty()))
        };
        let Some(first) = next_content(0) else {
            return Err(bad("empty file".into()));
        };
        if lines
            .get(first)
            .is_some_and(|l| l.trim_start().to_ascii_uppercase().starts_with("BEGIN"))
        {
            idx = first + 1;
        }
        let Some(header_at) = next_content(idx) else {
            return Err(bad("no header line".into()));
        };
        let header = lines.get(header_at).cloned().unwrap_or_default();
        let mut columns = Vec::new();
        let chars: Vec<char> = header.chars().collect();
        let mut i = 0;
        while i < chars.len() {
            if chars.get(i).is_some_and(|c| c.is_whitespace()) {
                i += 1;
                continue;
            }
            let start = i;
            while chars.get(i).is_some_and(|c| !c.is_whitespace()) {
                i += 1;
            }
            let name: String = chars.get(start..i).unwrap_or(&[]).iter().collect();
            columns.push((name.to_ascii_uppercase(), start));
        }
        if columns.first().is_none_or(|(n, _)| n != "NR") {
            return Err(bad("the header line must start with the column NR".into()));
        }
        Ok(Table {
            path: path.to_path_buf(),
            lines,
            columns,
            data_from: header_at + 1,
        })
    }

    /// Character range of a column (the last one runs to the end of the line).
    fn span(&self, col: usize) -> (usize, usize) {
        let start = self.columns.get(col).map_or(0, |c| c.1);
        let end = self.columns.get(col + 1).map_or(usize::MAX, |c| c.1);
        (start, end)
    }

    fn column(&self, name: &str) -> Result<usize, ProgramError> {
        let n = name.trim().to_ascii_uppercase();
        self.columns
            .iter()
            .position(|(c, _)| *c == n)
            .ok_or_else(|| {
                ProgramError::FileData(format!(
                    "table {}: no column '{}'",
                    self.path.display(),
                    name.trim()
                ))
            })
    }

    fn cell(&self, line: usize, col: usize) -> String {
        let (s, e) = self.span(col);
        self.lines
            .get(line)
            .map(|l| {
                l.chars()
                    .skip(s)
                    .take(e.saturating_sub(s))
                    .collect::<String>()
            })
            .unwrap_or_default()
            .trim()
            .to_string()
    }

    /// The file line of the row whose NR is `nr`.
    fn row(&self, nr: f64) -> Result<usize, ProgramError> {
        (self.data_from..self.lines.len())
            .take_while(|&i| {
                self.lines
                    .get(i)
                    .is_none_or(|l| !l.trim_start().starts_with("[END]"))
            })
            .find(|&i| {
                let c = self.cell(i, 0);
                !c.is_empty() && c.replace(',', ".").parse::<f64>().ok() == Some(nr)
            })
            .ok_or_else(|| {
                ProgramError::FileData(format!("table {}: no line NR {nr}", self.path.display()))
            })
    }

    /// The numbers in `cols` of row `nr`.
    pub fn read(&self, nr: f64, cols: &str) -> Result<Vec<f64>, ProgramError> {
        let line = self.row(nr)?;
        let mut out = Vec::new();
        for name in cols.split(',') {
            let c = self.column(name)?;
            let text = self.cell(line, c);
            let v = if text.is_empty() {
                0.0
            } else {
                text.replace(',', ".").parse::<f64>().map_err(|_| {
                    ProgramError::FileData(format!(
                        "table {}: NR {nr} column {}: '{text}' is not a number",
                        self.path.display(),
                        name.trim()
                    ))
                })?
            };
            out.push(v);
        }
        Ok(out)
    }

    /// Writes `values` into `cols` of row `nr` (in memory).
    pub fn write(&mut self, nr: f64, cols: &str, values: &[f64]) -> Result<(), ProgramError> {
        let line = self.row(nr)?;
        for (name, v) in cols.split(',').zip(values) {
            let c = self.column(name)?;
            let (s, e) = self.span(c);
            // a cell keeps one blank before the next column
            let width = e.saturating_sub(s).saturating_sub(1).min(64);
            let text = fit(*v, width).ok_or_else(|| {
                ProgramError::FileData(format!(
                    "table {}: {v} does not fit column {} ({width} characters)",
                    self.path.display(),
                    name.trim()
                ))
            })?;
            let Some(l) = self.lines.get_mut(line) else {
                continue;
            };
            let mut chars: Vec<char> = l.chars().collect();
            if chars.len() < s + width {
                chars.resize(s + width, ' ');
            }
            let mut cell: Vec<char> = text.chars().collect();
            cell.resize(width, ' ');
            chars.splice(s..s + width, cell);
            *l = chars.into_iter().collect::<String>().trim_end().to_string();
        }
        Ok(())
    }

    /// Saves the table.
    pub fn save(&self) -> Result<(), ProgramError> {
        let mut text = self.lines.join("\n");
        text.push('\n');
        std::fs::write(&self.path, latin1(&text))
            .map_err(|e| ProgramError::FileData(format!("table {}: {e}", self.path.display())))
    }
}

/// The shortest text of `v` with at most `width` characters (fewer decimals if needed).
fn fit(v: f64, width: usize) -> Option<String> {
    let plain = format!("{v}");
    if plain.chars().count() <= width {
        return Some(plain);
    }
    (0..=6)
        .rev()
        .map(|d| format!("{v:.d$}"))
        .find(|s| s.chars().count() <= width)
}

impl Machine {
    /// FN 26/27/28: opens a table, writes or reads cells.
    pub(super) fn table_op(&mut self, op: &TableOp, text: &[u8]) -> Result<(), ExecError> {
        let slice = |s: u32, e: u32| -> String {
            text.get(s as usize..e as usize)
                .unwrap_or(&[])
                .iter()
                .map(|&b| char::from(b))
                .collect()
        };
        match *op {
            TableOp::Open { start, end } => {
                let written = slice(start, end);
                let Some(dir) = self.io.dir.clone() else {
                    return Err(here(ProgramError::FileData(
                        "FN 26: a program run from memory has no folder for tables".into(),
                    )));
                };
                let mut path = program_relative(&dir, &written, "FN 26 table").map_err(here)?;
                if path.extension().is_none() {
                    path.set_extension("TAB");
                }
                self.io.table = Some(Table::load(&path).map_err(here)?);
                Ok(())
            }
            TableOp::Write { line, cols, first } => {
                let nr = self.params.value(line);
                let names = slice(cols.0, cols.1);
                let values: Vec<f64> = (0..names.split(',').count() as u32)
                    .map(|i| {
                        self.params.get(ParamRef {
                            kind: first.kind,
                            index: first.index.saturating_add(i),
                        })
                    })
                    .collect();
                let dry = self.io.dry_run;
                let Some(t) = self.io.table.as_mut() else {
                    return Err(here(no_table()));
                };
                t.write(nr, &names, &values).map_err(here)?;
                if !dry {
                    t.save().map_err(here)?;
                }
                Ok(())
            }
            TableOp::Read { target, line, cols } => {
                let nr = self.params.value(line);
                let names = slice(cols.0, cols.1);
                let Some(t) = self.io.table.as_ref() else {
                    return Err(here(no_table()));
                };
                let values = t.read(nr, &names).map_err(here)?;
                for (i, v) in values.into_iter().enumerate() {
                    let index = target.index.saturating_add(i as u32);
                    self.params.set(
                        ParamRef {
                            kind: target.kind,
                            index,
                        },
                        v,
                    );
                }
                Ok(())
            }
        }
    }
}

fn no_table() -> ProgramError {
    ProgramError::FileData("FN 27/28 without a table: open one with FN 26 TABOPEN first".into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::klartext::parser::Parser;
    use crate::klartext::test_support::{folder, run};
    use crate::op::Pose;
    use crate::tnc::exec::Machine;
    use crate::tnc::expr::ParamKind;

    fn q(m: &Machine, n: u32) -> f64 {
        m.params.get(ParamRef {
            kind: ParamKind::Q,
            index: n,
        })
    }

    const TAB: &str = "BEGIN 90304.TAB MM\n\
                       NR   STUECK  X       Y\n\
                       0    17      1.5     -2\n\
                       1    3\n\
                       [END]\n";

    #[test]
    fn tables_read_write_and_keep_check_runs_in_memory() {
        let d = folder("tab");
        std::fs::write(d.join("90304.TAB"), TAB).unwrap();
        let prog = "FN 26: TABOPEN 90304.TAB\n\
                    FN 28: TABREAD Q80 =0 /\"Stueck\"\n\
                    FN 1: Q80 =+Q80 + +1\n\
                    FN 27: TABWRITE 0 /\"Stueck\" = Q80\n\
                    FN 28: TABREAD Q1 = 0 / \"X,Y\"\n\
                    Q5 = 1\n\
                    FN 28: TABREAD Q3 = Q5 / \"Y\"";
        // check run: the write stays in memory
        let mut m = Machine::new(Pose::ZERO);
        m.set_program_file(&d.join("p.h"));
        m.set_dry_run(true);
        run(
            &mut m,
            &format!("{prog}\nFN 28: TABREAD Q81 = 0 /\"STUECK\""),
        )
        .unwrap();
        assert_eq!((q(&m, 80), q(&m, 81)), (18.0, 18.0));
        assert_eq!(std::fs::read_to_string(d.join("90304.TAB")).unwrap(), TAB);
        // a real run writes the file, keeping the column layout
        let mut m = Machine::new(Pose::ZERO);
        m.set_program_file(&d.join("p.h"));
        run(&mut m, prog).unwrap();
        assert_eq!(
            (q(&m, 80), q(&m, 1), q(&m, 2), q(&m, 3)),
            (18.0, 1.5, -2.0, 0.0)
        );
        let text = std::fs::read_to_string(d.join("90304.TAB")).unwrap();
        assert_eq!(text, TAB.replace("0    17      1.5", "0    18      1.5"));
        // a second run counts on
        let mut m = Machine::new(Pose::ZERO);
        m.set_program_file(&d.join("p.h"));
        run(&mut m, prog).unwrap();
        assert_eq!(q(&m, 80), 19.0);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn table_errors() {
        let d = folder("taberr");
        std::fs::write(d.join("T.TAB"), TAB).unwrap();
        let mut m = Machine::new(Pose::ZERO);
        m.set_program_file(&d.join("p.h"));
        let e = run(&mut m, "FN 28: TABREAD Q1 = 0 /\"X\"").unwrap_err();
        assert!(e.contains("open one with FN 26"), "{e}");
        let e = run(&mut m, "FN 26: TABOPEN T\nFN 28: TABREAD Q1 = 0 /\"Z\"").unwrap_err();
        assert!(e.contains("no column 'Z'"), "{e}");
        let e = run(&mut m, "FN 28: TABREAD Q1 = 7 /\"X\"").unwrap_err();
        assert!(e.contains("no line NR 7"), "{e}");
        let e = run(&mut m, "Q1 = 123456789\nFN 27: TABWRITE 0 /\"STUECK\" = Q1").unwrap_err();
        assert!(e.contains("does not fit column"), "{e}");
        let e = run(&mut m, "FN 26: TABOPEN ../T.TAB").unwrap_err();
        assert!(e.contains("may not leave the program folder"), "{e}");
        let e = Parser::default()
            .parse(b"FN 28: TABREAD Q1 = 0 X")
            .unwrap_err();
        assert_eq!(e.pos, 22);
        let _ = std::fs::remove_dir_all(&d);
    }
}
