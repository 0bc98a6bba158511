//! CiA 402 servo drives as machine axes and spindle: the power state machine, the objects
//! and PDO layouts klar uses, scaling between counts and mm/degrees/rpm, the machine-config
//! shape, the shared CANopen network, [`Cia402Backend`] (the
//! [`klar_motion::AxisBackend`]) and [`Cia402Spindle`] (the [`klar_motion::SpindleBackend`]).

pub mod backend;
pub mod config;
pub mod network;
pub mod objects;
pub mod scaling;
mod setup;
pub mod spindle;
pub mod state;
pub mod touch_probe;

pub use backend::Cia402Backend;
pub use config::{
    AxisMode, BusConfig, CanOpenConfig, DriveConfig, HomingConfig, SpindleConfig, SpindleMode,
};
pub use network::{Cia402Error, cyclic_traffic, spindle_position_traffic};
pub use spindle::Cia402Spindle;
pub use state::PowerState;
