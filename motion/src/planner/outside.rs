//! Moves the servo loop makes itself between two stretches of planned path: a probing move
//! that must stop when the probe triggers, wherever that is. The planner first brings the
//! machine to rest at the end of what it was given ([`Planner::end_in_stop`],
//! [`Planner::drained`]); the servo loop then moves the axes and tells the planner where they
//! stand ([`Planner::moved_to`]), and the path goes on from there.

use super::{Planner, ROUNDING};
use crate::MotionError;
use klar_interp::Pose;

impl Planner {
    /// Ends the path pushed so far in a stop, as [`Planner::finish`] does, but more input may
    /// follow.
    pub fn end_in_stop(&mut self) -> Result<(), MotionError> {
        self.flush()
    }

    /// True when the machine stands at rest at the end of everything pushed, with no event,
    /// dwell or sample left to give out.
    pub fn drained(&self) -> bool {
        self.waiting.is_empty()
            && self.markers.is_empty()
            && self.stash.is_none()
            && self.hold_until.is_none()
            && self.overlap.is_empty()
            && self.at_rest()
            && self.state.s >= self.committed_end - ROUNDING
    }

    /// The servo loop has moved the machine, drained ([`Planner::drained`]), to `p`: the
    /// path goes on from there. False (and nothing changes) when the planner is not drained.
    pub fn moved_to(&mut self, p: Pose) -> bool {
        if !self.drained() {
            return false;
        }
        self.reframe(p);
        self.planned_pose = p;
        true
    }
}
