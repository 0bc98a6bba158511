//! klar against CiA 402 drives it was not written together with: the independent drive
//! emulator and slcan hub in `../shared/peers` (python-canopen behind emulated slcan
//! adapters, one process per drive). A program completes with the drives tracking; faults
//! (drive fault, heartbeat silence, a node going offline, a drive power-cycled), a missing
//! node, a wrong node ID and a silent adapter end in a controlled stop naming the node and the
//! axis; runs start where the drives stand, not at the machine file's `start`; the drives
//! are switched off only once they stand at the program's end point.
//!
//! The cases run one after the other (each starts four Python processes; in parallel they
//! would compete for the CPU with the servo loop they test).

mod common;

use common::peers::*;
use serde_json::Value;
use serialport::SerialPort as _;
use std::path::PathBuf;
use std::process::Command;
use std::sync::Mutex;
use std::time::Duration;

/// One case at a time.
static SERIAL: Mutex<()> = Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|p| p.into_inner())
}

/// Longest a klar run may take here.
const RUN_TIMEOUT: Duration = Duration::from_secs(40);

/// In-position window at the program's end (the default), counts.
const WINDOW_COUNTS: f64 = 0.01 * COUNTS_PER_MM;

fn xyz(peers: &CanPeers, z_start: f64) -> PathBuf {
    let axes = [
        PeerAxis {
            letter: 'X',
            node: 1,
            start: 0.0,
        },
        PeerAxis {
            letter: 'Y',
            node: 2,
            start: 0.0,
        },
        PeerAxis {
            letter: 'Z',
            node: 3,
            start: z_start,
        },
    ];
    peers.write("machine.toml", &machine_toml(&peers.port, &axes, ""))
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The drive's receive PDOs while enabled: (target counts, actual counts when it came).
fn rpdos(log: &[Value]) -> Vec<(i64, i64)> {
    log.iter()
        .filter(|e| {
            e["ev"] == "rpdo"
                && e["state"] == "OPERATION ENABLED"
                && e["values"]["0x6040:00"]
                    .as_i64()
                    .is_some_and(|cw| cw & 0x0F == 0x0F)
        })
        .filter_map(|e| {
            let target = e["values"]["0x607A:00"].as_i64()?;
            Some((target, e["actual"].as_i64()?))
        })
        .collect()
}

/// EMCY codes the drive sent (errors only, not the reset).
fn emcys(log: &[Value]) -> Vec<String> {
    log.iter()
        .filter(|e| e["ev"] == "emcy" && e["code"] != "0x0000")
        .filter_map(|e| e["code"].as_str().map(str::to_string))
        .collect()
}

/// The drive's state changes as (from, to, actual counts).
fn states(log: &[Value]) -> Vec<(String, String, i64)> {
    log.iter()
        .filter(|e| e["ev"] == "state")
        .map(|e| {
            (
                e["frm"].as_str().unwrap_or_default().to_string(),
                e["to"].as_str().unwrap_or_default().to_string(),
                e["actual"].as_i64().unwrap_or(i64::MIN),
            )
        })
        .collect()
}

/// The actual position (counts) at which the drive left OPERATION ENABLED the last time.
fn disabled_at(log: &[Value]) -> Option<i64> {
    states(log)
        .into_iter()
        .rev()
        .find(|(from, _, _)| from == "OPERATION ENABLED")
        .map(|(_, _, x)| x)
}

/// The largest difference between a target the drive took and where it stood one cycle
/// later (in CSP a target is reached over one interpolation period), counts.
fn tracking_error(log: &[Value]) -> i64 {
    rpdos(log)
        .windows(2)
        .map(|w| (w[0].0 - w[1].1).abs())
        .max()
        .unwrap_or(i64::MAX)
}

const TRACK: &str = "0 BEGIN PGM TRACK MM
1 L X+4.95 Y+2 Z+1 F600
2 L X+1 Y+3 Z+0.5
3 END PGM TRACK MM
";

#[test]
fn a_program_completes_with_the_drives_tracking_and_ends_in_position() {
    let _one = serial();
    // Drives tuned with velocity feed-forward (their lag does not grow with speed).
    let peers = CanPeers::start("track", &[1, 2, 3], &["--kff", "1.0"]);
    let machine = xyz(&peers, 0.0);
    let program = peers.write("track.h", TRACK);
    let out = run_klar(&program, &machine, RUN_TIMEOUT);
    assert!(
        out.status.success(),
        "{}\n{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    for (node, end) in [(1u8, 1000i64), (2, 3000), (3, 500)] {
        let log = peers.log(node);
        assert!(emcys(&log).is_empty(), "node {node}: {:?}", emcys(&log));
        assert!(rpdos(&log).len() > 20, "node {node}: too few setpoints");
        let e = tracking_error(&log);
        assert!(e <= 100, "node {node}: tracking error {e} counts > 0.1 mm");
        // Switched off only at the end point, within the in-position window.
        let at = disabled_at(&log).expect("the drive was disabled");
        eprintln!("node {node}: tracking error {e} counts, disabled at {at} (end point {end})");
        assert!(
            ((at - end) as f64).abs() <= WINDOW_COUNTS,
            "node {node}: disabled at {at}, end point {end}"
        );
        let last_target = rpdos(&log).last().map(|r| r.0);
        assert_eq!(last_target, Some(end), "node {node}: last target");
    }
}

#[test]
fn a_second_run_starts_where_the_drives_stand() {
    let _one = serial();
    let peers = CanPeers::start("second", &[1, 2, 3], &[]);
    let machine = xyz(&peers, 0.0);
    let first = peers.write(
        "first.h",
        "0 BEGIN PGM A MM\n1 L X+4.95 F600\n2 END PGM A MM\n",
    );
    let out = run_klar(&first, &machine, RUN_TIMEOUT);
    assert!(out.status.success(), "first run: {}", text(&out.stderr));
    let before = rpdos(&peers.log(1)).len();
    // The drives stay powered (their processes run on) at X = 4.95 mm.
    let second = peers.write(
        "second.h",
        "0 BEGIN PGM B MM\n1 L X+5 F600\n2 L X+4 F600\n3 END PGM B MM\n",
    );
    // The check says where the drives stand, read without enabling any.
    let enabled = |log: &[Value]| {
        log.iter()
            .filter(|e| e["ev"] == "state" && e["to"] == "OPERATION ENABLED")
            .count()
    };
    let enabled_before = enabled(&peers.log(1));
    let check = Command::new(env!("CARGO_BIN_EXE_klar"))
        .arg("check")
        .arg(&second)
        .arg("--machine")
        .arg(&machine)
        .output()
        .expect("klar check runs");
    let checked = text(&check.stdout);
    assert!(
        check.status.success(),
        "check: {checked}\n{}",
        text(&check.stderr)
    );
    let stands: f64 = checked
        .lines()
        .find_map(|l| l.trim().strip_prefix("X stands at"))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|x| x.parse().ok())
        .expect("the check says where X stands");
    assert!(
        (stands - 4.95).abs() <= WINDOW_COUNTS / COUNTS_PER_MM,
        "the check says X stands at {stands}"
    );
    assert_eq!(
        enabled(&peers.log(1)),
        enabled_before,
        "the check enabled the drive"
    );
    let out = run_klar(&second, &machine, RUN_TIMEOUT);
    let stdout = text(&out.stdout);
    assert!(
        out.status.success(),
        "second run: {stdout}\n{}",
        text(&out.stderr)
    );
    let said: f64 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("start X:"))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|x| x.parse().ok())
        .expect("the run says where X stands");
    let log = peers.log(1);
    assert!(emcys(&log).is_empty(), "{:?}", emcys(&log));
    let second_run = &rpdos(&log)[before..];
    // The first setpoint of the second run is where the drive stands (within the
    // in-position window of the first run's end point), and the run said so.
    let (target, actual) = second_run[0];
    assert!(
        (target - actual).abs() <= 1 && (actual - 4950).abs() <= WINDOW_COUNTS as i64,
        "first setpoint {target} with the drive at {actual}"
    );
    assert!(
        (said * COUNTS_PER_MM - actual as f64).abs() <= 1.0,
        "start X {said} mm, the drive at {actual} counts"
    );
    assert_eq!(second_run.last().map(|r| r.0), Some(4000));
}

