//! slcan (Lawicel ASCII) CAN adapters over a serial port.
//!
//! The protocol: every message is ASCII ending in carriage return (CR). The host sends
//! commands (`S0`..`S8` bitrate, `O` open, `C` close, `tIIILDD..` / `TIIIIIIIILDD..` data
//! frames, `rIIIL` / `RIIIIIIIIL` remote frames); the adapter answers CR for success and
//! BEL (0x07) for an error, and forwards frames from the bus in the same `t`/`T`/`r`/`R`
//! notation, optionally followed by a 4-hex-digit timestamp.
//!
//! [`SlcanBus`] can play either end of the serial line: [`SlcanRole::Host`] talks to a
//! real adapter (sends the open sequence and checks the answers), [`SlcanRole::Adapter`]
//! plays the adapter for a host on the other end of a pseudo-terminal (answers the host's
//! commands), which links two programs as if they shared a CAN bus.

use std::sync::Arc;
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::sync::mpsc;

use super::bridge::{Bridge, Inbox, Ready};
use super::{BusErrorKind, CanBus, CanError, CanEvent, CanFrame, CanId, STANDARD_BITRATES};

/// The BEL byte an adapter answers errors with.
pub const BEL: u8 = 0x07;
/// The carriage return that ends every message (alone: success).
pub const CR: u8 = b'\r';
/// Longest message the decoder accepts (an extended frame with 8 bytes and a timestamp
/// has 1 + 8 + 1 + 16 + 4 = 30 characters).
const MAX_LINE: usize = 64;

/// The bitrate command (`S0`..`S8`) for a bitrate in bit/s.
pub fn bitrate_command(bitrate: u32) -> Result<String, CanError> {
    STANDARD_BITRATES
        .iter()
        .position(|&b| b == bitrate)
        .map(|i| format!("S{i}"))
        .ok_or(CanError::UnsupportedBitrate(bitrate))
}

/// Appends the slcan text of `frame` (with the trailing CR) to `out`.
pub fn encode_frame(frame: &CanFrame, out: &mut Vec<u8>) {
    const HEX: &[u8; 16] = b"0123456789ABCDEF";
    let (tag, digits, id) = match (frame.id(), frame.is_remote()) {
        (CanId::Standard(id), false) => (b't', 3, u32::from(id)),
        (CanId::Standard(id), true) => (b'r', 3, u32::from(id)),
        (CanId::Extended(id), false) => (b'T', 8, id),
        (CanId::Extended(id), true) => (b'R', 8, id),
    };
    out.push(tag);
    for i in (0..digits).rev() {
        out.push(HEX[((id >> (4 * i)) & 0xF) as usize]);
    }
    out.push(b'0' + frame.dlc());
    for b in frame.data() {
        out.push(HEX[usize::from(b >> 4)]);
        out.push(HEX[usize::from(b & 0xF)]);
    }
    out.push(CR);
}

/// One decoded slcan message.
#[derive(Debug, Clone, PartialEq)]
pub enum SlcanMessage {
    /// A data or remote frame, with the adapter's timestamp (ms, 0..60000) if present.
    Frame {
        /// The frame.
        frame: CanFrame,
        /// The adapter's millisecond timestamp, when timestamps are on.
        adapter_ms: Option<u16>,
    },
    /// A lone CR: success (from an adapter) or an empty command (from a host).
    Ok,
    /// BEL: the adapter refused the last command.
    Error,
    /// Any other message (a command from a host, or an adapter's version/status answer).
    Other(String),
    /// A message that claims to be a frame but is not well formed.
    Malformed(String),
}

/// Incremental decoder of an slcan byte stream.
#[derive(Debug, Default, Clone)]
pub struct SlcanDecoder {
    line: Vec<u8>,
    overlong: bool,
}

