//! A feed hold that takes effect at the end of the next move instead of at once.
//!
//! A thread pass runs geared to the spindle, outside the planner; a feed hold asked for
//! during it must not leave the tool standing in the groove. The control finishes the pass,
//! runs the move after it (the retract) and only then holds. [`Planner::hold_after_move`]
//! asks for that: once the path stands at the start of the next move and that move's pieces
//! are committed, a standstill is placed at the end of the programmed element it stands on
//! (before the blend into the next one, within the path tolerance of its end point), and the
//! planner holds when it gets there.

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
        // The pieces of one programmed element follow on along its shape (a piece cut off
        // for the jerk of its neighbour goes on where the one before ends); a blend or the
        // next element starts a shape of its own. A cycle's moves all come from one block,
        // so the block alone would not tell them apart.
        let mut prev = first;
        for p in self.pieces.iter().skip(k + 1) {
            let same_shape = p.loc == prev.loc
                && (p.start - prev.end()).abs() <= ROUNDING
                && (p.offset - (prev.offset + prev.length)).abs() <= ROUNDING
                && p.shape.length() == prev.shape.length();
            if !same_shape {
                break;
            }
            prev = p;
        }
        let end = prev.end();
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
                corner: None,
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

#[cfg(test)]
mod tests {
    use super::super::Step;
    use super::super::test_machine::planner;
    use klar_interp::{Feed, Op, OpKind, Pose, SourceLoc};

    fn line(from: [f64; 3], to: [f64; 3], line: u32) -> Op {
        Op {
            kind: OpKind::Line {
                from: Pose::xyz(from[0], from[1], from[2]),
                to: Pose::xyz(to[0], to[1], to[2]),
                feed: Feed::Rate(100.0),
            },
            loc: SourceLoc {
                line,
                ..SourceLoc::default()
            },
        }
    }

    #[test]
    fn a_hold_after_the_move_rests_at_its_end_and_resumes() {
        rests_at_the_end_of_the_first_move([1, 2, 3]);
    }

    #[test]
    fn moves_of_one_block_are_told_apart() {
        // A cycle's moves all come from its block.
        rests_at_the_end_of_the_first_move([4, 4, 4]);
    }

    fn rests_at_the_end_of_the_first_move(lines: [u32; 3]) {
        let mut p = planner();
        // Up Y 20 mm, then along X 30 mm, then up Z 5 mm: two corners (blended within
        // the 0.01 mm tolerance).
        let mut ops = vec![
            line([0.0; 3], [0.0, 20.0, 0.0], lines[0]),
            line([0.0, 20.0, 0.0], [30.0, 20.0, 0.0], lines[1]),
            line([30.0, 20.0, 0.0], [30.0, 20.0, 5.0], lines[2]),
        ]
        .into_iter();
        p.hold_after_move();
        assert!(p.hold_pending() && !p.is_held());
        let mut poses = Vec::new();
        let mut held_at = None;
        for cycle in 0..5000 {
            while p.needs_input() {
                match ops.next() {
                    Some(op) => p.push(op).expect("op accepted"),
                    None => p.finish(),
                }
            }
            if held_at.is_none() && p.is_held() {
                held_at = Some(cycle);
            }
            if held_at.is_some_and(|h| cycle == h + 1000) {
                p.resume();
            }
            match p.next_step() {
                Some(Step::Sample(s)) => poses.push(s.pose.0),
                Some(Step::Event(_)) => {}
                None => break,
            }
        }
        let h = held_at.expect("the hold took effect");
        // At rest at the end of the first move (Y 20, within the corner tolerance), for
        // every cycle of the hold.
        let rest = poses[h];
        assert!(
            rest[0].abs() <= 0.01 && (rest[1] - 20.0).abs() <= 0.01 && rest[2] == 0.0,
            "{rest:?}"
        );
        for q in &poses[h..h + 1000] {
            assert_eq!(q, &rest);
        }
        // Moving right up to it: the hold did not brake early (the last 10 µm before it
        // were covered in the last 20 cycles).
        let before = poses[h - 20];
        let gap = ((rest[0] - before[0]).powi(2) + (rest[1] - before[1]).powi(2)).sqrt();
        assert!(gap > 0.01, "crept in: {gap} mm in 20 cycles");
        // The resume runs the rest of the path to its end.
        let end = poses[poses.len() - 1];
        assert!(
            (end[0] - 30.0).abs() < 1e-9
                && (end[1] - 20.0).abs() < 1e-9
                && (end[2] - 5.0).abs() < 1e-9,
            "{end:?}"
        );
        assert!(!p.hold_pending());
    }

    #[test]
    fn resume_cancels_a_pending_hold() {
        let mut p = planner();
        p.hold_after_move();
        p.resume();
        assert!(!p.hold_pending() && !p.is_held());
    }
}
