//! TNC DIN/ISO (`.i`) programs: recognised by [`crate::detect_dialect`], not executed yet.
//!
//! The interpreter reports "dialect not supported yet" for these files; the ISO lexer,
//! parser and executor will live in this module next to the Klartext ones.
