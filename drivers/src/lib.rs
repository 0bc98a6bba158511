//! klar-drivers: backends for real hardware behind [`klar_motion::AxisBackend`].
//!
//! - [`can`]: the CAN bus trait and its adapters (socketcan, slcan, in-memory).
//! - [`canopen`]: a CANopen (CiA 301) master: NMT, SDO, PDO, SYNC, EMCY, heartbeat.
//! - [`cia402`]: CiA 402 servo drives as axes.
//! - [`modbus`]: Modbus RTU servo drives and spindle VFDs.
//! - [`stepdir`]: step/direction outputs and switch inputs over embedded-hal.

#![warn(missing_docs)]

pub mod can;
pub mod canopen;
pub mod cia402;
pub mod modbus;
pub mod stepdir;
