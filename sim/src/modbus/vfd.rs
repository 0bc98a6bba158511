//! A simulated spindle VFD answering Modbus RTU with either register map of the driver
//! (generic or Delta), built on [`SpindleModel`].

use klar_drivers::modbus::vfd_map::{
    DELTA_COMMAND, DELTA_ERROR, DELTA_FREQUENCY, DELTA_OUTPUT_FREQUENCY, DELTA_RESET, DELTA_STATUS,
};
use klar_drivers::modbus::words::{bit, with_bit};
use klar_drivers::modbus::{RegisterTable, VfdProfile};
use tokio_modbus::prelude::ExceptionCode;

use super::bus::{ModbusDevice, addresses};
use super::spindle::{SpindleModel, SpindleParams};

/// A simulated VFD on the line.
#[derive(Debug, Clone)]
pub struct SimModbusVfd {
    profile: VfdProfile,
    model: SpindleModel,
    last_now: Option<f64>,
    /// Raw setpoint register (generic: units; Delta: 0.01 Hz).
    speed_register: u16,
    /// Raw control/command register.
    control_register: u16,
    running: bool,
    reverse: bool,
    responds: bool,
    writes: u64,
}

impl SimModbusVfd {
    /// A stopped VFD speaking `profile`.
    pub fn new(profile: VfdProfile, params: SpindleParams) -> Self {
        Self {
            profile,
            model: SpindleModel::new(params),
            last_now: None,
            speed_register: 0,
            control_register: 0,
            running: false,
            reverse: false,
            responds: true,
            writes: 0,
        }
    }

    /// The motor model.
    pub fn model(&self) -> &SpindleModel {
        &self.model
    }

    /// Faults the VFD with `code` (it ramps down and ignores run commands until reset).
    pub fn inject_fault(&mut self, code: u16) {
        self.model.inject_fault(code);
    }

    /// Makes the VFD stop (false) or resume (true) answering.
    pub fn set_responding(&mut self, responds: bool) {
        self.responds = responds;
    }

    /// Register writes accepted so far.
    pub fn writes(&self) -> u64 {
        self.writes
    }

    fn advance(&mut self, now: f64) {
        if let Some(last) = self.last_now {
            self.model.advance(now - last);
        }
        self.last_now = Some(now);
    }

    fn apply(&mut self) {
        let magnitude = match &self.profile {
            VfdProfile::Generic(r) => f64::from(self.speed_register) / r.units_per_rpm,
            VfdProfile::Delta { rpm_per_hz } => f64::from(self.speed_register) / 100.0 * rpm_per_hz,
        };
        let command = if self.running {
            if self.reverse { -magnitude } else { magnitude }
        } else {
            0.0
        };
        self.model.set_command(command);
    }

    fn write_one(&mut self, address: u16, value: u16) -> Result<(), ExceptionCode> {
        match self.profile.clone() {
            VfdProfile::Generic(r) => {
                if address == r.control {
                    self.control_register = value;
                    if bit(value, r.fault_reset_bit) {
                        self.model.reset_fault();
                    }
                    self.running = bit(value, r.run_bit);
                    self.reverse = bit(value, r.reverse_bit);
                } else if address == r.speed_setpoint {
                    self.speed_register = value;
                } else {
                    return Err(ExceptionCode::IllegalDataAddress);
                }
            }
            VfdProfile::Delta { .. } => match address {
                DELTA_COMMAND => {
                    self.control_register = value;
                    match value & 0b11 {
                        0b01 => self.running = false,
                        0b10 | 0b11 => self.running = true,
                        _ => {}
                    }
                    match (value >> 4) & 0b11 {
                        0b01 => self.reverse = false,
                        0b10 => self.reverse = true,
                        0b11 => self.reverse = !self.reverse,
                        _ => {}
                    }
                }
                DELTA_FREQUENCY => self.speed_register = value,
                DELTA_RESET => {
                    if bit(value, 1) {
                        self.model.reset_fault();
                        self.running = false;
                    }
                }
                _ => return Err(ExceptionCode::IllegalDataAddress),
            },
        }
        self.apply();
        Ok(())
    }

    fn read_one(&self, table: RegisterTable, address: u16) -> Result<u16, ExceptionCode> {
        let rpm = self.model.rpm();
        match &self.profile {
            VfdProfile::Generic(r) => {
                if table != r.status_table && !(address == r.control || address == r.speed_setpoint)
                {
                    return Err(ExceptionCode::IllegalDataAddress);
                }
                if address == r.control {
                    Ok(self.control_register)
                } else if address == r.speed_setpoint {
                    Ok(self.speed_register)
                } else if address == r.status {
                    let mut s = with_bit(0, r.running_bit, rpm.abs() > 0.0 || self.running);
                    s = with_bit(s, r.reverse_status_bit, rpm < 0.0);
                    Ok(with_bit(s, r.fault_bit, self.model.fault().is_some()))
                } else if address == r.actual_speed {
                    Ok(saturate(rpm.abs() * r.units_per_rpm))
                } else if address == r.fault_code {
                    Ok(self.model.fault().unwrap_or(0))
                } else {
                    Err(ExceptionCode::IllegalDataAddress)
                }
            }
            VfdProfile::Delta { rpm_per_hz } => {
                if table != RegisterTable::Holding {
                    return Err(ExceptionCode::IllegalDataAddress);
                }
                match address {
                    DELTA_COMMAND => Ok(self.control_register),
                    DELTA_FREQUENCY => Ok(self.speed_register),
                    DELTA_RESET => Ok(0),
                    DELTA_ERROR => Ok(self.model.fault().unwrap_or(0)),
                    DELTA_STATUS => {
                        let run = match (self.running && self.model.fault().is_none(), rpm != 0.0) {
                            (true, _) => 0b11,
                            (false, true) => 0b01,
                            (false, false) => 0b00,
                        };
                        let dir = if rpm < 0.0 || (rpm == 0.0 && self.reverse) {
                            0b11
                        } else {
                            0b00
                        };
                        Ok(run | (dir << 3))
                    }
                    0x2102 => Ok(self.speed_register),
                    DELTA_OUTPUT_FREQUENCY => Ok(saturate(rpm.abs() / rpm_per_hz * 100.0)),
                    0x2104 => Ok(0),
                    _ => Err(ExceptionCode::IllegalDataAddress),
                }
            }
        }
    }
}

fn saturate(v: f64) -> u16 {
    let r = v.round();
    if r.is_nan() || r <= 0.0 {
        0
    } else {
        r.min(f64::from(u16::MAX)) as u16
    }
}

impl ModbusDevice for SimModbusVfd {
    fn read(
        &mut self,
        table: RegisterTable,
        address: u16,
        count: u16,
        now: f64,
    ) -> Result<Vec<u16>, ExceptionCode> {
        self.advance(now);
        addresses(address, usize::from(count))
            .map(|a| self.read_one(table, a?))
            .collect()
    }

    fn write(&mut self, address: u16, values: &[u16], now: f64) -> Result<(), ExceptionCode> {
        self.advance(now);
        for (a, v) in addresses(address, values.len()).zip(values) {
            self.write_one(a?, *v)?;
            self.writes += 1;
        }
        Ok(())
    }

    fn responds(&self) -> bool {
        self.responds
    }
}
