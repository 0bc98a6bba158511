//! The dashboard on a lathe, the spindle by hand and touch-probe results in Chromium: the
//! lathe's view (Z across, X up, framed on the cutting moves, an X ⌀ ruler) and its DRO (X as
//! a diameter, the radius in small print and in the tooltip) at 1280 px and at 360 px with
//! every control inside the viewport; the main spindle on and off from the page, its
//! measured speed reaching the command; a probing program on the probing mill whose results
//! and written preset the page shows. Screenshots go to `target/screenshots/`.

use super::manual::{outside, shot, wait_state};
use super::{browser, click, load_program, start_driver, start_server_on, text, wait_for};
use fantoccini::{Client, Locator};
use std::path::Path;

/// The page's script state, read through `expr` (a JavaScript expression).
async fn eval(c: &Client, expr: &str) -> serde_json::Value {
    c.execute(&format!("return {expr};"), vec![])
        .await
        .unwrap_or_else(|e| panic!("{expr}: {e}"))
}

async fn attr(c: &Client, id: &str, name: &str) -> String {
    c.find(Locator::Id(id))
        .await
        .unwrap_or_else(|e| panic!("#{id}: {e}"))
        .attr(name)
        .await
        .unwrap_or_else(|e| panic!("#{id}: {e}"))
        .unwrap_or_default()
}

async fn visible(c: &Client, id: &str) -> bool {
    c.find(Locator::Id(id))
        .await
        .unwrap_or_else(|e| panic!("#{id}: {e}"))
        .is_displayed()
        .await
        .unwrap_or_else(|e| panic!("#{id}: {e}"))
}

/// No control outside the viewport's width, and no sideways scrolling.
async fn all_inside(c: &Client, width: u32) {
    let (out, _, _) = outside(c).await;
    assert!(
        out.is_empty(),
        "outside the viewport at {width} px: {out:?}"
    );
}

pub(super) async fn scenario() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("browser");
    std::fs::create_dir_all(&out).expect("artifact folder");
    let (_server, url) = start_server_on(
        Some(&root.join("machines/lathe.toml")),
        &root.join("programs/lathe"),
    );
    let (_driver, driver_url) = start_driver().await;
    let profile = out.join(format!("profile-lathe-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&profile);
    let c = browser(&driver_url, &profile).await;
    c.set_window_size(1280, 900).await.expect("window size");
    load_program(&c, &url, "shaft_turning.nc").await;

    // The lathe's view: Z across, X up; the milling views are not offered.
    assert!(visible(&c, "lathe-view").await);
    assert_eq!(
        eval(&c, "project([10, 0, 30])").await,
        serde_json::json!([30, 10])
    );
    assert_eq!(
        eval(&c, "document.querySelector('.mill-view').hidden").await,
        true
    );
    // The cutting moves fill the view, the tool change point (X radius 100, Z 200) far off
    // notwithstanding: their extent on the canvas is at least half of it one way.
    let fill = eval(
        &c,
        "(() => { const cv = $('toolpath'); let x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9; \
           for (const s of state.planned) if (!s.rapid) for (const p of s.points) { \
             const [a, b] = state.toScreen(project(p)); \
             x0 = Math.min(x0, a); x1 = Math.max(x1, a); y0 = Math.min(y0, b); y1 = Math.max(y1, b); } \
           return [x0, x1, y0, y1, cv.width, cv.height]; })()",
    )
    .await;
    let f: Vec<f64> = fill
        .as_array()
        .expect("extent")
        .iter()
        .map(|v| v.as_f64().unwrap_or(f64::NAN))
        .collect();
    assert!(
        f[0] >= 0.0 && f[1] <= f[4] && f[2] >= 0.0 && f[3] <= f[5],
        "inside: {f:?}"
    );
    assert!(
        f[1] - f[0] > 0.5 * f[4] || f[3] - f[2] > 0.5 * f[5],
        "the cutting moves fill the view: {f:?}"
    );
    // The DRO: X as a diameter, the radius in small print and in the tooltip.
    let x = text(&c, "act-X").await;
    assert!(x.starts_with("⌀ +200.000"), "{x}");
    assert!(x.contains("r +100.000"), "{x}");
    assert_eq!(
        attr(&c, "act-X", "title").await,
        "diameter; radius +100.000"
    );
    assert_eq!(text(&c, "act-Z").await, "+200.000");

    // The main spindle from the page.
    assert!(text(&c, "spindle-bar").await.contains("main spindle"));
    let speed = c.find(Locator::Id("spindle-speed")).await.expect("speed");
    speed.clear().await.expect("clear");
    speed.send_keys("800").await.expect("type");
    click(&c, "spindle-cw").await;
    wait_for("the spindle at 800 rpm", || async {
        (text(&c, "spindle").await == "M3 ⟳ 800 / 800 rpm").then_some(())
    })
    .await;
    shot(&c, "lathe-1280.png").await;
    all_inside(&c, 1280).await;
    c.set_window_size(360, 780).await.expect("window size");
    tokio::time::sleep(std::time::Duration::from_millis(300)).await;
    all_inside(&c, 360).await;
    shot(&c, "lathe-360.png").await;
    c.set_window_size(1280, 900).await.expect("window size");
    click(&c, "spindle-stop").await;
    wait_for("the spindle at rest", || async {
        (text(&c, "spindle").await == "M5 / 0 rpm").then_some(())
    })
    .await;
    c.close().await.expect("browser closes");
    let _ = std::fs::remove_dir_all(&profile);

    // A probing program on the probing mill: its results and the preset written.
    let (_server, url) = start_server_on(
        Some(&root.join("machines/probing-mill.toml")),
        &root.join("programs"),
    );
    let profile = out.join(format!("profile-probe-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&profile);
    let c = browser(&driver_url, &profile).await;
    c.set_window_size(1280, 900).await.expect("window size");
    load_program(&c, &url, "probing_412.h").await;
    assert!(!visible(&c, "probe-box").await, "no results before the run");
    click(&c, "start").await;
    wait_state(&c, "finished").await;
    assert!(visible(&c, "probe-box").await);
    assert_eq!(text(&c, "probe-cycle").await, "cycle 412");
    let params = text(&c, "probe-params").await;
    assert!(params.contains("Q153 = +24.0000"), "{params}");
    let preset = text(&c, "probe-preset").await;
    assert!(
        preset.starts_with("written to preset 1 (active): X +78.4"),
        "{preset}"
    );
    shot(&c, "probe-1280.png").await;
    c.close().await.expect("browser closes");
    let _ = std::fs::remove_dir_all(&profile);
}
