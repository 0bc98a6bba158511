//! The independent Delta VFD of ../shared/peers (`delta_vfd_server.py`, pymodbus RTU) behind
//! the peers' null modem (`serial_relay.py`, whose link can be cut or garbled), and `klar
//! run` against them: a machine TOML with the Modbus spindle on the relay's far end, the
//! server's and the relay's control files for injecting faults, the server's JSON log to
//! check what reached the device. Every child process is killed on drop.

#![allow(dead_code)]

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// Longest wait for anything in these tests.
pub const WAIT: Duration = Duration::from_secs(30);

/// The Delta map's command register and words (from the Delta communication chapter).
pub const COMMAND: u64 = 0x2000;
/// Frequency command register, 0.01 Hz.
pub const FREQUENCY: u64 = 0x2001;
/// Command word: stop.
pub const STOP: u64 = 0x01;
/// Command word: run forward.
pub const RUN_FORWARD: u64 = 0x12;
/// Command word: run reverse.
pub const RUN_REVERSE: u64 = 0x22;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn peers() -> PathBuf {
    repo().join("../shared/peers")
}

/// A child killed (and reaped) on drop.
struct Guarded(Child);

impl Drop for Guarded {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// What one `klar run` did.
#[derive(Debug)]
pub struct KlarRun {
    /// The exit status.
    pub status: ExitStatus,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
}

impl KlarRun {
    /// The last non-empty line of standard error.
    pub fn last_error_line(&self) -> &str {
        self.stderr
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("")
    }
}

/// A running `klar run`, killed on drop.
pub struct Klar {
    child: Guarded,
    started: Instant,
}

impl Klar {
    /// Sends `signal` (e.g. "INT") to klar.
    pub fn signal(&self, signal: &str) {
        let ok = Command::new("kill")
            .arg(format!("-{signal}"))
            .arg(self.child.0.id().to_string())
            .status()
            .is_ok_and(|s| s.success());
        assert!(ok, "kill -{signal} klar");
    }

