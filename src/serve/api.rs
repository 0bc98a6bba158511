//! The dashboard's HTTP routes and WebSocket, and the access-token check.

use super::ServeOptions;
use super::manual::{ManualOp, Refusal, is_lathe};
use super::program::{ProgramView, program_view, wrong_machine};
use super::session::{Command, MachineLoop, MachineState, Snapshot, idle_snapshot};
use crate::config::MachineConfig;
use crate::runtime::OperatorStop;
use axum::Json;
use axum::Router;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Query, Request, State};
use axum::http::{HeaderValue, StatusCode, header};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};
use tokio::sync::broadcast;

const INDEX_HTML: &str = include_str!("assets/index.html");
const APP_JS: &str = include_str!("assets/app.js");
const STYLE_CSS: &str = include_str!("assets/style.css");
const VIEW_JS: &str = include_str!("assets/view.js");

mod spindle;

/// Largest program text `POST /api/upload` accepts, bytes.
pub const MAX_UPLOAD: usize = 1024 * 1024;

/// Longest program name `POST /api/upload` accepts, characters.
const MAX_UPLOAD_NAME: usize = 100;

/// How long an API call waits for the machine thread's answer (a test run of a manual
/// block, or a homing sequence in simulated time).
const REPLY_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(60);

/// Program file extensions the page offers.
const PROGRAM_EXTENSIONS: [&str; 3] = ["h", "i", "nc"];

/// Shared state of the web side: the channel to the machine thread and what it published.
#[derive(Clone)]
pub struct App {
    inner: Arc<Inner>,
}

struct Inner {
    commands: Mutex<Sender<Command>>,
    snapshots: broadcast::Sender<Snapshot>,
    latest: Arc<Mutex<Snapshot>>,
    programs: PathBuf,
    token: Option<String>,
    machine: MachineConfig,
}

impl App {
    /// Starts the machine thread for `options.machine`, which watches `stop` (it ends a
    /// running program under control and the thread once asked); returns the app and the
    /// thread.
    pub fn start(
        options: &ServeOptions,
        stop: OperatorStop,
    ) -> std::io::Result<(Self, std::thread::JoinHandle<()>)> {
        let (tx, rx) = std::sync::mpsc::channel();
        let (snapshots, _) = broadcast::channel(256);
        let latest = Arc::new(Mutex::new(idle_snapshot(&options.machine)));
        let (config, to_pages, slot) = (options.machine.clone(), snapshots.clone(), latest.clone());
        // Built on its thread: what it holds between runs (a spindle) stays there.
        let thread = std::thread::Builder::new()
            .name("klar-machine".into())
            .spawn(move || match MachineLoop::new(config, rx, to_pages, slot) {
                Ok(m) => m.with_operator_stop(stop).run(),
                Err(e) => tracing::error!("the snapshot publisher could not start: {e}"),
            })?;
        let app = App {
            inner: Arc::new(Inner {
                commands: Mutex::new(tx),
                snapshots,
                latest,
                programs: options.programs.clone(),
                token: options.token.clone(),
                machine: options.machine.clone(),
            }),
        };
        Ok((app, thread))
    }

    fn send(&self, command: Command) -> Result<(), ApiError> {
        let tx = self
            .inner
            .commands
            .lock()
            .map_err(|_| ApiError::MachineGone)?;
        tx.send(command).map_err(|_| ApiError::MachineGone)
    }

    fn latest(&self) -> Option<Snapshot> {
        self.inner.latest.lock().ok().map(|s| s.clone())
    }
}

