//! The independent CANopen peers beside the repository (`../shared/peers`): one emulated CAN
//! bus (`slcan_hub.py`) with one slcan port for klar and one per drive, and a CiA 402 drive
//! emulator (`cia402_drive.py`) per node with a JSON-lines log and a control file for fault
//! injection. A test writes a machine file pointing klar at the hub, runs `klar run`, injects
//! faults when the drive logs show what it waits for, and reads the drives' logs. Every wait
//! is bounded; every child process is killed when the [`CanPeers`] is dropped.

use super::vfd_peer::VfdPeer;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The independent peers' folder beside the repository.
pub fn peers_dir() -> PathBuf {
    repo().join("../shared/peers")
}

/// The Python of the project's venv (scripts/setup-peers.sh).
pub fn python() -> PathBuf {
    let p = repo().join(".venv/bin/python");
    assert!(
        p.exists(),
        "{} missing: run scripts/setup-peers.sh first",
        p.display()
    );
    p
}

/// A fresh, empty folder for one test's ports, logs and files.
pub fn temp_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicU32 = AtomicU32::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("klar-peers-{}-{name}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A child process killed (and reaped) on drop.
pub struct Proc(pub Child);

impl Drop for Proc {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// One emulated drive.
pub struct Drive {
    /// Its node ID.
    pub node: u8,
    /// Its JSON-lines log.
    pub log: PathBuf,
    /// Its control file.
    pub control: PathBuf,
    proc: Proc,
}

/// An emulated CAN bus with drives on it and a port for klar.
pub struct CanPeers {
    /// The test's folder.
    pub dir: PathBuf,
    /// The slcan port klar opens.
    pub port: PathBuf,
    /// The drives, in the order given.
    pub drives: Vec<Drive>,
    /// A spindle VFD and its line, when the test started one.
    vfd: Option<VfdPeer>,
    _hub: Proc,
}

/// Bitrate of the emulated bus.
pub const BITRATE: u32 = 1_000_000;

impl CanPeers {
    /// Starts the hub and one drive per node (`args` are extra drive options for all of
    /// them), and waits until every drive is on the bus.
    pub fn start(name: &str, nodes: &[u8], args: &[&str]) -> Self {
        let pairs: Vec<(u8, u8)> = nodes.iter().map(|&n| (n, n)).collect();
        Self::start_with_ids(name, &pairs, args)
    }

    /// Starts the hub with one drive port per `(port, node ID)` pair (the ID differs from
    /// the port's number for a drive set to the wrong node ID), and waits until every drive
    /// is on the bus.
    pub fn start_with_ids(name: &str, drives: &[(u8, u8)], args: &[&str]) -> Self {
        let dir = temp_dir(name);
        let port = dir.join("can_klar");
        let mut hub = Command::new(python());
        hub.arg(peers_dir().join("slcan_hub.py"))
            .arg("--port")
            .arg(format!("klar={}", port.display()))
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        for &(n, _) in drives {
            hub.arg("--port")
                .arg(format!("n{n}={}", dir.join(format!("can_n{n}")).display()));
        }
        let hub = Proc(hub.spawn().expect("slcan_hub.py starts"));
        let all_ports = || {
            port.exists()
                && drives
                    .iter()
                    .all(|(n, _)| dir.join(format!("can_n{n}")).exists())
        };
        assert!(
            wait_for(Duration::from_secs(10), all_ports),
            "slcan_hub.py made no ports"
        );
        let drives: Vec<Drive> = drives
            .iter()
            .map(|&(p, id)| Self::spawn_drive(&dir, p, id, args))
            .collect();
        for d in &drives {
            let up = wait_for(Duration::from_secs(15), || {
                read_log(&d.log).iter().any(|e| e["ev"] == "bootup")
            });
            assert!(up, "drive on port n{} did not boot", d.node);
        }
        Self {
            dir,
            port,
            drives,
            vfd: None,
            _hub: hub,
        }
    }

    fn spawn_drive(dir: &Path, port_node: u8, node: u8, args: &[&str]) -> Drive {
        let log = dir.join(format!("drive{port_node}.jsonl"));
        let control = dir.join(format!("drive{port_node}.ctl"));
        std::fs::write(&control, "").expect("control file");
        let child = Command::new(python())
            .arg(peers_dir().join("cia402_drive.py"))
            .args(["--iface", "slcan", "--channel"])
            .arg(dir.join(format!("can_n{port_node}")))
            .args(["--bitrate", &BITRATE.to_string()])
            .args(["--node-id", &node.to_string()])
            .arg("--log")
            .arg(&log)
            .arg("--control")
            .arg(&control)
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("cia402_drive.py starts");
        Drive {
            node: port_node,
            log,
            control,
            proc: Proc(child),
        }
    }

    /// Starts a Delta-map spindle VFD behind a null modem ([`VfdPeer`], unit 1, no parity:
    /// a pseudo-terminal refuses a parity setting); returns the machine file's `[spindle]`
    /// table for it. Its JSON-lines log is [`CanPeers::vfd_log`].
    pub fn start_vfd(&mut self) -> String {
        let name = self
            .dir
            .file_name()
            .map_or_else(|| "can".to_string(), |n| n.to_string_lossy().into_owned());
        let vfd = VfdPeer::start(&name, 2000.0);
        let table = vfd.spindle_table("none");
        self.vfd = Some(vfd);
        table
    }

    /// The VFD's log records so far (none without [`CanPeers::start_vfd`]).
    pub fn vfd_log(&self) -> Vec<serde_json::Value> {
        self.vfd.as_ref().map(VfdPeer::log).unwrap_or_default()
    }

    /// The drive on the port of `node`.
    pub fn drive(&self, node: u8) -> &Drive {
        self.drives
            .iter()
            .find(|d| d.node == node)
            .expect("no such drive")
    }

    /// The log records of `node`'s drive so far.
    pub fn log(&self, node: u8) -> Vec<serde_json::Value> {
        read_log(&self.drive(node).log)
    }

    /// Appends a command to `node`'s control file (the drive runs it within 0.1 s).
    pub fn control(&self, node: u8, command: &str) {
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(&self.drive(node).control)
            .expect("control file");
        writeln!(f, "{command}").expect("control write");
    }

    /// Waits up to `timeout` until `node`'s log has a record for which `pred` holds.
    pub fn wait_log(
        &self,
        node: u8,
        timeout: Duration,
        pred: impl Fn(&serde_json::Value) -> bool,
    ) -> bool {
        wait_for(timeout, || self.log(node).iter().any(&pred))
    }

    /// True while `node`'s drive process runs.
    pub fn alive(&mut self, node: u8) -> bool {
        let d = self
            .drives
            .iter_mut()
            .find(|d| d.node == node)
            .expect("no such drive");
        matches!(d.proc.0.try_wait(), Ok(None))
    }

    /// Writes a file into the test's folder and returns its path.
    pub fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.dir.join(name);
        std::fs::write(&p, text).expect("write file");
        p
    }
}

/// Reads a JSON-lines log (incomplete last lines are skipped).
pub fn read_log(path: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect()
}

/// Polls `cond` every 20 ms for up to `timeout`.
pub fn wait_for(timeout: Duration, mut cond: impl FnMut() -> bool) -> bool {
    let deadline = Instant::now() + timeout;
    loop {
        if cond() {
            return true;
        }
        if Instant::now() >= deadline {
            return false;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// `klar run PROGRAM --machine MACHINE` started in the background.
pub fn spawn_klar(program: &Path, machine: &Path) -> Proc {
    let child = Command::new(env!("CARGO_BIN_EXE_klar"))
        .arg("run")
        .arg(program)
        .arg("--machine")
        .arg(machine)
        .env("RUST_LOG", "warn")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("klar starts");
    Proc(child)
}

/// Waits up to `timeout` for a spawned klar to end and returns its output (None: still
/// running at the timeout; it is killed).
pub fn finish_klar(mut klar: Proc, timeout: Duration) -> Option<Output> {
    let ended = wait_for(timeout, || matches!(klar.0.try_wait(), Ok(Some(_))));
    if !ended {
        return None;
    }
    let Proc(child) = &mut klar;
    let stdout = child.stdout.take();
    let stderr = child.stderr.take();
    let status = child.wait().ok()?;
    let read = |r: Option<Box<dyn std::io::Read>>| {
        let mut v = Vec::new();
        if let Some(mut r) = r {
            let _ = r.read_to_end(&mut v);
        }
        v
    };
    Some(Output {
        status,
        stdout: read(stdout.map(|s| Box::new(s) as Box<dyn std::io::Read>)),
        stderr: read(stderr.map(|s| Box::new(s) as Box<dyn std::io::Read>)),
    })
}

/// Runs klar to its end (at most `timeout`).
pub fn run_klar(program: &Path, machine: &Path, timeout: Duration) -> Output {
    finish_klar(spawn_klar(program, machine), timeout).expect("klar run did not end in time")
}

/// One axis of a machine file on the peers' bus.
pub struct PeerAxis {
    /// Axis letter.
    pub letter: char,
    /// Node ID in the machine file.
    pub node: u8,
    /// `start` in the machine file.
    pub start: f64,
}

/// Encoder counts per mm of the drives in the machine files written here (1 count = 1 µm).
pub const COUNTS_PER_MM: f64 = 1000.0;

/// A machine file for `axes` on the peers' bus; `bus_extra` adds keys to the bus table.
pub fn machine_toml(port: &Path, axes: &[PeerAxis], bus_extra: &str) -> String {
    let mut s = format!(
        r#"name = "peers"
servo_period = 0.008
max_setpoint_lateness = 0.3
tolerance = 0.01
start_homed = true

[canopen.main]
bus = {{ adapter = "slcan", port = "{}", bitrate = {BITRATE} }}
heartbeat_ms = 50
heartbeat_timeout_ms = 500
sdo_timeout_ms = 1000
boot_timeout_ms = 3000
pdo_wait_ms = 50.0
state_timeout_ms = 3000
{bus_extra}
"#,
        port.display()
    );
    for a in axes {
        s.push_str(&format!(
            r#"
[[axis]]
letter = "{}"
kind = "linear"
travel = [-300.0, 300.0]
start = {}
max_velocity = 50.0
max_acceleration = 500.0
max_jerk = 10000.0
backend = {{ kind = "canopen", bus = "main", drive = {{ node = {}, counts_per_unit = {COUNTS_PER_MM} }} }}
"#,
            a.letter, a.start, a.node
        ));
    }
    s
}
