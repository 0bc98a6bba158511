//! Tools and system data: TOOL CALL, TOOL DEF, FN 18 SYSREAD and FN 15/16 output.
//!
//! FN 18 reads the system data the HEIDENHAIN tables list under these group numbers (ID):
//! 10 NR1 program unit (0 = mm, 1 = inch); 50 tool table, IDX = tool number: NR1 L, NR2 R,
//! NR3 R2, NR4 DL, NR5 DR, NR6 DR2; 20 machine status: NR1 active tool number, NR3
//! tool axis (0 = X, 1 = Y, 2 = Z), NR4 programmed spindle speed, NR5 spindle status (0 M3,
//! 1 M4; this version reads -1 while the spindle stands), NR8 coolant (0 off, 1 on), NR9 feed;
//! 200 tool compensation: NR1 active radius, NR2 active length (deltas included); 240 NR1
//! IDX1..9 nominal position of axis 1..9 (X Y Z A B C U V W) in the reference system; 270 NR1
//! IDX1..9 position in the active coordinate system. This version has no datum shifts, so
//! 240 and 270 read the same last programmed position. Lengths are given in program units.
//!
//! **FN 16 format file** (`.A`), one output line per format line (TNC syntax as this
//! interpreter reads it; the TNC manual's format-file section was not at hand, so the
//! details below are the project's reading of it):
//!
//! ```text
//! "MEASURING LOG";                       text only
//! "X1 = %9.3F mm", Q31;                  text with a value: %[flags][width][.prec]conv
//! "Tool %D, program %S", Q1, CALL_PATH;  items: Q/QL/QR n, QS n, DAY, MONTH, STR_MONTH,
//!                                        YEAR2, YEAR4, HOUR, MIN, SEC, CALL_PATH
//! L_ENGLISH "only in English";           L_<language>: only L_ENGLISH and L_ALL lines print
//! MM_DISPLAY / INCH_DISPLAY / ALL_DISPLAY  the following lines print only in MM / INCH
//!                                        programs, or always
//! M_CLOSE;                               ends the output (later lines are ignored)
//! ```
//!
//! Conversions: `F` (also `LF`) fixed-point (6 decimals unless `.prec`), `D`/`I` whole number
//! (rounded), `S` text of a QS item (also `RS`); flags `-` (left-align), `+`, `0`, blank;
//! `%%` is a percent sign. A line starting with `;` is a comment. Date and time are UTC.
//! The first FN 16 of a run to an output file replaces the file; later ones append. A run
//! writes at most [`super::table::MAX_OUTPUT`] bytes per file. In a check run the format is filled in (so
//! its errors are reported) but nothing is written. `SCREEN:` as output file writes to the
//! log.

use std::path::{Path, PathBuf};

use super::exec::{ExecError, Machine, here};
use super::expr::{ParamKind, ParamRef, Params, Value};
use super::stmt::{ToolCall, ToolId};
use super::tools::Tool;
use crate::diag::ProgramError;
use crate::op::{AxisLetter, OpKind, Plane, SpindleDir};

/// Files and folders a program reads and writes: FN 16 output and FN 26–28 tables.
#[derive(Debug, Default)]
pub(crate) struct ProgramIo {
    /// Folder of the main program; `None` for programs run from memory (no file access).
    pub dir: Option<PathBuf>,
    /// The main program file (CALL_PATH in FN 16 formats).
    pub program: Option<PathBuf>,
    /// Check run: files are read, nothing is written.
    pub dry_run: bool,
    /// FN 16 output files written in this run and their sizes: the first FN 16 to a file
    /// replaces it, later ones append.
    pub written: Vec<(PathBuf, usize)>,
    /// The table opened by FN 26.
    pub table: Option<super::table::Table>,
}

impl Machine {
    /// The program file being run: FN 16 and table paths are relative to its folder.
    pub fn set_program_file(&mut self, path: &Path) {
        self.io.dir = Some(
            path.parent()
                .map_or_else(|| PathBuf::from("."), Path::to_path_buf),
        );
        self.io.program = Some(path.to_path_buf());
    }