/// Why an API call failed; answered as a status code with a JSON `{"error": ...}` body.
#[derive(Debug, thiserror::Error)]
enum ApiError {
    #[error("missing or wrong access token")]
    Unauthorized,
    #[error("request from another site or host refused")]
    CrossSite,
    #[error("no program named {0:?} in the programs folder")]
    UnknownProgram(String),
    #[error("cannot read the program: {0}")]
    Read(String),
    #[error("the machine thread has ended")]
    MachineGone,
    #[error("a program is running: stop it first")]
    Busy,
    #[error("{0}")]
    Refused(Refusal),
    #[error("{0}")]
    BadRequest(String),
    #[error("the machine thread did not answer in time")]
    NoAnswer,
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let code = match &self {
            ApiError::Unauthorized => StatusCode::UNAUTHORIZED,
            ApiError::CrossSite => StatusCode::FORBIDDEN,
            ApiError::UnknownProgram(_) => StatusCode::NOT_FOUND,
            ApiError::Busy => StatusCode::CONFLICT,
            ApiError::Refused(r) if r.is_conflict() => StatusCode::CONFLICT,
            ApiError::Refused(_) | ApiError::BadRequest(_) => StatusCode::UNPROCESSABLE_ENTITY,
            ApiError::Read(_) | ApiError::MachineGone | ApiError::NoAnswer => {
                StatusCode::INTERNAL_SERVER_ERROR
            }
        };
        (code, Json(serde_json::json!({ "error": self.to_string() }))).into_response()
    }
}

/// The dashboard's routes on `app`.
pub fn router(app: App) -> Router {
    let api =
        Router::new()
            .route("/api/machine", get(machine))
            .route("/api/programs", get(programs))
            .route("/api/program", get(program))
            .route("/api/status", get(status))
            .route("/api/load", post(load))
            .route(
                "/api/start",
                post(|State(app): State<App>| async move {
                    ask(&app, |r| Command::Start(Some(r))).await
                }),
            )
            .route(
                "/api/reset",
                post(|State(app): State<App>| async move { ask(&app, Command::Reset).await }),
            )
            .route("/api/jog", post(jog))
            .route("/api/home", post(home))
            .route("/api/mdi", post(mdi))
            .route("/api/spindle", post(spindle::spindle))
            .route("/api/upload", post(upload))
            .route("/api/hold", post(|s: State<App>| simple(s, Command::Hold)))
            .route(
                "/api/resume",
                post(|s: State<App>| simple(s, Command::Resume)),
            )
            .route("/api/stop", post(|s: State<App>| simple(s, Command::Stop)))
            .route("/api/override", post(feed_override))
            .route("/api/single_block", post(single_block))
            .route("/ws", get(ws))
            .route_layer(middleware::from_fn_with_state(app.clone(), require_token));
    Router::new()
        .route("/", get(|| asset(INDEX_HTML, "text/html; charset=utf-8")))
        .route(
            "/app.js",
            get(|| asset(APP_JS, "text/javascript; charset=utf-8")),
        )
        .route(
            "/view.js",
            get(|| asset(VIEW_JS, "text/javascript; charset=utf-8")),
        )
        .route(
            "/style.css",
            get(|| asset(STYLE_CSS, "text/css; charset=utf-8")),
        )
        .merge(api)
        .with_state(app)
}

async fn asset(body: &'static str, content_type: &'static str) -> Response {
    let mut r = body.into_response();
    r.headers_mut()
        .insert(header::CONTENT_TYPE, HeaderValue::from_static(content_type));
    r
}

/// Lets a request through when it comes from the page itself (no `Origin` of another site,
/// so a web page elsewhere cannot start the machine through the operator's browser) and, on
/// a server without a token, names a loopback host (no DNS rebinding); with a token it must
/// carry it as `?token=` or `Authorization: Bearer`.
async fn require_token(State(app): State<App>, request: Request, next: Next) -> Response {
    let host = request
        .headers()
        .get(header::HOST)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("");
    let origin = request
        .headers()
        .get(header::ORIGIN)
        .map(|v| v.to_str().unwrap_or("?"));
    if let Some(o) = origin {
        let o = o
            .strip_prefix("http://")
            .or_else(|| o.strip_prefix("https://"))
            .unwrap_or("?");
        if !o.eq_ignore_ascii_case(host) {
            return ApiError::CrossSite.into_response();
        }
    }
    let Some(expected) = &app.inner.token else {
        if !is_loopback_host(host) {
            return ApiError::CrossSite.into_response();
        }
        return next.run(request).await;
    };
    let from_query = request
        .uri()
        .query()
        .unwrap_or("")
        .split('&')
        .find_map(|kv| kv.strip_prefix("token="))
        .map(str::to_string);
    let from_header = request
        .headers()
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "))
        .map(str::to_string);
    let ok = [from_query, from_header]
        .iter()
        .flatten()
        .any(|given| same_secret(given, expected));
    if ok {
        next.run(request).await
    } else {
        ApiError::Unauthorized.into_response()
    }
}

