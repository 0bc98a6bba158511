//! The dashboard's HTTP API without a browser: access rules (loopback by default, a token for
//! anything else), the program listing and its limits, and a short program run to its end
//! through the API on the simulated mill.

use klar::config::MachineConfig;
use klar::serve::{ServeError, ServeOptions, check_access, serve};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

#[path = "serve_api/spindle_probe.rs"]
mod spindle_probe;

/// One feed move X+50 at F6000 (100 mm/s) from the mill's start X0 Y0 Z100.
const ONE_LINE: &str = "0 BEGIN PGM ONE MM\n1 L X+50 R0 F6000\n2 END PGM ONE MM\n";

pub(crate) fn programs_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("klar-serve-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("one.h"), ONE_LINE).unwrap();
    dir
}

pub(crate) fn options(programs: &Path, token: Option<&str>) -> ServeOptions {
    ServeOptions {
        listen: "127.0.0.1:0".parse().unwrap(),
        token: token.map(str::to_string),
        programs: programs.to_path_buf(),
        machine: MachineConfig::builtin_mill(),
    }
}

/// Starts the server on a runtime of its own; returns its address.
pub(crate) fn start(options: ServeOptions) -> (tokio::runtime::Runtime, SocketAddr) {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    rt.spawn(async move {
        serve(options, move |addr| {
            let _ = tx.send(addr);
        })
        .await
    });
    let addr = rx.recv_timeout(Duration::from_secs(10)).expect("server up");
    (rt, addr)
}

/// One HTTP/1.1 request; returns the status code and the body.
pub(crate) fn request(
    addr: SocketAddr,
    method: &str,
    path: &str,
    headers: &str,
    body: &str,
) -> (u16, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    let extra = if body.is_empty() {
        String::new()
    } else {
        format!(
            "Content-Type: application/json\r\nContent-Length: {}\r\n",
            body.len()
        )
    };
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n{headers}{extra}\r\n{body}"
    )
    .unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    let code = out
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    let body = out.split_once("\r\n\r\n").map(|(_, b)| b).unwrap_or("");
    (code, body.to_string())
}

pub(crate) fn json(body: &str) -> serde_json::Value {
    serde_json::from_str(body).unwrap_or_else(|e| panic!("{e}: {body}"))
}

#[test]
fn remote_access_needs_a_token_of_some_length() {
    let dir = programs_dir("access");
    let mut o = options(&dir, None);
    assert!(check_access(&o).is_ok());
    o.listen = "0.0.0.0:8080".parse().unwrap();
    assert!(matches!(
        check_access(&o),
        Err(ServeError::RemoteWithoutToken(_))
    ));
    o.token = Some("short".into());
    assert!(matches!(check_access(&o), Err(ServeError::WeakToken)));
    o.token = Some("long enough secret".into());
    assert!(check_access(&o).is_ok());
}

#[test]
fn with_a_token_the_api_refuses_requests_without_it() {
    let dir = programs_dir("token");
    let (_rt, addr) = start(options(&dir, Some("s3cret-token")));
    // The page itself carries no secret.
    let (code, page) = request(addr, "GET", "/", "", "");
    assert_eq!(code, 200);
    assert!(page.contains("<canvas id=\"toolpath\""));
    assert_eq!(request(addr, "GET", "/api/status", "", "").0, 401);
    let wrong = "Authorization: Bearer s3cret-tokeX\r\n";
    assert_eq!(request(addr, "GET", "/api/status", wrong, "").0, 401);
    assert_eq!(request(addr, "POST", "/api/start", "", "").0, 401);
    assert_eq!(
        request(addr, "GET", "/api/status?token=s3cret-token", "", "").0,
        200
    );
    let right = "Authorization: Bearer s3cret-token\r\n";
    let (code, body) = request(addr, "GET", "/api/status", right, "");
    assert_eq!(code, 200);
    assert_eq!(json(&body)["state"], "idle");
}