    /// Check runs read files but write none (FN 16 output, TABWRITE keep nothing on disk).
    pub fn set_dry_run(&mut self, on: bool) {
        self.io.dry_run = on;
    }
}

impl Machine {
    /// FN 18: reads one system datum.
    pub(super) fn sysread(
        &self,
        id: Value,
        nr: Value,
        idx: Option<Value>,
    ) -> Result<f64, ExecError> {
        let id = self.params.value(id);
        let nr = self.params.value(nr);
        let idx = idx.map_or(0.0, |v| self.params.value(v));
        let unit = self.unit;
        let unsupported = || {
            here(ProgramError::NotSupported(format!(
                "FN 18 SYSREAD ID{id} NR{nr} IDX{idx}"
            )))
        };
        let whole = |x: f64| (x.fract() == 0.0 && (0.0..1e6).contains(&x)).then_some(x as u32);
        let (Some(id_n), Some(nr_n), Some(idx_n)) = (whole(id), whole(nr), whole(idx)) else {
            return Err(unsupported());
        };
        Ok(match (id_n, nr_n) {
            (10, 1) => {
                if unit == 1.0 {
                    0.0
                } else {
                    1.0
                }
            }
            (20, 1) => f64::from(self.tool.unwrap_or(0)),
            (20, 3) => self.tool_axis.index() as f64,
            (20, 4) => self.speed,
            (20, 5) => match self.spindle {
                SpindleDir::Cw => 0.0,
                SpindleDir::Ccw => 1.0,
                SpindleDir::Off => -1.0,
            },
            (20, 8) => {
                if self.coolant {
                    1.0
                } else {
                    0.0
                }
            }
            (20, 9) => match self.feed {
                Some(f) => f * 60.0 / if unit == 1.0 { 1.0 } else { 2.54 },
                None => 0.0,
            },
            (50, 1..=6) => {
                let Some(t) = self.tools.get(idx_n) else {
                    return Err(here(ProgramError::UnknownTool(idx_n.to_string())));
                };
                let v = match nr_n {
                    1 => t.length,
                    2 => t.radius,
                    3 => t.r2,
                    4 => t.dl,
                    5 => t.dr,
                    _ => t.dr2,
                };
                v / unit
            }
            (200, 1) => self.tool_radius / unit,
            (200, 2) => self.tool_length / unit,
            (240 | 270, 1) => {
                let Some(axis) = idx_n
                    .checked_sub(1)
                    .and_then(|i| AxisLetter::ALL.get(i as usize).copied())
                else {
                    return Err(unsupported());
                };
                let v = self.pos[axis];
                if axis.is_rotary() { v } else { v / unit }
            }
            _ => return Err(unsupported()),
        })
    }

    /// FN 15 PRINT: the text and the values of the parameters named in its `Q1/Q2/…` list
    /// go to the log (target `klar::program`). FN 16 F-PRINT: see [`Machine::f_print`].
    pub(super) fn print(&mut self, file: bool, arg: &str) -> Result<(), ExecError> {
        if file {
            return self.f_print(arg).map_err(here);
        }
        let text = self.print_text(arg).map_err(here)?;
        tracing::info!(target: "klar::program", "FN 15 PRINT {text}");
        Ok(())
    }

    /// The text of FN 15 PRINT `item/item/…`: Q, QL, QR items as `Q1 = 2.5`, QS items as
    /// their text, quoted or other text as written.
    fn print_text(&self, arg: &str) -> Result<String, ProgramError> {
        let mut parts = Vec::new();
        for item in arg.split('/') {
            let item = item.trim();
            let upper = item.to_ascii_uppercase();
            let index = |p: &str| {
                upper
                    .strip_prefix(p)
                    .and_then(|n| n.trim().parse::<u32>().ok())
            };
            let number =
                |kind, index| format!("{item} = {}", self.params.get(ParamRef { kind, index }));
            parts.push(if let Some(n) = index("QS") {
                match self.params.get_str(n) {
                    Some(t) => t.to_string(),
                    None => {
                        return Err(ProgramError::Arithmetic(format!(
                            "QS{n} is not defined (assign it before use)"
                        )));
                    }
                }
            } else if let Some(n) = index("QL") {
                number(ParamKind::QL, n)
            } else if let Some(n) = index("QR") {
                number(ParamKind::QR, n)
            } else if let Some(n) = index("Q") {
                number(ParamKind::Q, n)
            } else {
                item.trim_matches('"').to_string()
            });
        }
        Ok(parts.join(", "))
    }