/// True for `localhost`, `127.x.x.x` or `[::1]`, with or without a port.
fn is_loopback_host(host: &str) -> bool {
    let name = match host.strip_prefix('[') {
        Some(v6) => v6.split(']').next().unwrap_or(""),
        None => host.split(':').next().unwrap_or(""),
    };
    name.eq_ignore_ascii_case("localhost")
        || name
            .parse::<std::net::IpAddr>()
            .is_ok_and(|ip| ip.is_loopback())
}

/// Compares two secrets in time that depends only on their lengths.
fn same_secret(a: &str, b: &str) -> bool {
    a.len() == b.len()
        && a.bytes()
            .zip(b.bytes())
            .fold(0u8, |acc, (x, y)| acc | (x ^ y))
            == 0
}

/// The machine as the page shows it.
#[derive(Serialize)]
struct MachineInfo {
    name: String,
    letters: Vec<String>,
    travel: Vec<[f64; 2]>,
    servo_period: f64,
    /// The preset programs start from (the machine file's `active_preset`), in words.
    preset: String,
    /// True for a lathe (its programs are lathe DIN).
    lathe: bool,
    /// The tool table: number, name, length, radius (empty without one).
    tools: Vec<ToolRow>,
    /// The spindle's highest speed, rpm; `None` without a spindle.
    spindle_max_rpm: Option<f64>,
}

/// One row of the tool table as the page shows it.
#[derive(Serialize)]
struct ToolRow {
    number: u32,
    name: String,
    length: f64,
    radius: f64,
}

async fn machine(State(app): State<App>) -> Json<MachineInfo> {
    let m = &app.inner.machine;
    Json(MachineInfo {
        name: m.name.clone(),
        letters: m.axes.iter().map(|a| a.letter.to_string()).collect(),
        travel: m.axes.iter().map(|a| a.travel).collect(),
        servo_period: m.servo_period,
        preset: match m.active_preset() {
            Ok(p) => p.to_string(),
            Err(e) => e,
        },
        lathe: is_lathe(m),
        spindle_max_rpm: m.spindle.as_ref().map(|s| s.max_rpm),
        tools: match m.tool_table() {
            Ok(Some(t)) => t
                .iter()
                .map(|t| ToolRow {
                    number: t.number,
                    name: t.name.clone(),
                    length: t.length,
                    radius: t.radius,
                })
                .collect(),
            _ => Vec::new(),
        },
    })
}

/// Program files under `dir` (and one folder level down), as `/`-separated relative names.
fn list_programs(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut visit = |sub: &str| {
        let Ok(entries) = std::fs::read_dir(dir.join(sub)) else {
            return Vec::new();
        };
        let mut dirs = Vec::new();
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let rel = if sub.is_empty() {
                name.clone()
            } else {
                format!("{sub}/{name}")
            };
            let path = e.path();
            if path.is_dir() {
                dirs.push(rel);
            } else if path
                .extension()
                .is_some_and(|x| PROGRAM_EXTENSIONS.iter().any(|p| x.eq_ignore_ascii_case(p)))
            {
                out.push(rel);
            }
        }
        dirs
    };
    for sub in visit("") {
        visit(&sub);
    }
    out.sort();
    out
}