impl SlcanDecoder {
    /// A decoder with an empty buffer.
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds bytes and appends every complete message to `out`.
    pub fn feed(&mut self, bytes: &[u8], out: &mut Vec<SlcanMessage>) {
        for &b in bytes {
            match b {
                CR => {
                    if self.overlong {
                        out.push(SlcanMessage::Malformed(format!(
                            "message longer than {MAX_LINE} bytes"
                        )));
                    } else {
                        out.push(decode_line(&self.line));
                    }
                    self.line.clear();
                    self.overlong = false;
                }
                BEL => {
                    if !self.line.is_empty() {
                        out.push(SlcanMessage::Malformed(format!(
                            "unterminated `{}` before error reply",
                            String::from_utf8_lossy(&self.line)
                        )));
                        self.line.clear();
                    }
                    self.overlong = false;
                    out.push(SlcanMessage::Error);
                }
                b'\n' => {}
                _ if self.line.len() >= MAX_LINE => self.overlong = true,
                _ => self.line.push(b),
            }
        }
    }
}

fn hex_value(digits: &[u8]) -> Option<u32> {
    if digits.is_empty() || digits.len() > 8 {
        return None;
    }
    digits.iter().try_fold(0u32, |acc, &d| {
        let v = (d as char).to_digit(16)?;
        Some((acc << 4) | v)
    })
}

/// Decodes one message without its CR.
pub fn decode_line(line: &[u8]) -> SlcanMessage {
    let Some((&tag, rest)) = line.split_first() else {
        return SlcanMessage::Ok;
    };
    let (id_len, extended, remote) = match tag {
        b't' => (3, false, false),
        b'T' => (8, true, false),
        b'r' => (3, false, true),
        b'R' => (8, true, true),
        _ => return SlcanMessage::Other(String::from_utf8_lossy(line).into_owned()),
    };
    let text = || String::from_utf8_lossy(line).into_owned();
    let bad = |why: &str| SlcanMessage::Malformed(format!("`{}`: {why}", text()));
    let (Some(id_digits), Some(&dlc_char)) = (rest.get(..id_len), rest.get(id_len)) else {
        return bad("too short");
    };
    let Some(raw_id) = hex_value(id_digits) else {
        return bad("identifier is not hexadecimal");
    };
    let dlc = match (dlc_char as char).to_digit(10) {
        Some(d) if d <= 8 => d as usize,
        _ => return bad("length is not 0..8"),
    };
    let id = if extended {
        CanId::Extended(raw_id)
    } else {
        match u16::try_from(raw_id) {
            Ok(v) => CanId::Standard(v),
            Err(_) => return bad("identifier out of range"),
        }
    };
    let body = rest.get(id_len + 1..).unwrap_or_default();
    let data_chars = if remote { 0 } else { 2 * dlc };
    let timestamp = match body.len().checked_sub(data_chars) {
        Some(0) => None,
        Some(4) => match body.get(data_chars..).and_then(hex_value) {
            Some(ms) => u16::try_from(ms).ok(),
            None => return bad("timestamp is not hexadecimal"),
        },
        _ => return bad("data length does not match the length digit"),
    };
    let frame = if remote {
        CanFrame::remote(id, dlc as u8)
    } else {
        let mut data = [0u8; 8];
        for (i, slot) in data.iter_mut().take(dlc).enumerate() {
            match body.get(2 * i..2 * i + 2).and_then(hex_value) {
                Some(v) => *slot = v as u8,
                None => return bad("data is not hexadecimal"),
            }
        }
        CanFrame::new(id, &data[..dlc])
    };
    match frame {
        Ok(frame) => SlcanMessage::Frame {
            frame,
            adapter_ms: timestamp,
        },
        Err(e) => bad(&e.to_string()),
    }
}

/// Which end of the serial line [`SlcanBus`] plays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlcanRole {
    /// The computer side of a real adapter: sends close, bitrate and open commands at
    /// start-up and expects CR answers.
    Host,
    /// The adapter side: answers the host's configuration commands with CR and forwards
    /// frames both ways (for linking two programs over a pseudo-terminal).
    Adapter,
}

