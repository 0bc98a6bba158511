//! Errors of the Modbus RTU backends.

use std::time::Duration;

/// What went wrong talking to a Modbus RTU device or setting a backend up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModbusError {
    /// The serial port could not be opened.
    #[error("cannot open serial port {port}: {reason}")]
    Open {
        /// Port path from the configuration.
        port: String,
        /// What the operating system said.
        reason: String,
    },
    /// No (valid) response arrived in time. A frame with a bad CRC is discarded by the
    /// decoder, so CRC errors also end up here.
    #[error(
        "unit {unit}: no valid response to {operation} within {timeout:?} (lost frame or bad CRC)"
    )]
    Timeout {
        /// Modbus unit (slave) address.
        unit: u8,
        /// The request, e.g. "read 0x2100+4".
        operation: String,
        /// The response timeout.
        timeout: Duration,
    },
    /// The device answered with a Modbus exception.
    #[error("unit {unit}: {operation} rejected with exception 0x{code:02X} ({})", exception_name(*.code))]
    Exception {
        /// Modbus unit (slave) address.
        unit: u8,
        /// The request.
        operation: String,
        /// The exception code (0x01 illegal function, 0x02 illegal data address, ...).
        code: u8,
    },
    /// The serial transport failed or the response did not match the request.
    #[error("unit {unit}: {operation} failed: {reason}")]
    Transport {
        /// Modbus unit (slave) address.
        unit: u8,
        /// The request.
        operation: String,
        /// Description of the failure.
        reason: String,
    },
    /// A response did not belong to the request (wrong unit or function; often a late
    /// answer to an earlier, timed-out request).
    #[error("unit {unit}: {operation}: response does not match the request: {reason}")]
    Mismatch {
        /// Modbus unit (slave) address.
        unit: u8,
        /// The request.
        operation: String,
        /// Description of the mismatch.
        reason: String,
    },
    /// A response had the wrong number of registers.
    #[error("unit {unit}: {operation} returned {got} registers, expected {expected}")]
    ShortResponse {
        /// Modbus unit (slave) address.
        unit: u8,
        /// The request.
        operation: String,
        /// Registers expected.
        expected: usize,
        /// Registers received.
        got: usize,
    },
    /// All attempts of one transaction failed; `last` is the final failure.
    #[error("unit {unit}: giving up after {attempts} attempts: {last}")]
    RetriesExhausted {
        /// Modbus unit (slave) address.
        unit: u8,
        /// Attempts made (first try plus retries).
        attempts: u32,
        /// The last failure.
        last: Box<ModbusError>,
    },
    /// The port opened but does not keep a line setting: it reads back something else
    /// than was set (a pseudo-terminal, for one, has no parity bit).
    #[error(
        "serial port {port} cannot be set to {setting} {wanted}: it reads back {got} \
         (a pseudo-terminal or an adapter without this setting); use a port that supports \
         it or configure the devices and klar for what the port can do"
    )]
    LineSetting {
        /// Port path from the configuration.
        port: String,
        /// Which setting, e.g. "parity".
        setting: &'static str,
        /// What the configuration asks for.
        wanted: String,
        /// What the port reports after setting it.
        got: String,
    },
    /// A spindle stop could not be confirmed by the device within the time allowed.
    #[error("{device} did not confirm the stop within {waited:.1?}: {reason}")]
    StopUnconfirmed {
        /// The device, e.g. "spindle VFD (Modbus unit 1 on /dev/ttyUSB1)".
        device: String,
        /// How long the stop was tried.
        waited: Duration,
        /// The last thing that went wrong.
        reason: String,
    },
    /// The configuration is not usable.
    #[error("invalid Modbus configuration: {0}")]
    Config(String),
    /// The backend's worker thread is gone or did not answer in time.
    #[error("Modbus worker: {0}")]
    Worker(String),
}

impl ModbusError {
    /// True when trying the same transaction again may succeed (timeouts, transport
    /// hiccups, busy devices); false for deterministic refusals such as an illegal address.
    pub fn is_transient(&self) -> bool {
        match self {
            ModbusError::Timeout { .. }
            | ModbusError::Transport { .. }
            | ModbusError::Mismatch { .. }
            | ModbusError::ShortResponse { .. } => true,
            // 0x05 acknowledge (long operation running), 0x06 busy.
            ModbusError::Exception { code, .. } => matches!(code, 0x05 | 0x06),
            _ => false,
        }
    }
}

impl ModbusError {
    /// True for failures of the link itself (retries used up, or a transient failure),
    /// as opposed to refusals and configuration errors.
    pub fn is_transient_or_exhausted(&self) -> bool {
        self.is_transient() || matches!(self, ModbusError::RetriesExhausted { .. })
    }
}

/// The name of a Modbus exception code as the Modbus application protocol defines it.
pub fn exception_name(code: u8) -> &'static str {
    match code {
        0x01 => "illegal function",
        0x02 => "illegal data address",
        0x03 => "illegal data value",
        0x04 => "server device failure",
        0x05 => "acknowledge",
        0x06 => "server device busy",
        0x08 => "memory parity error",
        0x0A => "gateway path unavailable",
        0x0B => "gateway target device failed to respond",
        _ => "unknown exception",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn exception(code: u8) -> ModbusError {
        ModbusError::Exception {
            unit: 1,
            operation: "read holding 0x0000+1".into(),
            code,
        }
    }

    #[test]
    fn only_passing_failures_are_retried() {
        // Busy (0x06) and acknowledge (0x05) mean "try later"; a wrong address never heals.
        assert!(exception(0x06).is_transient());
        assert!(exception(0x05).is_transient());
        assert!(!exception(0x02).is_transient());
        assert!(!exception(0x01).is_transient());
        assert!(
            ModbusError::Timeout {
                unit: 1,
                operation: String::new(),
                timeout: Duration::from_millis(1)
            }
            .is_transient()
        );
        assert!(!ModbusError::Config(String::new()).is_transient());
    }

    #[test]
    fn messages_name_the_exception() {
        assert_eq!(
            exception(0x02).to_string(),
            "unit 1: read holding 0x0000+1 rejected with exception 0x02 (illegal data address)"
        );
    }
}