async fn programs(State(app): State<App>) -> Json<Vec<String>> {
    let dir = app.inner.programs.clone();
    Json(
        tokio::task::spawn_blocking(move || list_programs(&dir))
            .await
            .unwrap_or_default(),
    )
}

/// Resolves a program name to its file; only names the listing offers are accepted.
async fn resolve(app: &App, name: &str) -> Result<PathBuf, ApiError> {
    let dir = app.inner.programs.clone();
    let listed = tokio::task::spawn_blocking(move || list_programs(&dir))
        .await
        .unwrap_or_default();
    if listed.iter().any(|n| n == name) {
        Ok(app.inner.programs.join(name))
    } else {
        Err(ApiError::UnknownProgram(name.to_string()))
    }
}

#[derive(Deserialize)]
struct NameQuery {
    name: String,
}

async fn program(
    State(app): State<App>,
    Query(q): Query<NameQuery>,
) -> Result<Json<ProgramView>, ApiError> {
    let path = resolve(&app, &q.name).await?;
    let standing = match app.latest() {
        Some(s) => app.inner.machine.starting_at(s.actual),
        None => app.inner.machine.clone(),
    };
    let name = q.name.clone();
    let inner = Arc::clone(&app.inner);
    let view = tokio::task::spawn_blocking(move || {
        program_view(name, &path, &inner.machine, &standing).map_err(ApiError::Read)
    })
    .await
    .map_err(|e| ApiError::Read(e.to_string()))??;
    Ok(Json(view))
}

async fn status(State(app): State<App>) -> Result<Json<Snapshot>, ApiError> {
    app.latest().map(Json).ok_or(ApiError::MachineGone)
}

#[derive(Deserialize)]
struct LoadRequest {
    name: String,
}

async fn load(
    State(app): State<App>,
    Json(req): Json<LoadRequest>,
) -> Result<StatusCode, ApiError> {
    let path = resolve(&app, &req.name).await?;
    let running = app
        .latest()
        .is_some_and(|s| matches!(s.state, MachineState::Running | MachineState::Held));
    if running {
        return Err(ApiError::Busy);
    }
    if let Some(why) = wrong_machine(&path, &app.inner.machine) {
        return Err(ApiError::BadRequest(why));
    }
    app.send(Command::Load {
        name: req.name,
        path,
    })?;
    Ok(StatusCode::NO_CONTENT)
}

/// Sends a command that the machine thread answers, and answers with its verdict.
async fn ask(
    app: &App,
    command: impl FnOnce(super::session::Reply) -> Command,
) -> Result<StatusCode, ApiError> {
    let (tx, rx) = tokio::sync::oneshot::channel();
    app.send(command(tx))?;
    match tokio::time::timeout(REPLY_TIMEOUT, rx).await {
        Ok(Ok(Ok(()))) => Ok(StatusCode::NO_CONTENT),
        Ok(Ok(Err(r))) => Err(ApiError::Refused(r)),
        Ok(Err(_)) => Err(ApiError::MachineGone),
        Err(_) => Err(ApiError::NoAnswer),
    }
}

/// `POST /api/jog`: `{"axis", "distance", "speed"}` moves by the distance;
/// `{"axis", "direction", "speed"}` moves until `POST /api/stop` or the end of the travel.
#[derive(Deserialize)]
struct JogRequest {
    axis: String,
    distance: Option<f64>,
    direction: Option<f64>,
    speed: f64,
}

async fn jog(State(app): State<App>, Json(req): Json<JogRequest>) -> Result<StatusCode, ApiError> {
    let op = match (req.distance, req.direction) {
        (Some(distance), None) => ManualOp::Jog {
            axis: req.axis,
            distance,
            speed: req.speed,
        },
        (None, Some(direction)) => ManualOp::JogContinuous {
            axis: req.axis,
            direction,
            speed: req.speed,
        },
        _ => {
            return Err(ApiError::BadRequest(
                "a jog has either a distance or a direction".into(),
            ));
        }
    };
    ask(&app, |r| Command::Manual(op, r)).await
}

