//! klar: a CNC control for HEIDENHAIN programs (Klartext, TNC ISO, lathe DIN).
//!
//! This root crate holds the machine configuration ([`config`]), the machine's backends
//! ([`machine`]), the runtime that wires interpreter → planner → kinematics → backends
//! ([`runtime`]), the trace CSV ([`trace`]) and
//! toolpath plots ([`plot`]). The command-line front end lives in `main.rs`.

pub mod bounds;
pub mod config;
pub mod machine;
pub mod plot;
pub mod runtime;
pub mod trace;
