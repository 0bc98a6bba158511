//! The CAN bus boundary: frames, bus events, the [`CanBus`] trait, and its adapters.
//!
//! The trait is synchronous and non-blocking-with-timeout, because the servo loop
//! ([`klar_motion::AxisBackend::cycle`]) is synchronous. Adapters that talk to the
//! operating system asynchronously (socketcan, slcan over tokio-serial) run their I/O on
//! a dedicated thread and hand frames over through a queue ([`bridge`]).
//!
//! - [`frame`]: CAN 2.0 frames and identifiers.
//! - [`memory`]: an in-memory bus with attachable simulated devices and fault injection.
//! - [`slcan`]: the Lawicel ASCII protocol (codec) and an adapter over a serial port.
//! - [`socketcan`]: Linux SocketCAN.
//! - [`device`]: a thread that runs a simulated device on any [`CanBus`].

pub mod bridge;
pub mod device;
pub mod frame;
pub mod memory;
pub mod slcan;
pub mod socketcan;

use std::time::Duration;

pub use frame::{CanFrame, CanId, FrameError};

/// A bus-level error condition reported by the controller or adapter.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BusErrorKind {
    /// The controller went bus-off and no longer takes part in traffic.
    BusOff,
    /// The controller is error passive (error counters above 127).
    ErrorPassive,
    /// The controller error counters passed the warning level (96).
    ErrorWarning,
    /// Received frames were lost because a buffer overflowed.
    Overrun,
    /// A protocol violation on the wire (bit, stuff, form, CRC, ACK errors).
    Protocol(String),
    /// The adapter answered a command with an error reply.
    ErrorReply,
    /// Bytes from the adapter that are not a valid message.
    Malformed(String),
}

impl std::fmt::Display for BusErrorKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BusErrorKind::BusOff => write!(f, "bus-off"),
            BusErrorKind::ErrorPassive => write!(f, "error passive"),
            BusErrorKind::ErrorWarning => write!(f, "error warning level"),
            BusErrorKind::Overrun => write!(f, "receive overrun (frames lost)"),
            BusErrorKind::Protocol(s) => write!(f, "protocol error: {s}"),
            BusErrorKind::ErrorReply => write!(f, "adapter replied with an error"),
            BusErrorKind::Malformed(s) => write!(f, "malformed adapter message: {s}"),
        }
    }
}

/// Something that arrived from the bus.
#[derive(Debug, Clone, PartialEq)]
pub enum CanEvent {
    /// A data or remote frame with its reception time (seconds since the bus was opened).
    Frame {
        /// The frame.
        frame: CanFrame,
        /// Reception time in seconds since the bus was opened.
        timestamp: f64,
    },
    /// An error condition of the bus or adapter.
    Error(BusErrorKind),
}

/// Failures of a bus adapter.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CanError {
    /// The controller is bus-off; frames cannot be sent.
    #[error("CAN bus-off")]
    BusOff,
    /// The adapter or its I/O thread is gone.
    #[error("CAN adapter closed: {0}")]
    Closed(String),
    /// An operating-system I/O error.
    #[error("CAN I/O error: {0}")]
    Io(String),
    /// The adapter did not answer a command in time.
    #[error("CAN adapter did not answer `{command}` within {timeout_ms} ms")]
    AdapterTimeout {
        /// The command sent.
        command: String,
        /// The wait in milliseconds.
        timeout_ms: u64,
    },
    /// The adapter refused a command.
    #[error("CAN adapter refused `{0}`")]
    AdapterRefused(String),
    /// A bitrate the adapter cannot set.
    #[error(
        "unsupported CAN bitrate {0} bit/s (use 10k, 20k, 50k, 100k, 125k, 250k, 500k, 800k or 1M)"
    )]
    UnsupportedBitrate(u32),
    /// The send queue is full.
    #[error("CAN send queue full")]
    QueueFull,
}

/// A CAN bus as seen by one participant.
pub trait CanBus: Send {
    /// Queues one frame for transmission.
    fn send(&mut self, frame: &CanFrame) -> Result<(), CanError>;

    /// Waits up to `timeout` for the next event; `Ok(None)` when nothing arrived.
    fn recv_timeout(&mut self, timeout: Duration) -> Result<Option<CanEvent>, CanError>;

    /// Returns the next event if one is already waiting.
    fn try_recv(&mut self) -> Result<Option<CanEvent>, CanError> {
        self.recv_timeout(Duration::ZERO)
    }
}

impl<B: CanBus + ?Sized> CanBus for Box<B> {
    fn send(&mut self, frame: &CanFrame) -> Result<(), CanError> {
        (**self).send(frame)
    }
    fn recv_timeout(&mut self, timeout: Duration) -> Result<Option<CanEvent>, CanError> {
        (**self).recv_timeout(timeout)
    }
}

/// The CAN bitrates CANopen (CiA 301) recommends, which slcan adapters also know.
pub const STANDARD_BITRATES: [u32; 9] = [
    10_000, 20_000, 50_000, 100_000, 125_000, 250_000, 500_000, 800_000, 1_000_000,
];
