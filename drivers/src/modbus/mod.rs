//! Modbus RTU servo drives and spindle VFDs over a serial line.
//!
//! Each device gets a worker thread that owns its [`ModbusLink`] and polls the device at
//! its `poll_period`; the servo loop only swaps setpoints and reads the latest snapshot,
//! so it never waits for the line. Every transaction has a response timeout and bounded
//! retries; when they are used up the backend reports a fault and stops the device.
//!
//! What Modbus RTU is good for: a transaction costs milliseconds to tens of milliseconds
//! (see [`limits`]), so Modbus drives suit auxiliary positioning axes (rotary tables,
//! tool changers) and spindles, never contouring axes.

mod config;
mod error;
pub mod image;
pub mod limits;
pub mod link;
mod servo;
mod vfd;
pub mod vfd_map;
pub mod words;
mod worker;

pub use config::{
    GenericVfdRegisters, ModbusServoConfig, ModbusVfdConfig, Parity, RegisterTable,
    SerialLineConfig, ServoRegisterMap, VfdPreset, WordOrder,
};
pub use error::{ModbusError, exception_name};
pub use link::{LinkStats, ModbusLink, Request};
pub use servo::{ModbusServo, ServoSnapshot};
pub use vfd::{ModbusVfd, VfdSnapshot};
pub use vfd_map::{VfdProfile, VfdStatus};
