//! The machine's tables: tools (TOOL.T and `[[tool]]`), presets (PRESET.PR) and datums
//! (.D), each file named relative to the machine file, read when the machine file is loaded
//! and handed to every program opened on the machine.

use super::MachineConfig;
use klar_interp::{DatumTable, Interpreter, Tool, ToolTable};
use std::path::{Path, PathBuf};

/// Which preset the program starts from, for the check report and the dashboard.
#[derive(Debug, Clone, PartialEq)]
pub enum ActivePreset {
    /// No preset: program coordinates are machine coordinates.
    MachineDatum,
    /// Row `nr` of the preset table, with its axis values (mm, degrees; unset axes 0).
    Row {
        /// The row number.
        nr: i64,
        /// The preset's values in pose order (X Y Z A B C U V W).
        values: [f64; 9],
    },
}

impl std::fmt::Display for ActivePreset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ActivePreset::MachineDatum => write!(f, "none (machine datum)"),
            ActivePreset::Row { nr, values } => {
                write!(f, "{nr}")?;
                let letters = ["X", "Y", "Z", "A", "B", "C", "U", "V", "W"];
                for (l, v) in letters.iter().zip(values) {
                    if *v != 0.0 {
                        write!(f, " {l}{v:+}")?;
                    }
                }
                Ok(())
            }
        }
    }
}

fn load_datums(path: &Path, what: &str) -> Result<DatumTable, String> {
    let text = klar_interp::read_bounded(path, klar_interp::MAX_TABLE_FILE)
        .map_err(|e| format!("{what} {}: {e}", path.display()))?;
    // Tables saved on a control may be latin-1.
    let text: String = match String::from_utf8(text) {
        Ok(s) => s,
        Err(e) => e.into_bytes().iter().map(|&b| b as char).collect(),
    };
    DatumTable::parse(&text).map_err(|e| format!("{what} {}: {e}", path.display()))
}

impl MachineConfig {
    /// A path of the machine file, resolved from the machine file's folder.
    fn resolve(&self, file: &Path) -> PathBuf {
        match &self.base_dir {
            Some(dir) => dir.join(file),
            None => file.to_path_buf(),
        }
    }

    /// The machine's tool table: the `tool_table` file, then the `[[tool]]` entries (which
    /// win for the same number). `None` when the machine names no tools.
    pub fn tool_table(&self) -> Result<Option<ToolTable>, String> {
        let mut table = match &self.tool_table {
            None => None,
            Some(file) => {
                let path = self.resolve(file);
                Some(ToolTable::load(&path).map_err(|e| format!("{}: {e}", path.display()))?)
            }
        };
        if let Some(tools) = &self.tools {
            let t = table.get_or_insert_with(ToolTable::new);
            for tool in tools {
                t.insert(Tool {
                    number: tool.number,
                    name: tool.name.clone().unwrap_or_default(),
                    length: tool.length,
                    radius: tool.radius,
                    r2: 0.0,
                    dl: 0.0,
                    dr: 0.0,
                    dr2: 0.0,
                });
            }
        }
        Ok(table)
    }

    /// The machine's preset table, when it names one.
    pub fn preset_table(&self) -> Result<Option<DatumTable>, String> {
        self.preset_table
            .as_ref()
            .map(|f| load_datums(&self.resolve(f), "preset_table"))
            .transpose()
    }

    /// The machine's datum table, when it names one.
    pub fn datum_table(&self) -> Result<Option<DatumTable>, String> {
        self.datum_table
            .as_ref()
            .map(|f| load_datums(&self.resolve(f), "datum_table"))
            .transpose()
    }

    /// The preset a program starts from.
    pub fn active_preset(&self) -> Result<ActivePreset, String> {
        let Some(nr) = self.active_preset else {
            return Ok(ActivePreset::MachineDatum);
        };
        let table = self
            .preset_table()?
            .ok_or_else(|| format!("active_preset = {nr} needs a preset_table"))?;
        let row = table
            .row(nr)
            .ok_or_else(|| format!("active_preset = {nr}: the preset table has no row {nr}"))?;
        Ok(ActivePreset::Row {
            nr,
            values: row.map(|v| v.unwrap_or(0.0)),
        })
    }

    /// Reads every table the machine names: the first error, if any.
    pub(super) fn check_tables(&self) -> Result<(), String> {
        self.tool_table()?;
        self.datum_table()?;
        self.active_preset()?;
        Ok(())
    }

    /// `interp` told the machine's tables and active preset. Tables that cannot be read were
    /// refused when the machine file was loaded; a machine built in code without loading
    /// skips them.
    pub(super) fn with_tables(&self, mut interp: Interpreter) -> Interpreter {
        if let Ok(Some(t)) = self.tool_table() {
            interp = interp.with_tools(t);
        }
        if let Ok(Some(t)) = self.datum_table() {
            interp = interp.with_datum_table(t);
        }
        if let Ok(Some(t)) = self.preset_table() {
            interp = interp.with_preset_table(t);
            if let Some(nr) = self.active_preset {
                interp = interp.with_active_preset(nr);
            }
        }
        interp
    }
}
