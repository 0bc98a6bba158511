//! klar-interp: HEIDENHAIN program text → canonical [`op::Op`] stream.
//!
//! Dialects: TNC conversational Klartext (`.h`), TNC ISO (`.i`, mapped onto the Klartext
//! machine: [`iso`]) and lathe DIN (`.nc`: [`din`]). The interpreter streams: it reads a
//! block, executes it against its modal state and emits the resulting ops, each with the
//! source location of its block, so memory use does not grow with the program.

#![warn(missing_docs)]

pub mod cycles;
pub mod diag;
pub mod dialect;
pub mod din;
mod files;
mod interpreter;
pub mod iso;
pub(crate) mod klartext;
pub mod op;
mod source;

pub use diag::{Diagnostic, MAX_QUOTED_CHARS, ProgramError, shorten_words};
pub use dialect::{Dialect, detect_dialect};
pub use files::{not_a_file, read_bounded};
pub use interpreter::{
    CHECK_DIAGNOSTIC_LIMIT, CHECK_JUMP_LIMIT, CheckReport, Interpreter, MAX_PROGRAM_DEPTH,
    MAX_SUBPROGRAM_DEPTH, RUN_IDLE_JUMP_LIMIT, check, check_report, syntax_check,
};
pub use klartext::contour::SPLINE_START_TOLERANCE;
pub use klartext::cycle_table::{DatumTable, DatumTableError};
pub use klartext::exec::{Blank, C_RADIUS_TOLERANCE, MAX_IPA};
pub use klartext::table::MAX_TABLE_FILE;
pub use klartext::tools::{Tool, ToolTable, ToolTableError};
pub use op::{
    ApproachShape, AxisLetter, CompSide, CornerRule, Feed, Op, OpKind, Plane, Pose, SourceLoc,
    SplineAxis,
};
pub use source::MAX_BLOCK_BYTES;
