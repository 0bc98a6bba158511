//! klar's CANopen master and CiA 402 backend against drives emulated by an independent
//! stack: Python's `canopen` (LocalNode) on python-can's slcan interface, on the other end
//! of a pseudo-terminal (scripts/peers/canopen_cia402_drive.py).
//!
//! Boot-up, NMT start, PDO configuration by SDO, enable, homing, CSP motion of a short
//! program, an injected EMCY fault and the quick stop of the other axis, fault reset and
//! re-enable. The peer checks the master's side of the protocol and reports; this test
//! checks the backend's side and the peer's verdict. Every wait is bounded and the peer is
//! killed if the test ends early.

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use klar_drivers::can::CanFrame;
use klar_drivers::can::slcan::{SlcanBus, SlcanOptions};
use klar_drivers::canopen::{CanOpenError, Master, NmtCommand};
use klar_drivers::cia402::{CanOpenConfig, Cia402Backend};
use klar_motion::{AxisBackend, AxisFault, AxisFeedback, AxisState, Setpoint};
use serialport::SerialPort as _;

const PERIOD: f64 = 0.004;
const COUNTS: f64 = 1000.0;

fn repo() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// Kills the peer when the test ends, however it ends.
struct Peer(Child);

impl Drop for Peer {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

impl Peer {
    fn wait_exit(&mut self, timeout: Duration) -> Option<i32> {
        let deadline = Instant::now() + timeout;
        while Instant::now() < deadline {
            if let Ok(Some(status)) = self.0.try_wait() {
                return status.code();
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        None
    }
}

fn config() -> CanOpenConfig {
    toml::from_str(
        r#"
        bus = { adapter = "slcan", port = "(pty)", bitrate = 1000000 }
        heartbeat_ms = 100
        heartbeat_timeout_ms = 1000
        sdo_timeout_ms = 1000
        boot_timeout_ms = 10000
        pdo_wait_ms = 200.0
        state_timeout_ms = 3000
        [[drives]]
        node = 1
        counts_per_unit = 1000.0
        homing = { method = 35, offset = 2.0 }
        [[drives]]
        node = 2
        counts_per_unit = 1000.0
        "#,
    )
    .expect("config parses")
}

/// The program: a rectangle with X on node 1 and Y on node 2 at 20 mm/s, then back.
fn program() -> Vec<[f64; 2]> {
    vec![[2.0, 0.0], [6.0, 0.0], [6.0, 3.0], [2.0, 3.0], [2.0, 0.0]]
}

/// Linear interpolation along the program at `feed` mm/s, sampled every period.
fn samples(points: &[[f64; 2]], feed: f64) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    for w in points.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let n = (len / (feed * PERIOD)).ceil().max(1.0) as usize;
        for k in 1..=n {
            let s = k as f64 / n as f64;
            out.push([a[0] + (b[0] - a[0]) * s, a[1] + (b[1] - a[1]) * s]);
        }
    }
    out
}

/// Starts the peer on a fresh pseudo-terminal and waits for its READY; returns it with the
/// adapter end of the line for klar and the report path.
fn start_peer(extra: &[&str]) -> (Peer, SlcanBus, PathBuf) {
    let python = repo().join(".venv/bin/python");
    assert!(
        python.exists(),
        "run scripts/setup-peers.sh first ({} missing)",
        python.display()
    );
    let script = repo().join("scripts/peers/canopen_cia402_drive.py");
    static RUN: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let run = RUN.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    let report_path = std::env::temp_dir().join(format!(
        "klar-canopen-peer-{}-{run}.json",
        std::process::id()
    ));
    let _ = std::fs::remove_file(&report_path);
    let (host_end, device_end) = serialport::TTYPort::pair().expect("pty pair");
    let device_path = device_end.name().expect("pty has a name");
    // The peer is the slcan host (python-can sends the open sequence); klar plays the
    // adapter end, which links the two like one CAN bus.
    let bus = SlcanBus::from_tty(host_end, SlcanOptions::adapter(1_000_000)).expect("adapter end");
    let child = Command::new(&python)
        .arg(&script)
        .args(["--port", &device_path, "--nodes", "1", "2", "--report"])
        .arg(&report_path)
        .args(["--timeout", "60"])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("peer starts");
    let mut peer = Peer(child);
    let stdout = peer.0.stdout.take().expect("peer stdout");
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let ready = rx
        .recv_timeout(Duration::from_secs(30))
        .expect("peer says READY within 30 s");
    assert_eq!(ready, "READY");
    drop(device_end);
    (peer, bus, report_path)
}

/// Waits for the peer to end and reads its report.
fn finish_peer(mut peer: Peer, report_path: &PathBuf) -> (Option<i32>, serde_json::Value) {
    let code = peer.wait_exit(Duration::from_secs(20));
    let text = std::fs::read_to_string(report_path).expect("peer wrote its report");
    let _ = std::fs::remove_file(report_path);
    (code, serde_json::from_str(&text).expect("report is JSON"))
}

#[test]
fn sdo_transfers_against_the_python_stack() {
    let (peer, bus, report_path) = start_peer(&[]);
    let mut m = Master::new(Box::new(bus), Duration::from_secs(2));
    m.reset_and_wait_boot(&[1, 2], Duration::from_secs(10))
        .expect("boot-up");
    // Expedited upload.
    assert_eq!(
        m.sdo_read_u32(1, 0x1000, 0).expect("device type"),
        0x0002_0192
    );
    // Segmented upload: the name the peer script gives its drives.
    let name = m.sdo_read(2, 0x1008, 0).expect("device name");
    assert_eq!(String::from_utf8_lossy(&name), "canopen peer CiA 402 drive");
    // Segmented download, read back by segmented upload.
    let blob: Vec<u8> = (0u8..40).map(|i| i.wrapping_mul(37)).collect();
    m.sdo_write(1, 0x2000, 0, &blob).expect("segmented write");
    assert_eq!(m.sdo_read(1, 0x2000, 0).expect("read back"), blob);
    // Aborts from the independent stack, decoded by name.
    match m.sdo_read(1, 0x1234, 0) {
        Err(CanOpenError::SdoAbort { code, name, .. }) => {
            assert_eq!(code, 0x0602_0000);
            assert_eq!(name, "object does not exist in the object dictionary");
        }
        other => panic!("{other:?}"),
    }
    match m.sdo_write(2, 0x1008, 0, b"renamed drive") {
        Err(CanOpenError::SdoAbort { code, name, .. }) => {
            assert_eq!(code, 0x0601_0002);
            assert_eq!(name, "attempt to write a read-only object");
        }
        other => panic!("{other:?}"),
    }
    m.nmt(NmtCommand::Stop, 0).expect("NMT stop");
    let (code, report) = finish_peer(peer, &report_path);
    assert_eq!(report["violations"], serde_json::json!([]));
    assert_eq!(code, Some(0));
}

#[test]
fn the_peer_catches_a_master_that_skips_states() {
    let (peer, bus, report_path) = start_peer(&[]);
    let backend = Cia402Backend::with_bus(&config(), PERIOD, Box::new(bus)).expect("master starts");
    // Enable operation straight from switch-on disabled: not a CiA 402 transition.
    backend.with_master(|master| {
        master
            .bus_send(&CanFrame::standard(0x201, &[0x0F, 0x00, 0, 0, 0, 0]).expect("frame"))
            .expect("send");
        master.sync().expect("sync");
    });
    std::thread::sleep(Duration::from_millis(200));
    backend
        .with_master(|master| master.nmt(NmtCommand::Stop, 0))
        .expect("NMT stop");
    let (code, report) = finish_peer(peer, &report_path);
    assert_eq!(code, Some(1), "the peer must fail");
    let v = report["violations"].as_array().expect("violations");
    assert!(
        v.iter()
            .any(|x| x.as_str().is_some_and(|s| s
                .contains("node 1: controlword 0x000F (enable_operation) in SWITCH_ON_DISABLED"))),
        "{v:?}"
    );
}

#[test]
fn master_runs_a_program_against_the_python_canopen_peer() {
    let (peer, bus, report_path) = start_peer(&[
        "--fault-node",
        "2",
        "--fault-after",
        "150",
        "--fault-code",
        "0x2310",
        "--max-step",
        "100",
    ]);

    let mut backend =
        Cia402Backend::with_bus(&config(), PERIOD, Box::new(bus)).expect("master starts");
    backend.enable().expect("drives enable");
    let mut fb = vec![AxisFeedback::default(); 2];
    let start = Instant::now();
    let mut t = 0.0;
    let mut step = |backend: &mut Cia402Backend, sp: [f64; 2], fb: &mut [AxisFeedback]| {
        t += PERIOD;
        // Real-time pacing: the peer's heartbeats run on the wall clock.
        let due = start + Duration::from_secs_f64(t);
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let sps = sp.map(|p| Setpoint {
            position: p,
            ..Default::default()
        });
        backend.cycle(t, &sps, fb).expect("cycle");
    };

    // Homing on node 1 (method 35 with a 2 mm home offset).
    step(&mut backend, [0.0, 0.0], &mut fb);
    backend.start_homing(0).expect("homing starts");
    for _ in 0..20 {
        step(&mut backend, [0.0, 0.0], &mut fb);
        if fb[0].homed {
            break;
        }
    }
    assert!(fb[0].homed, "homing finished");
    assert!(
        (fb[0].position - 2.0).abs() < 1e-12,
        "home offset applied: {}",
        fb[0].position
    );

    // The program: a perfect servo reports back exactly the commanded count.
    let path = samples(&program(), 20.0);
    let mut fault_seen_at = None;
    for (k, p) in path.iter().enumerate() {
        step(&mut backend, *p, &mut fb);
        if fb.iter().any(|f| f.fault.is_some()) {
            fault_seen_at = Some(k);
            break;
        }
        for (f, c) in fb.iter().zip(p) {
            assert_eq!(f.state, AxisState::Enabled);
            assert!(
                (f.position - (c * COUNTS).round() / COUNTS).abs() < 1e-12,
                "{} vs {c}",
                f.position
            );
            assert!(f.following_error.abs() <= 0.5 / COUNTS + 1e-12);
        }
    }
    let k = fault_seen_at.expect("the peer's fault arrives during the program");
    // The peer faults node 2 after 150 SYNCs in operation enabled.
    assert!(k > 100 && k < path.len(), "fault at sample {k}");
    match &fb[1].fault {
        Some(AxisFault::Drive { code, text }) => {
            assert_eq!(*code, 0x2310);
            assert!(text.contains("node 2"), "{text}");
        }
        other => panic!("node 2 fault expected, got {other:?}"),
    }
    assert!(fb[0].fault.is_some(), "X is stopped too");
    assert!(backend.stop_report().expect("report").contains("node 2"));
    let held = [fb[0].position, fb[1].position];
    for _ in 0..5 {
        step(&mut backend, held, &mut fb);
    }
    // Reset, enable again, hold, and switch off.
    backend.reset_fault(1).expect("reset node 2");
    backend.reset_fault(0).expect("reset node 1");
    backend.enable().expect("enables again");
    for _ in 0..10 {
        step(&mut backend, held, &mut fb);
    }
    assert!(
        fb.iter()
            .all(|f| f.state == AxisState::Enabled && f.fault.is_none())
    );
    backend.disable().expect("disables");
    backend
        .with_master(|m| m.nmt(NmtCommand::Stop, 0))
        .expect("NMT stop");

    let (code, report) = finish_peer(peer, &report_path);
    assert_eq!(
        report["violations"],
        serde_json::json!([]),
        "peer saw protocol violations"
    );
    assert_eq!(code, Some(0), "peer exit code");
    for node in ["1", "2"] {
        let n = &report["nodes"][node];
        assert_eq!(n["heartbeat_ms"], 100);
        assert_eq!(n["interpolation"], serde_json::json!([4, -3]));
        let id: u64 = node.parse().expect("node id");
        let pdos = &n["pdos"];
        assert_eq!(
            pdos["rpdo1"]["entries"],
            serde_json::json!([0x6040_0010u32, 0x607A_0020u32])
        );
        assert_eq!(
            pdos["tpdo1"]["entries"],
            serde_json::json!([0x6041_0010u32, 0x6064_0020u32])
        );
        assert_eq!(pdos["rpdo1"]["cob_id"], 0x200 + id);
        assert_eq!(pdos["tpdo1"]["cob_id"], 0x180 + id);
        assert_eq!(pdos["tpdo1"]["transmission"], 1);
        for other in ["rpdo2", "rpdo3", "rpdo4", "tpdo2", "tpdo3", "tpdo4"] {
            assert!(
                pdos.get(other).is_none(),
                "{other} left enabled on node {node}"
            );
        }
        assert!(
            n["states"]
                .as_array()
                .expect("states")
                .contains(&serde_json::json!("OPERATION_ENABLED"))
        );
    }
    assert_eq!(report["nodes"]["1"]["homed"], true);
    assert!(
        report["nodes"]["1"]["quick_stop_at_sync"]
            .as_u64()
            .is_some()
    );
    assert_eq!(report["nodes"]["2"]["fault_resets"], 1);
    assert_eq!(
        report["nodes"]["1"]["position"],
        (held[0] * COUNTS).round() as i64
    );
    assert_eq!(
        report["nodes"]["2"]["position"],
        (held[1] * COUNTS).round() as i64
    );
}

#[test]
fn csv_axes_follow_a_program_against_the_python_canopen_peer() {
    // The peer moves by exactly target velocity × period per SYNC: the position loop is
    // klar's alone, and with the feed-forward exact it holds the path to a count.
    let (peer, bus, report_path) = start_peer(&["--max-step", "100"]);
    let mut cfg = config();
    for d in &mut cfg.drives {
        d.mode = klar_drivers::cia402::AxisMode::Csv;
        d.homing = None;
    }
    let mut backend = Cia402Backend::with_bus(&cfg, PERIOD, Box::new(bus)).expect("master starts");
    backend.enable().expect("drives enable");
    let mut fb = vec![AxisFeedback::default(); 2];
    let start = Instant::now();
    let mut t = 0.0;
    // From where the drives stand (0, 0) to the program's start, then the program.
    let mut points = vec![[0.0, 0.0]];
    points.extend(program());
    let path = samples(&points, 20.0);
    let held = *path.last().expect("samples");
    let mut worst: f64 = 0.0;
    for p in path.iter().chain(std::iter::repeat_n(&held, 20)) {
        t += PERIOD;
        let due = start + Duration::from_secs_f64(t);
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let sps = p.map(|x| Setpoint {
            position: x,
            ..Default::default()
        });
        backend.cycle(t, &sps, &mut fb).expect("cycle");
        for f in &fb {
            assert_eq!(f.state, AxisState::Enabled, "{:?}", backend.stop_report());
            worst = worst.max(f.following_error.abs());
        }
    }
    // Each cycle the peer rounds to a whole count (carrying the fraction): within a count.
    assert!(
        worst <= 1.0 / COUNTS + 1e-12,
        "worst following error {worst}"
    );
    backend.disable().expect("disables");
    backend
        .with_master(|m| m.nmt(NmtCommand::Stop, 0))
        .expect("NMT stop");
    let (code, report) = finish_peer(peer, &report_path);
    assert_eq!(report["violations"], serde_json::json!([]));
    assert_eq!(code, Some(0), "peer exit code");
    for (node, end) in [("1", held[0]), ("2", held[1])] {
        let n = &report["nodes"][node];
        assert_eq!(
            n["pdos"]["rpdo1"]["entries"],
            serde_json::json!([0x6040_0010u32, 0x60FF_0020u32])
        );
        assert_eq!(
            n["pdos"]["tpdo1"]["entries"],
            serde_json::json!([0x6041_0010u32, 0x6064_0020u32])
        );
        assert!(n["csv_syncs"].as_u64().expect("csv syncs") >= path.len() as u64);
        let position = n["position"].as_i64().expect("position");
        assert!(
            (position - (end * COUNTS).round() as i64).abs() <= 1,
            "node {node} ended at {position}"
        );
    }
}