#[test]
fn other_sites_and_foreign_host_names_are_refused() {
    let dir = programs_dir("origin");
    let (_rt, addr) = start(options(&dir, None));
    // A form on another site posting to the machine through the operator's browser.
    let evil = "Origin: http://evil.example\r\n";
    assert_eq!(request(addr, "POST", "/api/start", evil, "").0, 403);
    // The page's own requests carry its own origin.
    let own = format!("Origin: http://{addr}\r\n");
    assert_eq!(request(addr, "GET", "/api/status", &own, "").0, 200);
    assert_eq!(request(addr, "GET", "/api/status", "", "").0, 200);
    let status = |host: &str| {
        let mut s = TcpStream::connect(addr).unwrap();
        write!(
            s,
            "GET /api/status HTTP/1.1\r\nHost: {host}\r\nOrigin: http://{host}\r\nConnection: close\r\n\r\n"
        )
        .unwrap();
        let mut out = String::new();
        s.read_to_string(&mut out).unwrap();
        out.split_whitespace().nth(1).unwrap_or("").to_string()
    };
    assert_eq!(status(&format!("127.0.0.1:{}", addr.port())), "200");
    assert_eq!(status(&format!("localhost:{}", addr.port())), "200");
    // A name that resolves here only by DNS rebinding.
    assert_eq!(status(&format!("evil.example:{}", addr.port())), "403");
}

#[test]
fn only_listed_programs_can_be_read_or_loaded() {
    let dir = programs_dir("list");
    std::fs::write(dir.join("notes.txt"), "not a program").unwrap();
    let (_rt, addr) = start(options(&dir, None));
    let (code, body) = request(addr, "GET", "/api/programs", "", "");
    assert_eq!(code, 200);
    assert_eq!(json(&body), serde_json::json!(["one.h"]));
    for name in ["notes.txt", "../one.h", "%2Fetc%2Fpasswd"] {
        let (code, _) = request(addr, "GET", &format!("/api/program?name={name}"), "", "");
        assert_eq!(code, 404, "{name}");
        let (code, _) = request(
            addr,
            "POST",
            "/api/load",
            "",
            &format!("{{\"name\": \"{name}\"}}"),
        );
        assert_eq!(code, 404, "{name}");
    }
    // Malformed JSON is refused without harm.
    let (code, _) = request(addr, "POST", "/api/load", "", "{\"name\": ");
    assert!((400..500).contains(&code), "{code}");
}

#[test]
fn a_program_runs_to_its_end_through_the_api() {
    let dir = programs_dir("run");
    let (_rt, addr) = start(options(&dir, None));
    let (code, body) = request(addr, "GET", "/api/program?name=one.h", "", "");
    assert_eq!(code, 200);
    let view = json(&body);
    assert_eq!(view["text"], ONE_LINE);
    // The planned path: one feed stroke from the start X0 Y0 Z100 to X+50.
    assert_eq!(
        view["path"],
        serde_json::json!([{"rapid": false, "points": [[0.0, 0.0, 100.0], [50.0, 0.0, 100.0]]}])
    );
    assert_eq!(
        request(addr, "POST", "/api/load", "", "{\"name\": \"one.h\"}").0,
        204
    );
    assert_eq!(
        request(addr, "POST", "/api/override", "", "{\"factor\": 0.5}").0,
        204
    );
    assert_eq!(request(addr, "POST", "/api/start", "", "").0, 204);
    // 50 mm at 50 mm/s: about a second on the wall clock.
    let until = Instant::now() + Duration::from_secs(20);
    let mut longest = 0.0f64;
    let status = loop {
        let s = json(&request(addr, "GET", "/api/status", "", "").1);
        if s["state"] == "finished" {
            break s;
        }
        longest = longest.max(s["t"].as_f64().unwrap());
        assert!(Instant::now() < until, "no end: {s}");
        std::thread::sleep(Duration::from_millis(50));
    };
    assert_eq!(status["program"], "one.h");
    assert_eq!(status["commanded"], serde_json::json!([50.0, 0.0, 100.0]));
    assert_eq!(status["feed_override"], 0.5);
    assert!(status["message"].is_null());
    // Machine time while it ran: toward the 1 s the move needs at 50 % of 100 mm/s; once
    // the run has ended it is cleared like the path speed.
    assert!(longest > 0.8, "{longest}");
    assert_eq!(status["t"], 0.0, "{status}");
    assert_eq!(status["path_speed"], 0.0, "{status}");
}

/// Two feed moves at a right angle: X+50, then Y+20, both at F6000.
const TWO_BLOCKS: &str = "0 BEGIN PGM TWO MM\n1 L X+50 R0 F6000\n2 L Y+20\n3 END PGM TWO MM\n";

