//! The dashboard's manual operation, programs and honest state in Chromium: jog by a step,
//! MDI, homing to a home switch, a limit-switch fault that blocks everything until Reset, an
//! upload whose error line is marked, the buttons enabled only where they act, zoom on the
//! toolpath, the page at 1280 px and at phone width (360 px) with every control inside the
//! viewport, and the page without its server. Screenshots go to `target/screenshots/`.

use super::{Guard, browser, click, number, start_driver, start_server_on, text, wait_for};
use fantoccini::{Client, Locator};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The built-in mill with X's home switch at X+20 and a negative limit switch at X-5.
const SWITCHED_MILL: &str = r#"
name = "mill with X switches"
servo_period = 0.001
tolerance = 0.01
start_homed = true

[[axis]]
letter = "X"
kind = "linear"
travel = [-300.0, 300.0]
max_velocity = 166.0
max_acceleration = 2000.0
max_jerk = 50000.0
backend = { kind = "sim", limit_switch_negative = -5.0, home_switch = 20.0 }

[[axis]]
letter = "Y"
kind = "linear"
travel = [-300.0, 300.0]
max_velocity = 166.0
max_acceleration = 2000.0
max_jerk = 50000.0
backend = { kind = "sim" }

[[axis]]
letter = "Z"
kind = "linear"
travel = [-200.0, 200.0]
start = 100.0
max_velocity = 100.0
max_acceleration = 1500.0
max_jerk = 40000.0
backend = { kind = "sim" }

[spindle]
max_rpm = 12000.0
"#;

/// A slow move along +Y with a blank: long enough to look at each state.
const SLOW: &str = "0 BEGIN PGM SLOW MM\n1 BLK FORM 0.1 Z X+0 Y+0 Z-20\n2 BLK FORM 0.2 X+100 Y+60 Z+0\n3 L Y+60 R0 F600\n4 L Y+0\n5 END PGM SLOW MM\n";

/// A program whose line 3 the test run refuses (an unknown word).
const FAULTY: &str = "0 BEGIN PGM UP MM\n1 L X+10 R0 F1000\n2 L Y+10 FOO\n3 END PGM UP MM\n";

pub(super) fn screenshots() -> PathBuf {
    let target = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .map_or_else(|| PathBuf::from("target"), Path::to_path_buf);
    let dir = target.join("screenshots");
    std::fs::create_dir_all(&dir).expect("screenshot folder");
    dir
}

/// Which of the page's state-dependent buttons are enabled, in a fixed order.
async fn enabled(c: &Client) -> Vec<(String, bool)> {
    let mut out = Vec::new();
    for id in [
        "start", "hold", "resume", "stop", "reset", "jog-plus", "mdi-run", "load",
    ] {
        let e = c.find(Locator::Id(id)).await.expect(id);
        let on = e.is_enabled().await.expect(id);
        out.push((id.to_string(), on));
    }
    out
}

async fn expect_enabled(c: &Client, state: &str, on: &[&str]) {
    let want: Vec<(String, bool)> = [
        "start", "hold", "resume", "stop", "reset", "jog-plus", "mdi-run", "load",
    ]
    .iter()
    .map(|id| (id.to_string(), on.contains(id)))
    .collect();
    let got = wait_for(&format!("the buttons of state {state}"), || async {
        let got = enabled(c).await;
        (got == want).then_some(got)
    })
    .await;
    assert_eq!(got, want, "{state}");
}

pub(super) async fn wait_state(c: &Client, state: &str) {
    wait_for(&format!("state {state}"), || async {
        (text(c, "state").await == state).then_some(())
    })
    .await;
}

async fn wait_cmd(c: &Client, axis: &str, value: f64) {
    wait_for(&format!("{axis} at {value}"), || async {
        let v = number(c, &format!("cmd-{axis}")).await;
        ((v - value).abs() < 1e-3 && text(c, "path-speed").await == "0.0").then_some(())
    })
    .await;
}

async fn select(c: &Client, id: &str, value: &str) {
    c.find(Locator::Id(id))
        .await
        .expect(id)
        .select_by_value(value)
        .await
        .unwrap_or_else(|e| panic!("#{id} = {value}: {e}"));
}

