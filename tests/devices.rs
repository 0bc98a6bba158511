//! End-to-end: programs through the real driver stacks against simulated devices and an
//! independent peer — CANopen CiA 402 drives (in-memory bus and slcan on a pseudo-terminal),
//! Modbus RTU drive and VFD, step/dir, and a pymodbus VFD.

mod common;

use common::{distance_to_rectangle, program, run, temp_program};
use klar::config::MachineConfig;
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

fn machine(name: &str) -> MachineConfig {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("machines")
        .join(name);
    MachineConfig::load(&p).unwrap_or_else(|e| panic!("{e}"))
}

/// The rectangle on drives: the commanded path lies on the contour, the drives follow within
/// `fe_bound`, and the run ends where the program ends.
fn check_rectangle_run(machine: &MachineConfig, fe_bound: f64) -> common::Trace {
    let (result, trace) = run(&program("rectangle.h"), machine);
    let report = result.unwrap_or_else(|f| panic!("{}", f.error));
    assert_eq!(report.blocks, 19);
    let (x, y, z) = (
        trace.column("X").unwrap(),
        trace.column("Y").unwrap(),
        trace.column("Z").unwrap(),
    );
    let (xa, ya) = (
        trace.column("X_act").unwrap(),
        trace.column("Y_act").unwrap(),
    );
    for i in 0..x.len() {
        if z[i] == -5.0 {
            // The planner may blend corners, never beyond the machine's path tolerance.
            assert!(distance_to_rectangle([x[i], y[i]]) <= machine.tolerance + 1e-9);
            assert!(
                distance_to_rectangle([xa[i], ya[i]]) < fe_bound,
                "row {i}: the drives left the contour"
            );
        }
    }
    let n = x.len() - 1;
    assert_eq!((x[n], y[n], z[n]), (-10.0, 10.0, 50.0));
    for (l, fe) in &report.max_following_error {
        assert!(*fe < fe_bound, "axis {l}: following error {fe}");
    }
    // S3000 from standstill: the spindle drive ramps before the first feed move.
    assert!(report.spindle_wait > 0.0);
    trace
}

#[test]
fn a_program_runs_on_cia402_drives_over_the_in_memory_bus_and_over_slcan() {
    let memory = check_rectangle_run(&machine("canopen-sim.toml"), 0.5);
    let slcan = check_rectangle_run(&machine("canopen-slcan-sim.toml"), 0.5);
    // The transport must not change the path: the commanded columns are identical. The
    // simulated drives report the same positions, except that the slcan line runs over a
    // pseudo-terminal in real time: on a loaded machine a PDO can miss the master's wait and
    // the cycle works with the previous feedback, so the actual positions may lag by a few
    // cycles of travel there (10 mm/s × 2 ms = 0.02 mm a cycle on the contour).
    for col in ["X", "Y", "Z"] {
        assert_eq!(memory.column(col), slcan.column(col), "commanded {col}");
        let (a, b) = (
            memory.column(&format!("{col}_act")).unwrap(),
            slcan.column(&format!("{col}_act")).unwrap(),
        );
        let worst = a
            .iter()
            .zip(&b)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        let differ = a
            .iter()
            .zip(&b)
            .filter(|(p, q)| (*p - *q).abs() > 1e-4)
            .count();
        eprintln!(
            "{col}: {differ} of {} rows differ, worst {worst:.5} mm",
            a.len()
        );
        assert!(
            worst <= 0.1,
            "{col}: memory and slcan runs differ by {worst}"
        );
    }
}

#[test]
fn auxiliary_modbus_and_step_dir_axes_position_and_the_vfd_reaches_speed() {
    let m = machine("modbus-sim.toml");
    assert!(m.needs_wall_clock());
    let (result, trace) = run(&program("aux_axes.h"), &m);
    let report = result.unwrap_or_else(|f| panic!("{}", f.error));
    assert!(report.realtime);
    // S6000 at the simulated VFD's 8000 rpm/s ramp takes 0.75 s; the Modbus poll adds latency,
    // and the wait is measured on the wall clock of a computer that may be busy with other
    // tests (seen up to 1.5 s under a load of 12 on two cores).
    assert!(
        (0.75..3.0).contains(&report.spindle_wait),
        "spindle wait {} s",
        report.spindle_wait
    );
    let c_act = trace.column("C_act").unwrap();
    let w = trace.column("W").unwrap();
    let w_act = trace.column("W_act").unwrap();
    // The quill (block 4) starts only after the table is in position at C+90 (block 3).
    let first_w = w.iter().position(|&v| v != 0.0).expect("W moves");
    assert!(
        (c_act[first_w] - 90.0).abs() <= 0.01,
        "C at {}",
        c_act[first_w]
    );
    // The stepper follows to the step: W actual is the commanded position rounded to 1/400 mm.
    for i in 0..w.len() {
        assert!((w[i] - w_act[i]).abs() <= 1.0 / 400.0 + 1e-9, "row {i}");
    }
    let n = w.len() - 1;
    assert!(c_act[n].abs() <= 0.01 && w_act[n] == 0.0);
}

