//! The hand-over between a synchronous [`super::CanBus`] user and an asynchronous adapter.
//!
//! The adapter's I/O runs as one task on a single-threaded tokio runtime on its own thread.
//! Received events go into an [`Inbox`] (a queue with a condition variable, so
//! `recv_timeout` blocks without polling); frames to send go out through an unbounded
//! channel. Dropping the [`Bridge`] closes the channel, which ends the task and the thread.

use std::collections::VecDeque;
use std::future::Future;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use tokio::sync::mpsc;

use super::{CanError, CanEvent};

/// Queue of received events shared by the I/O thread and the bus user.
pub struct Inbox {
    state: Mutex<InboxState>,
    arrived: Condvar,
    start: Instant,
}

struct InboxState {
    events: VecDeque<CanEvent>,
    closed: Option<String>,
}

/// Received events kept at most; older ones are dropped (and an overrun reported) beyond.
const INBOX_LIMIT: usize = 65_536;

impl Inbox {
    fn new() -> Self {
        Self {
            state: Mutex::new(InboxState {
                events: VecDeque::new(),
                closed: None,
            }),
            arrived: Condvar::new(),
            start: Instant::now(),
        }
    }

    fn lock(&self) -> MutexGuard<'_, InboxState> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Seconds since the adapter was opened, for frame timestamps.
    pub fn now(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// Queues one received event.
    pub fn push(&self, event: CanEvent) {
        let mut s = self.lock();
        if s.events.len() >= INBOX_LIMIT {
            s.events.pop_front();
            s.events
                .push_back(CanEvent::Error(super::BusErrorKind::Overrun));
        }
        s.events.push_back(event);
        drop(s);
        self.arrived.notify_all();
    }

    /// Marks the adapter as gone, with the reason.
    pub fn close(&self, reason: String) {
        self.lock().closed = Some(reason);
        self.arrived.notify_all();
    }

    fn pop(&self, timeout: Duration) -> Result<Option<CanEvent>, CanError> {
        let deadline = Instant::now() + timeout;
        let mut s = self.lock();
        loop {
            if let Some(ev) = s.events.pop_front() {
                return Ok(Some(ev));
            }
            if let Some(reason) = &s.closed {
                return Err(CanError::Closed(reason.clone()));
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(None);
            }
            s = self
                .arrived
                .wait_timeout(s, deadline - now)
                .map(|(g, _)| g)
                .unwrap_or_else(|p| p.into_inner().0);
        }
    }
}

/// A running I/O thread with its inbox and outgoing channel (items of type `T`).
pub struct Bridge<T> {
    inbox: Arc<Inbox>,
    outbox: Option<mpsc::UnboundedSender<T>>,
    thread: Option<JoinHandle<()>>,
}

impl<T: Send + 'static> Bridge<T> {
    /// Starts the I/O thread running `task(inbox, outgoing, ready)` and waits until the
    /// task reports through `ready` that it started, or fails.
    pub fn spawn<F, Fut>(name: &str, task: F) -> Result<Self, CanError>
    where
        F: FnOnce(Arc<Inbox>, mpsc::UnboundedReceiver<T>, Ready) -> Fut + Send + 'static,
        Fut: Future<Output = Result<(), String>>,
    {
        let inbox = Arc::new(Inbox::new());
        let (tx, rx) = mpsc::unbounded_channel();
        let (ready_tx, ready_rx) = std::sync::mpsc::channel();
        let task_inbox = Arc::clone(&inbox);
        let thread = std::thread::Builder::new()
            .name(name.to_string())
            .spawn(move || {
                let runtime = match tokio::runtime::Builder::new_current_thread()
                    .enable_all()
                    .build()
                {
                    Ok(rt) => rt,
                    Err(e) => {
                        let _ = ready_tx.send(Err(CanError::Io(e.to_string())));
                        return;
                    }
                };
                let ready = Ready(ready_tx.clone());
                let result = runtime.block_on(task(Arc::clone(&task_inbox), rx, ready));
                let reason = match result {
                    Ok(()) => "adapter closed".to_string(),
                    Err(e) => {
                        tracing::error!(error = %e, "CAN adapter I/O stopped");
                        // Only read if the task failed before it reported readiness.
                        let _ = ready_tx.send(Err(CanError::Io(e.clone())));
                        e
                    }
                };
                task_inbox.close(reason);
            })
            .map_err(|e| CanError::Io(e.to_string()))?;
        let started = ready_rx
            .recv()
            .unwrap_or_else(|_| Err(CanError::Closed("adapter thread ended early".into())));
        let mut bridge = Self {
            inbox,
            outbox: Some(tx),
            thread: Some(thread),
        };
        match started {
            Ok(()) => Ok(bridge),
            Err(e) => {
                bridge.shutdown();
                Err(e)
            }
        }
    }

    /// Hands one item to the I/O thread.
    pub fn send(&self, item: T) -> Result<(), CanError> {
        match &self.outbox {
            Some(tx) => tx
                .send(item)
                .map_err(|_| CanError::Closed("adapter thread ended".into())),
            None => Err(CanError::Closed("adapter shut down".into())),
        }
    }

    /// Waits up to `timeout` for the next received event.
    pub fn recv_timeout(&self, timeout: Duration) -> Result<Option<CanEvent>, CanError> {
        self.inbox.pop(timeout)
    }

    fn shutdown(&mut self) {
        self.outbox = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl<T> Drop for Bridge<T> {
    fn drop(&mut self) {
        self.outbox = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The I/O task's way to report that it started (or why it could not).
pub struct Ready(std::sync::mpsc::Sender<Result<(), CanError>>);

impl Ready {
    /// Reports the outcome of the adapter's start-up.
    pub fn report(self, outcome: Result<(), CanError>) {
        let _ = self.0.send(outcome);
    }
}
