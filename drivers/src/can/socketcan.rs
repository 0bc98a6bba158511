//! Linux SocketCAN adapter (`can0`, `vcan0`, ...), through socketcan's tokio socket.
//!
//! Frames are converted to and from [`CanFrame`]; error frames (the socket is opened with
//! all error classes enabled) become [`BusErrorKind`] events, decoded by
//! [`decode_error_frame`] from the class bits of the identifier and the controller byte, as
//! the kernel's `linux/can/error.h` defines them.

use std::time::Duration;

use socketcan::{EmbeddedFrame, SocketOptions as _};

use super::bridge::Bridge;
use super::{BusErrorKind, CanBus, CanError, CanEvent, CanFrame, CanId};

/// Error class: transmission timeout.
const ERR_TX_TIMEOUT: u32 = 0x001;
/// Error class: controller problem (details in data byte 1).
const ERR_CRTL: u32 = 0x004;
/// Error class: protocol violation.
const ERR_PROT: u32 = 0x008;
/// Error class: no acknowledge on transmission.
const ERR_ACK: u32 = 0x020;
/// Error class: bus-off.
const ERR_BUSOFF: u32 = 0x040;
/// Error class: bus error.
const ERR_BUSERROR: u32 = 0x080;
/// Controller byte: receive buffer overflow.
const CRTL_RX_OVERFLOW: u8 = 0x01;
/// Controller byte: transmit buffer overflow.
const CRTL_TX_OVERFLOW: u8 = 0x02;
/// Controller byte: warning level reached (receive or transmit).
const CRTL_WARNING: u8 = 0x04 | 0x08;
/// Controller byte: error passive (receive or transmit).
const CRTL_PASSIVE: u8 = 0x10 | 0x20;

/// Decodes a SocketCAN error frame (class bits of its identifier and its data) into the
/// conditions it reports, most severe first.
pub fn decode_error_frame(class: u32, data: &[u8]) -> Vec<BusErrorKind> {
    let mut kinds = Vec::new();
    if class & ERR_BUSOFF != 0 {
        kinds.push(BusErrorKind::BusOff);
    }
    if class & ERR_CRTL != 0 {
        let ctrl = data.get(1).copied().unwrap_or(0);
        if ctrl & CRTL_PASSIVE != 0 {
            kinds.push(BusErrorKind::ErrorPassive);
        }
        if ctrl & CRTL_WARNING != 0 {
            kinds.push(BusErrorKind::ErrorWarning);
        }
        if ctrl & (CRTL_RX_OVERFLOW | CRTL_TX_OVERFLOW) != 0 {
            kinds.push(BusErrorKind::Overrun);
        }
    }
    if class & ERR_PROT != 0 {
        kinds.push(BusErrorKind::Protocol(
            "bit, stuff, form or CRC error".into(),
        ));
    }
    if class & ERR_ACK != 0 {
        kinds.push(BusErrorKind::Protocol(
            "no acknowledge (no other node on the bus?)".into(),
        ));
    }
    if class & ERR_TX_TIMEOUT != 0 {
        kinds.push(BusErrorKind::Protocol("transmission timeout".into()));
    }
    if class & ERR_BUSERROR != 0 && kinds.is_empty() {
        kinds.push(BusErrorKind::Protocol("bus error".into()));
    }
    kinds
}

/// Converts a klar frame to a socketcan frame.
pub fn to_socketcan(frame: &CanFrame) -> Option<socketcan::CanFrame> {
    let id: socketcan::Id = match frame.id() {
        CanId::Standard(v) => socketcan::StandardId::new(v)?.into(),
        CanId::Extended(v) => socketcan::ExtendedId::new(v)?.into(),
    };
    if frame.is_remote() {
        socketcan::CanFrame::new_remote(id, usize::from(frame.dlc()))
    } else {
        socketcan::CanFrame::new(id, frame.data())
    }
}

/// Converts a received socketcan frame to a bus event.
pub fn from_socketcan(frame: &socketcan::CanFrame, timestamp: f64) -> Vec<CanEvent> {
    let id = |id: socketcan::Id| match id {
        socketcan::Id::Standard(s) => CanId::Standard(s.as_raw()),
        socketcan::Id::Extended(e) => CanId::Extended(e.as_raw()),
    };
    let converted = match frame {
        socketcan::CanFrame::Data(d) => CanFrame::new(id(d.id()), d.data()),
        socketcan::CanFrame::Remote(r) => CanFrame::remote(id(r.id()), r.dlc() as u8),
        socketcan::CanFrame::Error(e) => {
            return decode_error_frame(e.error_bits(), e.data())
                .into_iter()
                .map(CanEvent::Error)
                .collect();
        }
    };
    match converted {
        Ok(frame) => vec![CanEvent::Frame { frame, timestamp }],
        Err(e) => vec![CanEvent::Error(BusErrorKind::Malformed(e.to_string()))],
    }
}

/// A CAN bus reached through a Linux SocketCAN interface.
pub struct SocketCanBus {
    bridge: Bridge<socketcan::CanFrame>,
}

impl SocketCanBus {
    /// Opens the interface `ifname` (e.g. `can0`); its bitrate is set by the system
    /// (`ip link set can0 type can bitrate 500000`), not here.
    pub fn open(ifname: &str) -> Result<Self, CanError> {
        let ifname = ifname.to_string();
        let bridge = Bridge::spawn("socketcan", move |inbox, mut rx, ready| async move {
            let socket = match socketcan::tokio::CanSocket::open(&ifname) {
                Ok(s) => s,
                Err(e) => {
                    let msg = format!("cannot open CAN interface {ifname}: {e}");
                    ready.report(Err(CanError::Io(msg.clone())));
                    return Err(msg);
                }
            };
            if let Err(e) = socket.set_error_filter_accept_all() {
                tracing::warn!(error = %e, "socketcan: error frames not enabled");
            }
            ready.report(Ok(()));
            loop {
                tokio::select! {
                    read = socket.read_frame() => {
                        let frame = read.map_err(|e| format!("{ifname}: read: {e}"))?;
                        for ev in from_socketcan(&frame, inbox.now()) {
                            inbox.push(ev);
                        }
                    }
                    out = rx.recv() => match out {
                        Some(frame) => {
                            if let Err(e) = socket.write_frame(frame).await {
                                // ENOBUFS while the controller is bus-off or the queue is full.
                                tracing::warn!(error = %e, "socketcan: write failed");
                                inbox.push(CanEvent::Error(BusErrorKind::Protocol(format!("write failed: {e}"))));
                            }
                        }
                        None => return Ok(()),
                    }
                }
            }
        })?;
        Ok(Self { bridge })
    }
}

impl CanBus for SocketCanBus {
    fn send(&mut self, frame: &CanFrame) -> Result<(), CanError> {
        let f = to_socketcan(frame)
            .ok_or_else(|| CanError::Io(format!("frame {frame:?} not representable")))?;
        self.bridge.send(f)
    }

    fn recv_timeout(&mut self, timeout: Duration) -> Result<Option<CanEvent>, CanError> {
        self.bridge.recv_timeout(timeout)
    }
}
