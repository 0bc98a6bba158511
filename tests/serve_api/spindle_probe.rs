//! The spindle by hand (`POST /api/spindle`), the tool in the path's frame under a preset,
//! and the touch-probe results in the snapshot.

use super::{ServeOptions, at_rest, json, options, post, programs_dir, request, start, wait_for};
use klar::config::MachineConfig;
use std::path::Path;

/// The spindle status of a snapshot: (direction, commanded rpm, measured rpm).
fn spindle(s: &serde_json::Value) -> (String, f64, f64) {
    let sp = &s["spindle"];
    (
        sp["direction"].as_str().unwrap_or("?").to_string(),
        sp["commanded"].as_f64().unwrap_or(f64::NAN),
        sp["measured"].as_f64().unwrap_or(f64::NAN),
    )
}

#[test]
fn the_spindle_turns_by_hand_and_keeps_turning_across_jogs() {
    let dir = programs_dir("spindle");
    let (_rt, addr) = start(options(&dir, None));
    let s = json(&request(addr, "GET", "/api/status", "", "").1);
    assert_eq!(spindle(&s), ("stop".into(), 0.0, 0.0), "{s}");
    let (code, v) = post(
        addr,
        "/api/spindle",
        r#"{"direction": "cw", "speed": 1200}"#,
    );
    assert_eq!(code, 204, "{v}");
    // The simulated spindle ramps up and its measured speed reaches the command.
    let s = wait_for(addr, "the spindle at speed", &|s| {
        (spindle(s).2 - 1200.0).abs() < 1.0
    });
    assert_eq!(spindle(&s).0, "cw", "{s}");
    assert_eq!(spindle(&s).1, 1200.0, "{s}");
    assert_eq!(s["spindle_rpm"], s["spindle"]["measured"], "{s}");
    // A jog does not stop it: the run takes it over and hands it back turning.
    let (code, v) = post(
        addr,
        "/api/jog",
        r#"{"axis": "X", "distance": 2, "speed": 20}"#,
    );
    assert_eq!(code, 204, "{v}");
    let s = wait_for(addr, "the jog's end", &|s| {
        at_rest(s) && s["manual"] == "jog X +2.000"
    });
    assert_eq!(spindle(&s).0, "cw", "{s}");
    assert!((spindle(&s).2 - 1200.0).abs() < 1.0, "{s}");
    // Counter-clockwise: the measured speed goes through zero to -800.
    assert_eq!(
        post(
            addr,
            "/api/spindle",
            r#"{"direction": "ccw", "speed": 800}"#
        )
        .0,
        204
    );
    let s = wait_for(addr, "the reversed spindle", &|s| {
        (spindle(s).2 + 800.0).abs() < 1.0
    });
    assert_eq!(spindle(&s).0, "ccw", "{s}");
    // Off: it runs down to a standstill.
    assert_eq!(
        post(addr, "/api/spindle", r#"{"direction": "stop"}"#).0,
        204
    );
    let s = wait_for(addr, "the spindle at rest", &|s| spindle(s).2 == 0.0);
    assert_eq!(spindle(&s), ("stop".into(), 0.0, 0.0), "{s}");
}

#[test]
fn spindle_requests_outside_its_range_or_while_running_are_refused() {
    let dir = programs_dir("spindle-refused");
    let (_rt, addr) = start(options(&dir, None));
    // The built-in mill's spindle turns up to 12000 rpm.
    for bad in [
        r#"{"direction": "cw", "speed": 12001}"#,
        r#"{"direction": "ccw", "speed": 0}"#,
        r#"{"direction": "cw", "speed": -100}"#,
        r#"{"direction": "cw"}"#,
        r#"{"direction": "left", "speed": 100}"#,
        r#"{"speed": 100}"#,
        "[]",
    ] {
        let (code, v) = post(addr, "/api/spindle", bad);
        assert_eq!(code, 422, "{bad}: {v}");
        assert!(v["error"].is_string(), "{bad}: {v}");
    }
    let (_, v) = post(
        addr,
        "/api/spindle",
        r#"{"direction": "cw", "speed": 12001}"#,
    );
    assert!(v["error"].as_str().unwrap().contains("12000"), "{v}");
    let s = json(&request(addr, "GET", "/api/status", "", "").1);
    assert_eq!(spindle(&s).1, 0.0, "nothing commanded: {s}");
    // While a program runs: 409.
    assert_eq!(post(addr, "/api/override", r#"{"factor": 0.2}"#).0, 204);
    assert_eq!(post(addr, "/api/load", r#"{"name": "one.h"}"#).0, 204);
    assert_eq!(post(addr, "/api/start", "").0, 204);
    let (code, v) = post(
        addr,
        "/api/spindle",
        r#"{"direction": "cw", "speed": 1000}"#,
    );
    assert_eq!(code, 409, "{v}");
    assert!(v["error"].as_str().unwrap().contains("running"), "{v}");
    assert_eq!(post(addr, "/api/stop", "").0, 204);
    wait_for(addr, "the stop", &|s| s["state"] == "stopped");
    // A machine without a spindle has none to turn.
    let mut bare = MachineConfig::builtin_mill();
    bare.spindle = None;
    let (_rt2, bare_addr) = start(ServeOptions {
        machine: bare,
        ..options(&dir, None)
    });
    let (code, v) = post(
        bare_addr,
        "/api/spindle",
        r#"{"direction": "cw", "speed": 100}"#,
    );
    assert_eq!(code, 422, "{v}");
    assert!(v["error"].as_str().unwrap().contains("no spindle"), "{v}");
}

#[test]
fn a_program_takes_the_spindle_over_and_a_fault_or_reset_stops_it() {
    let dir = programs_dir("spindle-program");
    let machine = super::switched_mill(&dir);
    let (_rt, addr) = start(ServeOptions {
        machine,
        ..options(&dir, None)
    });
    let on = r#"{"direction": "cw", "speed": 3000}"#;
    assert_eq!(post(addr, "/api/spindle", on).0, 204);
    wait_for(addr, "the spindle at speed", &|s| {
        (spindle(s).2 - 3000.0).abs() < 1.0
    });
    // one.h has no M3: it runs with the spindle it took over; its end stops it.
    assert_eq!(post(addr, "/api/load", r#"{"name": "one.h"}"#).0, 204);
    assert_eq!(post(addr, "/api/start", "").0, 204);
    let running = wait_for(addr, "the run", &|s| s["state"] == "running");
    assert_eq!(spindle(&running).0, "cw", "taken over turning: {running}");
    let end = wait_for(addr, "the end", &|s| s["state"] == "finished");
    assert_eq!(spindle(&end), ("stop".into(), 0.0, 0.0), "{end}");
    // On again, then a jog into the limit switch at X-5 (the axes stand at X+50): the
    // fault stops the spindle, and it stays off after Reset.
    assert_eq!(post(addr, "/api/spindle", on).0, 204);
    wait_for(addr, "the spindle at speed", &|s| {
        (spindle(s).2 - 3000.0).abs() < 1.0
    });
    let (code, v) = post(
        addr,
        "/api/jog",
        r#"{"axis": "X", "distance": -60, "speed": 50}"#,
    );
    assert_eq!(code, 204, "{v}");
    let s = wait_for(addr, "the fault", &|s| s["state"] == "fault");
    assert_eq!(spindle(&s).0, "stop", "{s}");
    let (code, _) = post(addr, "/api/spindle", on);
    assert_eq!(code, 409, "refused until Reset");
    assert_eq!(post(addr, "/api/reset", "").0, 204);
    let s = wait_for(addr, "the reset", &|s| s["state"] == "idle");
    assert_eq!(spindle(&s), ("stop".into(), 0.0, 0.0), "{s}");
    assert_eq!(s["t"], 0.0, "{s}");
}

/// The probing mill of `machines/`, its preset table beside it.
fn probing_mill() -> MachineConfig {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing-mill.toml");
    MachineConfig::load(&p).expect("the probing machine loads")
}

#[test]
fn a_probing_program_shows_its_results_and_the_tool_stays_on_the_path() {
    let dir = programs_dir("probe");
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("programs/probing_412.h");
    std::fs::copy(&src, dir.join("probing_412.h")).unwrap();
    let (_rt, addr) = start(ServeOptions {
        machine: probing_mill(),
        ..options(&dir, None)
    });
    let s = json(&request(addr, "GET", "/api/status", "", "").1);
    assert!(s["probe"].is_null(), "{s}");
    let (code, body) = request(addr, "GET", "/api/program?name=probing_412.h", "", "");
    assert_eq!(code, 200, "{body}");
    let view = json(&body);
    let last_stroke = view["path"].as_array().unwrap().last().unwrap().clone();
    let path_end = last_stroke["points"]
        .as_array()
        .unwrap()
        .last()
        .unwrap()
        .clone();
    assert_eq!(
        post(addr, "/api/load", r#"{"name": "probing_412.h"}"#).0,
        204
    );
    assert_eq!(post(addr, "/api/start", "").0, 204);
    let s = wait_for(addr, "the end", &|s| s["state"] == "finished");
    // Cycle 412 found the bore (nominal X-25 Y-10, ⌀24) and wrote preset row 1.
    let probe = &s["probe"];
    assert_eq!(probe["cycle"], 412, "{s}");
    let q = |n: u64| {
        probe["params"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p[0] == n)
            .and_then(|p| p[1].as_f64())
            .unwrap_or_else(|| panic!("Q{n} in {probe}"))
    };
    assert!((q(153) - 24.0).abs() < 1e-3, "{probe}");
    assert!((q(151) + 25.0).abs() < 6.0, "{probe}");
    let preset = &probe["preset"];
    assert_eq!(
        (preset["row"].as_i64(), preset["active"].as_bool()),
        (Some(1), Some(true)),
        "{probe}"
    );
    // The preset moved the program's datum (preset 1 at X+100 before); the program then
    // went over the new datum. The tool, reported in the path's frame, ends where the
    // planned path ends: no shift puts it beside the path.
    for k in 0..3 {
        let (tool, end) = (
            s["tool"][k].as_f64().unwrap(),
            path_end[k].as_f64().unwrap(),
        );
        assert!(
            (tool - end).abs() < 1e-3,
            "axis {k}: tool {tool}, path end {end}: {s}"
        );
    }
    let x = preset["values"]
        .as_array()
        .unwrap()
        .iter()
        .find(|v| v[0] == "X")
        .unwrap();
    assert!(
        (s["tool"][0].as_f64().unwrap() - x[1].as_f64().unwrap()).abs() < 1e-3,
        "{s}"
    );
}
