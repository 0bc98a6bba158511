//! Configuration of the Modbus RTU backends, as it appears in the machine TOML.
//!
//! Times are in seconds, positions in mm or degrees, speeds in rpm. Every struct refuses
//! unknown keys so a typo in the machine file is an error, not a silently ignored line.

use serde::Deserialize;
use std::time::Duration;

use super::ModbusError;

/// Parity of the serial line (the Modbus RTU specification's default is even).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Parity {
    /// No parity bit (usually with two stop bits on strict devices, one on most VFDs).
    None,
    /// Even parity.
    #[default]
    Even,
    /// Odd parity.
    Odd,
}

/// One RS-485/RS-232 serial line and how patiently to talk on it.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SerialLineConfig {
    /// Device path, e.g. `/dev/ttyUSB0`.
    pub port: String,
    /// Baud rate.
    #[serde(default = "default_baud")]
    pub baud: u32,
    /// Parity.
    #[serde(default)]
    pub parity: Parity,
    /// Stop bits (1 or 2).
    #[serde(default = "default_stop_bits")]
    pub stop_bits: u8,
    /// Response timeout of one transaction, seconds.
    #[serde(default = "default_timeout")]
    pub timeout: f64,
    /// Retries after a failed transaction before the link is declared lost.
    #[serde(default = "default_retries")]
    pub retries: u32,
    /// Typical time the device takes to answer after the request, seconds (used only to
    /// estimate transaction times for the limits check).
    #[serde(default = "default_turnaround")]
    pub turnaround: f64,
}

fn default_baud() -> u32 {
    19_200
}
fn default_stop_bits() -> u8 {
    1
}
fn default_timeout() -> f64 {
    0.1
}
fn default_retries() -> u32 {
    2
}
fn default_turnaround() -> f64 {
    0.005
}

impl SerialLineConfig {
    /// A line on `port` with the defaults (19200 baud 8E1, 100 ms timeout, 2 retries).
    pub fn new(port: impl Into<String>) -> Self {
        Self {
            port: port.into(),
            baud: default_baud(),
            parity: Parity::default(),
            stop_bits: default_stop_bits(),
            timeout: default_timeout(),
            retries: default_retries(),
            turnaround: default_turnaround(),
        }
    }

    /// Checks ranges; the error says which value is wrong.
    pub fn validate(&self) -> Result<(), ModbusError> {
        if self.port.trim().is_empty() {
            return Err(ModbusError::Config("serial port path is empty".into()));
        }
        if !(300..=4_000_000).contains(&self.baud) {
            return Err(ModbusError::Config(format!(
                "baud rate {} outside 300..4000000",
                self.baud
            )));
        }
        if !matches!(self.stop_bits, 1 | 2) {
            return Err(ModbusError::Config(format!(
                "stop_bits must be 1 or 2, not {}",
                self.stop_bits
            )));
        }
        positive_seconds("timeout", self.timeout)?;
        if !(self.turnaround.is_finite() && self.turnaround >= 0.0) {
            return Err(ModbusError::Config(format!(
                "turnaround must be a time >= 0 s, not {}",
                self.turnaround
            )));
        }
        if self.retries > 20 {
            return Err(ModbusError::Config(format!(
                "retries {} is more than 20: a dead link would block for too long",
                self.retries
            )));
        }
        Ok(())
    }

    /// The response timeout as a [`Duration`] (call [`Self::validate`] first).
    pub fn timeout_duration(&self) -> Duration {
        Duration::try_from_secs_f64(self.timeout).unwrap_or(Duration::from_millis(100))
    }
}

/// Checks that a configured time is finite and positive.
pub(crate) fn positive_seconds(name: &str, value: f64) -> Result<Duration, ModbusError> {
    if value.is_finite() && value > 0.0 && value < 3600.0 {
        Duration::try_from_secs_f64(value).map_err(|e| ModbusError::Config(format!("{name}: {e}")))
    } else {
        Err(ModbusError::Config(format!(
            "{name} must be a time between 0 and 3600 s, not {value}"
        )))
    }
}

/// Order of the two 16-bit registers that carry one 32-bit value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WordOrder {
    /// The register at the lower address holds the high word (most drives).
    #[default]
    HighFirst,
    /// The register at the lower address holds the low word.
    LowFirst,
}

/// Which Modbus table a value is read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RegisterTable {
    /// Holding registers (function 3).
    #[default]
    Holding,
    /// Input registers (function 4).
    Input,
}