#[test]
fn single_block_holds_as_the_next_block_begins() {
    let dir = programs_dir("single");
    std::fs::write(dir.join("two.h"), TWO_BLOCKS).unwrap();
    let (_rt, addr) = start(options(&dir, None));
    let post = |path: &str, body: &str| request(addr, "POST", path, "", body).0;
    assert_eq!(post("/api/load", "{\"name\": \"two.h\"}"), 204);
    assert_eq!(post("/api/single_block", "{\"on\": true}"), 204);
    assert_eq!(post("/api/start", ""), 204);
    let wait = |what: &str, done: &dyn Fn(&serde_json::Value) -> bool| {
        let until = Instant::now() + Duration::from_secs(20);
        loop {
            let s = json(&request(addr, "GET", "/api/status", "", "").1);
            if done(&s) {
                return s;
            }
            assert!(Instant::now() < until, "no {what}: {s}");
            std::thread::sleep(Duration::from_millis(20));
        }
    };
    // Held at rest in block 2 (file line 3): X at its end, Y short of its end.
    let held = wait("hold in block 2", &|s| {
        s["state"] == "held" && s["line"] == 3 && s["path_speed"] == 0.0
    });
    assert_eq!(held["commanded"][0], 50.0, "{held}");
    let y = held["commanded"][1].as_f64().unwrap();
    assert!((0.0..20.0).contains(&y), "{held}");
    std::thread::sleep(Duration::from_millis(200));
    let still = json(&request(addr, "GET", "/api/status", "", "").1);
    assert_eq!(still["commanded"], held["commanded"]);
    // No other program can be loaded meanwhile.
    assert_eq!(post("/api/load", "{\"name\": \"one.h\"}"), 409);
    // Resume runs block 2 to its end.
    assert_eq!(post("/api/resume", ""), 204);
    let end = wait("the end", &|s| s["state"] == "finished");
    assert_eq!(end["commanded"], serde_json::json!([50.0, 20.0, 100.0]));
}

#[test]
fn the_machine_api_names_the_preset_programs_start_from() {
    let dir = programs_dir("preset");
    std::fs::write(
        dir.join("PRESET.PR"),
        "BEGIN PRESET.PR MM\nNR X Y Z\n0 +0 +0 +0\n4 +150 -25 +0\n[END]\n",
    )
    .unwrap();
    let text = format!(
        "preset_table = \"PRESET.PR\"\nactive_preset = 4\n{}",
        klar::config::BUILTIN_MILL
    );
    std::fs::write(dir.join("machine.toml"), text).unwrap();
    let machine = MachineConfig::load(&dir.join("machine.toml")).expect("machine loads");
    let (_rt, addr) = start(ServeOptions {
        machine,
        ..options(&dir, None)
    });
    let (code, body) = request(addr, "GET", "/api/machine", "", "");
    assert_eq!(code, 200, "{body}");
    assert_eq!(json(&body)["preset"], "4 X+150 Y-25");
    // the built-in mill has none
    let (_rt2, addr2) = start(options(&dir, None));
    let (_, body) = request(addr2, "GET", "/api/machine", "", "");
    assert_eq!(json(&body)["preset"], "none (machine datum)");
    assert_eq!(json(&body)["lathe"], false);
}

#[test]
fn the_machine_api_says_when_the_machine_is_a_lathe() {
    let dir = programs_dir("lathe");
    let machine = MachineConfig::builtin_lathe();
    let (_rt, addr) = start(ServeOptions {
        machine,
        ..options(&dir, None)
    });
    let (code, body) = request(addr, "GET", "/api/machine", "", "");
    assert_eq!(code, 200, "{body}");
    assert_eq!(json(&body)["lathe"], true);
}

// ---- manual operation, programs and honest state -------------------------------------------

/// The built-in mill with X's home switch at X+40 and a negative limit switch at X-5.
pub(crate) fn switched_mill(dir: &Path) -> MachineConfig {
    let text = klar::config::BUILTIN_MILL.replacen(
        "backend = { kind = \"sim\" }",
        "backend = { kind = \"sim\", home_switch = 40.0, limit_switch_negative = -5.0 }",
        1,
    );
    let file = dir.join("switched.toml");
    std::fs::write(&file, text).unwrap();
    MachineConfig::load(&file).expect("machine loads")
}