    /// FN 16 F-PRINT `format / output`: fills the format file's lines with parameter values
    /// and writes them to the output file (format rules in the module documentation; paths
    /// as in [`super::table`]).
    fn f_print(&mut self, arg: &str) -> Result<(), ProgramError> {
        let (source, target) = match arg.split_once(" / ").or_else(|| arg.split_once('/')) {
            Some((s, t)) => (s.trim(), t.trim()),
            None => {
                return Err(ProgramError::FileData(
                    "FN 16 needs `format-file / output-file`".into(),
                ));
            }
        };
        let Some(dir) = self.io.dir.clone() else {
            tracing::info!(target: "klar::program", "FN 16 F-PRINT {arg} (program run from memory: no files)");
            return Ok(());
        };
        let fmt_path = super::table::program_relative(&dir, source, "FN 16 format file")?;
        let format = super::table::read_bounded(&fmt_path, super::table::MAX_FORMAT_FILE)?;
        let unit_inch = self.unit != 1.0;
        let text = render(&format, &self.params, self.io.program.as_deref(), unit_inch)
            .map_err(|e| ProgramError::FileData(format!("FN 16 {}: {e}", fmt_path.display())))?;
        let screen = target
            .get(..7)
            .is_some_and(|p| p.eq_ignore_ascii_case("SCREEN:"));
        if screen {
            tracing::info!(target: "klar::program", "FN 16 F-PRINT\n{text}");
            return Ok(());
        }
        let out = super::table::program_relative(&dir, target, "FN 16 output file")?;
        if self.io.dry_run {
            tracing::debug!(target: "klar::program", file = %out.display(), "FN 16 (check run, not written)\n{text}");
            return Ok(());
        }
        super::table::write_output(&mut self.io, &out, &text)
    }

    /// TOOL DEF with L and R defines (or redefines) a tool in the table; without them it
    /// only preselects the next tool, which has no effect on the op stream.
    pub(super) fn tool_def(
        &mut self,
        number: Option<Value>,
        length: Option<Value>,
        radius: Option<Value>,
    ) -> Result<(), ExecError> {
        if length.is_none() && radius.is_none() {
            return Ok(());
        }
        let Some(n) = number.map(|v| self.params.value(v)) else {
            return Err(here(ProgramError::Missing(
                "TOOL DEF with L/R needs a tool number",
            )));
        };
        if !(n >= 0.0 && n.fract() == 0.0 && n <= f64::from(u32::MAX)) {
            return Err(here(ProgramError::OutOfRange(format!(
                "tool number {n} is not a whole number"
            ))));
        }
        let unit = self.unit;
        let len = length.map_or(0.0, |v| self.params.value(v)) * unit;
        let rad = radius.map_or(0.0, |v| self.params.value(v)) * unit;
        self.tools.insert(Tool {
            number: n as u32,
            length: len,
            radius: rad,
            ..Tool::default()
        });
        Ok(())
    }
}