/// Where a positioning servo drive keeps its values. Addresses are 0-based protocol
/// addresses (what goes on the wire), bits are 0..=15.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoRegisterMap {
    /// First of the two holding registers of the target position (signed 32-bit counts).
    pub target_position: u16,
    /// First of the two registers of the actual position (signed 32-bit counts).
    pub actual_position: u16,
    /// Status word register.
    pub status: u16,
    /// Table holding `actual_position`, `status` and `fault_code`.
    #[serde(default)]
    pub status_table: RegisterTable,
    /// Control word holding register.
    pub control: u16,
    /// Optional register with the drive's fault code.
    #[serde(default)]
    pub fault_code: Option<u16>,
    /// Control bit that enables the power stage.
    pub enable_bit: u8,
    /// Control bit that acknowledges a fault (pulsed).
    pub fault_reset_bit: u8,
    /// Control bit that starts the drive's homing sequence, if it has one.
    #[serde(default)]
    pub home_bit: Option<u8>,
    /// Status bit: power stage enabled.
    pub enabled_bit: u8,
    /// Status bit: drive in fault.
    pub fault_bit: u8,
    /// Status bit: drive referenced. Without it the drive is taken as absolute (always homed).
    #[serde(default)]
    pub homed_bit: Option<u8>,
    /// Encoder counts per mm (linear) or per degree (rotary). Negative reverses the axis.
    pub counts_per_unit: f64,
    /// Word order of 32-bit values.
    #[serde(default)]
    pub word_order: WordOrder,
}

impl ServoRegisterMap {
    /// Checks bit numbers, scaling and that 32-bit values do not wrap the address space.
    pub fn validate(&self) -> Result<(), ModbusError> {
        for (name, bit) in [
            ("enable_bit", Some(self.enable_bit)),
            ("fault_reset_bit", Some(self.fault_reset_bit)),
            ("home_bit", self.home_bit),
            ("enabled_bit", Some(self.enabled_bit)),
            ("fault_bit", Some(self.fault_bit)),
            ("homed_bit", self.homed_bit),
        ] {
            if let Some(b) = bit
                && b > 15
            {
                return Err(ModbusError::Config(format!(
                    "{name} = {b}: a register has bits 0..15"
                )));
            }
        }
        if !(self.counts_per_unit.is_finite() && self.counts_per_unit.abs() > 1e-9) {
            return Err(ModbusError::Config(format!(
                "counts_per_unit must be a non-zero number, not {}",
                self.counts_per_unit
            )));
        }
        for (name, addr) in [
            ("target_position", self.target_position),
            ("actual_position", self.actual_position),
        ] {
            if addr == u16::MAX {
                return Err(ModbusError::Config(format!(
                    "{name} = 0xFFFF: a 32-bit value needs two registers"
                )));
            }
        }
        Ok(())
    }
}

/// A positioning servo drive on Modbus RTU used as one machine axis.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModbusServoConfig {
    /// The serial line.
    pub serial: SerialLineConfig,
    /// Modbus unit (slave) address, 1..=247.
    pub unit: u8,
    /// How often the drive is polled (target written, status read), seconds.
    #[serde(default = "default_poll_period")]
    pub poll_period: f64,
    /// The drive's register map.
    pub registers: ServoRegisterMap,
}

fn default_poll_period() -> f64 {
    0.02
}

impl ModbusServoConfig {
    /// Checks the whole configuration.
    pub fn validate(&self) -> Result<(), ModbusError> {
        self.serial.validate()?;
        validate_unit(self.unit)?;
        positive_seconds("poll_period", self.poll_period)?;
        self.registers.validate()
    }
}

/// Checks a unit address: 0 is broadcast (no answers) and 248..255 are reserved.
pub(crate) fn validate_unit(unit: u8) -> Result<(), ModbusError> {
    if (1..=247).contains(&unit) {
        Ok(())
    } else {
        Err(ModbusError::Config(format!(
            "unit address {unit} outside 1..247"
        )))
    }
}

/// The register map of the generic VFD profile (see `docs/modbus.md`). Every address has
/// a default so an empty table selects the documented layout.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GenericVfdRegisters {
    /// Control word (holding): run, reverse and fault-reset bits.
    pub control: u16,
    /// Speed setpoint (holding), unsigned magnitude in `units_per_rpm`.
    pub speed_setpoint: u16,
    /// Status word.
    pub status: u16,
    /// Actual speed, unsigned magnitude in `units_per_rpm`.
    pub actual_speed: u16,
    /// Fault code.
    pub fault_code: u16,
    /// Table of status, actual speed and fault code.
    pub status_table: RegisterTable,
    /// Control bit: run.
    pub run_bit: u8,
    /// Control bit: reverse (counter-clockwise, M4).
    pub reverse_bit: u8,
    /// Control bit: fault reset (pulsed).
    pub fault_reset_bit: u8,
    /// Status bit: running.
    pub running_bit: u8,
    /// Status bit: turning in reverse.
    pub reverse_status_bit: u8,
    /// Status bit: fault.
    pub fault_bit: u8,
    /// Register units per rpm (1.0: the registers hold rpm; 0.1: tens of rpm).
    pub units_per_rpm: f64,
}

impl Default for GenericVfdRegisters {
    fn default() -> Self {
        Self {
            control: 0x0000,
            speed_setpoint: 0x0001,
            status: 0x0002,
            actual_speed: 0x0003,
            fault_code: 0x0004,
            status_table: RegisterTable::Holding,
            run_bit: 0,
            reverse_bit: 1,
            fault_reset_bit: 2,
            running_bit: 0,
            reverse_status_bit: 1,
            fault_bit: 3,
            units_per_rpm: 1.0,
        }
    }
}

