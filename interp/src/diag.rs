//! Diagnostics: what the interpreter reports about a program, and the error kinds behind them.

use std::fmt;
use std::path::PathBuf;
use thiserror::Error;

/// One problem found in a program, located by file, line and column.
///
/// Displayed as `file:line:col: message`; when the block carries a block number the message
/// starts with `block N: `.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    /// The program file (as given to the interpreter, or the name passed to `from_source`).
    pub file: PathBuf,
    /// 1-based line.
    pub line: u32,
    /// 1-based column in characters.
    pub col: u32,
    /// The block number written in the program, if the block has one.
    pub block: Option<u64>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}:{}: {}",
            self.file.display(),
            self.line,
            self.col,
            self.message
        )
    }
}

impl std::error::Error for Diagnostic {}

impl Diagnostic {
    /// Builds a diagnostic from an error kind, prefixing the block number when known.
    pub(crate) fn new(
        file: PathBuf,
        line: u32,
        col: u32,
        block: Option<u64>,
        error: &ProgramError,
    ) -> Self {
        Self::with_message(file, line, col, block, error.to_string())
    }

    /// Builds a diagnostic (an error or a warning) from its message, prefixing the block
    /// number when known.
    pub(crate) fn with_message(
        file: PathBuf,
        line: u32,
        col: u32,
        block: Option<u64>,
        message: String,
    ) -> Self {
        let message = shorten_words(&message);
        let message = match block {
            Some(n) => format!("block {n}: {message}"),
            None => message,
        };
        Diagnostic {
            file,
            line,
            col,
            block,
            message,
        }
    }
}

/// Longest word a diagnostic quotes from a program, in characters; a longer one is cut there
/// and ends in `…`.
pub const MAX_QUOTED_CHARS: usize = 80;

/// `message` with every run of non-blank characters longer than [`MAX_QUOTED_CHARS`] cut to
/// that length and marked with `…` (words of the program quoted in a message stay readable
/// whatever the program holds; the message's own words are all shorter).
pub fn shorten_words(message: &str) -> String {
    let mut out = String::with_capacity(message.len().min(1024));
    let mut run = 0usize;
    for c in message.chars() {
        if c.is_whitespace() {
            run = 0;
            out.push(c);
            continue;
        }
        run += 1;
        if run <= MAX_QUOTED_CHARS {
            out.push(c);
        } else if run == MAX_QUOTED_CHARS + 1 {
            out.push('…');
        }
    }
    out
}