#[test]
fn a_start_with_z_far_from_the_machine_files_start() {
    let _one = serial();
    let peers = CanPeers::start("zfar", &[1, 2, 3], &[]);
    // The file says Z starts at 100 mm; the drive stands at 0.
    let machine = xyz(&peers, 100.0);
    let program = peers.write(
        "z.h",
        "0 BEGIN PGM Z MM\n1 L Z+2 F600\n2 L X+1 F600\n3 END PGM Z MM\n",
    );
    let out = run_klar(&program, &machine, RUN_TIMEOUT);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    assert!(stdout.contains("start Z:      0.0000 mm"), "{stdout}");
    let log = peers.log(3);
    assert!(emcys(&log).is_empty(), "{:?}", emcys(&log));
    let targets = rpdos(&log);
    // No setpoint ever left the drive's neighbourhood for the file's start.
    let far = targets.iter().map(|r| r.0.abs()).max().unwrap_or(0);
    assert!(far <= 2000, "a target {far} counts away");
    assert_eq!(targets.last().map(|r| r.0), Some(2000));
}

/// A long move, so that a fault injected once the drives move strikes mid-path.
const LONG: &str = "0 BEGIN PGM LONG MM
1 L X+30 Y+30 Z+10 F900
2 END PGM LONG MM
";

