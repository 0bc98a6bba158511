//! Ready-made simulated devices for a configured Modbus backend: start the simulated
//! line, put the device on it at the configured unit, and hand back the configuration
//! with the port replaced by the line's path (for `klar run` without hardware).

use std::sync::{Arc, Mutex};

use klar_drivers::modbus::{ModbusServoConfig, ModbusVfdConfig, VfdProfile};

use super::bus::{SharedDevice, SimBusError, SimModbusBus};
use super::servo::{PositioningLimits, SimModbusServo};
use super::spindle::SpindleParams;
use super::vfd::SimModbusVfd;
use crate::plant::SimAxisParams;

/// A simulated VFD on its own line.
#[derive(Debug)]
pub struct SimulatedVfd {
    /// The running line (drop it to stop the device).
    pub bus: SimModbusBus,
    /// The device, for inspection and fault injection.
    pub device: Arc<Mutex<SimModbusVfd>>,
    /// The configuration to open the client with.
    pub config: ModbusVfdConfig,
}

/// Starts a simulated VFD speaking the register map of `config`.
pub fn simulate_vfd(
    config: &ModbusVfdConfig,
    params: SpindleParams,
) -> Result<SimulatedVfd, SimBusError> {
    let device = Arc::new(Mutex::new(SimModbusVfd::new(
        VfdProfile::from_preset(&config.profile),
        params,
    )));
    let shared: SharedDevice = device.clone();
    let bus = SimModbusBus::start(vec![(config.unit, shared)])?;
    let mut config = config.clone();
    config.serial.port = bus.path().to_string();
    Ok(SimulatedVfd {
        bus,
        device,
        config,
    })
}

/// A simulated positioning drive on its own line.
#[derive(Debug)]
pub struct SimulatedServo {
    /// The running line (drop it to stop the device).
    pub bus: SimModbusBus,
    /// The device, for inspection and fault injection.
    pub device: Arc<Mutex<SimModbusServo>>,
    /// The configuration to open the client with.
    pub config: ModbusServoConfig,
}

/// Starts a simulated positioning drive with the register map of `config`, at rest at
/// `position`.
pub fn simulate_servo(
    config: &ModbusServoConfig,
    params: SimAxisParams,
    limits: PositioningLimits,
    position: f64,
) -> Result<SimulatedServo, SimBusError> {
    let device = Arc::new(Mutex::new(SimModbusServo::new(
        config.registers.clone(),
        params,
        limits,
        position,
    )));
    let shared: SharedDevice = device.clone();
    let bus = SimModbusBus::start(vec![(config.unit, shared)])?;
    let mut config = config.clone();
    config.serial.port = bus.path().to_string();
    Ok(SimulatedServo {
        bus,
        device,
        config,
    })
}
