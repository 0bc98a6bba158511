//! Recognising which HEIDENHAIN language a program is written in.
//!
//! Content wins over the file name: the first meaningful line decides when it is conclusive
//! (`BEGIN PGM` → Klartext; `%NAME G70|G71` → TNC ISO; `%name.nc`, a `"TURN_V…"` marker, `#`
//! header lines or a lathe section code such as `PROGRAMMKOPF`/`HEADER` → lathe DIN). Otherwise
//! the extension decides: `.h` Klartext, `.i` ISO, `.nc`/`.ncs` lathe DIN (case-insensitive).

use std::path::Path;

use crate::diag::Diagnostic;
use crate::op::{Op, Pose};

/// A running program in a dialect other than Klartext (TNC ISO, lathe DIN): what the
/// [`crate::Interpreter`] delegates to.
pub(crate) trait DialectRun: Iterator<Item = Result<Op, Diagnostic>> + Send {
    /// Runs to the end without stopping at errors (`syntax_only`: parse only) and returns
    /// every diagnostic.
    fn check_all(&mut self, syntax_only: bool) -> Vec<Diagnostic>;
    /// Blocks executed so far.
    fn blocks_executed(&self) -> u64;
    /// The last programmed position.
    fn last_position(&self) -> Pose;
    /// Switches block skip (`/` blocks) on or off.
    fn set_block_skip(&mut self, on: bool);
    /// The Klartext machine that executes this dialect's blocks, if it has one (TNC ISO: its
    /// blocks are run as the Klartext statements with the same meaning). Everything the
    /// [`crate::Interpreter`] is told about the machine (tools, rotary axes, M functions,
    /// datum and preset tables, working-plane ops, …) goes to this machine. Lathe DIN has its
    /// own lathe model and takes none of these (see [`crate::Interpreter::with_tools`]).
    fn klartext_machine(&mut self) -> Option<&mut crate::tnc::exec::Machine> {
        None
    }
    /// Read access to [`DialectRun::klartext_machine`].
    fn klartext_machine_ref(&self) -> Option<&crate::tnc::exec::Machine> {
        None
    }
}

/// A HEIDENHAIN program language.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Dialect {
    /// TNC conversational programming (`.h`).
    Klartext,
    /// TNC DIN/ISO programming (`.i`).
    Iso,
    /// Lathe DIN PLUS of CNC PILOT / MANUALplus / smart.Turn (`.nc`, `.ncs`).
    LatheDin,
}

/// The runner for a non-Klartext dialect reading `input` (None for Klartext, which the
/// [`crate::Interpreter`] runs itself).
pub(crate) fn runner(
    dialect: Dialect,
    file: std::path::PathBuf,
    input: Box<dyn crate::source::ProgramInput>,
    start: Pose,
) -> Option<Box<dyn DialectRun>> {
    match dialect {
        Dialect::Klartext => None,
        Dialect::Iso => Some(Box::new(crate::iso::run::IsoProgram::new(
            file, input, start,
        ))),
        Dialect::LatheDin => Some(Box::new(crate::din::run::DinProgram::new(
            file, input, start,
        ))),
    }
}

impl Dialect {
    /// A human-readable name.
    pub fn name(self) -> &'static str {
        match self {
            Dialect::Klartext => "Klartext",
            Dialect::Iso => "TNC ISO",
            Dialect::LatheDin => "lathe DIN",
        }
    }
}

const LATHE_SECTIONS: [&str; 16] = [
    "PROGRAMMKOPF",
    "HEADER",
    "PROGRAM HEAD",
    "REVOLVER",
    "TURRET",
    "SPANNMITTEL",
    "CHUCKING EQUIPMENT",
    "ROHTEIL",
    "BLANK",
    "FERTIGTEIL",
    "FINISHED",
    "BEARBEITUNG",
    "MACHINING",
    "ENDE",
    "CONST",
    "VAR",
];

/// Detects the dialect from the file name and the first bytes of the text (`head`, a few
/// hundred bytes are enough). Returns `None` when neither is conclusive.
pub fn detect_dialect(path: &Path, head: &[u8]) -> Option<Dialect> {
    from_content(head).or_else(|| from_extension(path))
}

fn from_extension(path: &Path) -> Option<Dialect> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "h" => Some(Dialect::Klartext),
        "i" => Some(Dialect::Iso),
        "nc" | "ncs" => Some(Dialect::LatheDin),
        _ => None,
    }
}

fn from_content(head: &[u8]) -> Option<Dialect> {
    for raw in head.split(|&b| b == b'\n') {
        let line: String = raw.iter().map(|&b| char::from(b)).collect();
        let line = line.trim();
        if line.is_empty() || line.starts_with(';') || line.starts_with('(') {
            continue;
        }
        let upper = line.to_ascii_uppercase();
        if upper.contains("BEGIN PGM") {
            return Some(Dialect::Klartext);
        }
        if upper.starts_with("\"TURN_V") || upper.starts_with('#') {
            return Some(Dialect::LatheDin);
        }
        if let Some(rest) = upper.strip_prefix('%') {
            let name = rest.split_whitespace().next().unwrap_or("");
            if name.ends_with(".NC") || name.ends_with(".NCS") {
                return Some(Dialect::LatheDin);
            }
            if rest
                .split_whitespace()
                .any(|w| w.starts_with("G70") || w.starts_with("G71"))
            {
                return Some(Dialect::Iso);
            }
        }
        if LATHE_SECTIONS.iter().any(|s| upper == *s) {
            return Some(Dialect::LatheDin);
        }
        return None;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn content_decides() {
        let p = Path::new("prog.txt");
        assert_eq!(
            detect_dialect(p, b"0 BEGIN PGM A MM\n"),
            Some(Dialect::Klartext)
        );
        assert_eq!(detect_dialect(p, b"%ABC G71 *\r\n"), Some(Dialect::Iso));
        assert_eq!(detect_dialect(p, b"%shaft.nc\n"), Some(Dialect::LatheDin));
        assert_eq!(
            detect_dialect(p, b"; header\nPROGRAMMKOPF\n"),
            Some(Dialect::LatheDin)
        );
        assert_eq!(detect_dialect(p, b"G0 X1\n"), None);
    }

    #[test]
    fn extension_when_content_is_silent() {
        assert_eq!(
            detect_dialect(Path::new("a.H"), b""),
            Some(Dialect::Klartext)
        );
        assert_eq!(detect_dialect(Path::new("a.i"), b""), Some(Dialect::Iso));
        assert_eq!(
            detect_dialect(Path::new("a.NCS"), b""),
            Some(Dialect::LatheDin)
        );
        assert_eq!(detect_dialect(Path::new("a.txt"), b""), None);
    }
}