/// The long move with the spindle turning.
const LONG_SPINDLE: &str = "0 BEGIN PGM LONG MM
1 TOOL CALL 1 Z S3000
2 L X+30 Y+30 Z+10 F900 M3
3 END PGM LONG MM
";

/// Starts the program (with a Delta VFD spindle turning when `spindle`), waits until X
/// moves, injects `command` into `target`'s drive and returns klar's output and the peers.
fn fault_case(
    name: &str,
    target: u8,
    command: &str,
    spindle: bool,
) -> (std::process::Output, CanPeers) {
    let mut peers = CanPeers::start(name, &[1, 2, 3], &["--heartbeat", "50"]);
    let machine = xyz(&peers, 0.0);
    let program = if spindle {
        let table = peers.start_vfd();
        let text = std::fs::read_to_string(&machine).expect("machine file") + &table;
        std::fs::write(&machine, text).expect("machine file");
        peers.write("long.h", LONG_SPINDLE)
    } else {
        peers.write("long.h", LONG)
    };
    let klar = spawn_klar(&program, &machine);
    let moving = peers.wait_log(1, Duration::from_secs(20), |e| {
        e["ev"] == "rpdo"
            && e["state"] == "OPERATION ENABLED"
            && e["values"]["0x607A:00"].as_i64().unwrap_or(0) > 2000
    });
    if !moving {
        let out = finish_klar(klar, Duration::from_secs(1));
        let said = out.map(|o| text(&o.stderr)).unwrap_or_default();
        panic!("{name}: X never moved\n{said}");
    }
    peers.control(target, command);
    let out = finish_klar(klar, RUN_TIMEOUT).expect("klar ended after the fault");
    (out, peers)
}

/// The last line klar writes, the one that says why it stopped.
fn final_line(out: &std::process::Output) -> String {
    text(&out.stderr)
        .lines()
        .rev()
        .find(|l| l.starts_with("stopped:"))
        .unwrap_or_default()
        .to_string()
}

/// The spindle was running (a run command to the VFD, 0x2000 bits 0-1 = 10) and was
/// commanded to stop afterwards (bits 0-1 = 01).
fn assert_spindle_stopped(peers: &CanPeers) {
    let commands: Vec<i64> = peers
        .vfd_log()
        .iter()
        .filter(|e| e["addr"].as_i64() == Some(0x2000))
        .filter_map(|e| e["values"].get(0).and_then(Value::as_i64))
        .collect();
    let run = commands.iter().position(|c| c & 0x3 == 0x2);
    assert!(run.is_some(), "the spindle never ran: {commands:?}");
    let stopped = commands
        .iter()
        .skip(run.unwrap_or(0))
        .any(|c| c & 0x3 == 0x1);
    assert!(stopped, "the spindle was not stopped: {commands:?}");
}

/// The other drives were brought to rest under control: each left OPERATION ENABLED by a
/// quick stop or a disable, none tripped.
fn assert_others_stopped(peers: &CanPeers, faulted: u8) {
    for node in [1u8, 2, 3].into_iter().filter(|&n| n != faulted) {
        let log = peers.log(node);
        assert!(emcys(&log).is_empty(), "node {node}: {:?}", emcys(&log));
        let left = states(&log)
            .into_iter()
            .any(|(from, to, _)| from == "OPERATION ENABLED" && to != "FAULT REACTION ACTIVE");
        assert!(left, "node {node} was not stopped: {:?}", states(&log));
        let enabled_at_end = states(&log)
            .last()
            .is_some_and(|(_, to, _)| to == "OPERATION ENABLED");
        assert!(!enabled_at_end, "node {node} still enabled");
    }
}