#[derive(Deserialize)]
struct HomeRequest {
    axis: Option<String>,
}

/// `POST /api/home`: no body (or `{}`) homes every axis, `{"axis": "X"}` one.
async fn home(State(app): State<App>, body: axum::body::Bytes) -> Result<StatusCode, ApiError> {
    let axis = if body.iter().all(u8::is_ascii_whitespace) {
        None
    } else {
        serde_json::from_slice::<HomeRequest>(&body)
            .map_err(|e| ApiError::BadRequest(format!("home: {e}")))?
            .axis
    };
    ask(&app, |r| Command::Manual(ManualOp::Home { axis }, r)).await
}

#[derive(Deserialize)]
struct MdiRequest {
    block: String,
}

async fn mdi(State(app): State<App>, Json(req): Json<MdiRequest>) -> Result<StatusCode, ApiError> {
    let op = ManualOp::Mdi { block: req.block };
    ask(&app, |r| Command::Manual(op, r)).await
}

#[derive(Deserialize)]
struct UploadRequest {
    name: String,
    text: String,
}

/// Why `name` is no name an uploaded program may have: a plain file name (no folders, no
/// leading dot, printable) of at most [`MAX_UPLOAD_NAME`] characters with a program
/// extension.
fn bad_upload_name(name: &str) -> Option<String> {
    if name.is_empty() || name.chars().count() > MAX_UPLOAD_NAME {
        return Some(format!(
            "a program name has 1 to {MAX_UPLOAD_NAME} characters"
        ));
    }
    if name.contains(['/', '\\', ':']) || name.starts_with('.') {
        return Some(format!(
            "{name:?}: a program name is a plain file name, without folders"
        ));
    }
    if name.chars().any(char::is_control) {
        return Some("a program name has no control characters".into());
    }
    let ext = Path::new(name)
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("");
    if !PROGRAM_EXTENSIONS
        .iter()
        .any(|p| ext.eq_ignore_ascii_case(p))
    {
        return Some(format!(
            "{name:?}: a program name ends in .h (Klartext), .i (ISO) or .nc (lathe DIN)"
        ));
    }
    None
}

/// `POST /api/upload`: saves the text as a program in the programs folder (a file of that
/// name is replaced, unless it is the program running).
async fn upload(
    State(app): State<App>,
    Json(req): Json<UploadRequest>,
) -> Result<Response, ApiError> {
    if let Some(why) = bad_upload_name(&req.name) {
        return Err(ApiError::BadRequest(why));
    }
    if req.text.len() > MAX_UPLOAD {
        return Err(ApiError::BadRequest(format!(
            "the program has {} bytes; at most {MAX_UPLOAD} are accepted",
            req.text.len()
        )));
    }
    let running = app.latest().is_some_and(|s| {
        matches!(s.state, MachineState::Running | MachineState::Held)
            && s.program.as_deref() == Some(req.name.as_str())
    });
    if running {
        return Err(ApiError::Busy);
    }
    let dir = app.inner.programs.clone();
    let name = req.name.clone();
    tokio::task::spawn_blocking(move || {
        std::fs::create_dir_all(&dir)?;
        // Written beside and renamed: a reader never sees half a program.
        let part = dir.join(format!(".{name}.part"));
        std::fs::write(&part, req.text.as_bytes())?;
        std::fs::rename(&part, dir.join(&name))
    })
    .await
    .map_err(|e| ApiError::Read(e.to_string()))?
    .map_err(|e| ApiError::Read(format!("cannot save the program: {e}")))?;
    Ok((
        StatusCode::CREATED,
        Json(serde_json::json!({ "name": req.name })),
    )
        .into_response())
}

async fn simple(State(app): State<App>, command: Command) -> Result<StatusCode, ApiError> {
    app.send(command)?;
    Ok(StatusCode::NO_CONTENT)
}