/// The VFD register-map preset and its parameters.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "preset", rename_all = "snake_case", deny_unknown_fields)]
pub enum VfdPreset {
    /// The generic map (defaults documented in `docs/modbus.md`, each address overridable).
    Generic {
        /// Register addresses and bits.
        #[serde(default)]
        registers: GenericVfdRegisters,
    },
    /// Delta VFD family communication map (2000H command, 2001H frequency, 2100H..2103H
    /// status), frequencies in 0.01 Hz.
    Delta {
        /// Spindle rpm per Hz of output frequency (60 for a 2-pole motor direct-coupled).
        rpm_per_hz: f64,
    },
}

/// A spindle VFD on Modbus RTU.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModbusVfdConfig {
    /// The serial line.
    pub serial: SerialLineConfig,
    /// Modbus unit (slave) address, 1..=247.
    pub unit: u8,
    /// How often the VFD is polled, seconds.
    #[serde(default = "default_vfd_poll_period")]
    pub poll_period: f64,
    /// Highest speed that may be commanded, rpm.
    pub max_rpm: f64,
    /// At-speed window as a fraction of the commanded speed.
    #[serde(default = "default_at_speed_fraction")]
    pub at_speed_fraction: f64,
    /// Smallest at-speed window, rpm (also the "stopped" window).
    #[serde(default = "default_at_speed_min_rpm")]
    pub at_speed_min_rpm: f64,
    /// Register map.
    pub profile: VfdPreset,
}

fn default_vfd_poll_period() -> f64 {
    0.05
}
fn default_at_speed_fraction() -> f64 {
    0.05
}
fn default_at_speed_min_rpm() -> f64 {
    10.0
}

impl ModbusVfdConfig {
    /// A VFD on `serial` at `unit` with the given preset and the default windows.
    pub fn new(serial: SerialLineConfig, unit: u8, max_rpm: f64, profile: VfdPreset) -> Self {
        Self {
            serial,
            unit,
            poll_period: default_vfd_poll_period(),
            max_rpm,
            at_speed_fraction: default_at_speed_fraction(),
            at_speed_min_rpm: default_at_speed_min_rpm(),
            profile,
        }
    }

    /// Checks the whole configuration.
    pub fn validate(&self) -> Result<(), ModbusError> {
        self.serial.validate()?;
        validate_unit(self.unit)?;
        positive_seconds("poll_period", self.poll_period)?;
        if !(self.max_rpm.is_finite() && self.max_rpm > 0.0) {
            return Err(ModbusError::Config(format!(
                "max_rpm must be positive, not {}",
                self.max_rpm
            )));
        }
        if !(self.at_speed_fraction.is_finite() && (0.0..1.0).contains(&self.at_speed_fraction)) {
            return Err(ModbusError::Config(format!(
                "at_speed_fraction must be in 0..1, not {}",
                self.at_speed_fraction
            )));
        }
        if !(self.at_speed_min_rpm.is_finite() && self.at_speed_min_rpm >= 0.0) {
            return Err(ModbusError::Config(format!(
                "at_speed_min_rpm must be >= 0, not {}",
                self.at_speed_min_rpm
            )));
        }
        match &self.profile {
            VfdPreset::Generic { registers } => {
                for (name, b) in [
                    ("run_bit", registers.run_bit),
                    ("reverse_bit", registers.reverse_bit),
                    ("fault_reset_bit", registers.fault_reset_bit),
                    ("running_bit", registers.running_bit),
                    ("reverse_status_bit", registers.reverse_status_bit),
                    ("fault_bit", registers.fault_bit),
                ] {
                    if b > 15 {
                        return Err(ModbusError::Config(format!(
                            "{name} = {b}: a register has bits 0..15"
                        )));
                    }
                }
                if !(registers.units_per_rpm.is_finite() && registers.units_per_rpm > 0.0) {
                    return Err(ModbusError::Config(format!(
                        "units_per_rpm must be positive, not {}",
                        registers.units_per_rpm
                    )));
                }
                if self.max_rpm * registers.units_per_rpm > f64::from(u16::MAX) {
                    return Err(ModbusError::Config(format!(
                        "max_rpm {} x units_per_rpm {} does not fit a 16-bit register",
                        self.max_rpm, registers.units_per_rpm
                    )));
                }
            }
            VfdPreset::Delta { rpm_per_hz } => {
                if !(rpm_per_hz.is_finite() && *rpm_per_hz > 0.0) {
                    return Err(ModbusError::Config(format!(
                        "rpm_per_hz must be positive, not {rpm_per_hz}"
                    )));
                }
                if self.max_rpm / rpm_per_hz * 100.0 > f64::from(u16::MAX) {
                    return Err(ModbusError::Config(format!(
                        "max_rpm {} at {} rpm/Hz exceeds 655.35 Hz",
                        self.max_rpm, rpm_per_hz
                    )));
                }
            }
        }
        Ok(())
    }
}