/// A fault injected into `target` by `command` ends the run with a final line that holds
/// every one of `words`, every drive but `target` (all of them when `target` is 0) is brought
/// to a controlled stop, and with `spindle` the VFD is commanded to stop after it ran.
/// Returns the peers for further checks.
fn fault_named(
    name: &str,
    (target, command): (u8, &str),
    spindle: bool,
    words: &[&str],
    others_of: u8,
) -> CanPeers {
    let (out, peers) = fault_case(name, target, command, spindle);
    assert!(!out.status.success());
    let last = final_line(&out);
    assert!(
        words.iter().all(|w| last.contains(w)),
        "{last}\n{}",
        text(&out.stderr)
    );
    assert_others_stopped(&peers, others_of);
    if spindle {
        assert_spindle_stopped(&peers);
    }
    peers
}

#[test]
fn a_drive_fault_names_its_node_axis_and_code() {
    let _one = serial();
    let words = [
        "axis Y: drive fault 0x2310",
        "node 2",
        "continuous over-current",
    ];
    let peers = fault_named("fault", (2, "fault 0x2310"), true, &words, 2);
    assert_eq!(emcys(&peers.log(2)), vec!["0x2310".to_string()]);
}

#[test]
fn a_silent_heartbeat_names_its_node_and_axis() {
    let _one = serial();
    let words = ["axis X: communication lost", "node 1: heartbeat lost"];
    // The muted drive itself still listens: it is stopped with the others.
    fault_named("mute", (1, "mute"), false, &words, 0);
}

#[test]
fn a_node_going_offline_names_its_node_and_axis() {
    let _one = serial();
    let words = ["axis Z: communication lost", "node 3"];
    fault_named("offline", (3, "offline"), true, &words, 3);
}

#[test]
fn a_power_cycled_drive_names_its_node_and_axis() {
    let _one = serial();
    let words = ["axis Y: communication lost", "node 2"];
    fault_named("powercycle", (2, "power-cycle"), false, &words, 2);
}

/// Nothing was enabled: the drives never reached OPERATION ENABLED.
fn assert_nothing_enabled(peers: &CanPeers) {
    for d in &peers.drives {
        let log = peers.log(d.node);
        assert!(
            !states(&log)
                .iter()
                .any(|(_, to, _)| to == "OPERATION ENABLED"),
            "node {} was enabled",
            d.node
        );
    }
}

#[test]
fn an_absent_node_is_named_with_its_axis() {
    let _one = serial();
    let peers = CanPeers::start("absent", &[1, 2], &[]);
    let machine = xyz(&peers, 0.0);
    let program = peers.write("long.h", LONG);
    let out = run_klar(&program, &machine, RUN_TIMEOUT);
    assert!(!out.status.success());
    let last = final_line(&out);
    assert!(
        last.contains("no boot-up from node(s) [3]") && last.contains("node 3 is axis Z"),
        "{last}\n{}",
        text(&out.stderr)
    );
    assert_nothing_enabled(&peers);
}

#[test]
fn a_wrong_node_id_is_named_with_its_axis() {
    let _one = serial();
    // The third drive is set to node 4 while the machine file expects node 3.
    let peers = CanPeers::start_with_ids("wrongid", &[(1, 1), (2, 2), (3, 4)], &[]);
    let machine = xyz(&peers, 0.0);
    let program = peers.write("long.h", LONG);
    let out = run_klar(&program, &machine, RUN_TIMEOUT);
    assert!(!out.status.success());
    let last = final_line(&out);
    assert!(
        last.contains("no boot-up from node(s) [3]")
            && last.contains("node 3 is axis Z")
            && last.contains("boot-up from node(s) [4]"),
        "{last}\n{}",
        text(&out.stderr)
    );
    assert_nothing_enabled(&peers);
}

#[test]
fn a_silent_adapter_is_named() {
    let _one = serial();
    let peers = CanPeers::start("silent", &[1], &[]);
    // A pseudo-terminal nobody answers on, in place of the hub's port.
    let (_master, slave) = serialport::TTYPort::pair().expect("pty");
    let tty = slave.name().expect("pty name");
    let axes = [PeerAxis {
        letter: 'X',
        node: 1,
        start: 0.0,
    }];
    let machine = peers.write(
        "machine.toml",
        &machine_toml(std::path::Path::new(&tty), &axes, ""),
    );
    let program = peers.write("x.h", "0 BEGIN PGM X MM\n1 L X+1 F600\n2 END PGM X MM\n");
    let out = run_klar(&program, &machine, RUN_TIMEOUT);
    assert!(!out.status.success());
    let last = final_line(&out);
    assert!(
        last.contains("CANopen bus main") && last.contains(&tty),
        "{last}\n{}",
        text(&out.stderr)
    );
    assert_nothing_enabled(&peers);
}
