//! TNC conversational (Klartext) programs: lexer, parser, executor, contour geometry,
//! program structure (labels, calls, jumps), system data and the tool table.

pub(crate) mod block;
pub(crate) mod contour;
pub(crate) mod cycle;
pub(crate) mod cycle_exec;
pub(crate) mod cycle_pattern;
pub(crate) mod cycle_sl;
pub(crate) mod cycle_table;
pub(crate) mod exec;
pub(crate) mod expr;
pub(crate) mod fk;
pub(crate) mod fk_build;
pub(crate) mod fk_eqs;
pub(crate) mod fk_lm;
pub(crate) mod fk_solve;
pub(crate) mod formula;
pub(crate) mod geom;
pub(crate) mod lexer;
pub(crate) mod mfunc;
pub(crate) mod parser;
pub(crate) mod paths;
pub(crate) mod plane;
pub(crate) mod plane_math;
pub(crate) mod plane_output;
pub(crate) mod plane_turn;
pub(crate) mod retract;
pub(crate) mod rotary_feed;
pub(crate) mod strings;
pub(crate) mod structure;
pub(crate) mod system;
pub(crate) mod table;
pub(crate) mod tcpm;
#[cfg(test)]
mod test_support;
pub(crate) mod tools;
pub(crate) mod transform;
pub(crate) mod words;
