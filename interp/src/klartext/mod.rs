//! TNC conversational (Klartext) programs: lexer, parser, executor and arc geometry.

pub(crate) mod exec;
pub(crate) mod expr;
pub(crate) mod formula;
pub(crate) mod geom;
pub(crate) mod lexer;
pub(crate) mod mfunc;
pub(crate) mod parser;
pub(crate) mod words;
