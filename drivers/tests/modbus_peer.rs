//! klar's Modbus VFD backend against an independent pymodbus VFD (scripts/peers/
//! modbus_vfd_peer.py) on a pseudo-terminal. The peer implements the register maps from
//! their written definitions and logs every write, so a wrong register, a wrong bit or a
//! misread status fails these tests.

use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use klar_drivers::modbus::{
    GenericVfdRegisters, ModbusVfd, ModbusVfdConfig, Parity, SerialLineConfig, VfdPreset,
};
use klar_motion::{AxisFault, SpindleBackend, SpindleFeedback};
use serde_json::Value;

const WAIT: Duration = Duration::from_secs(10);

fn repo() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// The pymodbus peer process; killed on drop.
struct Peer {
    child: Child,
    stdin: ChildStdin,
    events: Receiver<Value>,
    log: Vec<Value>,
    port: String,
}

impl Peer {
    fn start(args: &[&str]) -> Peer {
        let python = repo().join(".venv/bin/python");
        assert!(
            python.exists(),
            "{} is missing: run scripts/setup-peers.sh first",
            python.display()
        );
        let mut child = Command::new(python)
            .arg(repo().join("scripts/peers/modbus_vfd_peer.py"))
            .args(args)
            .args(["--max-seconds", "60"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start the pymodbus peer");
        let stdin = child.stdin.take().expect("peer stdin");
        let stdout = child.stdout.take().expect("peer stdout");
        let (tx, events) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                let Ok(v) = serde_json::from_str::<Value>(&line) else {
                    continue;
                };
                if tx.send(v).is_err() {
                    break;
                }
            }
        });
        let mut peer = Peer {
            child,
            stdin,
            events,
            log: Vec::new(),
            port: String::new(),
        };
        let ready = peer.wait_event(|e| e["event"] == "ready");
        peer.port = ready["port"].as_str().expect("port path").to_string();
        peer
    }

    fn wait_event(&mut self, pred: impl Fn(&Value) -> bool) -> Value {
        let deadline = Instant::now() + WAIT;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let e = self
                .events
                .recv_timeout(left)
                .expect("the peer did not send the expected event in time");
            self.log.push(e.clone());
            if pred(&e) {
                return e;
            }
        }
    }

    fn send(&mut self, line: &str) {
        writeln!(self.stdin, "{line}").expect("write to peer");
        self.stdin.flush().expect("flush peer stdin");
    }

    /// The peer's own view of its drive.
    fn state(&mut self) -> Value {
        self.send("state");
        self.wait_event(|e| e["event"] == "state")
    }

    /// Drains events that arrived so far into the log.
    fn drain(&mut self) {
        while let Ok(e) = self.events.try_recv() {
            self.log.push(e);
        }
    }

    /// Register writes (address, value) seen so far, in order.
    fn writes(&mut self) -> Vec<(u64, u64)> {
        self.drain();
        self.log
            .iter()
            .filter(|e| e["event"] == "write")
            .flat_map(|e| {
                let a = e["address"].as_u64().unwrap_or(u64::MAX);
                e["values"]
                    .as_array()
                    .cloned()
                    .unwrap_or_default()
                    .into_iter()
                    .enumerate()
                    .map(move |(i, v)| (a + i as u64, v.as_u64().unwrap_or(u64::MAX)))
            })
            .collect()
    }

    fn rejected(&mut self) -> Vec<Value> {
        self.drain();
        self.log
            .iter()
            .filter(|e| e["event"] == "rejected")
            .cloned()
            .collect()
    }
}

impl Drop for Peer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn config(port: &str, profile: VfdPreset) -> ModbusVfdConfig {
    config_max(port, profile, 24_000.0)
}

fn config_max(port: &str, profile: VfdPreset, max_rpm: f64) -> ModbusVfdConfig {
    let mut line = SerialLineConfig::new(port);
    line.baud = 115_200;
    line.parity = Parity::None;
    line.timeout = 0.25;
    line.retries = 2;
    let mut c = ModbusVfdConfig::new(line, 1, max_rpm, profile);
    c.poll_period = 0.02;
    c
}

