//! The subcommand handlers of the `klar` binary that are large enough for files of their own.

pub(crate) mod check;
pub(crate) mod run;
