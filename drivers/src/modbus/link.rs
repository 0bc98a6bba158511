//! One Modbus RTU client link: a unit on a serial line, with a response timeout on every
//! transaction and a bounded number of retries.

use std::time::Duration;

use tokio_modbus::client::{Context, Reader, Writer};
use tokio_modbus::prelude::Slave;
use tokio_serial::{SerialPort, SerialPortBuilderExt, SerialStream};
use tracing::{debug, warn};

use super::{ModbusError, Parity, RegisterTable, SerialLineConfig};

/// Counters of one link, for reports and benchmarks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LinkStats {
    /// Transactions that completed (after retries, if any).
    pub transactions: u64,
    /// Attempts that failed and were retried or given up.
    pub failed_attempts: u64,
    /// Attempts that timed out (including frames dropped for a bad CRC).
    pub timeouts: u64,
    /// Exception responses received.
    pub exceptions: u64,
    /// Transactions given up after all retries.
    pub given_up: u64,
}

/// One Modbus request.
#[derive(Debug, Clone, PartialEq)]
pub enum Request {
    /// Read `count` registers from `table` starting at `address`.
    Read {
        /// Holding or input registers.
        table: RegisterTable,
        /// First register.
        address: u16,
        /// Number of registers.
        count: u16,
    },
    /// Write one holding register (function 6).
    WriteSingle {
        /// Register.
        address: u16,
        /// Value.
        value: u16,
    },
    /// Write consecutive holding registers (function 16).
    WriteMultiple {
        /// First register.
        address: u16,
        /// Values.
        values: Vec<u16>,
    },
}

impl Request {
    /// A short description for messages, e.g. "read holding 0x2100+4".
    pub fn describe(&self) -> String {
        match self {
            Request::Read {
                table,
                address,
                count,
            } => {
                let t = match table {
                    RegisterTable::Holding => "holding",
                    RegisterTable::Input => "input",
                };
                format!("read {t} 0x{address:04X}+{count}")
            }
            Request::WriteSingle { address, value } => {
                format!("write 0x{address:04X} = 0x{value:04X}")
            }
            Request::WriteMultiple { address, values } => {
                format!("write 0x{address:04X}+{} = {values:04X?}", values.len())
            }
        }
    }
}

/// A Modbus RTU client for one unit on one serial line.
///
/// Must be created and used inside a tokio runtime (the serial port registers with its
/// reactor).
pub struct ModbusLink {
    context: Option<Context>,
    unit: u8,
    timeout: Duration,
    retries: u32,
    line: Option<SerialLineConfig>,
    stats: LinkStats,
}

impl std::fmt::Debug for ModbusLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ModbusLink")
            .field("unit", &self.unit)
            .field("timeout", &self.timeout)
            .field("retries", &self.retries)
            .field("stats", &self.stats)
            .finish()
    }
}

/// Opens the serial port of `line` as an async stream (8 data bits) and reads the line
/// settings back: a port that does not keep the parity or the stop bits it was given (a
/// pseudo-terminal has no parity bit) is refused with [`ModbusError::LineSetting`] rather
/// than used with a framing the devices do not expect.
pub fn open_serial(line: &SerialLineConfig) -> Result<SerialStream, ModbusError> {
    line.validate()?;
    let parity = match line.parity {
        Parity::None => tokio_serial::Parity::None,
        Parity::Even => tokio_serial::Parity::Even,
        Parity::Odd => tokio_serial::Parity::Odd,
    };
    let stop_bits = if line.stop_bits == 2 {
        tokio_serial::StopBits::Two
    } else {
        tokio_serial::StopBits::One
    };
    let stream = tokio_serial::new(&line.port, line.baud)
        .data_bits(tokio_serial::DataBits::Eight)
        .parity(parity)
        .stop_bits(stop_bits)
        .flow_control(tokio_serial::FlowControl::None)
        .open_native_async()
        .map_err(|e| ModbusError::Open {
            port: line.port.clone(),
            reason: format!(
                "{e} (asked for {} baud, 8 data bits, parity {}, {} stop bit(s))",
                line.baud,
                parity_name(parity),
                line.stop_bits
            ),
        })?;
    check_line(&line.port, &stream, parity, stop_bits)?;
    Ok(stream)
}

