//! Honest limits of Modbus RTU: how long a poll takes on the wire, and the check that
//! refuses a configuration which cannot meet its period.
//!
//! An RTU character is 1 start + 8 data + parity + stop bits; frames are separated by a
//! silent interval of 3.5 characters (fixed at 1.75 ms above 19200 baud, as the Modbus
//! serial line specification recommends); the device needs a turnaround time to answer.
//! At 115200 baud a status read of 4 registers and a 2-register target write take about
//! 9 ms including a 2 ms turnaround per transaction: fine for a rotary table, useless for
//! an axis that must follow a contour every millisecond.

use super::image::plan_reads;
use super::vfd_map::VfdProfile;
use super::{ModbusServoConfig, ModbusVfdConfig, Parity, SerialLineConfig};

/// Why a Modbus configuration cannot work as asked.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModbusLimitError {
    /// A contouring axis needs a new position every servo period.
    #[error(
        "a Modbus RTU axis cannot contour: one poll takes {poll_ms:.2} ms on the wire \
         (polled every {period_ms:.2} ms) but a contouring axis needs a new setpoint every \
         servo period of {servo_ms:.3} ms; use it as an auxiliary positioning axis or a \
         CANopen/step-dir axis"
    )]
    Contouring {
        /// Wire time of one poll, ms.
        poll_ms: f64,
        /// Configured poll period, ms.
        period_ms: f64,
        /// Servo period, ms.
        servo_ms: f64,
    },
    /// The poll does not fit its own period on this line.
    #[error(
        "one poll needs {poll_ms:.2} ms at {baud} baud but poll_period is {period_ms:.2} ms; \
         raise poll_period or the baud rate"
    )]
    PollTooShort {
        /// Wire time of one poll, ms.
        poll_ms: f64,
        /// Configured poll period, ms.
        period_ms: f64,
        /// Baud rate.
        baud: u32,
    },
    /// The servo period itself is not a usable number.
    #[error("servo period {0} s is not a positive time")]
    BadServoPeriod(f64),
    /// The configuration is invalid.
    #[error("{0}")]
    Config(String),
}

/// The timing a Modbus device will have, for reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModbusTiming {
    /// Wire time of one steady-state poll (writes + reads + gaps + turnarounds), seconds.
    pub poll_time: f64,
    /// Configured poll period, seconds.
    pub poll_period: f64,
    /// Time until a dead device is reported (all attempts of one transaction), seconds.
    pub loss_detection: f64,
    /// Extra wire time of a poll that also sends a new command (VFD speed change), seconds.
    pub command_time: f64,
}

impl std::fmt::Display for ModbusTiming {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Modbus RTU: one poll takes {:.2} ms on the wire, polled every {:.1} ms; a dead \
             device is detected after {:.0} ms; good for auxiliary positioning axes and \
             spindles, not for contouring axes",
            self.poll_time * 1e3,
            self.poll_period * 1e3,
            self.loss_detection * 1e3
        )
    }
}

/// Bits per RTU character on `line`.
pub fn bits_per_char(line: &SerialLineConfig) -> f64 {
    let parity = if line.parity == Parity::None {
        0.0
    } else {
        1.0
    };
    1.0 + 8.0 + parity + f64::from(line.stop_bits)
}

/// Silent interval between frames, seconds.
pub fn frame_gap(line: &SerialLineConfig) -> f64 {
    if line.baud > 19_200 {
        0.001_75
    } else {
        3.5 * bits_per_char(line) / f64::from(line.baud)
    }
}

/// Wire time of one transaction with a `request`-byte request and a `response`-byte
/// response (both including address and CRC), seconds.
pub fn transaction_time(line: &SerialLineConfig, request: usize, response: usize) -> f64 {
    let bytes = (request + response) as f64;
    bytes * bits_per_char(line) / f64::from(line.baud) + 2.0 * frame_gap(line) + line.turnaround
}

