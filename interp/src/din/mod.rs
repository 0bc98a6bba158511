//! Lathe DIN PLUS (`.nc`, `.ncs`) programs: recognised by [`crate::detect_dialect`], not
//! executed yet.
//!
//! The interpreter reports "dialect not supported yet" for these files; the section-aware
//! lathe parser and executor will live in this module.