impl Machine {
    pub(super) fn tool_call(
        &mut self,
        tc: &ToolCall,
        text: &[u8],
        emit: &mut impl FnMut(OpKind),
    ) -> Result<(), ExecError> {
        match tc.tool {
            Some(ToolId::Number(v)) => {
                let n = self.params.value(v);
                if !(n >= 0.0 && n.fract() == 0.0 && n <= f64::from(u32::MAX)) {
                    return Err(here(ProgramError::OutOfRange(format!(
                        "tool number {n} is not a whole number from 0 to {}",
                        u32::MAX
                    ))));
                }
                self.tool = Some(n as u32);
                self.tool_name = None;
            }
            Some(ToolId::Name(s, e)) => {
                let name: String = text
                    .get(s..e)
                    .unwrap_or(&[])
                    .iter()
                    .map(|&b| char::from(b))
                    .collect();
                self.tool = self.tools.number_of(&name).or(Some(0));
                self.tool_name = Some(name);
            }
            None => {}
        }
        if let Some(axis) = tc.axis {
            match Plane::from_tool_axis(axis) {
                Some(p) => {
                    self.tool_axis = axis;
                    self.plane = p;
                    // Q109: active tool axis, 0 = X, 1 = Y, 2 = Z
                    self.params.set(
                        ParamRef {
                            kind: ParamKind::Q,
                            index: 109,
                        },
                        axis.index() as f64,
                    );
                }
                None => {
                    return Err(here(ProgramError::NotSupported(format!(
                        "tool axis {axis}"
                    ))));
                }
            }
        }
        let val = |v: Option<Value>| v.map(|v| self.params.value(v));
        let (base_len, base_rad) = match tc.tool {
            None => (self.tool_base.0, self.tool_base.1),
            Some(_) => match self.tools.lookup(self.tool, self.tool_name.as_deref()) {
                Some(t) => {
                    self.tool_unknown = None;
                    (t.length + t.dl, t.radius + t.dr)
                }
                None if self.tools.is_empty() || self.tool == Some(0) => {
                    // tool 0 is the zero tool; any other is known to nobody here
                    self.tool_unknown = match (&self.tool_name, self.tool) {
                        (Some(n), _) => Some(format!("\"{n}\"")),
                        (None, Some(0)) => None,
                        (None, t) => Some(t.unwrap_or(0).to_string()),
                    };
                    (0.0, 0.0)
                }
                None => {
                    return Err(here(ProgramError::UnknownTool(match &self.tool_name {
                        Some(n) => format!("\"{n}\""),
                        None => self.tool.unwrap_or(0).to_string(),
                    })));
                }
            },
        };
        self.tool_base = (base_len, base_rad);
        let length = base_len + val(tc.dl).unwrap_or(0.0) * self.scale;
        let radius = base_rad + val(tc.dr).unwrap_or(0.0) * self.scale;
        self.tool_length = length;
        self.tool_radius = radius;
        if let Some(f) = val(tc.feed) {
            if !(f > 0.0 && f.is_finite()) {
                return Err(here(ProgramError::OutOfRange(format!(
                    "feed rate F{f} must be positive"
                ))));
            }
            self.fauto = Some(f * self.feed_scale() / 60.0);
        }
        let new_speed = val(tc.speed);
        if let Some(s) = new_speed
            && !(s >= 0.0 && s.is_finite())
        {
            return Err(here(ProgramError::OutOfRange(format!(
                "spindle speed S{s} must not be negative"
            ))));
        }
        emit(OpKind::ToolChange {
            tool: self.tool.unwrap_or(0),
            name: self.tool_name.clone(),
            axis: self.tool_axis,
            length,
            radius,
        });
        // Q108: active tool radius, Q114: active tool length (program units)
        self.params.set(
            ParamRef {
                kind: ParamKind::Q,
                index: 108,
            },
            radius / self.scale,
        );
        self.params.set(
            ParamRef {
                kind: ParamKind::Q,
                index: 114,
            },
            length / self.scale,
        );
        if let Some(s) = new_speed {
            self.speed = s;
            if self.spindle != SpindleDir::Off {
                emit(self.spindle_op());
            }
        }
        Ok(())
    }
}

/// One item of a format line's value list.
enum Item {
    Num(f64),
    Text(String),
}

