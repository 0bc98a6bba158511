//! klar-interp: HEIDENHAIN program text → canonical [`op::Op`] stream.
//!
//! Dialects: TNC conversational Klartext (`.h`), TNC ISO (`.i`) and lathe DIN (`.nc`).
//! The interpreter streams: it reads a block, executes it against its modal state and emits
//! the resulting ops, each with the source location of its block.

pub mod op;

pub use op::{AxisLetter, CompSide, Feed, Op, OpKind, Plane, Pose, SourceLoc};
