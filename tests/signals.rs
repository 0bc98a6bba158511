//! SIGINT and SIGTERM are controlled stops: `klar run` (with and without `--realtime`) and
//! `klar serve` run as real child processes, get signals while the axes move, and must bring
//! the axes to rest within their limits, end the trace with whole rows at rest, report where
//! the program was stopped and exit with 128 + the signal number (`klar serve`: 0).

mod common;

use common::{Trace, assert_within_limits};
use klar::config::MachineConfig;
use klar::monitor::braking_distance;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// From the mill's start (X0 Y0 Z100) down to Z50, then X+250 at F3000 (50 mm/s, 5 s),
/// then Y+250: the signal comes on the long line of block 2 (line 3).
const LONG_LINE: &str = "0 BEGIN PGM LONG MM\n\
                         1 L X+0 Y+0 Z+50 R0 FMAX\n\
                         2 L X+250 R0 F3000\n\
                         3 L Y+250\n\
                         4 END PGM LONG MM\n";

/// Feed of the long line, mm/s.
const FEED: f64 = 50.0;

/// A fresh temporary folder for one test.
fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("klar-signals-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Sends `signal` (TERM or INT) to the child with the `kill` command.
fn send(child: &Child, signal: &str) {
    let status = Command::new("kill")
        .args(["-s", signal, &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success(), "kill -s {signal} failed");
}

/// Waits for the child to exit (at most 30 s: a stop takes well under one).
fn wait_exit(child: &mut Child) -> ExitStatus {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("klar did not exit after the signal");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The last whole row of the trace file written so far, if any.
fn last_row(trace: &Path) -> Option<Vec<f64>> {
    let text = std::fs::read_to_string(trace).ok()?;
    let whole = &text[..text.rfind('\n')?];
    let line = whole.lines().skip(1).last()?;
    // An empty field (a spindle angle the machine does not measure) reads as NaN.
    line.split(',')
        .map(|v| {
            if v.is_empty() {
                Some(f64::NAN)
            } else {
                v.parse().ok()
            }
        })
        .collect()
}

/// Starts `klar run PROGRAM --trace TRACE [extra]` with stderr captured.
fn start_run(program: &Path, trace: &Path, extra: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_klar"))
        .arg("run")
        .arg(program)
        .arg("--trace")
        .arg(trace)
        .args(extra)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("klar starts")
}

/// Waits until the trace shows X past `x` (the axes move); false when the child exited
/// first.
fn wait_for_motion(child: &mut Child, trace: &Path, x: f64) -> bool {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        if last_row(trace).is_some_and(|r| r.get(1).is_some_and(|&v| v > x)) {
            return true;
        }
        assert!(Instant::now() < deadline, "no motion in the trace");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Everything stderr said.
fn stderr_of(child: &mut Child) -> String {
    let mut text = String::new();
    if let Some(mut e) = child.stderr.take() {
        e.read_to_string(&mut text).unwrap();
    }
    text
}

/// Reads the trace: it must end with a whole row and every row must have the header's
/// number of fields (`Trace::parse` refuses any other).
fn read_trace(path: &Path) -> Trace {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.ends_with('\n'), "the trace ends mid-row");
    Trace::parse(&text).unwrap_or_else(|e| panic!("trace: {e}"))
}

/// `t = T s` of the stop report on stderr: the machine time the stop began.
fn stop_time(stderr: &str) -> f64 {
    let at = stderr
        .split("stop on the path at t = ")
        .nth(1)
        .or_else(|| stderr.split("quick stop at t = ").nth(1))
        .unwrap_or_else(|| panic!("no stop report in: {stderr}"));
    at.split_whitespace().next().unwrap().parse().unwrap()
}

/// What the trace says about a stop that began at machine time `t_stop`.
#[derive(Debug)]
struct StopFigures {
    /// Path speed when the stop began, mm/s.
    speed: f64,
    /// Path length from the stop's beginning to rest, mm.
    distance: f64,
    /// Machine time from the stop's beginning to the last moving row, s.
    time: f64,
}

/// Checks a stop in the trace of the built-in mill: every axis within its velocity,
/// acceleration and jerk limits throughout (so no step anywhere), the path speed by finite
/// differences falling to zero from its highest value after `t_stop` without rising again,
/// and the last rows at rest (command still, measured position still and on the command).
fn check_stop(trace: &Trace, t_stop: f64) -> StopFigures {
    let machine = MachineConfig::builtin_mill();
    assert_within_limits(trace, &machine);
    let dt = machine.servo_period;
    let xyz: Vec<Vec<f64>> = ["X", "Y", "Z"]
        .iter()
        .map(|c| trace.column(c).unwrap())
        .collect();
    let n = trace.t.len();
    let speed: Vec<f64> = (1..n)
        .map(|k| {
            let d2: f64 = xyz.iter().map(|x| (x[k] - x[k - 1]).powi(2)).sum();
            d2.sqrt() / dt
        })
        .collect();
    // speed[k] is the speed over rows k..k+1
    let k0 = trace.t.iter().position(|&t| t >= t_stop).unwrap();
    let peak = (k0..speed.len())
        .max_by(|&a, &b| speed[a].total_cmp(&speed[b]))
        .unwrap();
    for k in peak + 1..speed.len() {
        assert!(
            speed[k] <= speed[k - 1] + 1e-6,
            "the path speed rises during the stop at t = {}: {} after {}",
            trace.t[k],
            speed[k],
            speed[k - 1]
        );
    }
    let moving = speed.iter().rposition(|&v| v > 1e-9).unwrap();
    assert!(
        n - moving > 10,
        "the trace ends {} rows after the last motion: not at rest",
        n - moving
    );
    for (i, name) in ["X_act", "Y_act", "Z_act"].iter().enumerate() {
        let act = trace.column(name).unwrap();
        let tail = &act[n - 5..];
        assert!(
            tail.iter().all(|&a| (a - tail[0]).abs() < 1e-6),
            "{name} still moves at the end: {tail:?}"
        );
        let cmd = xyz[i][n - 1];
        assert!(
            (tail[4] - cmd).abs() < 1e-3,
            "{name} rests at {} off the command {cmd}",
            tail[4]
        );
    }
    let distance: f64 = speed[k0..].iter().map(|v| v * dt).sum();
    StopFigures {
        speed: speed[k0.saturating_sub(1)],
        distance,
        time: trace.t[moving + 1] - trace.t[k0],
    }
}

/// Runs the long line with `--realtime`, sends `signals` (the later ones `gap` apart) once
/// the axes move, and checks the controlled stop; returns stderr and the figures.
fn realtime_stop(tag: &str, signals: &[&str], gap: Duration, code: i32) -> (String, StopFigures) {
    let dir = temp_dir(tag);
    let program = dir.join("long.h");
    std::fs::write(&program, LONG_LINE).unwrap();
    let trace_path = dir.join("trace.csv");
    let mut child = start_run(&program, &trace_path, &["--realtime"]);
    // 20 mm into the line: cruising at 50 mm/s, about 4.6 s before its end
    assert!(
        wait_for_motion(&mut child, &trace_path, 20.0),
        "the run ended before the signal"
    );
    for (i, s) in signals.iter().enumerate() {
        if i > 0 {
            std::thread::sleep(gap);
        }
        send(&child, s);
    }
    let status = wait_exit(&mut child);
    let stderr = stderr_of(&mut child);
    assert!(!status.success(), "{stderr}");
    assert_eq!(status.code(), Some(code), "exit status {status}: {stderr}");
    assert!(
        stderr.contains("stopped by the operator at block 2 (line 3)"),
        "{stderr}"
    );
    let trace = read_trace(&trace_path);
    let figures = check_stop(&trace, stop_time(&stderr));
    // on the line: from its start on, Y and Z never left it; the corner from the rapid
    // into it may be crossed within the path tolerance (0.01 mm), so there Z stays within
    // it of the line or X of the rapid's; past the line's first mm, exactly
    let (xs, ys, zs) = (
        trace.column("X").unwrap(),
        trace.column("Y").unwrap(),
        trace.column("Z").unwrap(),
    );
    let from = xs.iter().position(|&x| x > 0.0).unwrap();
    let past = xs.iter().position(|&x| x > 1.0).unwrap();
    assert!(
        ys[from..].iter().all(|&y| y.abs() < 1e-9),
        "Y left the line"
    );
    assert!(
        (from..past).all(|i| xs[i].min((zs[i] - 50.0).abs()) <= 0.01 + 1e-9),
        "the corner left the band"
    );
    assert!(
        zs[past..].iter().all(|&z| (z - 50.0).abs() < 1e-9),
        "Z left the line"
    );
    eprintln!("{tag}: {figures:?}");
    let _ = std::fs::remove_dir_all(&dir);
    (stderr, figures)
}

/// The braking distance of X (the axis of the long line) from `speed` plus one servo cycle
/// of travel.
fn x_braking(speed: f64) -> f64 {
    let m = MachineConfig::builtin_mill();
    let x = &m.axes[0];
    braking_distance(speed, x.max_acceleration, x.max_jerk) + speed * m.servo_period
}

/// The time X takes to stop from `speed` at its limits (trapezoidal or triangular
/// acceleration profile) plus two servo cycles.
fn x_stop_time(speed: f64) -> f64 {
    let m = MachineConfig::builtin_mill();
    let (a, j) = (m.axes[0].max_acceleration, m.axes[0].max_jerk);
    let t = if speed * j >= a * a {
        speed / a + a / j
    } else {
        2.0 * (speed / j).sqrt()
    };
    t + 2.0 * m.servo_period
}

#[test]
fn sigterm_during_a_realtime_run_stops_on_the_path() {
    let (stderr, f) = realtime_stop("term", &["TERM"], Duration::ZERO, 143);
    assert!(stderr.contains("controlled stop on the path"), "{stderr}");
    assert!(
        (f.speed - FEED).abs() < 0.01 * FEED,
        "speed at the stop {}",
        f.speed
    );
    assert!(
        f.distance <= x_braking(f.speed),
        "stopped in {} mm, braking distance {}",
        f.distance,
        x_braking(f.speed)
    );
    assert!(f.time <= x_stop_time(f.speed), "stopped in {} s", f.time);
}

#[test]
fn sigint_during_a_realtime_run_stops_on_the_path() {
    let (stderr, f) = realtime_stop("int", &["INT"], Duration::ZERO, 130);
    assert!(stderr.contains("controlled stop on the path"), "{stderr}");
    assert!(
        f.distance <= x_braking(f.speed),
        "stopped in {} mm",
        f.distance
    );
    assert!(f.time <= x_stop_time(f.speed), "stopped in {} s", f.time);
}

#[test]
fn a_second_sigterm_during_the_stop_makes_it_a_quick_stop() {
    // The feed hold from 50 mm/s takes about 60 ms: the second signal comes within it,
    // unless this process was held up longer than that (a loaded machine), when the first
    // stop ends on the path and the test tries again.
    let mut tries = 0;
    let (stderr, f) = loop {
        let (stderr, f) = realtime_stop("twice", &["TERM", "TERM"], Duration::from_millis(15), 143);
        tries += 1;
        if stderr.contains("quick stop at t = ") || tries == 3 {
            break (stderr, f);
        }
    };
    assert!(stderr.contains("quick stop at t = "), "{stderr}");
    assert!(
        f.distance <= x_braking(FEED),
        "stopped in {} mm",
        f.distance
    );
    assert!(f.time <= x_stop_time(FEED), "stopped in {} s", f.time);
}

/// A program of `rep + 1` round trips X0 → X250 → X0 at 50 mm/s (10 s of machine time each).
fn round_trips(rep: u32) -> String {
    format!(
        "0 BEGIN PGM TRIPS MM\n1 L X+0 Y+0 Z+50 R0 FMAX\n2 LBL 1\n3 L X+250 R0 F3000\n\
         4 L X+0 R0 F3000\n5 LBL 0\n6 CALL LBL 1 REP {rep}\n7 END PGM TRIPS MM\n"
    )
}

#[test]
fn sigterm_during_a_run_faster_than_real_time_stops_it() {
    let dir = temp_dir("fast");
    let program = dir.join("trips.h");
    let trace_path = dir.join("trace.csv");
    // The simulated run goes hundreds of times faster than real time: if it ends before
    // the signal, the program gets ten times longer.
    let mut rep = 99;
    let (mut child, program_text) = loop {
        let text = round_trips(rep);
        std::fs::write(&program, &text).unwrap();
        let mut child = start_run(&program, &trace_path, &[]);
        if wait_for_motion(&mut child, &trace_path, 1.0) {
            std::thread::sleep(Duration::from_millis(100));
            if child.try_wait().unwrap().is_none() {
                send(&child, "TERM");
                break (child, text);
            }
        }
        let _ = wait_exit(&mut child);
        assert!(rep < 100_000, "the run always ends before the signal");
        rep = rep * 10 + 9;
    };
    let status = wait_exit(&mut child);
    let stderr = stderr_of(&mut child);
    assert_eq!(status.code(), Some(143), "exit status {status}: {stderr}");
    // The report names a block and its line: that line of the program starts with the
    // block number and is one of the two moves of the loop.
    let at = stderr
        .split("stopped by the operator at block ")
        .nth(1)
        .unwrap_or_else(|| panic!("{stderr}"));
    let block: u32 = at.split_whitespace().next().unwrap().parse().unwrap();
    let line: usize = at
        .split("(line ")
        .nth(1)
        .and_then(|l| l.split(')').next())
        .and_then(|l| l.parse().ok())
        .unwrap_or_else(|| panic!("{stderr}"));
    let text_line = program_text.lines().nth(line - 1).unwrap();
    assert!(
        text_line.starts_with(&format!("{block} L X+")),
        "{text_line}"
    );
    let trace = read_trace(&trace_path);
    let f = check_stop(&trace, stop_time(&stderr));
    assert!(
        f.distance <= x_braking(FEED),
        "stopped in {} mm",
        f.distance
    );
    assert!(f.time <= x_stop_time(FEED), "stopped in {} s", f.time);
    eprintln!("fast: {f:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// One HTTP/1.1 request to the dashboard; returns the body.
fn http(addr: SocketAddr, method: &str, path: &str, body: &str) -> String {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    )
    .unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    out.split_once("\r\n\r\n")
        .map(|(_, b)| b.to_string())
        .unwrap_or_default()
}

#[test]
fn sigterm_to_the_dashboard_stops_the_running_program_then_the_server() {
    let dir = temp_dir("serve");
    std::fs::write(dir.join("long.h"), LONG_LINE).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_klar"))
        .args(["serve", "--port", "0", "--programs"])
        .arg(&dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("klar serve starts");
    let mut first = String::new();
    let stdout = child.stdout.take().unwrap();
    BufReader::new(stdout).read_line(&mut first).unwrap();
    let addr: SocketAddr = first
        .split("http://")
        .nth(1)
        .and_then(|a| a.trim().trim_end_matches('/').parse().ok())
        .unwrap_or_else(|| panic!("no address in {first:?}"));
    http(addr, "POST", "/api/load", r#"{"name":"long.h"}"#);
    http(addr, "POST", "/api/start", "");
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let status: serde_json::Value =
            serde_json::from_str(&http(addr, "GET", "/api/status", "")).unwrap();
        let x = status["commanded"][0].as_f64().unwrap_or(0.0);
        if status["state"] == "running" && x > 20.0 {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "the program does not run: {status}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    send(&child, "TERM");
    let status = wait_exit(&mut child);
    let stderr = stderr_of(&mut child);
    assert_eq!(status.code(), Some(0), "exit status {status}: {stderr}");
    assert!(
        stderr.contains("controlled stop on the path")
            && stderr.contains("stopped by the operator"),
        "{stderr}"
    );
    assert!(
        stderr.contains("stopped by the operator at block 2 (line 3)"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