/// Fills in an FN 16 format file.
pub(crate) fn render(
    format: &str,
    params: &Params,
    program: Option<&Path>,
    inch: bool,
) -> Result<String, String> {
    let mut out = String::new();
    let mut show = true;
    for (i, raw) in format.lines().enumerate() {
        let at = |e: String| format!("line {}: {e}", i + 1);
        let mut line = raw.trim();
        if line.is_empty() || line.starts_with(';') {
            continue;
        }
        let word_end = line
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(line.len());
        let word = line.get(..word_end).unwrap_or("").to_ascii_uppercase();
        match word.as_str() {
            "M_CLOSE" => break,
            "ALL_DISPLAY" => {
                show = true;
                continue;
            }
            "MM_DISPLAY" => {
                show = !inch;
                continue;
            }
            "INCH_DISPLAY" => {
                show = inch;
                continue;
            }
            w if w.starts_with("L_") => {
                if !(w == "L_ENGLISH" || w == "L_ALL") {
                    continue;
                }
                line = line.get(word_end..).unwrap_or("").trim_start();
            }
            "" => {}
            other => return Err(at(format!("unknown word '{other}'"))),
        }
        let (fmt, rest) = quoted(line).map_err(at)?;
        let items = list(rest, params, program).map_err(at)?;
        if show {
            out.push_str(&fill(&fmt, &items).map_err(at)?);
            out.push('\n');
        }
    }
    Ok(out)
}

/// The quoted format text at the start of `line` and what follows it.
fn quoted(line: &str) -> Result<(String, &str), String> {
    let body = line
        .strip_prefix('"')
        .ok_or_else(|| "a format line starts with a quoted text".to_string())?;
    let end = body
        .find('"')
        .ok_or_else(|| "text without its closing '\"'".to_string())?;
    Ok((
        body.get(..end).unwrap_or("").to_string(),
        body.get(end + 1..).unwrap_or(""),
    ))
}

/// The values after the format text: `, item, item ;`.
fn list(rest: &str, params: &Params, program: Option<&Path>) -> Result<Vec<Item>, String> {
    let rest = rest.trim();
    let rest = rest.strip_suffix(';').unwrap_or(rest).trim();
    let mut items = Vec::new();
    if rest.is_empty() {
        return Ok(items);
    }
    let rest = rest
        .strip_prefix(',')
        .ok_or_else(|| format!("expected ',' before '{rest}'"))?;
    let now = civil_now();
    for raw in rest.split(',') {
        let w = raw.trim().to_ascii_uppercase();
        let digits = |p: &str| w.strip_prefix(p).and_then(|n| n.trim().parse::<u32>().ok());
        let param = |kind, index| Item::Num(params.get(ParamRef { kind, index }));
        let item = if let Some(n) = digits("QS") {
            Item::Text(
                params
                    .get_str(n)
                    .ok_or_else(|| format!("QS{n} is not defined"))?
                    .to_string(),
            )
        } else if let Some(n) = digits("QL") {
            param(ParamKind::QL, n)
        } else if let Some(n) = digits("QR") {
            param(ParamKind::QR, n)
        } else if let Some(n) = digits("Q") {
            param(ParamKind::Q, n)
        } else {
            match w.as_str() {
                "DAY" => Item::Num(f64::from(now.2)),
                "MONTH" => Item::Num(f64::from(now.1)),
                "STR_MONTH" => Item::Text(month_name(now.1).to_string()),
                "YEAR2" => Item::Num(f64::from(now.0 % 100)),
                "YEAR4" => Item::Num(f64::from(now.0)),
                "HOUR" => Item::Num(f64::from(now.3)),
                "MIN" => Item::Num(f64::from(now.4)),
                "SEC" => Item::Num(f64::from(now.5)),
                "CALL_PATH" => {
                    Item::Text(program.map_or_else(String::new, |p| p.display().to_string()))
                }
                _ => return Err(format!("unknown value '{}'", raw.trim())),
            }
        };
        items.push(item);
    }
    Ok(items)
}