/// Controls (buttons, inputs, selects) outside the viewport's width, and where Stop ends.
pub(super) async fn outside(c: &Client) -> (Vec<String>, f64, f64) {
    let v = c
        .execute(
            "const w = document.documentElement.clientWidth; const out = []; \
             for (const e of document.querySelectorAll('button, input, select')) { \
               const r = e.getBoundingClientRect(); \
               if (r.width === 0 && r.height === 0) continue; \
               if (r.left < 0 || r.right > w + 0.5) out.push((e.id || e.name || e.tagName) + ' ' + r.left + '..' + r.right); } \
             if (document.documentElement.scrollWidth > w) out.push('the page scrolls sideways: ' + document.documentElement.scrollWidth); \
             const s = document.getElementById('stop').getBoundingClientRect(); \
             return [out, s.bottom, window.innerHeight];",
            vec![],
        )
        .await
        .expect("script runs");
    let list = v[0]
        .as_array()
        .map(|a| a.iter().map(|x| x.to_string()).collect())
        .unwrap_or_default();
    (
        list,
        v[1].as_f64().unwrap_or(f64::NAN),
        v[2].as_f64().unwrap_or(f64::NAN),
    )
}

pub(super) async fn shot(c: &Client, name: &str) {
    let png = c.screenshot().await.expect("screenshot");
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    std::fs::write(screenshots().join(name), &png).expect("screenshot saved");
}

