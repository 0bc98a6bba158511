//! The dashboard end to end in a real browser: `klar serve` on the simulated mill, headless
//! Chromium driven over WebDriver (chromedriver), and the page checked the way an operator
//! would: load a program, start it, watch the DRO move and the highlighted block advance, hold
//! and resume, change the feed override, stop; then a machine whose simulated X axis has a
//! negative limit switch at X-5 — in the path of rectangle.h's rapid to X-10 — shows the fault.
//!
//! Needs `/usr/bin/chromium` and `/usr/bin/chromedriver` (scripts/setup-browser.sh installs
//! them). Screenshots go to `target/tmp/browser/`.

#[path = "browser/lathe.rs"]
mod lathe;
#[path = "browser/manual.rs"]
mod manual;

use fantoccini::{Client, ClientBuilder, Locator};
use std::io::{BufRead, BufReader};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The longest any single wait in this test may take.
const WAIT: Duration = Duration::from_secs(20);

/// A child process killed (with its whole process group) when dropped.
struct Guard {
    child: Child,
    name: &'static str,
}

impl Drop for Guard {
    fn drop(&mut self) {
        // The child leads its own process group: chromedriver's browsers go with it.
        let pgid = self.child.id();
        let _ = Command::new("kill")
            .args(["-KILL", "--", &format!("-{pgid}")])
            .status();
        let _ = self.child.kill();
        let _ = self.child.wait();
        eprintln!("stopped {}", self.name);
    }
}

fn spawn_group(cmd: &mut Command, name: &'static str) -> Guard {
    use std::os::unix::process::CommandExt;
    let child = cmd
        .process_group(0)
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {name}: {e} (run scripts/setup-browser.sh)"));
    Guard { child, name }
}

/// `klar serve` on a free port over the repository's programs; returns the guard and the
/// page's URL.
fn start_server(machine: Option<&Path>) -> (Guard, String) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    start_server_on(machine, &root.join("programs"))
}

/// `klar serve` on a free port over the programs in `programs`.
fn start_server_on(machine: Option<&Path>, programs: &Path) -> (Guard, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_klar"));
    cmd.args(["serve", "--port", "0", "--programs"])
        .arg(programs)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit());
    if let Some(m) = machine {
        cmd.arg("--machine").arg(m);
    }
    let mut guard = spawn_group(&mut cmd, "klar serve");
    let stdout = guard.child.stdout.take().expect("piped stdout");
    let mut line = String::new();
    BufReader::new(stdout)
        .read_line(&mut line)
        .expect("server prints its address");
    let url = line
        .split_whitespace()
        .find(|w| w.starts_with("http://"))
        .unwrap_or_else(|| panic!("no URL in {line:?}"))
        .to_string();
    (guard, url)
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

/// chromedriver on a free port, once it answers.
async fn start_driver() -> (Guard, String) {
    let port = free_port();
    let guard = spawn_group(
        Command::new("chromedriver")
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null()),
        "chromedriver",
    );
    let url = format!("http://127.0.0.1:{port}");
    let until = Instant::now() + WAIT;
    while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
        assert!(Instant::now() < until, "chromedriver did not start");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    (guard, url)
}

async fn browser(driver: &str, profile: &Path) -> Client {
    let mut caps = serde_json::Map::new();
    caps.insert(
        "goog:chromeOptions".into(),
        serde_json::json!({
            "binary": "/usr/bin/chromium",
            "args": [
                "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                "--no-first-run", "--disable-background-networking",
                "--disable-component-update", "--disable-sync",
                "--window-size=1900,1000",
                format!("--user-data-dir={}", profile.display()),
            ],
        }),
    );
    ClientBuilder::new(hyper_util::client::legacy::connect::HttpConnector::new())
        .capabilities(caps)
        .connect(driver)
        .await
        .expect("a WebDriver session")
}

async fn text(c: &Client, id: &str) -> String {
    c.find(Locator::Id(id))
        .await
        .unwrap_or_else(|e| panic!("#{id}: {e}"))
        .text()
        .await
        .unwrap_or_else(|e| panic!("#{id}: {e}"))
}

async fn number(c: &Client, id: &str) -> f64 {
    let t = text(c, id).await;
    t.trim()
        .trim_start_matches('+')
        .parse()
        .unwrap_or_else(|_| panic!("#{id} shows {t:?}, not a number"))
}

