//! The fuzz target bodies, shared by the cargo-fuzz binaries (fuzz_targets/) and the bounded
//! stable harness (tests/fuzz_bounded.rs). Each takes arbitrary bytes and must neither panic
//! nor hang; where an input decodes, a round trip or an invariant is checked too.

#![allow(dead_code)]

use klar::config::MachineConfig;
use klar_drivers::can::memory::MemoryBus;
use klar_drivers::can::slcan::{SlcanDecoder, SlcanMessage, decode_line, encode_frame};
use klar_drivers::can::{CanBus, CanFrame, CanId};
use klar_drivers::canopen::Master;
use klar_drivers::canopen::emcy::Emergency;
use klar_interp::{Interpreter, Pose};
use std::time::Duration;

/// Most ops taken from one fuzzed program (loops in a program may be endless by design).
const MAX_OPS: usize = 20_000;

fn program(name: &str, data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let interp = Interpreter::from_source(name, &text, Pose::ZERO);
    // Every op the interpreter lets out carries a real source line.
    for op in interp.take(MAX_OPS).flatten() {
        assert!(op.loc.line >= 1, "op without a line: {op:?}");
    }
}

/// Klartext parser and interpreter.
pub fn program_klartext(data: &[u8]) {
    program("fuzz.h", data);
}

/// TNC ISO parser and interpreter.
pub fn program_tnc_iso(data: &[u8]) {
    program("fuzz.i", data);
}

/// Lathe DIN parser and interpreter.
pub fn program_lathe_din(data: &[u8]) {
    program("fuzz.nc", data);
}

/// The machine TOML loader and its validation; an accepted machine is usable.
pub fn machine_toml(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    if let Ok(m) = MachineConfig::parse("fuzz.toml", &text) {
        assert!(!m.axes.is_empty());
        assert!(m.servo_period > 0.0 && m.servo_period.is_finite());
        let _ = m.axis_limits();
        let _ = m.needs_wall_clock();
    }
}

/// The slcan stream decoder: any byte stream, split anywhere, decodes without panic, and
/// every frame it yields survives an encode/decode round trip.
pub fn slcan_stream(data: &[u8]) {
    let split = data.first().map_or(0, |&b| usize::from(b)).min(data.len());
    let mut decoder = SlcanDecoder::new();
    let mut out = Vec::new();
    decoder.feed(&data[..split], &mut out);
    decoder.feed(&data[split..], &mut out);
    for line in data.split(|&b| b == b'\r') {
        let _ = decode_line(line);
    }
    for m in out {
        if let SlcanMessage::Frame { frame, .. } = m {
            let mut bytes = Vec::new();
            encode_frame(&frame, &mut bytes);
            let line = bytes.strip_suffix(b"\r").unwrap_or(&bytes);
            match decode_line(line) {
                SlcanMessage::Frame { frame: back, .. } => assert_eq!(back, frame),
                other => panic!("{frame:?} encoded as {bytes:?} decodes to {other:?}"),
            }
        }
    }
}

/// CANopen decoding in the master: arbitrary frames (id, length, data from the bytes) reach
/// a master, which classifies them (NMT, heartbeat, EMCY, PDO, SDO) without panic.
pub fn canopen_frames(data: &[u8]) {
    let bus = MemoryBus::new();
    let mut master = Master::new(Box::new(bus.endpoint()), Duration::from_millis(1));
    let mut sender = bus.endpoint();
    master.watch_heartbeat(1, 0.1);
    let mut rest = data;
    let mut t = 0.0;
    while let [hi, lo, len, tail @ ..] = rest {
        let n = usize::from(*len % 9).min(tail.len());
        let (payload, next) = tail.split_at(n);
        rest = next;
        let raw = u16::from_be_bytes([*hi, *lo]);
        let id = if hi & 0x80 != 0 {
            CanId::Extended(u32::from(raw) << 8 | u32::from(*len))
        } else {
            CanId::Standard(raw & 0x7FF)
        };
        if let Ok(frame) = CanFrame::new(id, payload) {
            let _ = Emergency::decode((raw & 0x7F) as u8, frame.data());
            if sender.send(&frame).is_err() {
                return;
            }
        }
        t += 0.01;
        master.set_time(t);
        let _ = master.poll();
        while master.next_event().is_some() {}
    }
}
