//! klar: a CNC control for HEIDENHAIN programs (Klartext, TNC ISO, lathe DIN).
//!
//! This root crate holds the machine configuration ([`config`]), the machine's backends
//! ([`machine`]), the runtime that wires interpreter → planner → kinematics → backends
//! ([`runtime`]), the trace CSV ([`trace`]), toolpath plots ([`plot`]) and the lab-bench web
//! dashboard ([`serve`]). The command-line front end lives in `main.rs`.

#![warn(missing_docs)]

pub mod bounds;
pub mod config;
pub mod faults;
pub mod latency;
pub mod machine;
pub mod monitor;
pub mod plot;
pub mod rt;
pub mod runtime;
pub mod serve;
pub mod state;
pub mod testrun;
pub mod trace;
pub mod workpiece;
