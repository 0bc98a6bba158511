//! Stop requests from outside the servo loop: the `klar` binary turns SIGINT and SIGTERM into
//! [`OperatorStop::request`] calls; the run looks at the request once per servo cycle (one
//! atomic load) and reacts like the control's stop key.
//!
//! The first request is a controlled stop: a feed hold along the path within the axis limits,
//! then, at rest, the usual end of the run (spindle off, drives disabled, trace flushed). A
//! further request while that stop is under way cuts it short with the quick stop the fault
//! reactions use (every axis on its own jerk-limited ramp): faster, but still a stop, never an
//! abrupt end mid-motion.

use super::{Run, RunError};
use crate::monitor::StopCause;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

/// How far the operator's stop requests have gone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum StopLevel {
    /// No stop requested.
    None,
    /// One request: a controlled stop on the path.
    Controlled,
    /// Two or more: a quick stop.
    Quick,
}

impl StopLevel {
    fn from_count(count: u8) -> Self {
        match count {
            0 => StopLevel::None,
            1 => StopLevel::Controlled,
            _ => StopLevel::Quick,
        }
    }
}

/// A stop request shared between whoever asks (a signal handler, another thread) and the
/// runs that watch it; clones share the same request. Asking is one atomic operation, so it
/// may be done from a signal handler.
#[derive(Debug, Clone, Default)]
pub struct OperatorStop {
    requests: Arc<AtomicU8>,
}

impl OperatorStop {
    /// A stop nobody has asked for yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks for a stop once more and returns the level now in force: the first request asks
    /// for a controlled stop, any further one for a quick stop.
    pub fn request(&self) -> StopLevel {
        let before = self
            .requests
            .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| {
                Some(n.saturating_add(1))
            })
            .unwrap_or(u8::MAX);
        StopLevel::from_count(before.saturating_add(1))
    }

    /// The level asked for so far.
    pub fn level(&self) -> StopLevel {
        StopLevel::from_count(self.requests.load(Ordering::Relaxed))
    }
}

impl Run<'_, '_> {
    /// Makes the run watch `stop`: from the next servo cycle on, a request stops it (see the
    /// module documentation); a request made before is acted on at once.
    pub fn watch_operator_stop(&mut self, stop: OperatorStop) {
        self.operator = Some(stop);
    }

    /// Once per servo cycle: acts on a new operator stop level. A controlled stop begins a
    /// feed hold (unless a stop on the path is already under way); a quick stop is run to
    /// rest here and its error comes back to end the run.
    pub(super) fn check_operator(&mut self) -> Result<(), RunError> {
        let Some(level) = self.operator.as_ref().map(OperatorStop::level) else {
            return Ok(());
        };
        if level <= self.operator_seen {
            return Ok(());
        }
        self.operator_seen = level;
        let error = RunError::Operator {
            line: self.line,
            block: self.last_loc.and_then(|l| l.block),
        };
        match level {
            StopLevel::None => Ok(()),
            StopLevel::Controlled => {
                self.log
                    .send(super::LogRecord::OperatorStop { line: self.line });
                if self.stopping.is_none() {
                    self.begin_path_stop(StopCause::Operator, None, error);
                }
                Ok(())
            }
            StopLevel::Quick => {
                self.log
                    .send(super::LogRecord::OperatorQuickStop { line: self.line });
                // A stop on the path under way keeps its cause (the operator's, or a fault's
                // that came first); the quick stop replaces its report.
                let error = match self.stopping.take() {
                    Some(pending) => pending.error,
                    None => error,
                };
                Err(self.quick_stop(error))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_escalate_from_controlled_to_quick_and_stay_there() {
        let stop = OperatorStop::new();
        let seen_by_run = stop.clone();
        assert_eq!(seen_by_run.level(), StopLevel::None);
        assert_eq!(stop.request(), StopLevel::Controlled);
        assert_eq!(seen_by_run.level(), StopLevel::Controlled);
        assert_eq!(stop.request(), StopLevel::Quick);
        for _ in 0..300 {
            stop.request();
        }
        assert_eq!(seen_by_run.level(), StopLevel::Quick);
    }
}