pub(super) async fn scenario() {
    let dir = std::env::temp_dir().join(format!("klar-browser-manual-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("nc")).expect("temp folder");
    std::fs::write(dir.join("nc/slow.h"), SLOW).expect("program");
    std::fs::write(dir.join("up.h"), FAULTY).expect("upload file");
    let machine = dir.join("switched.toml");
    std::fs::write(&machine, SWITCHED_MILL).expect("machine file");
    let (server, url) = start_server_on(Some(&machine), &dir.join("nc"));
    let (_driver, driver_url) = start_driver().await;
    let profile = dir.join("profile");
    let c = browser(&driver_url, &profile).await;
    c.set_window_size(1280, 900).await.expect("window size");
    c.goto(&url).await.expect("page opens");
    wait_for("the live link", || async {
        (text(&c, "link").await == "live" && !text(&c, "act-X").await.is_empty()).then_some(())
    })
    .await;
    // Idle, nothing loaded: manual operation and loading, no program control.
    expect_enabled(&c, "idle", &["jog-plus", "mdi-run", "load"]).await;

    // Jog X by a step of 10 at 20 mm/s.
    select(&c, "jog-axis", "X").await;
    select(&c, "jog-step", "10").await;
    click(&c, "jog-plus").await;
    wait_cmd(&c, "X", 10.0).await;
    assert_eq!(text(&c, "manual-op").await, "manual: jog X +10.000");
    // MDI from there.
    let mdi = c.find(Locator::Id("mdi-block")).await.expect("MDI field");
    mdi.send_keys("L Y+5 F1000").await.expect("typed");
    click(&c, "mdi-run").await;
    wait_cmd(&c, "Y", 5.0).await;
    assert_eq!(number(&c, "cmd-X").await, 10.0);
    // Home X: to its home switch at X+20.
    click(&c, "home-axis").await;
    wait_for("X homed", || async {
        let x = number(&c, "act-X").await;
        (text(&c, "manual-op").await == "manual: home X" && (x - 20.0).abs() < 1e-3).then_some(())
    })
    .await;

    // The limit switch at X-5 in an MDI move's way: a fault, and nothing starts until Reset.
    mdi.clear().await.expect("cleared");
    mdi.send_keys("L X-10 F3000").await.expect("typed");
    click(&c, "mdi-run").await;
    wait_state(&c, "fault").await;
    let message = text(&c, "message").await;
    assert!(message.contains("negative limit switch"), "{message}");
    expect_enabled(&c, "fault", &["reset", "load"]).await;
    shot(&c, "dashboard-fault-1280.png").await;
    click(&c, "reset").await;
    wait_state(&c, "idle").await;
    expect_enabled(&c, "idle after reset", &["jog-plus", "mdi-run", "load"]).await;
    let x = number(&c, "act-X").await;
    assert!((-6.0..=-5.0).contains(&x), "X stopped at the switch: {x}");
    click(&c, "jog-plus").await;
    wait_for("the jog off the switch", || async {
        let v = number(&c, "act-X").await;
        ((v - (x + 10.0)).abs() < 2e-3).then_some(())
    })
    .await;

    // Upload a program with an error: offered, and its error line marked when shown.
    let file = c
        .find(Locator::Id("upload-file"))
        .await
        .expect("file input");
    file.send_keys(&dir.join("up.h").display().to_string())
        .await
        .expect("file chosen");
    click(&c, "upload").await;
    wait_for("the uploaded program in the list", || async {
        c.find(Locator::Css("#program-select option[value='up.h']"))
            .await
            .ok()
            .map(|_| ())
    })
    .await;
    assert_eq!(
        std::fs::read_to_string(dir.join("nc/up.h")).expect("saved"),
        FAULTY
    );
    click(&c, "load").await;
    wait_for("line 3 marked as an error", || async {
        c.find(Locator::Css("#L3.err")).await.ok().map(|_| ())
    })
    .await;
    assert!(text(&c, "diagnostics").await.contains("FOO"));

    // A program through its states: each button enabled only where it acts.
    select(&c, "program-select", "slow.h").await;
    click(&c, "load").await;
    wait_for("slow.h shown", || async {
        c.find(Locator::Id("L4")).await.ok().map(|_| ())
    })
    .await;
    expect_enabled(
        &c,
        "idle, loaded",
        &["start", "jog-plus", "mdi-run", "load"],
    )
    .await;
    click(&c, "start").await;
    wait_state(&c, "running").await;
    expect_enabled(&c, "running", &["hold", "stop"]).await;
    // Progress by machine time, and the distance to go to the end of the block.
    wait_for("progress", || async {
        let p = number(&c, "progress-pct").await;
        (p > 0.0).then_some(())
    })
    .await;
    let to_go = number(&c, "togo-Y").await;
    assert!(to_go > 0.0 && to_go <= 60.0, "Y to go {to_go}");
    click(&c, "hold").await;
    wait_state(&c, "held").await;
    expect_enabled(&c, "held", &["resume", "stop"]).await;
    shot(&c, "dashboard-1280.png").await;
    let (out, _, _) = outside(&c).await;
    assert!(out.is_empty(), "controls outside 1280 px: {out:?}");

    // Zoom in on the toolpath with the wheel.
    let zoom = c
        .execute(
            "const cv = document.getElementById('toolpath'); const r = cv.getBoundingClientRect(); \
             cv.dispatchEvent(new WheelEvent('wheel', {deltaY: -400, clientX: r.left + r.width / 2, \
               clientY: r.top + r.height / 2, bubbles: true, cancelable: true})); return camera.zoom;",
            vec![],
        )
        .await
        .expect("wheel");
    let zoom = zoom.as_f64().unwrap_or(0.0);
    assert!(zoom > 1.5, "zoom {zoom}");
    shot(&c, "dashboard-zoomed-1280.png").await;

    // A phone: every control within the width, Stop on the first screen.
    c.set_window_size(360, 740).await.expect("window size");
    tokio::time::sleep(Duration::from_millis(300)).await;
    let (out, stop_bottom, height) = outside(&c).await;
    assert!(out.is_empty(), "controls outside 360 px: {out:?}");
    assert!(
        stop_bottom <= height,
        "Stop ends at {stop_bottom} of {height} px"
    );
    shot(&c, "dashboard-360.png").await;

    click(&c, "stop").await;
    wait_state(&c, "stopped").await;
    expect_enabled(&c, "stopped", &["start", "jog-plus", "mdi-run", "load"]).await;
    assert_eq!(text(&c, "spindle").await, "M5 / 0 rpm");

    // The server goes away: the page says so and offers nothing.
    drop::<Guard>(server);
    wait_state(&c, "no connection to the server").await;
    expect_enabled(&c, "offline", &[]).await;
    for id in [
        "override",
        "single-block",
        "jog-minus",
        "home-all",
        "upload",
    ] {
        let e = c.find(Locator::Id(id)).await.expect(id);
        assert!(
            !e.is_enabled().await.expect(id),
            "#{id} enabled without a server"
        );
    }
    c.set_window_size(1280, 900).await.expect("window size");
    shot(&c, "dashboard-offline-1280.png").await;
    c.close().await.expect("browser closes");
    let _ = std::fs::remove_dir_all(&dir);
}