fn parity_name(parity: tokio_serial::Parity) -> &'static str {
    match parity {
        tokio_serial::Parity::None => "none",
        tokio_serial::Parity::Even => "even",
        tokio_serial::Parity::Odd => "odd",
    }
}

fn stop_bits_name(bits: tokio_serial::StopBits) -> &'static str {
    match bits {
        tokio_serial::StopBits::One => "1",
        tokio_serial::StopBits::Two => "2",
    }
}

/// Compares what the open port reports with what was set.
fn check_line(
    port: &str,
    stream: &SerialStream,
    parity: tokio_serial::Parity,
    stop_bits: tokio_serial::StopBits,
) -> Result<(), ModbusError> {
    let unreadable = |what: &str, e: tokio_serial::Error| ModbusError::Open {
        port: port.to_string(),
        reason: format!("cannot read back the {what}: {e}"),
    };
    let got = stream.parity().map_err(|e| unreadable("parity", e))?;
    if got != parity {
        return Err(ModbusError::LineSetting {
            port: port.to_string(),
            setting: "parity",
            wanted: parity_name(parity).into(),
            got: parity_name(got).into(),
        });
    }
    let got = stream.stop_bits().map_err(|e| unreadable("stop bits", e))?;
    if got != stop_bits {
        return Err(ModbusError::LineSetting {
            port: port.to_string(),
            setting: "stop bits",
            wanted: stop_bits_name(stop_bits).into(),
            got: stop_bits_name(got).into(),
        });
    }
    Ok(())
}

impl ModbusLink {
    /// Opens `line` and talks to `unit` on it. A link opened this way reopens the port
    /// after a transport failure.
    pub fn open(line: &SerialLineConfig, unit: u8) -> Result<Self, ModbusError> {
        super::config::validate_unit(unit)?;
        let stream = open_serial(line)?;
        Ok(Self {
            context: Some(tokio_modbus::client::rtu::attach_slave(stream, Slave(unit))),
            unit,
            timeout: line.timeout_duration(),
            retries: line.retries,
            line: Some(line.clone()),
            stats: LinkStats::default(),
        })
    }

    /// Talks to `unit` over an already open stream (tests, pty pairs).
    pub fn from_stream(stream: SerialStream, unit: u8, timeout: Duration, retries: u32) -> Self {
        Self {
            context: Some(tokio_modbus::client::rtu::attach_slave(stream, Slave(unit))),
            unit,
            timeout,
            retries,
            line: None,
            stats: LinkStats::default(),
        }
    }

    /// The unit address.
    pub fn unit(&self) -> u8 {
        self.unit
    }

    /// The counters so far.
    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    /// Reads `count` registers.
    pub async fn read(
        &mut self,
        table: RegisterTable,
        address: u16,
        count: u16,
    ) -> Result<Vec<u16>, ModbusError> {
        self.transact(&Request::Read {
            table,
            address,
            count,
        })
        .await
    }

    /// Writes one holding register.
    pub async fn write_single(&mut self, address: u16, value: u16) -> Result<(), ModbusError> {
        self.transact(&Request::WriteSingle { address, value })
            .await
            .map(|_| ())
    }

    /// Writes consecutive holding registers.
    pub async fn write_multiple(
        &mut self,
        address: u16,
        values: &[u16],
    ) -> Result<(), ModbusError> {
        self.transact(&Request::WriteMultiple {
            address,
            values: values.to_vec(),
        })
        .await
        .map(|_| ())
    }

