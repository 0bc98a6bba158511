//! SIGINT and SIGTERM as operator stops for `klar run` and `klar serve`: the handlers are
//! installed here, in the binary only, and turn every signal into one
//! [`OperatorStop::request`]; the runtime looks at the request once per servo cycle.
//!
//! A thread of its own waits for the signals on a small tokio runtime (tokio's `signal`
//! feature), so the servo loop never does more than an atomic load. The first signal's number
//! is kept for the exit code: 128 + the signal number, as shells report a death by signal
//! (130 for SIGINT, 143 for SIGTERM), though the process ended under control.

use klar::runtime::{OperatorStop, StopLevel};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};
use tokio::signal::unix::{SignalKind, signal};

/// SIGINT's number.
const SIGINT: u8 = 2;
/// SIGTERM's number.
const SIGTERM: u8 = 15;

/// The installed handlers: the stop request they make and the first signal seen.
pub struct SignalWatch {
    stop: OperatorStop,
    first: Arc<AtomicU8>,
}

impl SignalWatch {
    /// Installs the SIGINT and SIGTERM handlers; from now on those signals no longer end the
    /// process but request a stop.
    pub fn install() -> std::io::Result<Self> {
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()?;
        // Registered here, before the run starts, so no signal finds the default action.
        let (mut interrupt, mut terminate) = {
            let _entered = runtime.enter();
            (
                signal(SignalKind::interrupt())?,
                signal(SignalKind::terminate())?,
            )
        };
        let stop = OperatorStop::new();
        let first = Arc::new(AtomicU8::new(0));
        let (asked, first_seen) = (stop.clone(), first.clone());
        std::thread::Builder::new()
            .name("klar-signals".into())
            .spawn(move || {
                runtime.block_on(async move {
                    loop {
                        let number = tokio::select! {
                            Some(()) = interrupt.recv() => SIGINT,
                            Some(()) = terminate.recv() => SIGTERM,
                            else => break,
                        };
                        // Only the first signal names the exit code.
                        let _ = first_seen.compare_exchange(
                            0,
                            number,
                            Ordering::SeqCst,
                            Ordering::SeqCst,
                        );
                        let what = match asked.request() {
                            StopLevel::Quick => "quick stop",
                            _ => "controlled stop (a second signal: quick stop)",
                        };
                        tracing::info!(signal = number, "signal: {what}");
                    }
                });
            })?;
        Ok(Self { stop, first })
    }

    /// The stop request the signals make, for the run or the server to watch.
    pub fn stop(&self) -> OperatorStop {
        self.stop.clone()
    }

    /// The exit code for a run the signals stopped: 128 + the first signal's number.
    pub fn exit_code(&self) -> ExitCode {
        match self.first.load(Ordering::SeqCst) {
            0 => ExitCode::FAILURE,
            n => ExitCode::from(128u8.saturating_add(n)),
        }
    }
}
