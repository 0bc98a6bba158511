//! The TNC machine both TNC languages run on: the statement model a front-end fills
//! ([`stmt`]), the executor with its modal state ([`exec::Machine`]), Q parameters and
//! formulas, contours and FK geometry, the working plane and TCPM, cycles, tables, tools
//! and system data. Klartext ([`crate::klartext`]) and TNC ISO ([`crate::iso`]) are thin
//! front-ends that turn program text into these statements.

pub(crate) mod contour;
pub(crate) mod cycle_exec;
pub(crate) mod cycle_pattern;
pub(crate) mod cycle_sl;
pub(crate) mod cycle_table;
pub(crate) mod cycle_words;
pub(crate) mod exec;
pub(crate) mod expr;
pub(crate) mod fk_build;
pub(crate) mod fk_eqs;
pub(crate) mod fk_lm;
pub(crate) mod fk_solve;
pub(crate) mod fk_words;
pub(crate) mod geom;
pub(crate) mod mfunc;
pub(crate) mod op_points;
pub(crate) mod paths;
pub(crate) mod plane;
pub(crate) mod plane_math;
pub(crate) mod plane_output;
pub(crate) mod plane_turn;
pub(crate) mod probe_cycles;
pub(crate) mod probe_exec;
pub(crate) mod probe_measure;
pub(crate) mod probe_ref;
pub mod probe_report;
pub(crate) mod probe_rotary;
pub(crate) mod probe_wait;
pub(crate) mod retract;
pub(crate) mod rotary_feed;
pub(crate) mod stmt;
pub(crate) mod strings;
pub(crate) mod system;
pub(crate) mod table;
pub(crate) mod tcpm;
pub(crate) mod tools;
pub(crate) mod transform;
