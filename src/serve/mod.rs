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
//! `POST /api/single_block` `{"on": B}`, `GET /ws` (snapshots as JSON text messages).

mod api;
pub mod session;

use crate::config::MachineConfig;
use std::net::SocketAddr;
use std::path::PathBuf;

pub use api::router;

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

/// Binds the listener, starts the machine thread and serves until Ctrl-C. `ready` is called
/// with the bound address once the server accepts connections.
pub async fn serve(
    options: ServeOptions,
    ready: impl FnOnce(SocketAddr),
) -> Result<(), ServeError> {
    check_access(&options)?;
    let listener = tokio::net::TcpListener::bind(options.listen).await?;
    let addr = listener.local_addr()?;
    let app = api::App::start(&options).map_err(|e| ServeError::Thread(e.to_string()))?;
    ready(addr);
    tracing::info!(%addr, "dashboard listening");
    axum::serve(listener, router(app))
        .with_graceful_shutdown(async {
            let _ = tokio::signal::ctrl_c().await;
        })
        .await?;
    Ok(())
}
