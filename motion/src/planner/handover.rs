//! Speeding up from the joint itself: the period in which the path crosses from a piece it
//! holds the speed limit of into a faster one.
//!
//! The checks keep the speed within the current piece's limit up to its end, so a state
//! that cruises at that limit cannot speed up before the joint, and a period's action is one
//! ramp from the period's start: the period in which the joint is crossed would hold the
//! speed all through, and the ramp up would start at the next period boundary, on average
//! half a period late. Instead that period is taken in two parts: at constant speed up to
//! the joint, then the generator's action from the joint over the rest of the period, with
//! the window seen from there.

use super::Planner;
use super::speed::{self, Motion};

impl Planner {
    /// The state at the end of the period that started at `before`, for which the generator
    /// chose `next` heading for `target`, when that period crosses into a faster piece at
    /// constant speed: the constant speed up to the joint, then the generator's action from
    /// the joint for the rest of the period. `None` where the period is not such a one.
    pub(super) fn hand_over(
        &mut self,
        before: &Motion,
        next: &Motion,
        target: f64,
    ) -> Option<Motion> {
        let holds = before.a == 0.0 && next.a == 0.0 && next.v == before.v && before.v > 0.0;
        if self.held || !holds || target <= before.v {
            return None;
        }
        let k = self.current_index();
        let (p, q) = (self.pieces.get(k)?, self.pieces.get(k + 1)?);
        let joint = p.end();
        let faster = q.speed_limit(self.factor) > p.speed_limit(self.factor);
        if !faster || joint <= before.s || joint >= next.s || self.next_stop() <= joint {
            return None;
        }
        let rest = self.config.period - (joint - before.s) / before.v;
        if rest <= 0.0 {
            return None;
        }
        self.state = Motion {
            s: joint,
            v: before.v,
            a: 0.0,
        };
        self.scan();
        let target = self.go_target();
        let after = speed::advance_with(&self.state, target, &self.window, rest, &mut self.scratch);
        self.state = *before;
        Some(after)
    }
}