#[derive(Deserialize)]
struct OverrideRequest {
    factor: f64,
}

async fn feed_override(
    State(app): State<App>,
    Json(req): Json<OverrideRequest>,
) -> Result<StatusCode, ApiError> {
    app.send(Command::Override(req.factor))?;
    Ok(StatusCode::NO_CONTENT)
}

#[derive(Deserialize)]
struct SingleBlockRequest {
    on: bool,
}

async fn single_block(
    State(app): State<App>,
    Json(req): Json<SingleBlockRequest>,
) -> Result<StatusCode, ApiError> {
    app.send(Command::SingleBlock(req.on))?;
    Ok(StatusCode::NO_CONTENT)
}

async fn ws(State(app): State<App>, upgrade: WebSocketUpgrade) -> Response {
    upgrade.on_upgrade(move |socket| stream_snapshots(app, socket))
}

/// Sends the latest snapshot, then every new one, until the page goes away.
async fn stream_snapshots(app: App, mut socket: WebSocket) {
    let mut rx = app.inner.snapshots.subscribe();
    if let Some(s) = app.latest()
        && send_snapshot(&mut socket, &s).await.is_err()
    {
        return;
    }
    loop {
        tokio::select! {
            got = rx.recv() => match got {
                Ok(s) => {
                    if send_snapshot(&mut socket, &s).await.is_err() {
                        return;
                    }
                }
                Err(broadcast::error::RecvError::Lagged(n)) => {
                    tracing::debug!(skipped = n, "slow page: snapshots skipped");
                }
                Err(broadcast::error::RecvError::Closed) => return,
            },
            msg = socket.recv() => match msg {
                Some(Ok(Message::Close(_))) | None | Some(Err(_)) => return,
                Some(Ok(_)) => {}
            },
        }
    }
}

async fn send_snapshot(socket: &mut WebSocket, s: &Snapshot) -> Result<(), axum::Error> {
    let text = serde_json::to_string(s).unwrap_or_else(|_| "{}".into());
    socket.send(Message::Text(text.into())).await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_hosts_are_told_from_others() {
        for h in [
            "localhost:8080",
            "127.0.0.1:80",
            "127.1.2.3",
            "[::1]:8080",
            "LOCALHOST",
        ] {
            assert!(is_loopback_host(h), "{h}");
        }
        for h in [
            "",
            "evil.example:8080",
            "10.0.0.1:8080",
            "[::2]:80",
            "localhost.evil",
        ] {
            assert!(!is_loopback_host(h), "{h}");
        }
    }

    #[test]
    fn secrets_compare_by_content() {
        assert!(same_secret("abcdefgh", "abcdefgh"));
        assert!(!same_secret("abcdefgh", "abcdefgX"));
        assert!(!same_secret("abcdefgh", "abcdefg"));
    }

    #[test]
    fn upload_names_are_plain_program_file_names() {
        for ok in ["part.h", "P1.I", "shaft 2.nc"] {
            assert_eq!(bad_upload_name(ok), None, "{ok}");
        }
        let long = format!("{}.h", "a".repeat(MAX_UPLOAD_NAME));
        for bad in [
            "",
            "../x.h",
            "sub/x.h",
            "a\\b.h",
            ".hidden.h",
            "c:x.h",
            "x.txt",
            "x",
            "x\n.h",
            long.as_str(),
        ] {
            assert!(bad_upload_name(bad).is_some(), "{bad:?}");
        }
    }

    #[test]
    fn the_listing_offers_programs_one_level_down_and_nothing_else() {
        let dir = std::env::temp_dir().join(format!("klar-list-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("iso/deeper")).unwrap();
        for f in ["a.h", "b.TXT", "iso/c.i", "iso/deeper/d.h", "e.NC"] {
            std::fs::write(dir.join(f), "").unwrap();
        }
        assert_eq!(list_programs(&dir), vec!["a.h", "e.NC", "iso/c.i"]);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