/// How to open an slcan adapter.
#[derive(Debug, Clone, PartialEq)]
pub struct SlcanOptions {
    /// CAN bitrate in bit/s (one of [`STANDARD_BITRATES`]).
    pub bitrate: u32,
    /// Serial line speed (USB adapters ignore it).
    pub serial_baud: u32,
    /// Which end of the line to play.
    pub role: SlcanRole,
    /// How long to wait for each answer of the adapter at start-up.
    pub answer_timeout: Duration,
}

impl SlcanOptions {
    /// Host-side options for `bitrate` with usual defaults (115200 baud, 1 s answers).
    pub fn host(bitrate: u32) -> Self {
        Self {
            bitrate,
            serial_baud: 115_200,
            role: SlcanRole::Host,
            answer_timeout: Duration::from_secs(1),
        }
    }

    /// Adapter-side options (for the far end of a pseudo-terminal).
    pub fn adapter(bitrate: u32) -> Self {
        Self {
            role: SlcanRole::Adapter,
            ..Self::host(bitrate)
        }
    }
}

/// A CAN bus reached through an slcan adapter on a serial port.
pub struct SlcanBus {
    bridge: Bridge<Vec<u8>>,
    scratch: Vec<u8>,
}

impl SlcanBus {
    /// Opens the serial device at `path` and starts the adapter.
    pub fn open(path: &str, options: SlcanOptions) -> Result<Self, CanError> {
        bitrate_command(options.bitrate)?;
        let path = path.to_string();
        let bridge = Bridge::spawn("slcan", move |inbox, rx, ready| async move {
            let builder = tokio_serial::new(&path, options.serial_baud);
            match tokio_serial::SerialStream::open(&builder) {
                Ok(port) => run(port, options, inbox, rx, ready).await,
                Err(e) => {
                    let msg = format!("cannot open {path}: {e}");
                    ready.report(Err(CanError::Io(msg.clone())));
                    Err(msg)
                }
            }
        })?;
        Ok(Self {
            bridge,
            scratch: Vec::with_capacity(32),
        })
    }

    /// Starts the adapter on an already open terminal (for example one end of
    /// [`serialport::TTYPort::pair`]).
    pub fn from_tty(port: serialport::TTYPort, options: SlcanOptions) -> Result<Self, CanError> {
        bitrate_command(options.bitrate)?;
        let bridge = Bridge::spawn("slcan", move |inbox, rx, ready| async move {
            match tokio_serial::SerialStream::try_from(port) {
                Ok(port) => run(port, options, inbox, rx, ready).await,
                Err(e) => {
                    let msg = format!("cannot use terminal: {e}");
                    ready.report(Err(CanError::Io(msg.clone())));
                    Err(msg)
                }
            }
        })?;
        Ok(Self {
            bridge,
            scratch: Vec::with_capacity(32),
        })
    }
}

impl CanBus for SlcanBus {
    fn send(&mut self, frame: &CanFrame) -> Result<(), CanError> {
        self.scratch.clear();
        encode_frame(frame, &mut self.scratch);
        self.bridge.send(self.scratch.clone())
    }

    fn recv_timeout(&mut self, timeout: Duration) -> Result<Option<CanEvent>, CanError> {
        self.bridge.recv_timeout(timeout)
    }
}