    /// Runs one request with the timeout and the bounded retries; returns the registers
    /// read (empty for writes).
    pub async fn transact(&mut self, request: &Request) -> Result<Vec<u16>, ModbusError> {
        let attempts = self.retries.saturating_add(1);
        let mut last = None;
        for attempt in 1..=attempts {
            match self.attempt(request).await {
                Ok(words) => {
                    self.stats.transactions += 1;
                    if attempt > 1 {
                        debug!(
                            unit = self.unit,
                            attempt,
                            "{} succeeded after retry",
                            request.describe()
                        );
                    }
                    return Ok(words);
                }
                Err(err) => {
                    self.stats.failed_attempts += 1;
                    match &err {
                        ModbusError::Timeout { .. } => self.stats.timeouts += 1,
                        ModbusError::Exception { .. } => self.stats.exceptions += 1,
                        ModbusError::Transport { .. } => self.reopen(),
                        _ => {}
                    }
                    if !err.is_transient() {
                        self.stats.given_up += 1;
                        return Err(err);
                    }
                    warn!(unit = self.unit, attempt, attempts, "{err}");
                    last = Some(err);
                }
            }
        }
        self.stats.given_up += 1;
        Err(ModbusError::RetriesExhausted {
            unit: self.unit,
            attempts,
            last: Box::new(last.unwrap_or(ModbusError::Worker("no attempt made".into()))),
        })
    }

    /// After a transport failure, opens the port anew when the link knows its path.
    fn reopen(&mut self) {
        let Some(line) = &self.line else { return };
        // Close the old port first: it holds the exclusive lock.
        self.context = None;
        match open_serial(line) {
            Ok(stream) => {
                self.context = Some(tokio_modbus::client::rtu::attach_slave(
                    stream,
                    Slave(self.unit),
                ));
                debug!(unit = self.unit, port = %line.port, "serial port reopened");
            }
            Err(e) => warn!(unit = self.unit, "{e}"),
        }
    }

    async fn attempt(&mut self, request: &Request) -> Result<Vec<u16>, ModbusError> {
        let operation = || request.describe();
        let unit = self.unit;
        let Some(context) = self.context.as_mut() else {
            return Err(ModbusError::Transport {
                unit,
                operation: operation(),
                reason: "serial port closed (reopening failed)".into(),
            });
        };
        let call = async move {
            match request {
                Request::Read {
                    table: RegisterTable::Holding,
                    address,
                    count,
                } => context.read_holding_registers(*address, *count).await,
                Request::Read {
                    table: RegisterTable::Input,
                    address,
                    count,
                } => context.read_input_registers(*address, *count).await,
                Request::WriteSingle { address, value } => context
                    .write_single_register(*address, *value)
                    .await
                    .map(|r| r.map(|()| Vec::new())),
                Request::WriteMultiple { address, values } => context
                    .write_multiple_registers(*address, values)
                    .await
                    .map(|r| r.map(|()| Vec::new())),
            }
        };
        let outcome = tokio::time::timeout(self.timeout, call).await;
        let words = match outcome {
            Err(_) => {
                return Err(ModbusError::Timeout {
                    unit,
                    operation: operation(),
                    timeout: self.timeout,
                });
            }
            Ok(Err(tokio_modbus::Error::Transport(e))) => {
                return Err(ModbusError::Transport {
                    unit,
                    operation: operation(),
                    reason: e.to_string(),
                });
            }
            Ok(Err(tokio_modbus::Error::Protocol(e))) => {
                return Err(ModbusError::Mismatch {
                    unit,
                    operation: operation(),
                    reason: e.to_string(),
                });
            }
            Ok(Ok(Err(exception))) => {
                return Err(ModbusError::Exception {
                    unit,
                    operation: operation(),
                    code: u8::from(exception),
                });
            }
            Ok(Ok(Ok(words))) => words,
        };
        if let Request::Read { count, .. } = request
            && words.len() != usize::from(*count)
        {
            return Err(ModbusError::ShortResponse {
                unit,
                operation: operation(),
                expected: usize::from(*count),
                got: words.len(),
            });
        }
        Ok(words)
    }
}
