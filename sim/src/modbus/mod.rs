//! Simulated Modbus RTU devices: a spindle VFD (generic or Delta register map) and a
//! positioning servo drive with a configured register map, served by a tokio-modbus RTU
//! server on a pseudo-terminal so the real Modbus client backends run end to end
//! without hardware. [`SimSpindle`] is the same spindle model without a bus.

mod bus;
mod harness;
mod servo;
mod spindle;
mod vfd;

pub use bus::{BusCounters, ModbusDevice, SharedDevice, SimBusError, SimModbusBus, lock_device};
pub use harness::{SimulatedServo, SimulatedVfd, simulate_servo, simulate_vfd};
pub use servo::{DRIVE_PERIOD, PositioningLimits, SimModbusServo, fault_code, profile_step};
pub use spindle::{SimSpindle, SpindleModel, SpindleParams};
pub use vfd::SimModbusVfd;
