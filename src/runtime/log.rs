//! Logging without logging in the servo loop: what the loop has to say (faults, warnings,
//! state changes) it puts as a fixed-size [`LogRecord`] of plain data into a bounded queue;
//! a `klar-log` thread takes the records out and hands them to `tracing`. The loop never
//! waits for the queue: a record that finds it full is dropped and counted, and the run's
//! summary gives the count.

use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::thread::JoinHandle;

/// Records the queue holds before the loop drops them.
pub const LOG_QUEUE: usize = 256;

/// Something the servo loop reports: plain data, no string built in the loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LogRecord {
    /// A cycle came later than the machine's limit: a feed hold follows.
    Underrun {
        /// Program line.
        line: u32,
        /// Lateness, s.
        late: f64,
    },
    /// The spindle reported a fault: a feed hold follows (the stop report names it).
    SpindleFault {
        /// Program line.
        line: u32,
    },
    /// A quick stop has begun (the stop report gives its cause).
    QuickStop {
        /// Program line.
        line: u32,
    },
    /// A spindle command on a machine without a spindle.
    NoSpindle {
        /// Program line.
        line: u32,
    },
    /// A program stop (M0/M1/STOP) in a run without an operator.
    ProgramStop {
        /// Program line.
        line: u32,
        /// True for the optional stop M1.
        optional: bool,
    },
    /// A machine function reached the loop.
    MachineFunction {
        /// Program line.
        line: u32,
        /// Its M number.
        number: u32,
        /// Whether the path stopped for it.
        stop: bool,
        /// Seconds the path holds for it.
        wait: f64,
    },
    /// Another non-motion event reached the loop.
    Event {
        /// Program line.
        line: u32,
    },
    /// The operator asked for a stop: feed hold.
    OperatorStop {
        /// Program line.
        line: u32,
    },
    /// The operator asked a second time: quick stop.
    OperatorQuickStop {
        /// Program line.
        line: u32,
    },
}

/// The servo loop's end of the log queue, and the thread at the other end.
pub struct LogQueue {
    tx: Option<SyncSender<LogRecord>>,
    thread: Option<JoinHandle<()>>,
    /// Records dropped because the queue was full (or the log thread could not start).
    pub dropped: u64,
}

impl LogQueue {
    /// Starts the `klar-log` thread; `functions` names the machine functions (M number,
    /// name) for its messages. When the thread cannot start, the error is returned and
    /// the queue counts every record as dropped.
    pub fn start(functions: Vec<(u32, String)>) -> (Self, Option<std::io::Error>) {
        let (tx, rx) = sync_channel(LOG_QUEUE);
        match std::thread::Builder::new()
            .name("klar-log".into())
            .spawn(move || drain(&rx, &functions))
        {
            Ok(thread) => (
                LogQueue {
                    tx: Some(tx),
                    thread: Some(thread),
                    dropped: 0,
                },
                None,
            ),
            Err(e) => (
                LogQueue {
                    tx: None,
                    thread: None,
                    dropped: 0,
                },
                Some(e),
            ),
        }
    }

    /// Puts a record into the queue without waiting: a full queue drops it and counts it.
    pub fn send(&mut self, record: LogRecord) {
        let sent = match &self.tx {
            Some(tx) => match tx.try_send(record) {
                Ok(()) => true,
                Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => false,
            },
            None => false,
        };
        if !sent {
            self.dropped += 1;
        }
    }

    /// Closes the queue and waits until the log thread has written every record.
    pub fn close(&mut self) {
        self.tx = None;
        if let Some(t) = self.thread.take() {
            // A log thread that panicked has lost its records; nothing more to do.
            let _ = t.join();
        }
    }
}

impl Drop for LogQueue {
    fn drop(&mut self) {
        self.close();
    }
}

/// The log thread: each record to `tracing` until the loop's end closes the queue.
fn drain(rx: &Receiver<LogRecord>, functions: &[(u32, String)]) {
    while let Ok(record) = rx.recv() {
        emit(record, functions);
    }
}

/// One record as a `tracing` event.
fn emit(record: LogRecord, functions: &[(u32, String)]) {
    match record {
        LogRecord::Underrun { line, late } => {
            tracing::error!(line, "setpoint underrun: {late:.4} s late: feed hold");
        }
        LogRecord::SpindleFault { line } => {
            tracing::error!(line, "spindle fault: feed hold");
        }
        LogRecord::QuickStop { line } => tracing::error!(line, "quick stop"),
        LogRecord::NoSpindle { line } => {
            tracing::warn!(line, "this machine has no spindle: S/M3/M4 ignored");
        }
        LogRecord::ProgramStop { line, optional } => {
            tracing::info!(line, optional, "program stop (no operator: continuing)");
        }
        LogRecord::MachineFunction {
            line,
            number,
            stop,
            wait,
        } => {
            let name = functions
                .iter()
                .find(|(n, _)| *n == number)
                .map_or("", |(_, name)| name.as_str());
            tracing::info!(line, number, name, stop, wait, "machine function M{number}");
        }
        LogRecord::Event { line } => tracing::debug!(line, "event"),
        LogRecord::OperatorStop { line } => {
            tracing::info!(line, "stop requested by the operator: feed hold");
        }
        LogRecord::OperatorQuickStop { line } => {
            tracing::info!(line, "second stop request: quick stop");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_queue_drops_and_counts_without_waiting() {
        let (tx, rx) = sync_channel(2);
        let mut q = LogQueue {
            tx: Some(tx),
            thread: None,
            dropped: 0,
        };
        for line in 0..5 {
            q.send(LogRecord::Event { line });
        }
        assert_eq!(q.dropped, 3);
        assert_eq!(rx.try_recv(), Ok(LogRecord::Event { line: 0 }));
        assert_eq!(rx.try_recv(), Ok(LogRecord::Event { line: 1 }));
        assert!(rx.try_recv().is_err());
    }

    #[test]
    fn records_reach_the_log_thread() {
        let (mut q, err) = LogQueue::start(vec![(25, "door open".into())]);
        assert!(err.is_none());
        for line in 0..10 {
            q.send(LogRecord::Event { line });
        }
        q.close();
        assert_eq!(q.dropped, 0);
        // Closed: further records count as dropped.
        q.send(LogRecord::Event { line: 11 });
        assert_eq!(q.dropped, 1);
    }
}