/// The 1-based number of the highlighted program line, 0 when none is.
async fn highlighted(c: &Client) -> u32 {
    let found = c
        .execute(
            "const e = document.querySelector('#program-text .current'); \
             return e ? Number(e.id.slice(1)) : 0;",
            vec![],
        )
        .await
        .expect("script runs");
    found
        .as_u64()
        .and_then(|n| u32::try_from(n).ok())
        .unwrap_or(0)
}

async fn click(c: &Client, id: &str) {
    c.find(Locator::Id(id))
        .await
        .unwrap_or_else(|e| panic!("#{id}: {e}"))
        .click()
        .await
        .unwrap_or_else(|e| panic!("click #{id}: {e}"));
}

/// Polls `probe` until it gives `Some`, for at most [`WAIT`].
async fn wait_for<T, F, Fut>(what: &str, mut probe: F) -> T
where
    F: FnMut() -> Fut,
    Fut: std::future::Future<Output = Option<T>>,
{
    let until = Instant::now() + WAIT;
    loop {
        if let Some(v) = probe().await {
            return v;
        }
        assert!(Instant::now() < until, "timed out waiting for {what}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

async fn dro(c: &Client) -> [f64; 3] {
    [
        number(c, "act-X").await,
        number(c, "act-Y").await,
        number(c, "act-Z").await,
    ]
}

async fn commanded(c: &Client) -> [f64; 3] {
    [
        number(c, "cmd-X").await,
        number(c, "cmd-Y").await,
        number(c, "cmd-Z").await,
    ]
}

async fn load_program(c: &Client, url: &str, name: &str) {
    c.goto(url).await.expect("page opens");
    wait_for("the program list", || async {
        let n = c
            .execute(
                "return document.querySelectorAll('#program-select option').length",
                vec![],
            )
            .await
            .ok()?;
        (n.as_u64()? > 0).then_some(())
    })
    .await;
    c.find(Locator::Id("program-select"))
        .await
        .expect("program list")
        .select_by_value(name)
        .await
        .expect("program offered");
    wait_for("the live link and the DRO", || async {
        let live = text(c, "link").await == "live";
        (live && !text(c, "act-X").await.is_empty()).then_some(())
    })
    .await;
    click(c, "load").await;
    wait_for("the program text", || async {
        c.find(Locator::Id("L7")).await.ok().map(|_| ())
    })
    .await;
}

fn artifacts() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("browser");
    std::fs::create_dir_all(&dir).expect("artifact folder");
    dir
}

/// The built-in mill with a hardware limit switch on X at X-5 (the test hook for faults:
/// a simulated axis trips its switch like a real one). rectangle.h's block 5 rapids to X-10.
const SWITCH_X_MILL: &str = r#"
name = "mill with an X limit switch at X-5"
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
backend = { kind = "sim", limit_switch_negative = -5.0 }

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

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn dashboard_runs_holds_resumes_overrides_and_shows_a_fault() {
    tokio::time::timeout(Duration::from_secs(240), scenario())
        .await
        .expect("the browser test finished in time");
    // One browser at a time: the manual-operation scenario after the first.
    tokio::time::timeout(Duration::from_secs(240), manual::scenario())
        .await
        .expect("the manual-operation browser test finished in time");
    tokio::time::timeout(Duration::from_secs(240), lathe::scenario())
        .await
        .expect("the lathe, spindle and probing browser test finished in time");
}

async fn scenario() {
    let out = artifacts();
    let (_server, url) = start_server(None);
    let (_driver, driver_url) = start_driver().await;
    let profile = out.join(format!("profile-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&profile);
    let c = browser(&driver_url, &profile).await;

    load_program(&c, &url, "rectangle.h").await;
    // Before the start: the DRO shows the mill's start position (X0 Y0 Z100).
    assert_eq!(dro(&c).await, [0.0, 0.0, 100.0]);
    // The built-in mill starts referenced (`start_homed`): every axis says so.
    for l in ["X", "Y", "Z"] {
        let title = c
            .find(Locator::Id(&format!("ref-{l}")))
            .await
            .unwrap_or_else(|e| panic!("#ref-{l}: {e}"))
            .attr("title")
            .await
            .unwrap_or_else(|e| panic!("#ref-{l}: {e}"));
        assert_eq!(title.as_deref(), Some("referenced"), "axis {l}");
    }
    click(&c, "start").await;

    // The DRO moves.
    let first = wait_for("the DRO to move", || async {
        let p = dro(&c).await;
        (p[2] < 99.0).then_some(p)
    })
    .await;
    let first_line = wait_for("a highlighted block", || async {
        let l = highlighted(&c).await;
        (l > 0).then_some(l)
    })
    .await;
    // rectangle.h, line 7: "6  L Z-5 F300 M8" — the first feed move, 300 mm/min = 5 mm/s.
    wait_for("the highlight to reach line 7", || async {
        (highlighted(&c).await == 7).then_some(())
    })
    .await;
    assert!(first_line < 7, "highlight started at line {first_line}");
    let speed = wait_for("the path speed of F300", || async {
        let v = number(&c, "path-speed").await;
        ((v - 5.0).abs() < 0.05).then_some(v)
    })
    .await;
    let moving = dro(&c).await;
    assert!(
        moving[2] < first[2],
        "Z goes down: {first:?} then {moving:?}"
    );
    assert_eq!([moving[0], moving[1]], [-10.0, 10.0], "plunge at X-10 Y+10");
    eprintln!("feed move at {speed} mm/s");

    // Feed hold: the machine comes to rest and the DRO stands still.
    click(&c, "hold").await;
    wait_for("state held at rest", || async {
        let state = text(&c, "state").await;
        let v = number(&c, "path-speed").await;
        (state == "held" && v == 0.0).then_some(())
    })
    .await;
    // Let the servo loops settle on the held setpoint, then watch the DRO.
    tokio::time::sleep(Duration::from_millis(300)).await;
    let held = dro(&c).await;
    let held_cmd = commanded(&c).await;
    tokio::time::sleep(Duration::from_millis(600)).await;
    // The commanded position stands still; the measured one within an encoder count or two
    // of servo jitter.
    assert_eq!(
        commanded(&c).await,
        held_cmd,
        "the setpoint moved during a feed hold"
    );
    let later = dro(&c).await;
    for (a, b) in held.iter().zip(&later) {
        assert!(
            (a - b).abs() <= 0.002,
            "the DRO moved during a feed hold: {held:?} {later:?}"
        );
    }
    assert_eq!(text(&c, "state").await, "held");

    // Resume: it moves on down.
    click(&c, "resume").await;
    wait_for("the DRO to move after resume", || async {
        (dro(&c).await[2] < held[2] - 0.1).then_some(())
    })
    .await;

    // Override 50 %: the path speed halves to 2.5 mm/s.
    c.execute(
        "const e = document.getElementById('override'); e.value = 50; \
         e.dispatchEvent(new Event('input'));",
        vec![],
    )
    .await
    .expect("slider moves");
    wait_for("the path speed at 50 % override", || async {
        let v = number(&c, "path-speed").await;
        ((v - 2.5).abs() < 0.05).then_some(())
    })
    .await;
    assert_eq!(text(&c, "override-value").await, "50 %");
    tokio::time::sleep(Duration::from_millis(300)).await;
    let shot = c.screenshot().await.expect("screenshot");
    std::fs::write(out.join("dashboard.png"), &shot).expect("screenshot saved");
    assert_eq!(&shot[..8], b"\x89PNG\r\n\x1a\n");

    // Stop: the run ends at rest with the state "stopped".
    click(&c, "stop").await;
    wait_for("state stopped", || async {
        (text(&c, "state").await == "stopped").then_some(())
    })
    .await;
    let stopped = commanded(&c).await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    assert_eq!(commanded(&c).await, stopped);

    // An injected fault: the X limit switch at X-5.
    let machine = out.join(format!("switch-x-{}.toml", std::process::id()));
    std::fs::write(&machine, SWITCH_X_MILL).expect("machine file");
    let (_faulty, fault_url) = start_server(Some(&machine));
    load_program(&c, &fault_url, "rectangle.h").await;
    click(&c, "start").await;
    let message = wait_for("the fault message", || async {
        let visible = c
            .find(Locator::Id("message"))
            .await
            .ok()?
            .is_displayed()
            .await
            .ok()?;
        let m = text(&c, "message").await;
        (visible && !m.is_empty()).then_some(m)
    })
    .await;
    assert!(
        message.contains("axis X") && message.contains("negative limit switch"),
        "{message}"
    );
    assert_eq!(text(&c, "state").await, "fault");
    // The axis got to the switch, not to the programmed X-10.
    let x = number(&c, "act-X").await;
    assert!((-10.0..=-5.0).contains(&x), "X stopped at {x}");
    let shot = c.screenshot().await.expect("screenshot");
    std::fs::write(out.join("dashboard-fault.png"), &shot).expect("screenshot saved");
    let _ = std::fs::remove_file(&machine);
    c.close().await.expect("browser closes");
    let _ = std::fs::remove_dir_all(&profile);
}