pub(crate) fn post(addr: SocketAddr, path: &str, body: &str) -> (u16, serde_json::Value) {
    let (code, text) = request(addr, "POST", path, "", body);
    let v = if text.trim().is_empty() {
        serde_json::Value::Null
    } else {
        json(&text)
    };
    (code, v)
}

/// Polls the status until `done` holds (20 s at most).
pub(crate) fn wait_for(
    addr: SocketAddr,
    what: &str,
    done: &dyn Fn(&serde_json::Value) -> bool,
) -> serde_json::Value {
    let until = Instant::now() + Duration::from_secs(20);
    loop {
        let s = json(&request(addr, "GET", "/api/status", "", "").1);
        if done(&s) {
            return s;
        }
        assert!(Instant::now() < until, "no {what}: {s}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

pub(crate) fn at_rest(s: &serde_json::Value) -> bool {
    s["state"] == "idle" && s["path_speed"] == 0.0
}

#[test]
fn a_jog_moves_its_axis_by_the_distance_within_the_soft_limits() {
    let dir = programs_dir("jog");
    let (_rt, addr) = start(options(&dir, None));
    let (code, v) = post(
        addr,
        "/api/jog",
        r#"{"axis": "X", "distance": 2.5, "speed": 20}"#,
    );
    assert_eq!(code, 204, "{v}");
    let s = wait_for(addr, "the jog's end", &|s| {
        at_rest(s) && s["manual"] == "jog X +2.500"
    });
    // From the start X0 Y0 Z100: exactly 2.5 mm along X, nothing else.
    assert_eq!(s["commanded"], serde_json::json!([2.5, 0.0, 100.0]));
    // Z travels -200 … 200 and stands at 100: +150 would end at 250.
    let (code, v) = post(
        addr,
        "/api/jog",
        r#"{"axis": "Z", "distance": 150, "speed": 20}"#,
    );
    assert_eq!(code, 422);
    let why = v["error"].as_str().unwrap();
    assert!(why.contains("250.000") && why.contains("travel"), "{why}");
    for bad in [
        r#"{"axis": "Q", "distance": 1, "speed": 20}"#,
        r#"{"axis": "X", "distance": 1, "speed": 0}"#,
        r#"{"axis": "X", "distance": 0, "speed": 20}"#,
        r#"{"axis": "X", "direction": 2, "speed": 20}"#,
        r#"{"axis": "X", "speed": 20}"#,
    ] {
        let (code, v) = post(addr, "/api/jog", bad);
        assert_eq!(code, 422, "{bad}: {v}");
        assert!(v["error"].is_string(), "{bad}: {v}");
    }
    // Nothing of that moved anything.
    let s = json(&request(addr, "GET", "/api/status", "", "").1);
    assert_eq!(s["commanded"], serde_json::json!([2.5, 0.0, 100.0]));
}

#[test]
fn a_continuous_jog_runs_until_stopped_and_the_next_run_starts_there() {
    let dir = programs_dir("jogc");
    let (_rt, addr) = start(options(&dir, None));
    let (code, v) = post(
        addr,
        "/api/jog",
        r#"{"axis": "Y", "direction": -1, "speed": 50}"#,
    );
    assert_eq!(code, 204, "{v}");
    wait_for(addr, "motion", &|s| {
        s["state"] == "running" && s["path_speed"].as_f64() > Some(10.0)
    });
    assert_eq!(post(addr, "/api/stop", "").0, 204);
    let s = wait_for(addr, "rest", &at_rest);
    let y = s["commanded"][1].as_f64().unwrap();
    // Stopped on the way: moved, but far from the end of the travel at -300.
    assert!((-290.0..-1.0).contains(&y), "{s}");
    // A program starts where the axes stand: one.h moves X only, Y stays.
    assert_eq!(post(addr, "/api/load", r#"{"name": "one.h"}"#).0, 204);
    assert_eq!(post(addr, "/api/start", "").0, 204);
    let end = wait_for(addr, "the end", &|s| s["state"] == "finished");
    assert_eq!(end["commanded"][0], 50.0, "{end}");
    assert_eq!(end["commanded"][1].as_f64().unwrap(), y, "{end}");
}

#[test]
fn manual_operation_is_refused_while_a_program_runs() {
    let dir = programs_dir("busy");
    let (_rt, addr) = start(options(&dir, None));
    assert_eq!(post(addr, "/api/load", r#"{"name": "one.h"}"#).0, 204);
    assert_eq!(post(addr, "/api/override", r#"{"factor": 0.2}"#).0, 204);
    assert_eq!(post(addr, "/api/start", "").0, 204);
    for (path, body) in [
        ("/api/jog", r#"{"axis": "X", "distance": 1, "speed": 20}"#),
        ("/api/jog", r#"{"axis": "X", "direction": 1, "speed": 20}"#),
        ("/api/mdi", r#"{"block": "L X+10 F1000"}"#),
        ("/api/home", ""),
        ("/api/reset", ""),
        ("/api/start", ""),
    ] {
        let (code, v) = post(addr, path, body);
        assert_eq!(code, 409, "{path} {body}: {v}");
        assert!(v["error"].as_str().unwrap().contains("running"), "{v}");
    }
    // The running program cannot be replaced under it either.
    let (code, _) = post(addr, "/api/upload", r#"{"name": "one.h", "text": "x"}"#);
    assert_eq!(code, 409);
    assert_eq!(post(addr, "/api/stop", "").0, 204);
    let s = wait_for(addr, "the stop", &|s| s["state"] == "stopped");
    // At rest: no path speed, the spindle (the mill has one) at 0.
    assert_eq!(s["path_speed"], 0.0);
    assert_eq!(s["spindle_rpm"], 0.0);
}

#[test]
fn mdi_runs_one_checked_block_from_where_the_axes_stand() {
    let dir = programs_dir("mdi");
    let (_rt, addr) = start(options(&dir, None));
    let (code, v) = post(addr, "/api/mdi", r#"{"block": "L X+10 Y+5 F1000"}"#);
    assert_eq!(code, 204, "{v}");
    let s = wait_for(addr, "the MDI block's end", &|s| {
        at_rest(s) && s["manual"] == "MDI L X+10 Y+5 F1000"
    });
    assert_eq!(s["commanded"], serde_json::json!([10.0, 5.0, 100.0]));
    // Incremental from there.
    assert_eq!(
        post(addr, "/api/mdi", r#"{"block": "L IX-4 F1000"}"#).0,
        204
    );
    let s = wait_for(addr, "the second block", &|s| {
        at_rest(s) && s["manual"] == "MDI L IX-4 F1000"
    });
    assert_eq!(s["commanded"], serde_json::json!([6.0, 5.0, 100.0]));
    // The test run refuses what the machine cannot do, and what is not a block.
    let (code, v) = post(addr, "/api/mdi", r#"{"block": "L X+1000 F1000"}"#);
    assert_eq!(code, 422);
    assert!(v["error"].as_str().unwrap().contains("travel"), "{v}");
    let (code, v) = post(addr, "/api/mdi", r#"{"block": "L X+10 FOO"}"#);
    assert_eq!(code, 422);
    assert!(v["error"].as_str().unwrap().contains("FOO"), "{v}");
    let (code, _) = post(addr, "/api/mdi", r#"{"block": "L X+1\nL X+2"}"#);
    assert_eq!(code, 422);
    let s = json(&request(addr, "GET", "/api/status", "", "").1);
    assert_eq!(s["commanded"], serde_json::json!([6.0, 5.0, 100.0]));
}

#[test]
fn homing_finds_the_home_switch() {
    let dir = programs_dir("home");
    let machine = switched_mill(&dir);
    let (_rt, addr) = start(ServeOptions {
        machine,
        ..options(&dir, None)
    });
    let (code, v) = post(addr, "/api/home", r#"{"axis": "X"}"#);
    assert_eq!(code, 204, "{v}");
    let s = wait_for(addr, "homing", &|s| {
        s["manual"] == "home X" && s["state"] == "idle"
    });
    // X stands at its home switch (to the count), Y and Z where they were.
    let x = s["actual"][0].as_f64().unwrap();
    assert!((x - 40.0).abs() < 1e-3, "{s}");
    assert_eq!(s["actual"][1], 0.0, "{s}");
    assert!(
        (s["actual"][2].as_f64().unwrap() - 100.0).abs() < 1e-3,
        "{s}"
    );
    let (code, _) = post(addr, "/api/home", r#"{"axis": "W"}"#);
    assert_eq!(code, 422);
}

#[test]
fn after_a_fault_nothing_starts_until_reset() {
    let dir = programs_dir("fault");
    let machine = switched_mill(&dir);
    let (_rt, addr) = start(ServeOptions {
        machine,
        ..options(&dir, None)
    });
    // Jogging X to -10 runs into the limit switch at -5.
    let (code, v) = post(
        addr,
        "/api/jog",
        r#"{"axis": "X", "distance": -10, "speed": 20}"#,
    );
    assert_eq!(code, 204, "{v}");
    let s = wait_for(addr, "the fault", &|s| s["state"] == "fault");
    assert!(
        s["message"].as_str().unwrap().contains("limit switch"),
        "{s}"
    );
    assert_eq!(post(addr, "/api/load", r#"{"name": "one.h"}"#).0, 204);
    let (code, v) = post(addr, "/api/start", "");
    assert_eq!(code, 409);
    assert!(v["error"].as_str().unwrap().contains("Reset"), "{v}");
    let (code, _) = post(
        addr,
        "/api/jog",
        r#"{"axis": "X", "distance": 3, "speed": 20}"#,
    );
    assert_eq!(code, 409);
    assert_eq!(post(addr, "/api/reset", "").0, 204);
    let s = wait_for(addr, "the reset", &|s| s["state"] == "idle");
    assert!(s["message"].is_null(), "{s}");
    let x = s["actual"][0].as_f64().unwrap();
    assert!(x <= -5.0 && x > -6.0, "stopped near the switch: {s}");
    // Away from the switch is allowed.
    let (code, v) = post(
        addr,
        "/api/jog",
        r#"{"axis": "X", "distance": 3, "speed": 20}"#,
    );
    assert_eq!(code, 204, "{v}");
    let s = wait_for(addr, "the jog off the switch", &|s| {
        at_rest(s) && s["manual"] == "jog X +3.000"
    });
    assert!(
        (s["actual"][0].as_f64().unwrap() - (x + 3.0)).abs() < 1e-3,
        "{s}"
    );
}

#[test]
fn uploads_are_checked_saved_and_shown_with_their_errors() {
    let dir = programs_dir("upload");
    let (_rt, addr) = start(options(&dir, None));
    for name in ["../evil.h", "sub/x.h", ".x.h", "x.txt", "", "a\\\\b.h"] {
        let body = serde_json::json!({"name": name, "text": ONE_LINE}).to_string();
        let (code, v) = post(addr, "/api/upload", &body);
        assert_eq!(code, 422, "{name:?}: {v}");
    }
    let big = "; x\n".repeat(300_000);
    let body = serde_json::json!({"name": "big.h", "text": big}).to_string();
    assert_eq!(post(addr, "/api/upload", &body).0, 422);
    assert!(!dir.join("big.h").exists());
    let bad = "0 BEGIN PGM BAD MM\n1 L X+10 R0 F1000\n2 L Y+10 FOO\n3 END PGM BAD MM\n";
    let body = serde_json::json!({"name": "bad.h", "text": bad}).to_string();
    assert_eq!(post(addr, "/api/upload", &body).0, 201);
    assert_eq!(std::fs::read_to_string(dir.join("bad.h")).unwrap(), bad);
    let (_, list) = request(addr, "GET", "/api/programs", "", "");
    assert_eq!(json(&list), serde_json::json!(["bad.h", "one.h"]));
    let (_, view) = request(addr, "GET", "/api/program?name=bad.h", "", "");
    let view = json(&view);
    let d = &view["diagnostics"][0];
    assert_eq!(
        (d["line"].as_u64(), d["error"].as_bool()),
        (Some(3), Some(true)),
        "{view}"
    );
    // A lathe program is refused on the mill when it is loaded, with the reason.
    let lathe = "%t.nc\nMACHINING\nN1 G0 X40 Z5\nEND\n";
    let body = serde_json::json!({"name": "t.nc", "text": lathe}).to_string();
    assert_eq!(post(addr, "/api/upload", &body).0, 201);
    let (code, v) = post(addr, "/api/load", r#"{"name": "t.nc"}"#);
    assert_eq!(code, 422);
    assert!(v["error"].as_str().unwrap().contains("lathe"), "{v}");
}

#[test]
fn the_program_view_has_the_blank_the_block_ends_and_the_machine_time() {
    let dir = programs_dir("view");
    let (_rt, addr) = start(options(&dir, None));
    let (_, view) = request(addr, "GET", "/api/program?name=one.h", "", "");
    let view = json(&view);
    // one.h: X+50 at 100 mm/s from rest is at least 0.5 s, plus the ramps.
    let t = view["machine_time"].as_f64().unwrap();
    assert!(t > 0.5 && t < 1.0, "{view}");
    assert_eq!(view["ends"]["2"], serde_json::json!([50.0, 0.0, 100.0]));
    assert!(view["stock"].is_null());
    let prog = "0 BEGIN PGM B MM\n1 BLK FORM 0.1 Z X-5 Y+0 Z-20\n2 BLK FORM 0.2 X+100 Y+60 Z+0\n3 L X+10 R0 FMAX\n4 END PGM B MM\n";
    std::fs::write(dir.join("blk.h"), prog).unwrap();
    let (_, view) = request(addr, "GET", "/api/program?name=blk.h", "", "");
    assert_eq!(
        json(&view)["stock"],
        serde_json::json!([[-5.0, 0.0, -20.0], [100.0, 60.0, 0.0]])
    );
}

#[test]
fn a_lathe_takes_lathe_din_mdi_and_refuses_milling_programs() {
    let dir = programs_dir("lathe");
    let (_rt, addr) = start(ServeOptions {
        machine: MachineConfig::builtin_lathe(),
        ..options(&dir, None)
    });
    let (_, info) = request(addr, "GET", "/api/machine", "", "");
    assert_eq!(json(&info)["lathe"], true);
    // one.h is Klartext: refused at load, with the reason.
    let (code, v) = post(addr, "/api/load", r#"{"name": "one.h"}"#);
    assert_eq!(code, 422);
    assert!(v["error"].as_str().unwrap().contains("lathe"), "{v}");
    // An MDI block of lathe DIN: X is programmed as a diameter, the X axis moves the radius.
    let (code, v) = post(addr, "/api/mdi", r#"{"block": "G0 X40 Z5"}"#);
    assert_eq!(code, 204, "{v}");
    let s = wait_for(addr, "the MDI block's end", &|s| {
        at_rest(s) && s["manual"] == "MDI G0 X40 Z5"
    });
    let letters: Vec<&str> = s["letters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    let at = |l: &str| s["commanded"][letters.iter().position(|&x| x == l).unwrap()].clone();
    assert_eq!((at("X"), at("Z")), (20.0.into(), 5.0.into()), "{s}");
    // A jog of X is a diameter: -10 in X moves the X axis (a radius) from 20 to 15.
    let (code, v) = post(
        addr,
        "/api/jog",
        r#"{"axis": "X", "distance": -10, "speed": 5}"#,
    );
    assert_eq!(code, 204, "{v}");
    let s = wait_for(addr, "the X jog's end", &|s| {
        at_rest(s) && s["manual"] == "jog X -10.000"
    });
    let at = |s: &serde_json::Value, l: &str| {
        s["commanded"][letters.iter().position(|&x| x == l).unwrap()]
            .as_f64()
            .unwrap()
    };
    assert!((at(&s, "X") - 15.0).abs() < 1e-9, "{s}");
    assert!((at(&s, "Z") - 5.0).abs() < 1e-9, "{s}");
    // Z by its own distance.
    let (code, v) = post(
        addr,
        "/api/jog",
        r#"{"axis": "Z", "distance": 2.5, "speed": 5}"#,
    );
    assert_eq!(code, 204, "{v}");
    let s = wait_for(addr, "the Z jog's end", &|s| {
        at_rest(s) && s["manual"] == "jog Z +2.500"
    });
    assert!((at(&s, "Z") - 7.5).abs() < 1e-9, "{s}");
    assert!((at(&s, "X") - 15.0).abs() < 1e-9, "{s}");
    // The soft limit counts the radius: X travels down to radius -20, so diameter -70 from
    // radius 15 (to -20) is the most, and -70.2 is refused with the radius it would reach.
    let (code, v) = post(
        addr,
        "/api/jog",
        r#"{"axis": "X", "distance": -70.2, "speed": 5}"#,
    );
    assert_eq!(code, 422, "{v}");
    assert!(v["error"].as_str().unwrap().contains("-20.100"), "{v}");
}
