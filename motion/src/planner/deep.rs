//! Pieces whose path limits lie below the floors the look-ahead distance is sized with.
//!
//! The look-ahead takes pieces into the window ([`super::Planner::scan`]) and commits the
//! path ahead ([`super::Planner::needs_input`]) over the braking distance with *floors* of
//! the path acceleration and jerk: half the smallest axis limits. On a move measured over
//! the linear axes, a linear axis moves at most as fast as the path (|dq/ds| ≤ 1), so its
//! limits bound the path's from below. A rotary axis turning along such a move has no such
//! bound: |dq/ds| is its turn per millimetre of path (29° over 0.25 mm is 116 °/mm), and the
//! move's path acceleration and jerk fall that many times below the axis's own limits, far
//! below the floors. Braking into such a piece with its jerk takes much longer than the
//! floors allow for, so a window sized with them saw it too late and the path ran into it
//! (and the blend before it) at the speed of the element before.
//!
//! The planner therefore keeps the lowest path acceleration and jerk of the pieces ahead
//! that turn a rotary axis and lie below a floor ([`LowAhead`]), and the scan looks ahead
//! over the braking distance with those as well. Pieces that turn no rotary axis are not
//! recorded, so the look-ahead of linear motion is what it was.
//!
//! A piece committed when the path state can no longer meet its limits (the state too fast
//! and too close to it) gets an exact stop in front of it instead (`Planner::commit_front`):
//! until then the end of the committed path was its end, which the state can always stop at.

use super::path::Piece;
use super::speed::{self, Motion};
use crate::geom::{AxisBounds, ZERO_LENGTH, letter};
use crate::limits::Grip;
use std::collections::VecDeque;

/// The lowest path acceleration and jerk over the recorded pieces that the path state has
/// not passed yet: two queues of (piece end, value) whose values rise from front to back
/// (a sliding minimum), so that recording a piece, passing one and reading the minimum
/// cost O(1) amortised.
#[derive(Debug, Clone, Default)]
pub struct LowAhead {
    accel: VecDeque<(f64, f64)>,
    jerk: VecDeque<(f64, f64)>,
}

impl LowAhead {
    /// Makes room for `n` entries in each queue.
    pub fn reserve(&mut self, n: usize) {
        self.accel.reserve(n);
        self.jerk.reserve(n);
    }
}

/// Appends `(end, value)` to a sliding-minimum queue.
fn push_min(queue: &mut VecDeque<(f64, f64)>, end: f64, value: f64) {
    while queue.back().is_some_and(|&(_, v)| v >= value) {
        queue.pop_back();
    }
    queue.push_back((end, value));
}

/// True when `bounds` over `length` turn a rotary axis by a measurable amount.
pub fn turns_rotary(bounds: &AxisBounds, length: f64) -> bool {
    (0..9).any(|i| letter(i).is_rotary() && bounds.d1[i] * length > ZERO_LENGTH)
}

/// The lowest path acceleration a piece allows at any speed up to its top speed (the
/// grip shrinks as the speed grows).
pub fn lowest_accel(piece: &Piece) -> f64 {
    piece.grip.at(piece.vmax)
}

impl LowAhead {
    /// Records `piece` when it turns a rotary axis (`turns`) and its acceleration or jerk
    /// lies below the floors `(accel, jerk)`; true when it was recorded.
    pub fn record(&mut self, piece: &Piece, turns: bool, floors: (f64, f64)) -> bool {
        let accel = lowest_accel(piece);
        if !turns || (accel >= floors.0 && piece.jerk >= floors.1) {
            return false;
        }
        let end = piece.end();
        push_min(&mut self.accel, end, accel);
        push_min(&mut self.jerk, end, piece.jerk);
        true
    }

    /// Forgets the pieces that end at or before path position `s`.
    pub fn pass(&mut self, s: f64) {
        for queue in [&mut self.accel, &mut self.jerk] {
            while queue.front().is_some_and(|&(end, _)| end <= s) {
                queue.pop_front();
            }
        }
    }

    /// The lowest acceleration and jerk over the recorded pieces ahead, each no higher than
    /// the floor given.
    pub fn lowest(&self, floors: (f64, f64)) -> (f64, f64) {
        let low =
            |q: &VecDeque<(f64, f64)>, floor: f64| q.front().map_or(floor, |f| f.1.min(floor));
        (low(&self.accel, floors.0), low(&self.jerk, floors.1))
    }

    /// True when no recorded piece lies ahead.
    pub fn is_empty(&self) -> bool {
        self.accel.is_empty()
    }
}

/// Look-ahead distance for a state `from` (speed and the positive part of its acceleration)
/// with path acceleration `accel` and jerk `jerk`: twice the distance to come to rest, and
/// two periods' travel (the form of the scan's own reach).
pub fn reach(from: &Motion, accel: f64, jerk: f64, period: f64) -> f64 {
    let x = Motion {
        s: 0.0,
        v: from.v,
        a: from.a.max(0.0),
    };
    2.0 * speed::brake_distance(&x, 0.0, &Grip::constant(accel), jerk) + 2.0 * x.v * period + 1e-9
}

/// True when the state `x` can no longer slow down to the speed limit `limit` of a piece
/// starting at `at`, with path acceleration `accel` and jerk `jerk` on the way (twice the
/// braking distance, as the scan's reach allows for).
pub fn too_close(x: &Motion, at: f64, limit: f64, accel: f64, jerk: f64, period: f64) -> bool {
    let from = Motion {
        s: 0.0,
        v: x.v,
        a: x.a.max(0.0),
    };
    let need = speed::brake_distance(&from, limit, &Grip::constant(accel), jerk);
    2.0 * need + 2.0 * x.v * period > at - x.s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lowest_values_ahead_follow_the_state_past_the_pieces() {
        let mut q = VecDeque::new();
        // (end, value) for four pieces in path order.
        for (end, v) in [(1.0, 5.0), (2.0, 3.0), (3.0, 4.0), (4.0, 6.0)] {
            push_min(&mut q, end, v);
        }
        let low = |q: &VecDeque<(f64, f64)>, s: f64| {
            q.iter()
                .filter(|e| e.0 > s)
                .map(|e| e.1)
                .fold(f64::INFINITY, f64::min)
        };
        // By hand: the minimum over the pieces ending after s.
        for (s, want) in [(0.0, 3.0), (1.5, 3.0), (2.0, 4.0), (3.5, 6.0)] {
            assert_eq!(low(&q, s), want, "{s}");
            let mut p = LowAhead {
                accel: q.clone(),
                jerk: q.clone(),
            };
            p.pass(s);
            assert_eq!(p.lowest((10.0, 10.0)), (want, want), "{s}");
            assert_eq!(p.lowest((3.5, 1.0)), (want.min(3.5), 1.0), "{s}");
        }
    }

    #[test]
    fn the_reach_is_twice_the_closed_form_braking_distance() {
        // From 100 mm/s with a = 1000 and j = 1e4: the jerk phases last 0.1 s each and the
        // constant deceleration 0.1 − 0.1 = 0 s more (v = a²/j exactly): distance v·t/2 with
        // t = 0.2 s, so 10 mm, doubled, plus two periods at 100 mm/s.
        let x = Motion {
            s: 0.0,
            v: 100.0,
            a: 0.0,
        };
        let r = reach(&x, 1000.0, 1e4, 0.001);
        assert!((r - (20.0 + 0.2)).abs() < 1e-6, "{r}");
        assert!(too_close(&x, 20.1, 0.0, 1000.0, 1e4, 0.001));
        assert!(!too_close(&x, 20.3, 0.0, 1000.0, 1e4, 0.001));
    }
}