/// Replaces the `%` conversions of `fmt` by the items, in order.
fn fill(fmt: &str, items: &[Item]) -> Result<String, String> {
    let mut out = String::new();
    let mut next = items.iter();
    let mut chars = fmt.chars().peekable();
    while let Some(c) = chars.next() {
        if c != '%' {
            out.push(c);
            continue;
        }
        if chars.peek() == Some(&'%') {
            chars.next();
            out.push('%');
            continue;
        }
        let (mut left, mut plus, mut zero, mut blank) = (false, false, false, false);
        while let Some(&f) = chars.peek() {
            match f {
                '-' => left = true,
                '+' => plus = true,
                '0' => zero = true,
                ' ' => blank = true,
                _ => break,
            }
            chars.next();
        }
        let mut width = 0usize;
        while let Some(d) = chars.peek().and_then(|c| c.to_digit(10)) {
            width = (width * 10 + d as usize).min(255);
            chars.next();
        }
        let mut prec = None;
        if chars.peek() == Some(&'.') {
            chars.next();
            let mut p = 0usize;
            while let Some(d) = chars.peek().and_then(|c| c.to_digit(10)) {
                p = (p * 10 + d as usize).min(16);
                chars.next();
            }
            prec = Some(p);
        }
        let mut conv = chars.next().map(|c| c.to_ascii_uppercase());
        if matches!(conv, Some('L' | 'R')) {
            conv = chars.next().map(|c| c.to_ascii_uppercase());
        }
        let item = next
            .next()
            .ok_or_else(|| "more % conversions than values".to_string())?;
        let body = match (conv, item) {
            (Some('F'), Item::Num(v)) => {
                let p = prec.unwrap_or(6);
                sign(format!("{v:.p$}"), plus, blank)
            }
            (Some('D' | 'I'), Item::Num(v)) => sign(format!("{:.0}", v.round()), plus, blank),
            (Some('S'), Item::Text(s)) => match prec {
                Some(p) => s.chars().take(p).collect(),
                None => s.clone(),
            },
            (Some('S'), Item::Num(_)) => return Err("%S needs a QS value".into()),
            (Some('F' | 'D' | 'I'), Item::Text(_)) => {
                return Err("a number conversion with a text value".into());
            }
            (c, _) => {
                return Err(format!(
                    "unknown conversion '%{}'",
                    c.map_or(String::new(), String::from)
                ));
            }
        };
        out.push_str(&pad(body, width, left, zero));
    }
    if next.next().is_some() {
        return Err("more values than % conversions".into());
    }
    Ok(out)
}

fn sign(s: String, plus: bool, blank: bool) -> String {
    if s.starts_with('-') {
        s
    } else if plus {
        format!("+{s}")
    } else if blank {
        format!(" {s}")
    } else {
        s
    }
}

fn pad(s: String, width: usize, left: bool, zero: bool) -> String {
    let n = s.chars().count();
    if n >= width {
        return s;
    }
    let fill = width - n;
    if left {
        format!("{s}{}", " ".repeat(fill))
    } else if zero {
        let (sign, digits) = match s.strip_prefix(['-', '+', ' ']) {
            Some(d) => (s.get(..1).unwrap_or(""), d),
            None => ("", s.as_str()),
        };
        format!("{sign}{}{digits}", "0".repeat(fill))
    } else {
        format!("{}{s}", " ".repeat(fill))
    }
}

fn month_name(m: u32) -> &'static str {
    const NAMES: [&str; 12] = [
        "January",
        "February",
        "March",
        "April",
        "May",
        "June",
        "July",
        "August",
        "September",
        "October",
        "November",
        "December",
    ];
    NAMES
        .get((m as usize).wrapping_sub(1))
        .copied()
        .unwrap_or("")
}

/// (year, month, day, hour, minute, second) now, UTC.
fn civil_now() -> (u32, u32, u32, u32, u32, u32) {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let days = secs / 86_400;
    let rem = secs % 86_400;
    let (y, m, d) = civil_from_days(days);
    (
        y,
        m,
        d,
        (rem / 3600) as u32,
        (rem % 3600 / 60) as u32,
        (rem % 60) as u32,
    )
}