/// Everything that can be wrong with a program or with reading it.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ProgramError {
    /// The file could not be read.
    #[error("cannot read program: {0}")]
    Io(String),
    /// The file is in a dialect this version cannot run.
    #[error("dialect not supported yet: {0}")]
    DialectNotSupported(&'static str),
    /// The dialect could not be recognised from the name or the text.
    #[error("cannot tell the program dialect (expected .h Klartext, .i TNC ISO or .nc lathe DIN)")]
    UnknownDialect,
    /// The path names something other than a regular file (a folder, a FIFO, a device):
    /// reading it could block or never end, so it is refused before it is opened.
    #[error("not a regular file ({0}): a program is read from a file")]
    NotAFile(&'static str),
    /// The first block is not `BEGIN PGM`.
    #[error("missing BEGIN PGM: a Klartext program starts with `BEGIN PGM name MM|INCH`")]
    MissingBegin,
    /// The text ended without `END PGM`.
    #[error("END PGM missing at end of file")]
    MissingEnd,
    /// A block follows `END PGM`.
    #[error("block after END PGM")]
    AfterEnd,
    /// The block keyword is not Klartext.
    #[error("unknown block type '{0}'")]
    UnknownBlock(String),
    /// A word that the block type does not know.
    #[error("unknown word '{word}' in {block} block")]
    UnknownWord {
        /// The word as written.
        word: String,
        /// The block type.
        block: &'static str,
    },
    /// A known word in a block type that does not take it.
    #[error("word {word} is not allowed in {block} block")]
    MisplacedWord {
        /// The word.
        word: String,
        /// The block type.
        block: &'static str,
    },
    /// A word appears twice in one block.
    #[error("word {0} programmed twice in one block")]
    DuplicateWord(String),
    /// A word that needs a value has none.
    #[error("missing value after {0}")]
    MissingValue(String),
    /// Something required by the block type is absent.
    #[error("{0}")]
    Missing(&'static str),
    /// A token that does not fit where it stands.
    #[error("unexpected {0}")]
    Unexpected(String),
    /// A template placeholder such as `{0:+d}` left in the text.
    #[error("template placeholder '{0}' in program text (fill in the template first)")]
    Placeholder(String),
    /// A number or parameter index that is out of range.
    #[error("{0}")]
    OutOfRange(String),
    /// A feature that will come later.
    #[error("{0} not supported yet")]
    NotSupported(String),
    /// An M function that is not implemented.
    #[error("M{0} not supported on this machine")]
    UnsupportedM(u32),
    /// TOOL CALL of a tool missing from the tool table.
    #[error("tool {0} is not in the tool table")]
    UnknownTool(String),
    /// A cycle needs the radius of a tool that no tool table and no TOOL DEF gives.
    #[error(
        "tool {tool} is not in the tool table: cycle {cycle} needs its radius (give it in the \
         machine's tool table or with TOOL DEF)"
    )]
    UnknownToolRadius {
        /// The tool as called (`7`, `"NAME"`).
        tool: String,
        /// The cycle that needs the radius.
        cycle: u32,
    },
    /// FN 14: the program stopped itself with an error number.
    #[error("FN 14: program stopped with error number {0}")]
    FnError(f64),
    /// CALL PGM could not open the called program.
    #[error("{0}")]
    CallPgm(String),
    /// A jump or call to a label that the program does not define.
    #[error("{0} not found in the program")]
    NoLabel(String),
    /// A subprogram or program call nested too deep, or a program calling itself.
    #[error("{0}")]
    Nesting(String),
    /// A C block whose end point lies on a different radius about CC than its start.
    #[error(
        "C end point is {end:.4} mm from CC, start point {start:.4} mm: radii differ by more than {tol} mm"
    )]
    RadiusMismatch {
        /// Start radius.
        start: f64,
        /// End radius.
        end: f64,
        /// Tolerance.
        tol: f64,
    },
    /// A CR block whose chord does not fit the radius.
    #[error("CR chord {chord:.3} mm longer than 2R = {two_r:.3} mm")]
    ChordTooLong {
        /// Distance from start to end point.
        chord: f64,
        /// Twice the programmed radius.
        two_r: f64,
    },
    /// An arc that needs a pole before CC was programmed.
    #[error("{0} without circle centre: program CC first")]
    NoPole(&'static str),
    /// CP with IPA whose sign is not the DR sign.
    #[error("IPA{ipa:+} and DR{dr} have different signs")]
    IpaSign {
        /// The incremental angle.
        ipa: f64,
        /// `+` or `-`.
        dr: char,
    },
    /// An arc block that describes no arc.
    #[error("{0}")]
    Geometry(String),
    /// A motion at feed with no feed programmed.
    #[error("no feed rate programmed: add F to this or an earlier block")]
    NoFeed,
    /// FN 16 output or a table (FN 26–28) that cannot be read or written.
    #[error("{0}")]
    FileData(String),
    /// A file the program reads (a table, an FN 16 format file) is not there.
    #[error("{0}")]
    MissingFile(String),
    /// Arithmetic failure in a Q parameter computation.
    #[error("{0}")]
    Arithmetic(String),
    /// A machining cycle cannot be generated (unknown number, parameter errors).
    #[error("{0}")]
    Cycle(crate::cycles::CycleError),
    /// A touch-probe cycle failed (nothing touched, already in contact, bad parameters).
    #[error("{0}")]
    Probe(crate::probe::ProbeError),
    /// A measuring touch-probe cycle found a result out of tolerance and Q309=1 asks to stop.
    #[error("{0}")]
    Tolerance(crate::tnc::probe_report::ToleranceError),
    /// A cycle call without a defined machining cycle.
    #[error("{0} without a defined machining cycle: program CYCL DEF first")]
    NoCycle(&'static str),
    /// A datum or preset table row that is not there (or no table at all).
    #[error("{table} table has no row {row}")]
    NoDatumRow {
        /// `datum` or `preset`.
        table: &'static str,
        /// The row asked for.
        row: f64,
    },
    /// A datum or preset row asked for on a machine without that table.
    #[error(
        "{table} {row} asked for, but the machine has no {table} table (`{key}` in the machine file)"
    )]
    NoTable {
        /// `datum` or `preset`.
        table: &'static str,
        /// The row asked for.
        row: f64,
        /// The machine-file key that names the table.
        key: &'static str,
    },
    /// An error inside a contour subprogram of an SL cycle.
    #[error("contour {label} (line {line}): {error}")]
    Contour {
        /// The contour's label.
        label: String,
        /// Line of the block with the error.
        line: u32,
        /// What is wrong.
        error: Box<ProgramError>,
    },
    /// A coordinate transform that cannot be applied (mirrored tool axis, arc that would
    /// become an ellipse, …).
    #[error("{0}")]
    Transform(String),
    /// A tilted working plane that cannot be set up (missing rotary axes, degenerate data).
    #[error("{0}")]
    Plane(String),
    /// FK data that leave several solutions and no FSELECT picks one.
    #[error("FK: {count} solutions for blocks {blocks}: add FSELECT")]
    FkAmbiguous {
        /// How many solutions were found.
        count: usize,
        /// The blocks concerned, e.g. `12–14`.
        blocks: String,
    },
    /// FK elements still not determined when the FK section ends.
    #[error("FK: blocks {0} are under-determined: the contour needs more data")]
    FkUnderdetermined(String),
    /// FK data that no contour satisfies.
    #[error("FK: the data of block {0} contradict the contour before it")]
    FkContradiction(String),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_words_are_cut_in_messages() {
        let long = "X".repeat(10_000);
        let d = Diagnostic::with_message(
            PathBuf::from("a.h"),
            1,
            1,
            Some(3),
            format!("unknown word '{long}' in L block"),
        );
        let quoted = format!("'{}…", "X".repeat(MAX_QUOTED_CHARS - 1));
        assert_eq!(
            d.message,
            format!("block 3: unknown word {quoted} in L block")
        );
        // short words and multi-byte characters are kept as they are
        assert_eq!(shorten_words("ä 'Ü' b"), "ä 'Ü' b");
    }
}