/// Sends one command and waits for its CR or BEL answer; frames arriving meanwhile are
/// kept.
async fn command(
    port: &mut tokio_serial::SerialStream,
    decoder: &mut SlcanDecoder,
    inbox: &Inbox,
    cmd: &str,
    timeout: Duration,
) -> Result<(), CanError> {
    let io = |e: std::io::Error| CanError::Io(e.to_string());
    port.write_all(cmd.as_bytes()).await.map_err(io)?;
    port.write_all(&[CR]).await.map_err(io)?;
    let deadline = tokio::time::Instant::now() + timeout;
    let mut buf = [0u8; 256];
    let mut msgs = Vec::new();
    loop {
        let n = match tokio::time::timeout_at(deadline, port.read(&mut buf)).await {
            Ok(r) => r.map_err(io)?,
            Err(_) => {
                return Err(CanError::AdapterTimeout {
                    command: cmd.to_string(),
                    timeout_ms: timeout.as_millis() as u64,
                });
            }
        };
        if n == 0 {
            return Err(CanError::Closed("serial line closed".into()));
        }
        decoder.feed(buf.get(..n).unwrap_or_default(), &mut msgs);
        for m in msgs.drain(..) {
            match m {
                SlcanMessage::Ok => return Ok(()),
                SlcanMessage::Error => return Err(CanError::AdapterRefused(cmd.to_string())),
                SlcanMessage::Frame { frame, .. } => inbox.push(CanEvent::Frame {
                    frame,
                    timestamp: inbox.now(),
                }),
                other => tracing::debug!(?other, "slcan: ignored during start-up"),
            }
        }
    }
}

/// The adapter's I/O task.
async fn run(
    mut port: tokio_serial::SerialStream,
    options: SlcanOptions,
    inbox: Arc<Inbox>,
    mut rx: mpsc::UnboundedReceiver<Vec<u8>>,
    ready: Ready,
) -> Result<(), String> {
    let mut decoder = SlcanDecoder::new();
    if options.role == SlcanRole::Host {
        let bitrate = bitrate_command(options.bitrate).map_err(|e| e.to_string())?;
        // Close first: the adapter may still be open from an earlier session, and then
        // refuses the bitrate command; its answer to this close is therefore not checked.
        let _ = command(&mut port, &mut decoder, &inbox, "C", options.answer_timeout).await;
        for cmd in [bitrate.as_str(), "O"] {
            if let Err(e) =
                command(&mut port, &mut decoder, &inbox, cmd, options.answer_timeout).await
            {
                let msg = e.to_string();
                ready.report(Err(e));
                return Err(msg);
            }
        }
    }
    ready.report(Ok(()));
    let mut buf = [0u8; 1024];
    let mut msgs = Vec::new();
    loop {
        tokio::select! {
            read = port.read(&mut buf) => {
                let n = read.map_err(|e| format!("serial read: {e}"))?;
                if n == 0 {
                    return Err("serial line closed".into());
                }
                decoder.feed(buf.get(..n).unwrap_or_default(), &mut msgs);
                for m in msgs.drain(..) {
                    match m {
                        SlcanMessage::Frame { frame, .. } => inbox.push(CanEvent::Frame {
                            frame,
                            timestamp: inbox.now(),
                        }),
                        SlcanMessage::Error => inbox.push(CanEvent::Error(BusErrorKind::ErrorReply)),
                        SlcanMessage::Malformed(s) => inbox.push(CanEvent::Error(BusErrorKind::Malformed(s))),
                        SlcanMessage::Ok => {}
                        SlcanMessage::Other(cmd) => {
                            if options.role == SlcanRole::Adapter {
                                let answer = adapter_answer(&cmd);
                                port.write_all(answer).await.map_err(|e| format!("serial write: {e}"))?;
                            } else {
                                tracing::debug!(%cmd, "slcan: ignored adapter message");
                            }
                        }
                    }
                }
            }
            out = rx.recv() => {
                match out {
                    Some(bytes) => port.write_all(&bytes).await.map_err(|e| format!("serial write: {e}"))?,
                    None => return Ok(()),
                }
            }
        }
    }
}

/// What a simple adapter answers to a host's command: CR for the commands every slcan
/// adapter knows, a version string for `V`, BEL otherwise.
pub fn adapter_answer(cmd: &str) -> &'static [u8] {
    match cmd.as_bytes() {
        b"O" | b"C" | b"L" | b"Z0" | [b'S', b'0'..=b'8'] => b"\r",
        b"V" => b"V1010\r",
        _ => &[BEL],
    }
}
