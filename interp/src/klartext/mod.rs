//! TNC conversational (Klartext) programs: the front-end that reads Klartext text — lexer,
//! parser, formulas, program structure (labels, calls), cycle, FK, PLANE, FUNCTION TCPM and
//! string syntax — into the statements the TNC core executes ([`crate::tnc`]).

pub(crate) mod cycle;
pub(crate) mod fk;
pub(crate) mod formula;
pub(crate) mod lexer;
pub(crate) mod parser;
pub(crate) mod plane;
pub(crate) mod probe;
pub(crate) mod strings;
pub(crate) mod structure;
pub(crate) mod tcpm;
#[cfg(test)]
pub(crate) mod test_support;
pub(crate) mod words;
