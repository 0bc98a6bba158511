//! slcan adapters on the two ends of a pseudo-terminal: the host's open sequence against
//! the adapter end, frames both ways, and the host's handling of silent or refusing
//! adapters.

use std::io::{Read, Write};

use serialport::SerialPort as _;
use std::time::{Duration, Instant};

use klar_drivers::can::slcan::{SlcanBus, SlcanOptions};
use klar_drivers::can::{CanBus, CanError, CanEvent, CanFrame, CanId};

fn pty() -> (serialport::TTYPort, serialport::TTYPort) {
    serialport::TTYPort::pair().expect("pseudo-terminal pair")
}

fn next_frame(bus: &mut dyn CanBus) -> CanFrame {
    let deadline = Instant::now() + Duration::from_secs(5);
    while Instant::now() < deadline {
        if let Some(CanEvent::Frame { frame, .. }) = bus
            .recv_timeout(Duration::from_millis(100))
            .expect("bus open")
        {
            return frame;
        }
    }
    panic!("no frame within 5 s");
}

#[test]
fn host_and_adapter_exchange_frames() {
    let (a, b) = pty();
    // The adapter end must be up before the host sends its open sequence.
    let mut adapter = SlcanBus::from_tty(b, SlcanOptions::adapter(500_000)).expect("adapter");
    let mut host = SlcanBus::from_tty(a, SlcanOptions::host(500_000)).expect("host opens");
    let frames = [
        CanFrame::standard(0x123, &[0x11, 0x22, 0x33]).expect("frame"),
        CanFrame::standard(0x000, &[]).expect("frame"),
        CanFrame::new(CanId::Extended(0x1ABC_DEF0), &[1, 2, 3, 4, 5, 6, 7, 8]).expect("frame"),
        CanFrame::remote(CanId::Standard(0x7FF), 4).expect("frame"),
    ];
    for f in &frames {
        host.send(f).expect("send");
    }
    for f in &frames {
        assert_eq!(&next_frame(&mut adapter), f);
    }
    for f in frames.iter().rev() {
        adapter.send(f).expect("send");
    }
    for f in frames.iter().rev() {
        assert_eq!(&next_frame(&mut host), f);
    }
}

#[test]
fn host_times_out_on_a_silent_adapter() {
    let (a, _b) = pty();
    let mut options = SlcanOptions::host(125_000);
    options.answer_timeout = Duration::from_millis(100);
    match SlcanBus::from_tty(a, options) {
        Err(CanError::AdapterTimeout {
            command,
            timeout_ms,
        }) => {
            assert_eq!(command, "S4");
            assert_eq!(timeout_ms, 100);
        }
        Err(e) => panic!("wrong error {e}"),
        Ok(_) => panic!("must not open"),
    }
}

#[test]
fn host_reports_a_refused_bitrate() {
    let (a, mut b) = pty();
    b.set_timeout(Duration::from_secs(5)).expect("timeout");
    // A scripted adapter: accepts C, refuses the bitrate command with BEL.
    let script = std::thread::spawn(move || {
        let mut seen = Vec::new();
        let mut buf = [0u8; 64];
        while seen.iter().filter(|&&c| c == b'\r').count() < 2 {
            let n = b.read(&mut buf).expect("read");
            for &c in &buf[..n] {
                seen.push(c);
                if c == b'\r' {
                    let answer: &[u8] = if seen.starts_with(b"C\r") && seen.len() == 2 {
                        b"\r"
                    } else {
                        b"\x07"
                    };
                    b.write_all(answer).expect("write");
                }
            }
        }
        String::from_utf8(seen).expect("ascii")
    });
    let mut options = SlcanOptions::host(1_000_000);
    options.answer_timeout = Duration::from_secs(2);
    match SlcanBus::from_tty(a, options) {
        Err(CanError::AdapterRefused(cmd)) => assert_eq!(cmd, "S8"),
        Err(e) => panic!("wrong error {e}"),
        Ok(_) => panic!("must not open"),
    }
    assert_eq!(script.join().expect("script"), "C\rS8\r");
}

#[test]
fn adapter_end_answers_commands_and_reports_garbage() {
    let (mut a, b) = pty();
    a.set_timeout(Duration::from_secs(5)).expect("timeout");
    let mut adapter = SlcanBus::from_tty(b, SlcanOptions::adapter(250_000)).expect("adapter");
    a.write_all(b"S5\rO\rX9\r").expect("write");
    let mut answers = Vec::new();
    let mut buf = [0u8; 16];
    while answers.len() < 3 {
        let n = a.read(&mut buf).expect("read");
        answers.extend_from_slice(&buf[..n]);
    }
    assert_eq!(answers, b"\r\r\x07");
    // A frame line with a bad length digit is reported, not delivered.
    a.write_all(b"t1239AA\r").expect("write");
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        assert!(Instant::now() < deadline, "no error event");
        if let Some(ev) = adapter
            .recv_timeout(Duration::from_millis(100))
            .expect("open")
        {
            match ev {
                CanEvent::Error(klar_drivers::can::BusErrorKind::Malformed(m)) => {
                    assert!(m.contains("t1239AA"), "{m}");
                    break;
                }
                other => panic!("unexpected {other:?}"),
            }
        }
    }
}

#[test]
fn opening_a_missing_device_is_an_error() {
    match SlcanBus::open("/dev/klar-no-such-tty", SlcanOptions::host(500_000)) {
        Err(CanError::Io(msg)) => assert!(msg.contains("klar-no-such-tty"), "{msg}"),
        Err(e) => panic!("wrong error {e}"),
        Ok(_) => panic!("must fail"),
    }
    assert!(matches!(
        SlcanBus::open("/dev/null", SlcanOptions::host(300_000)),
        Err(CanError::UnsupportedBitrate(300_000))
    ));
}
