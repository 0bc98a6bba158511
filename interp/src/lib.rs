//! klar-interp: HEIDENHAIN program text → canonical [`op::Op`] stream.
//!
//! Dialects: the two TNC languages — conversational Klartext (`.h`, front-end `klartext`)
//! and TNC ISO (`.i`, front-end [`iso`]) — read their text into the statements of one TNC
//! machine (`tnc`: the executor with its modal state, parameters, contours, working plane,
//! cycles and tables); the lathe DIN dialect (`.nc`: [`din`]) has its own. The shared
//! machining cycles are in [`cycles`]. The interpreter streams: it reads a block, executes it
//! against its modal state and emits the resulting ops, each with the source location of its
//! block, so memory use does not grow with the program.

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
pub mod probe;
mod source;
pub(crate) mod tnc;

pub use diag::{Diagnostic, MAX_QUOTED_CHARS, ProgramError, shorten_words};
pub use dialect::{Dialect, detect_dialect};
pub use files::{not_a_file, read_bounded};
pub use interpreter::{
    CHECK_DIAGNOSTIC_LIMIT, CHECK_JUMP_LIMIT, CheckReport, Interpreter, MAX_PROGRAM_DEPTH,
    MAX_SUBPROGRAM_DEPTH, RUN_IDLE_JUMP_LIMIT, check, check_report, syntax_check,
};
pub use op::{
    ApproachShape, AxisLetter, CompSide, CornerRule, Feed, Op, OpKind, Plane, Pose, PresetWrite,
    ProbeResult, SourceLoc, SplineAxis,
};
pub use probe::{Probe, ProbeAnswer, ProbeData, ProbeRequest, ProbeStop};
pub use source::MAX_BLOCK_BYTES;
pub use tnc::contour::SPLINE_START_TOLERANCE;
pub use tnc::cycle_table::{DatumTable, DatumTableError};
pub use tnc::exec::{Blank, C_RADIUS_TOLERANCE, MAX_IPA};
pub use tnc::probe_report::ToleranceError;
pub use tnc::table::MAX_TABLE_FILE;
pub use tnc::tools::{Tool, ToolTable, ToolTableError};
