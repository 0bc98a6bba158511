//! Which speed limits are steps down, decided piece by piece as the pieces are committed.
//!
//! The look-ahead settles a step down in the speed limit with its backward pass (the path
//! arrives there with zero acceleration); a limit barely below the one before it is soft
//! instead, met on its own. Measured against the piece just before, limits that drift down a
//! little from piece to piece (a curve turning towards an axis, at a feed above what the axes
//! allow) would all be soft and the drift never met as a whole; measured against the piece
//! the state is on, a piece's verdict would change as the state moves on. So each piece is
//! judged once, against the last step or the highest limit since.

/// Share below which a piece's speed limit counts as a step down (see [`DropTracker`]).
pub const DROP_SHARE: f64 = 0.01;

/// Decides, piece by piece as they are committed, which speed limits are steps down: those
/// at least [`DROP_SHARE`] below the last step, or below the highest limit since it. Limits
/// that drift down a little from piece to piece (a curve turning towards an axis) so add up
/// to steps, and a piece's verdict does not change as the path state moves on.
#[derive(Debug, Clone, Copy)]
pub struct DropTracker {
    anchor: f64,
}

impl Default for DropTracker {
    fn default() -> Self {
        DropTracker {
            anchor: f64::INFINITY,
        }
    }
}

impl DropTracker {
    /// True when speed limit `limit` of the next piece is a step down.
    pub fn next(&mut self, limit: f64) -> bool {
        if limit < self.anchor * (1.0 - DROP_SHARE) {
            self.anchor = limit;
            true
        } else {
            self.anchor = self.anchor.max(limit);
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_drifting_down_add_up_to_steps_and_a_rise_starts_afresh() {
        let mut drops = DropTracker::default();
        assert!(drops.next(100.0), "the first limit is a step from nothing");
        // 0.4 % lower piece by piece: the third is 1.2 % below the last step.
        let verdicts: Vec<bool> = [99.6, 99.2, 98.8, 98.4, 98.0, 97.6]
            .into_iter()
            .map(|v| drops.next(v))
            .collect();
        assert_eq!(verdicts, [false, false, true, false, false, true]);
        // A rise: the next step is measured from the highest limit since.
        assert!(!drops.next(120.0));
        assert!(!drops.next(118.9));
        assert!(drops.next(118.7));
    }
}
