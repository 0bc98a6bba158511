//! The thread that owns a Modbus link: a small tokio runtime polling one device, so the
//! servo loop never waits for the serial line.

use std::future::Future;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use super::{ModbusError, SerialLineConfig, link::ModbusLink};

/// Shared, lock-protected state between a backend handle and its worker.
#[derive(Debug, Default)]
pub(crate) struct Shared<T>(Arc<Mutex<T>>);

impl<T> Clone for Shared<T> {
    fn clone(&self) -> Self {
        Self(Arc::clone(&self.0))
    }
}

impl<T> Shared<T> {
    pub(crate) fn new(value: T) -> Self {
        Self(Arc::new(Mutex::new(value)))
    }

    /// Locks; a worker that panicked while holding the lock leaves usable data behind.
    pub(crate) fn lock(&self) -> MutexGuard<'_, T> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// A command with a reply channel.
pub(crate) struct Call<C> {
    pub(crate) command: C,
    pub(crate) reply: SyncSender<Result<(), ModbusError>>,
}

/// Sends a command to the worker and waits for its answer at most `wait`.
pub(crate) fn call<C>(
    commands: &tokio::sync::mpsc::UnboundedSender<Call<C>>,
    command: C,
    wait: Duration,
) -> Result<(), ModbusError> {
    let (reply, answer): (_, Receiver<_>) = sync_channel(1);
    commands
        .send(Call { command, reply })
        .map_err(|_| ModbusError::Worker("the worker thread has stopped".into()))?;
    answer
        .recv_timeout(wait)
        .map_err(|_| ModbusError::Worker(format!("no answer within {wait:?}")))?
}

/// The longest a command may take: every transaction with all retries, plus a poll period.
pub(crate) fn command_wait(line: &SerialLineConfig, transactions: u32, poll: Duration) -> Duration {
    let per = line
        .timeout_duration()
        .saturating_mul(line.retries.saturating_add(1));
    per.saturating_mul(transactions)
        .saturating_add(poll)
        .saturating_add(Duration::from_millis(500))
}

/// Starts a thread with a current-thread runtime, opens the link inside it and runs
/// `body` with it. Returns once the port is open (or failed to open).
pub(crate) fn spawn<F, Fut>(
    name: &str,
    line: SerialLineConfig,
    unit: u8,
    body: F,
) -> Result<JoinHandle<()>, ModbusError>
where
    F: FnOnce(ModbusLink) -> Fut + Send + 'static,
    Fut: Future<Output = ()>,
{
    let (opened_tx, opened_rx) = sync_channel(1);
    let handle = std::thread::Builder::new()
        .name(name.to_string())
        .spawn(move || {
            let runtime = match tokio::runtime::Builder::new_current_thread()
                .enable_all()
                .build()
            {
                Ok(rt) => rt,
                Err(e) => {
                    let _ = opened_tx.send(Err(ModbusError::Worker(format!(
                        "cannot start runtime: {e}"
                    ))));
                    return;
                }
            };
            runtime.block_on(async move {
                match ModbusLink::open(&line, unit) {
                    Ok(link) => {
                        let _ = opened_tx.send(Ok(()));
                        body(link).await;
                    }
                    Err(e) => {
                        let _ = opened_tx.send(Err(e));
                    }
                }
            });
        })
        .map_err(|e| ModbusError::Worker(format!("cannot start thread: {e}")))?;
    match opened_rx.recv_timeout(Duration::from_secs(10)) {
        Ok(Ok(())) => Ok(handle),
        Ok(Err(e)) => {
            let _ = handle.join();
            Err(e)
        }
        Err(_) => Err(ModbusError::Worker(
            "the worker did not open the port within 10 s".into(),
        )),
    }
}
