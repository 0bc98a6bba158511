//! klar-sim: simulated axes and devices behind [`klar_motion::AxisBackend`].
//!
//! - [`plant`]: the servo plant (mass, friction, position controller, encoder) every
//!   simulated axis and drive is built on.
//! - [`axis`]: simulated axes as an [`klar_motion::AxisBackend`].
//! - [`faults`]: fault injection (drive fault, lost link, encoder noise, jam, limit
//!   switch, e-stop) on a schedule.
//! - [`cia402`]: a simulated CANopen CiA 402 drive.
//! - [`modbus`]: simulated Modbus RTU devices (servo drive, spindle VFD).
//! - [`load`]: the speed dip of a simulated spindle under cut.
//! - [`stepper`]: a simulated stepper motor and switches behind step/dir pins.

#![warn(missing_docs)]

pub mod axis;
pub mod cia402;
pub mod faults;
pub mod load;
pub mod modbus;
pub mod plant;
pub mod stepper;