    /// Waits (bounded) for klar to end and collects its output.
    pub fn wait(mut self) -> KlarRun {
        loop {
            match self.child.0.try_wait() {
                Ok(Some(_)) => break,
                Ok(None) if self.started.elapsed() > WAIT => {
                    panic!("klar did not end within {WAIT:?}")
                }
                Ok(None) => std::thread::sleep(Duration::from_millis(20)),
                Err(e) => panic!("waiting for klar: {e}"),
            }
        }
        let child = &mut self.child.0;
        let mut stdout = String::new();
        let mut stderr = String::new();
        use std::io::Read as _;
        if let Some(o) = child.stdout.as_mut() {
            let _ = o.read_to_string(&mut stdout);
        }
        if let Some(e) = child.stderr.as_mut() {
            let _ = e.read_to_string(&mut stderr);
        }
        let status = child.wait().expect("klar's exit status");
        KlarRun {
            status,
            stdout,
            stderr,
        }
    }
}

/// The VFD server behind the relay, in a directory of its own.
pub struct VfdPeer {
    dir: PathBuf,
    /// The port klar opens (the relay's near end).
    pub port: String,
    log: PathBuf,
    relay_log: PathBuf,
    vfd_control: PathBuf,
    relay_control: PathBuf,
    // Dropped in this order: the server first, then the relay.
    server: Guarded,
    relay: Guarded,
}

impl Drop for VfdPeer {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn wait_for(what: &str, mut done: impl FnMut() -> bool) {
    let deadline = Instant::now() + WAIT;
    while !done() {
        assert!(Instant::now() < deadline, "{what} within {WAIT:?}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

impl VfdPeer {
    /// Starts the relay and the VFD server (unit 1, 115200 8N1, ramp `accel` Hz/s) on its
    /// far end; `name` keeps the files of parallel tests apart.
    pub fn start(name: &str, accel: f64) -> Self {
        let python = repo().join(".venv/bin/python");
        assert!(
            python.exists(),
            "{} is missing: run scripts/setup-peers.sh first",
            python.display()
        );
        let dir = std::env::temp_dir().join(format!("klar-vfd-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("peer directory");
        let near = dir.join("klar.tty");
        let far = dir.join("vfd.tty");
        let log = dir.join("vfd.jsonl");
        let relay_log = dir.join("relay.log");
        let vfd_control = dir.join("vfd.ctl");
        let relay_control = dir.join("relay.ctl");
        let relay = Guarded(
            Command::new(&python)
                .arg(peers().join("serial_relay.py"))
                .arg(&near)
                .arg(&far)
                .arg("--control")
                .arg(&relay_control)
                .arg("--log")
                .arg(&relay_log)
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("start serial_relay.py"),
        );
        wait_for("the relay's ports", || near.exists() && far.exists());
        let server = Guarded(
            Command::new(&python)
                .arg(peers().join("delta_vfd_server.py"))
                .arg(&far)
                .args(["--unit", "1", "--baud", "115200", "--parity", "N"])
                .args(["--accel", &accel.to_string()])
                .arg("--log")
                .arg(&log)
                .arg("--control")
                .arg(&vfd_control)
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("start delta_vfd_server.py"),
        );
        let peer = VfdPeer {
            port: near.to_str().expect("UTF-8 path").to_string(),
            dir,
            log,
            relay_log,
            vfd_control,
            relay_control,
            server,
            relay,
        };
        wait_for("the VFD server's start", || {
            peer.log().iter().any(|e| e["ev"] == "start")
        });
        // pymodbus opens the port after logging its start: give it a moment.
        std::thread::sleep(Duration::from_millis(300));
        peer
    }

    /// A directory for the test's own files (removed with the peer).
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The server's log so far, one JSON object per request or event.
    pub fn log(&self) -> Vec<Value> {
        std::fs::read_to_string(&self.log)
            .unwrap_or_default()
            .lines()
            .filter_map(|l| serde_json::from_str(l).ok())
            .collect()
    }

    /// The relay's log so far (one line per chunk or control command).
    pub fn relay_log(&self) -> String {
        std::fs::read_to_string(&self.relay_log).unwrap_or_default()
    }

    /// Appends a line to the VFD server's control file (`exception 4 1`, `fault 7`).
    pub fn vfd_control(&self, line: &str) {
        append(&self.vfd_control, line);
    }

    /// Appends a line to the relay's control file (`cut`, `restore`, `garble 3`).
    pub fn relay_control(&self, line: &str) {
        append(&self.relay_control, line);
    }

    /// Waits until the server's log has an entry `pred` accepts; returns its index.
    pub fn wait_log(&self, what: &str, pred: impl Fn(&Value) -> bool) -> usize {
        let mut found = None;
        wait_for(what, || {
            found = self.log().iter().position(&pred);
            found.is_some()
        });
        found.unwrap_or_default()
    }

    /// Ends the server (SIGTERM: it logs its final state) and returns that `exit` entry.
    pub fn stop_server(&mut self) -> Value {
        let _ = Command::new("kill")
            .arg("-TERM")
            .arg(self.server.0.id().to_string())
            .status();
        let deadline = Instant::now() + WAIT;
        while self.server.0.try_wait().ok().flatten().is_none() {
            assert!(Instant::now() < deadline, "the VFD server ends");
            std::thread::sleep(Duration::from_millis(20));
        }
        self.log()
            .into_iter()
            .rev()
            .find(|e| e["ev"] == "exit")
            .expect("the server logs its exit")
    }

    /// A machine TOML: one simulated X axis and the Modbus spindle on the relay's port
    /// ([`VfdPeer::spindle_table`]).
    pub fn machine(&self, parity: &str) -> PathBuf {
        let toml = format!(
            r#"name = "mill with the peers' Delta VFD"
servo_period = 0.001
tolerance = 0.01
start_homed = true
max_setpoint_lateness = 0.5
[[axis]]
letter = "X"
kind = "linear"
travel = [-100.0, 100.0]
max_velocity = 100.0
max_acceleration = 1000.0
max_jerk = 20000.0
{}"#,
            self.spindle_table(parity)
        );
        let path = self.dir.join(format!("machine-{parity}.toml"));
        std::fs::write(&path, toml).expect("write the machine TOML");
        path
    }

    /// The machine file's `[spindle]` table for the VFD on the relay's port (`parity` as
    /// given, 100 ms timeout, 2 retries).
    pub fn spindle_table(&self, parity: &str) -> String {
        let port = &self.port;
        format!(
            r#"
[spindle]
max_rpm = 12000.0
at_speed_timeout = 5.0
[spindle.backend]
kind = "modbus"
[spindle.backend.vfd]
unit = 1
max_rpm = 24000.0
poll_period = 0.05
[spindle.backend.vfd.serial]
port = "{port}"
baud = 115200
parity = "{parity}"
timeout = 0.1
retries = 2
[spindle.backend.vfd.profile]
preset = "delta"
rpm_per_hz = 60.0
"#
        )
    }

    /// Writes `text` as a program in the peer's directory.
    pub fn program(&self, name: &str, text: &str) -> PathBuf {
        let path = self.dir.join(name);
        std::fs::write(&path, text).expect("write the program");
        path
    }

    /// Starts `klar run PROGRAM --machine MACHINE --realtime`.
    pub fn klar(&self, program: &Path, machine: &Path) -> Klar {
        let child = Command::new(env!("CARGO_BIN_EXE_klar"))
            .arg("run")
            .arg(program)
            .arg("--machine")
            .arg(machine)
            .arg("--realtime")
            .arg("--quiet")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start klar");
        Klar {
            child: Guarded(child),
            started: Instant::now(),
        }
    }
}

fn append(path: &Path, line: &str) {
    use std::io::Write as _;
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .expect("open the control file");
    writeln!(f, "{line}").expect("write the control file");
}

/// The command-register writes (function 6 or 16 at 0x2000) of a log: (index, word).
pub fn command_writes(log: &[Value]) -> Vec<(usize, u64)> {
    log.iter()
        .enumerate()
        .filter(|(_, e)| e.get("exc").is_none() && e["addr"].as_u64() == Some(COMMAND))
        .filter_map(|(i, e)| {
            let v = e["values"].as_array()?.first()?.as_u64()?;
            Some((i, v))
        })
        .collect()
}

/// True for an answered read whose reply covers the output frequency (0x2103) with `pred`
/// true of it (0.01 Hz).
pub fn output_frequency_is(e: &Value, pred: impl Fn(u64) -> bool) -> bool {
    let (Some(addr), Some(reply)) = (e["addr"].as_u64(), e["reply"].as_array()) else {
        return false;
    };
    let out = 0x2103u64;
    if addr > out {
        return false;
    }
    let k = usize::try_from(out - addr).unwrap_or(usize::MAX);
    reply.get(k).and_then(Value::as_u64).is_some_and(pred)
}
