//! A feed hold that takes effect at the end of the next move instead of at once.
//!
//! A thread pass runs geared to the spindle, outside the planner; a feed hold asked for
//! during it must not leave the tool standing in the groove. The control finishes the pass,
//! runs the move after it (the retract) and only then holds. [`Planner::hold_after_move`]
//! asks for that: once the path stands at the start of the next move and that move's pieces
//! are committed, a standstill is placed at the end of its last piece (every piece with its
//! source block, up to the first other one), and the planner holds when it gets there.

use super::{Marker, Planner, ROUNDING};

impl Planner {
    /// Feed hold after the next move: the path runs the move that starts where it stands
    /// (or, if it stands between moves, the next one) to its end, comes to rest there and
    /// holds like [`Planner::hold`]. [`Planner::resume`] cancels it.
    pub fn hold_after_move(&mut self) {
        if !self.held {
            self.move_hold.pending = true;
        }
    }

    /// True while a hold after the next move is asked for and not yet in force.
    pub fn hold_pending(&self) -> bool {
        self.move_hold.pending || self.move_hold.at.is_some()
    }

    /// Places the standstill of a pending hold once the next move's pieces are known.
    pub(super) fn place_move_hold(&mut self) {
        if !self.move_hold.pending {
            return;
        }
        let s = self.state.s;
        let Some(k) = self.pieces.iter().position(|p| p.end() > s + ROUNDING) else {
            return;
        };
        let Some(first) = self.pieces.get(k) else {
            return;
        };
        let loc = first.loc;
        let mut end = first.end();
        for p in self.pieces.iter().skip(k + 1) {
            if p.loc != loc || (p.start - end).abs() > ROUNDING {
                break;
            }
            end = p.end();
        }
        // Not past the committed path: a move whose later pieces are still waiting to be
        // committed ends at most there.
        let end = end.min(self.committed_end);
        let at = self
            .markers
            .iter()
            .position(|m| match m {
                Marker::Stop { at, .. } | Marker::Event { at, .. } => *at > end,
            })
            .unwrap_or(self.markers.len());
        self.markers.insert(
            at,
            Marker::Stop {
                at: end,
                op: None,
                dwell: 0.0,
            },
        );
        self.move_hold = MoveHold {
            pending: false,
            at: Some(end),
        };
    }

    /// Called when the path has come to rest on a stop at `at`: the hold placed there
    /// takes effect.
    pub(super) fn reached_stop(&mut self, at: f64) {
        if self
            .move_hold
            .at
            .is_some_and(|h| (h - at).abs() <= ROUNDING)
        {
            self.move_hold.at = None;
            self.held = true;
        }
    }
}

/// The state of a hold after the next move.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct MoveHold {
    /// Asked for; the standstill is not placed yet.
    pub(super) pending: bool,
    /// The path position of the placed standstill.
    pub(super) at: Option<f64>,
}