/// Cycles the spindle (wall clock) until `pred` holds, returning every feedback seen.
fn run_until(vfd: &mut ModbusVfd, pred: impl Fn(&SpindleFeedback) -> bool) -> Vec<SpindleFeedback> {
    let start = Instant::now();
    let mut seen = Vec::new();
    loop {
        let fb = vfd
            .cycle(start.elapsed().as_secs_f64())
            .expect("spindle cycle");
        let done = pred(&fb);
        seen.push(fb);
        if done {
            return seen;
        }
        assert!(
            start.elapsed() < WAIT,
            "condition not reached in time; last feedback {:?}",
            seen.last()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// `pairs` occur in `writes` in this order (other writes may come between).
fn in_order(writes: &[(u64, u64)], pairs: &[(u64, u64)]) -> bool {
    let mut it = writes.iter();
    pairs.iter().all(|p| it.any(|w| w == p))
}

#[test]
fn delta_vfd_speed_direction_stop_against_pymodbus() {
    let mut peer = Peer::start(&["--map", "delta", "--rpm-per-hz", "60", "--accel", "20000"]);
    let mut vfd = ModbusVfd::open(&config(&peer.port, VfdPreset::Delta { rpm_per_hz: 60.0 }))
        .expect("open the VFD backend");

    vfd.command(12_000.0).unwrap();
    let seen = run_until(&mut vfd, |fb| fb.at_speed);
    // 12000 rpm / 60 rpm/Hz = 200.00 Hz = 20000 in 0.01 Hz; run forward = 0x12.
    let w = peer.writes();
    assert!(
        in_order(&w, &[(0x2001, 20_000), (0x2000, 0x12)]),
        "writes {w:?}"
    );
    // The ramp was seen, and at-speed was not claimed before the window was reached.
    assert!(
        seen.iter().any(|f| f.rpm > 100.0 && f.rpm < 11_000.0),
        "no ramp seen"
    );
    for f in &seen {
        if f.at_speed {
            assert!((f.rpm - 12_000.0).abs() <= 0.05 * 12_000.0, "{f:?}");
        }
    }
    // Once the ramp has ended, klar's reading agrees with the peer's own speed to the
    // register resolution (0.01 Hz = 0.6 rpm).
    let seen = run_until(&mut vfd, |fb| (fb.rpm - 12_000.0).abs() <= 0.6 + 1e-9);
    let state = peer.state();
    assert_eq!(state["target"].as_f64(), Some(12_000.0));
    assert_eq!(state["rpm"].as_f64(), Some(12_000.0));
    assert!(seen.last().unwrap().at_speed);

    vfd.command(-3_000.0).unwrap();
    let seen = run_until(&mut vfd, |fb| fb.at_speed && fb.rpm < 0.0);
    let w = peer.writes();
    // 3000 / 60 = 50.00 Hz; run reverse = 0x22.
    assert!(
        in_order(&w, &[(0x2001, 5_000), (0x2000, 0x22)]),
        "writes {w:?}"
    );
    assert!((seen.last().unwrap().rpm + 3_000.0).abs() <= 0.05 * 3_000.0);
    assert_eq!(peer.state()["target"].as_f64(), Some(-3_000.0));

    vfd.command(0.0).unwrap();
    let seen = run_until(&mut vfd, |fb| fb.at_speed);
    assert!(seen.last().unwrap().rpm.abs() <= 10.0);
    let w = peer.writes();
    assert_eq!(
        w.last(),
        Some(&(0x2000, 0x01)),
        "stop command last, writes {w:?}"
    );
    assert!(
        peer.rejected().is_empty(),
        "peer rejected requests: {:?}",
        peer.rejected()
    );
}

#[test]
fn delta_vfd_fault_is_reported_and_reset() {
    let mut peer = Peer::start(&["--map", "delta", "--rpm-per-hz", "30", "--accel", "50000"]);
    let profile = VfdPreset::Delta { rpm_per_hz: 30.0 };
    let mut vfd =
        ModbusVfd::open(&config_max(&peer.port, profile, 12_000.0)).expect("open the VFD backend");
    vfd.command(6_000.0).unwrap();
    run_until(&mut vfd, |fb| fb.at_speed);

    peer.send("fault 23");
    let seen = run_until(&mut vfd, |fb| fb.fault.is_some());
    let fault = seen.last().unwrap().fault.clone();
    assert!(
        matches!(fault, Some(AxisFault::Drive { code: 23, .. })),
        "{fault:?}"
    );
    // The controlled stop: klar commands stop once it sees the fault.
    let start = Instant::now();
    while !peer.writes().ends_with(&[(0x2000, 0x01)]) {
        assert!(start.elapsed() < WAIT, "no stop written after the fault");
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(!seen.last().unwrap().at_speed);

    vfd.command(0.0).unwrap();
    vfd.reset_fault().expect("fault reset");
    let w = peer.writes();
    assert!(
        in_order(&w, &[(0x2002, 0b10)]),
        "reset bit not written: {w:?}"
    );
    run_until(&mut vfd, |fb| fb.fault.is_none() && fb.at_speed);
    assert_eq!(peer.state()["fault"].as_u64(), Some(0));
    assert!(peer.rejected().is_empty());
}

#[test]
fn corrupted_response_is_retried_and_silence_is_a_fault() {
    let mut peer = Peer::start(&["--map", "delta", "--rpm-per-hz", "60"]);
    let mut vfd = ModbusVfd::open(&config(&peer.port, VfdPreset::Delta { rpm_per_hz: 60.0 }))
        .expect("open the VFD backend");
    run_until(&mut vfd, |_| true);
    let before = vfd.snapshot().stats;

    // One response with a broken CRC: dropped by the decoder, retried, no fault.
    peer.send("corrupt 1");
    peer.wait_event(|e| e["event"] == "corrupted");
    let start = Instant::now();
    while vfd.snapshot().stats.timeouts <= before.timeouts {
        assert!(
            start.elapsed() < WAIT,
            "the corrupted frame was not noticed"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(200));
    let snap = vfd.snapshot();
    assert_eq!(snap.fault, None, "one bad frame must not fault: {snap:?}");
    assert!(snap.stats.transactions > before.transactions);

    // Two "server device busy" answers: retried (2 retries allowed), no fault.
    let before = vfd.snapshot().stats;
    peer.send("busy 2");
    peer.wait_event(|e| e["event"] == "ok");
    let start = Instant::now();
    while vfd.snapshot().stats.exceptions < before.exceptions + 2 {
        assert!(start.elapsed() < WAIT, "busy answers not seen");
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(200));
    let snap = vfd.snapshot();
    assert_eq!(snap.fault, None, "busy is retried: {snap:?}");
    assert_eq!(snap.stats.given_up, before.given_up);

    // A silent device: after 1 + 2 attempts of 250 ms, communication is lost.
    vfd.command(1_200.0).unwrap();
    peer.send("silent 1");
    let seen = run_until(&mut vfd, |fb| fb.fault.is_some());
    assert_eq!(
        seen.last().unwrap().fault,
        Some(AxisFault::CommunicationLost)
    );
    assert!(
        vfd.snapshot()
            .last_error
            .is_some_and(|e| e.contains("giving up after 3 attempts"))
    );

    // Back on the line: the fault clears once the program has stopped the spindle.
    peer.send("silent 0");
    vfd.command(0.0).unwrap();
    run_until(&mut vfd, |fb| fb.fault.is_none());
    assert_eq!(peer.writes().last(), Some(&(0x2000, 0x01)));
}

#[test]
fn generic_vfd_map_against_pymodbus() {
    let mut peer = Peer::start(&["--map", "generic", "--accel", "30000"]);
    let profile = VfdPreset::Generic {
        registers: GenericVfdRegisters::default(),
    };
    let mut vfd = ModbusVfd::open(&config(&peer.port, profile)).expect("open the VFD backend");
    vfd.command(1_500.0).unwrap();
    let seen = run_until(&mut vfd, |fb| fb.at_speed);
    assert!((seen.last().unwrap().rpm - 1_500.0).abs() <= 75.0);
    vfd.command(-700.0).unwrap();
    let seen = run_until(&mut vfd, |fb| fb.at_speed && fb.rpm < 0.0);
    assert!((seen.last().unwrap().rpm + 700.0).abs() <= 35.0);
    let w = peer.writes();
    // Speed register 1 then control 0: run (bit 0), run + reverse (bits 0 and 1).
    assert!(
        in_order(&w, &[(1, 1_500), (0, 0b01), (1, 700), (0, 0b11)]),
        "writes {w:?}"
    );
    assert_eq!(peer.state()["target"].as_f64(), Some(-700.0));
    assert!(peer.rejected().is_empty());
}

#[test]
fn wrong_register_map_is_refused_by_the_device_and_reported() {
    let mut peer = Peer::start(&["--map", "generic"]);
    let registers = GenericVfdRegisters {
        status: 0x0010,
        actual_speed: 0x0011,
        fault_code: 0x0012,
        ..GenericVfdRegisters::default()
    };
    let mut vfd = ModbusVfd::open(&config(&peer.port, VfdPreset::Generic { registers }))
        .expect("open the VFD backend");
    let seen = run_until(&mut vfd, |fb| fb.fault.is_some());
    // The device answers with exception 02: its own refusal, not a lost line.
    assert_eq!(
        seen.last().unwrap().fault,
        Some(AxisFault::DeviceException {
            code: 2,
            meaning: "illegal data address"
        })
    );
    let err = vfd.snapshot().last_error.unwrap_or_default();
    assert!(err.contains("illegal data address"), "{err}");
    assert!(!peer.rejected().is_empty());
}
