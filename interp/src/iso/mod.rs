//! TNC DIN/ISO (`.i`) programs: block syntax, the mapping onto the Klartext machine, and the
//! streaming runner with labels, subprogram calls and jumps.
//!
//! ISO blocks are translated into the Klartext statements with the same meaning and executed
//! by the Klartext machine, so an ISO program and its Klartext twin yield the same op stream.

pub(crate) mod block;
pub(crate) mod cycles;
pub(crate) mod dfunc;
pub(crate) mod exec;
pub(crate) mod run;

pub use run::{MAX_CALL_DEPTH, MAX_IDLE_JUMPS};
