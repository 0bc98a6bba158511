//! The dashboard's HTTP API without a browser: access rules (loopback by default, a token for
//! anything else), the program listing and its limits, and a short program run to its end
//! through the API on the simulated mill.

use klar::config::MachineConfig;
use klar::serve::{ServeError, ServeOptions, check_access, serve};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// One feed move X+50 at F6000 (100 mm/s) from the mill's start X0 Y0 Z100.
const ONE_LINE: &str = "0 BEGIN PGM ONE MM\n1 L X+50 R0 F6000\n2 END PGM ONE MM\n";

fn programs_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("klar-serve-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("one.h"), ONE_LINE).unwrap();
    dir
}

fn options(programs: &Path, token: Option<&str>) -> ServeOptions {
    ServeOptions {
        listen: "127.0.0.1:0".parse().unwrap(),
        token: token.map(str::to_string),
        programs: programs.to_path_buf(),
        machine: MachineConfig::builtin_mill(),
    }
}

/// Starts the server on a runtime of its own; returns its address.
fn start(options: ServeOptions) -> (tokio::runtime::Runtime, SocketAddr) {
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
fn request(addr: SocketAddr, method: &str, path: &str, headers: &str, body: &str) -> (u16, String) {
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

fn json(body: &str) -> serde_json::Value {
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
    let status = loop {
        let s = json(&request(addr, "GET", "/api/status", "", "").1);
        if s["state"] == "finished" {
            break s;
        }
        assert!(Instant::now() < until, "no end: {s}");
        std::thread::sleep(Duration::from_millis(50));
    };
    assert_eq!(status["program"], "one.h");
    assert_eq!(status["commanded"], serde_json::json!([50.0, 0.0, 100.0]));
    assert_eq!(status["feed_override"], 0.5);
    assert!(status["message"].is_null());
    // Machine time: at least the 1 s the move needs at 50 % of 100 mm/s.
    assert!(status["t"].as_f64().unwrap() > 1.0, "{status}");
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