/// Read of `n` registers: 8-byte request, 5 + 2n byte response.
pub fn read_time(line: &SerialLineConfig, n: u16) -> f64 {
    transaction_time(line, 8, 5 + 2 * usize::from(n))
}

/// Write of one register (function 6): 8 bytes each way.
pub fn write_single_time(line: &SerialLineConfig) -> f64 {
    transaction_time(line, 8, 8)
}

/// Write of `n` registers (function 16): 9 + 2n byte request, 8-byte response.
pub fn write_multiple_time(line: &SerialLineConfig, n: u16) -> f64 {
    transaction_time(line, 9 + 2 * usize::from(n), 8)
}

fn loss_detection(line: &SerialLineConfig) -> f64 {
    line.timeout * f64::from(line.retries.saturating_add(1))
}

/// Timing of a servo drive's steady-state poll: one target write plus the status reads.
pub fn servo_timing(config: &ModbusServoConfig) -> ModbusTiming {
    let m = &config.registers;
    let mut addresses = vec![
        m.status,
        m.actual_position,
        m.actual_position.saturating_add(1),
    ];
    addresses.extend(m.fault_code);
    let reads: f64 = plan_reads(&addresses, 8)
        .iter()
        .map(|(_, n)| read_time(&config.serial, *n))
        .sum();
    ModbusTiming {
        poll_time: write_multiple_time(&config.serial, 2) + reads,
        poll_period: config.poll_period,
        loss_detection: loss_detection(&config.serial),
        command_time: 0.0,
    }
}

/// Timing of a VFD's steady-state poll (status reads); the command writes, sent only
/// when the speed changes, are reported as `command_time`.
pub fn vfd_timing(config: &ModbusVfdConfig) -> ModbusTiming {
    let profile = VfdProfile::from_preset(&config.profile);
    let (_, addresses) = profile.status_addresses();
    let reads: f64 = plan_reads(&addresses, 8)
        .iter()
        .map(|(_, n)| read_time(&config.serial, *n))
        .sum();
    let writes = profile.command_writes(1.0).len() as f64 * write_single_time(&config.serial);
    ModbusTiming {
        poll_time: reads,
        poll_period: config.poll_period,
        loss_detection: loss_detection(&config.serial),
        command_time: writes,
    }
}

fn check_period(line: &SerialLineConfig, t: ModbusTiming) -> Result<(), ModbusLimitError> {
    if t.poll_time > t.poll_period {
        return Err(ModbusLimitError::PollTooShort {
            poll_ms: t.poll_time * 1e3,
            period_ms: t.poll_period * 1e3,
            baud: line.baud,
        });
    }
    Ok(())
}

/// Accepts a Modbus servo axis for a machine with `servo_period` (seconds), or says why
/// not. `contouring` is true when the axis takes part in interpolated paths.
pub fn check_servo(
    config: &ModbusServoConfig,
    servo_period: f64,
    contouring: bool,
) -> Result<ModbusTiming, ModbusLimitError> {
    if !(servo_period.is_finite() && servo_period > 0.0) {
        return Err(ModbusLimitError::BadServoPeriod(servo_period));
    }
    config
        .validate()
        .map_err(|e| ModbusLimitError::Config(e.to_string()))?;
    let t = servo_timing(config);
    if contouring && (t.poll_time > servo_period || t.poll_period > servo_period) {
        return Err(ModbusLimitError::Contouring {
            poll_ms: t.poll_time * 1e3,
            period_ms: t.poll_period * 1e3,
            servo_ms: servo_period * 1e3,
        });
    }
    check_period(&config.serial, t)?;
    Ok(t)
}

/// Accepts a Modbus VFD, or says why its poll period cannot be met.
pub fn check_vfd(config: &ModbusVfdConfig) -> Result<ModbusTiming, ModbusLimitError> {
    config
        .validate()
        .map_err(|e| ModbusLimitError::Config(e.to_string()))?;
    let t = vfd_timing(config);
    check_period(&config.serial, t)?;
    Ok(t)
}