/// Gregorian date of a day count since 1970-01-01.
fn civil_from_days(days: u64) -> (u32, u32, u32) {
    // shift to an era starting on 0000-03-01 so that leap days end each cycle
    let z = days + 719_468;
    let era = z / 146_097;
    let doe = z % 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + u64::from(m <= 2);
    (y as u32, m as u32, d as u32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::klartext::test_support::{folder, run};
    use crate::op::Pose;

    #[test]
    fn fn15_text_lists_parameters_and_texts() {
        let mut m = Machine::new(Pose::ZERO);
        run(&mut m, "Q1 = 2.5\nQL3 = -1\nQS2 = \"done\"").unwrap();
        assert_eq!(
            m.print_text("Q1/QL3/QS2/\"end\"/QR9").unwrap(),
            "Q1 = 2.5, QL3 = -1, done, end, QR9 = 0"
        );
        let e = run(&mut m, "FN 15: PRINT QS4").unwrap_err();
        assert!(e.contains("QS4 is not defined"), "{e}");
    }

    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        // 2000-02-29 is day 11016; 2024-12-31 is day 20088
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(20_088), (2024, 12, 31));
    }

    #[test]
    fn fn16_writes_the_filled_format_next_to_the_program() {
        let d = folder("fn16");
        std::fs::write(
            d.join("LOG.A"),
            "\"MEASURING LOG\";\n\
             ; a comment line\n\
             \"X = %9.3F mm\", Q1;\n\
             \"N=%D %-4S|%05.1F\", Q2, QS1, Q3;\n\
             L_GERMAN \"nicht\";\n\
             L_ENGLISH \"100%%\";\n\
             INCH_DISPLAY\n\
             \"inch only\";\n\
             ALL_DISPLAY\n\
             M_CLOSE\n\
             \"after close\";\n",
        )
        .unwrap();
        let mut m = Machine::new(Pose::ZERO);
        m.set_program_file(&d.join("prog.h"));
        run(
            &mut m,
            "Q1 = 12.34567\nQ2 = 6.6\nQ3 = -2.25\nQS1 = \"ab\"\n\
             FN 16: F-PRINT TNC:\\LOG.A / TNC:\\out\\RESULT.TXT\n\
             Q1 = 1\nFN 16: F-PRINT LOG.A / RESULT.TXT",
        )
        .unwrap();
        let text = std::fs::read_to_string(d.join("RESULT.TXT")).unwrap();
        let once = |x: &str| format!("MEASURING LOG\nX = {x} mm\nN=7 ab  |-02.2\n100%\n");
        assert_eq!(text, once("   12.346") + &once("    1.000"));
        // the first FN 16 of a new run replaces the file
        let mut m2 = Machine::new(Pose::ZERO);
        m2.set_program_file(&d.join("prog.h"));
        run(&mut m2, "FN 16: F-PRINT LOG.A / RESULT.TXT").unwrap_err();
        run(&mut m2, "QS1 = \"c\"\nFN 16: F-PRINT LOG.A / RESULT.TXT").unwrap();
        let text = std::fs::read_to_string(d.join("RESULT.TXT")).unwrap();
        assert_eq!(
            text,
            "MEASURING LOG\nX =     0.000 mm\nN=0 c   |000.0\n100%\n"
        );
        // a check run writes nothing
        let mut m3 = Machine::new(Pose::ZERO);
        m3.set_program_file(&d.join("prog.h"));
        m3.set_dry_run(true);
        run(&mut m3, "QS1 = \"c\"\nFN 16: F-PRINT LOG.A / CHECK.TXT").unwrap();
        assert!(!d.join("CHECK.TXT").exists());
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn fn16_errors() {
        let d = folder("fn16err");
        std::fs::write(d.join("BAD.A"), "\"%F %F\", Q1;\n").unwrap();
        std::fs::write(d.join("WORD.A"), "FOO \"x\";\n").unwrap();
        let mut m = Machine::new(Pose::ZERO);
        m.set_program_file(&d.join("p.h"));
        let e = run(&mut m, "FN 16: F-PRINT BAD.A / O.TXT").unwrap_err();
        assert!(e.contains("line 1: more % conversions than values"), "{e}");
        let e = run(&mut m, "FN 16: F-PRINT WORD.A / O.TXT").unwrap_err();
        assert!(e.contains("unknown word 'FOO'"), "{e}");
        let e = run(&mut m, "FN 16: F-PRINT NONE.A / O.TXT").unwrap_err();
        assert!(e.contains("NONE.A"), "{e}");
        for escape in ["..\\x.A", "/etc/x.A", "PLC:\\x.A"] {
            let e = run(&mut m, &format!("FN 16: F-PRINT {escape} / O.TXT")).unwrap_err();
            assert!(e.contains("FN 16 format file"), "{escape}: {e}");
        }
        let _ = std::fs::remove_dir_all(&d);
    }
}
