//! Waiting for axes to arrive: positioning axes before the next block, and every axis with
//! an in-position window at the program's end, each within its timeout.

use super::{Run, RunError};
use klar_motion::AxisFault;

impl Run<'_, '_> {
    /// Holds until every positioning axis (one that follows its own profile behind a slow
    /// link) has reached its last commanded position, each within its window and timeout.
    pub(super) fn settle_all(&mut self) -> Result<(), RunError> {
        let from = self.t;
        for axis in 0..self.letters.len() {
            let Some((window, timeout)) = self.positioning[axis] else {
                continue;
            };
            while (self.commanded[axis] - self.actual[axis]).abs() > window {
                if self.t - from > timeout {
                    return Err(RunError::Fault {
                        axis: self.letters[axis],
                        fault: AxisFault::FollowingError(self.commanded[axis] - self.actual[axis]),
                        origin: None,
                        line: self.line,
                        block: self.last_loc.and_then(|l| l.block),
                    });
                }
                self.hold_cycle()?;
            }
        }
        Ok(())
    }

    /// At the program's end: holds the end point until every axis with an in-position
    /// window (drives that follow on their own) stands within it, so the drives are not
    /// switched off while still moving; an axis that does not get there in its time is an
    /// error.
    pub(super) fn settle_end(&mut self) -> Result<(), RunError> {
        let from = self.t;
        for axis in 0..self.letters.len() {
            let Some((window, timeout)) = self.end_windows[axis] else {
                continue;
            };
            loop {
                let distance = self.commanded[axis] - self.actual[axis];
                if distance.abs() <= window {
                    break;
                }
                if self.t - from > timeout {
                    return Err(RunError::NotInPosition {
                        axis: self.letters[axis],
                        distance,
                        window,
                        timeout,
                    });
                }
                self.hold_cycle()?;
            }
        }
        Ok(())
    }
}