#[test]
fn a_positioning_axis_in_a_contouring_block_is_refused() {
    let path = temp_program(
        "aux_contour.h",
        "0 BEGIN PGM A MM\n1 L X+10 C+45 F500\n2 END PGM A MM\n",
    );
    let (result, trace) = run(&path, &machine("modbus-sim.toml"));
    let failure = result.expect_err("C cannot contour");
    assert!(
        failure.error.to_string().contains("positioning axis"),
        "{}",
        failure.error
    );
    assert!(
        trace
            .column("X")
            .unwrap_or_default()
            .iter()
            .all(|&v| v == 0.0)
    );
}

/// The pymodbus VFD peer; killed on drop.
struct Peer {
    child: Child,
    events: Receiver<Value>,
    log: Vec<Value>,
}

impl Drop for Peer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

impl Peer {
    fn start() -> (Peer, String) {
        let python = repo().join(".venv/bin/python");
        assert!(python.exists(), "run scripts/setup-peers.sh first");
        let mut child = Command::new(python)
            .arg(repo().join("scripts/peers/modbus_vfd_peer.py"))
            .args([
                "--map",
                "delta",
                "--unit",
                "1",
                "--accel",
                "20000",
                "--max-seconds",
                "60",
            ])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start the pymodbus peer");
        let stdout = child.stdout.take().expect("stdout");
        let (tx, events) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if let Ok(v) = serde_json::from_str::<Value>(&line)
                    && tx.send(v).is_err()
                {
                    break;
                }
            }
        });
        let peer = Peer {
            child,
            events,
            log: Vec::new(),
        };
        let deadline = Instant::now() + Duration::from_secs(20);
        let port = loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let e = peer.events.recv_timeout(left).expect("peer ready in time");
            if e["event"] == "ready" {
                break e["port"].as_str().expect("port").to_string();
            }
        };
        (peer, port)
    }

    fn writes(&mut self) -> Vec<(u64, u64)> {
        while let Ok(e) = self.events.try_recv() {
            self.log.push(e);
        }
        self.log
            .iter()
            .filter(|e| e["event"] == "write")
            .flat_map(|e| {
                let a = e["address"].as_u64().unwrap_or(u64::MAX);
                let values = e["values"].as_array().cloned().unwrap_or_default();
                values
                    .into_iter()
                    .enumerate()
                    .map(move |(k, v)| (a + k as u64, v.as_u64().unwrap_or(u64::MAX)))
            })
            .collect()
    }
}

#[test]
fn spindle_commands_of_a_program_reach_a_pymodbus_vfd() {
    let (mut peer, port) = Peer::start();
    let toml = format!(
        r#"
name = "mill with a pymodbus VFD"
servo_period = 0.001
tolerance = 0.01
start_homed = true
[[axis]]
letter = "X"
kind = "linear"
travel = [-100.0, 100.0]
max_velocity = 100.0
max_acceleration = 1000.0
max_jerk = 20000.0
[spindle]
max_rpm = 12000.0
[spindle.backend]
kind = "modbus"
[spindle.backend.vfd]
unit = 1
max_rpm = 24000.0
[spindle.backend.vfd.serial]
port = "{port}"
baud = 115200
parity = "none"
[spindle.backend.vfd.profile]
preset = "delta"
rpm_per_hz = 60.0
"#
    );
    let m = MachineConfig::parse("peer.toml", &toml).unwrap();
    let path = temp_program(
        "peer_spindle.h",
        "0 BEGIN PGM P MM\n1 TOOL CALL 1 Z S6000\n2 L X+10 F3000 M3\n\
         3 L X+0 M5\n4 L X+5 M4\n5 L X+0 M5\n6 END PGM P MM\n",
    );
    let (result, _) = run(&path, &m);
    result.unwrap_or_else(|f| panic!("{}", f.error));
    // 6000 rpm at 60 rpm/Hz = 100.00 Hz = 10000 in the Delta map's 0.01 Hz units; 0x12 runs
    // forward, 0x22 reverse, 0x01 stops (the Delta communication map). The M4 waits until
    // the VFD has stopped after the M5, so the stop reaches the VFD between the two
    // directions; the final M5 must arrive.
    let w = peer.writes();
    let pos = |pair: (u64, u64), from: usize| {
        w[from..]
            .iter()
            .position(|&x| x == pair)
            .map(|p| p + from)
            .unwrap_or_else(|| panic!("write {pair:x?} missing after {from} in {w:x?}"))
    };
    let speed = pos((0x2001, 10_000), 0);
    let fwd = pos((0x2000, 0x12), speed);
    let between = pos((0x2000, 0x01), fwd);
    let rev = pos((0x2000, 0x22), between);
    let stop = pos((0x2000, 0x01), rev);
    assert_eq!(stop, w.len() - 1, "the last write stops the VFD: {w:x?}");
}
