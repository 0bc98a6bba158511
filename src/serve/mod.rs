//! `klar serve`: the lab-bench dashboard — an HTTP and WebSocket server on tokio with the
//! page (HTML, JavaScript, CSS) built into the binary.
//!
//! The machine runs on a thread of its own ([`session::MachineLoop`]); the web side sends it
//! [`session::Command`]s and streams its [`session::Snapshot`]s to every open page over a
//! WebSocket. The server binds to 127.0.0.1 unless told otherwise; any other address needs
//! an access token, which every API call and the WebSocket must then carry.
//!
//! Routes: `GET /` (the page), `GET /app.js`, `GET /style.css`, `GET /api/machine`,
//! `GET /api/programs`, `GET /api/program?name=N` (text and planned toolpath),
//! `GET /api/status`, `POST /api/load` `{"name": N}`, `POST /api/start`, `/api/hold`,
//! `/api/resume`, `/api/stop`, `POST /api/override` `{"factor": F}`,
//! `POST /api/single_block` `{"on": B}`, `POST /api/jog`, `POST /api/home`,
//! `POST /api/mdi`, `POST /api/reset`, `POST /api/upload`, `GET /ws` (snapshots as JSON
//! text messages); docs/dashboard.md has the bodies and answers.

mod api;
pub mod manual;
mod program;
pub mod session;

use crate::config::MachineConfig;
use crate::runtime::{OperatorStop, StopLevel};
use std::net::SocketAddr;
use std::path::PathBuf;

pub use api::router;

/// How often the server looks whether a stop was requested.
const STOP_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// How to serve.
#[derive(Debug, Clone)]
pub struct ServeOptions {
    /// Address to listen on (port 0 picks a free port).
    pub listen: SocketAddr,
    /// Access token; required when `listen` is not a loopback address.
    pub token: Option<String>,
    /// Folder whose programs (.h, .i, .nc, also one level down) the page offers.
    pub programs: PathBuf,
    /// The machine.
    pub machine: MachineConfig,
}

/// Why the server could not run.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// A non-loopback address without a token.
    #[error("listening on {0} (not a loopback address) needs --token")]
    RemoteWithoutToken(SocketAddr),
    /// The token is too short to be worth anything.
    #[error("the access token must have at least 8 characters")]
    WeakToken,
    /// The address could not be bound, or serving failed.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The machine thread could not be started.
    #[error("machine thread: {0}")]
    Thread(String),
}

/// Checks the options: remote access only with a token.
pub fn check_access(options: &ServeOptions) -> Result<(), ServeError> {
    if let Some(t) = &options.token
        && t.chars().count() < 8
    {
        return Err(ServeError::WeakToken);
    }
    if !options.listen.ip().is_loopback() && options.token.is_none() {
        return Err(ServeError::RemoteWithoutToken(options.listen));
    }
    Ok(())
}

/// Binds the listener, starts the machine thread and serves until the runtime is shut down.
/// `ready` is called with the bound address once the server accepts connections.
pub async fn serve(
    options: ServeOptions,
    ready: impl FnOnce(SocketAddr),
) -> Result<(), ServeError> {
    serve_until(options, OperatorStop::new(), ready).await
}

/// Like [`serve`], until `stop` is requested (the `klar` binary requests it on SIGINT and
/// SIGTERM): a running program then stops under control (a feed hold on the path; a second
/// request makes it a quick stop), the server stops accepting connections, and this returns
/// once the machine thread has brought the machine to rest and ended.
pub async fn serve_until(
    options: ServeOptions,
    stop: OperatorStop,
    ready: impl FnOnce(SocketAddr),
) -> Result<(), ServeError> {
    check_access(&options)?;
    let listener = tokio::net::TcpListener::bind(options.listen).await?;
    let addr = listener.local_addr()?;
    let (app, machine) =
        api::App::start(&options, stop.clone()).map_err(|e| ServeError::Thread(e.to_string()))?;
    ready(addr);
    tracing::info!(%addr, "dashboard listening");
    let requested = stop.clone();
    let served = axum::serve(listener, router(app))
        .with_graceful_shutdown(async move {
            while requested.level() == StopLevel::None {
                tokio::time::sleep(STOP_POLL).await;
            }
        })
        .await;
    // The machine thread ends once a stop is requested (after bringing a running program to
    // rest); a server that failed asks for it too.
    if stop.level() == StopLevel::None {
        stop.request();
    }
    let joined = tokio::task::spawn_blocking(move || machine.join()).await;
    if !matches!(joined, Ok(Ok(()))) {
        return Err(ServeError::Thread("the machine thread panicked".into()));
    }
    served?;
    tracing::info!("dashboard stopped");
    Ok(())
}
