//! The look-ahead window: which piece the path state moves on, where it must stop next, and
//! the speed limits ahead that can matter within the braking distance ([`speed::Window`]).

use super::speed::{self, Limit, Motion};
use super::{Marker, Planner, deep};
use crate::limits::Grip;

/// Largest distance (mm) over which a limit may join the one before it.
const MERGE_DISTANCE: f64 = 0.5;

/// Largest relative drop in speed with which a limit may join the one before it.
const MERGE_SHARE: f64 = 0.01;

impl Planner {
    /// Index of the piece the path state moves on: the first that ends beyond it (a state
    /// exactly at a piece's end moves on the next one).
    pub(super) fn current_index(&self) -> usize {
        let s = self.state.s;
        self.pieces
            .iter()
            .position(|p| p.end() > s)
            .unwrap_or(self.pieces.len().saturating_sub(1))
    }

    /// The next point where the path must stand still.
    pub(super) fn next_stop(&self) -> f64 {
        self.markers
            .iter()
            .find_map(|m| match m {
                Marker::Stop { at, .. } => Some(*at),
                Marker::Event { .. } => None,
            })
            .unwrap_or(self.committed_end)
            .min(self.committed_end)
    }

    /// Collects the speed limits ahead that can matter within the braking distance.
    pub(super) fn scan(&mut self) {
        let s = self.state.s;
        let stop = self.next_stop();
        let first = self.current_index();
        let current = match self.pieces.get(first) {
            Some(p) => p.speed_limit(self.factor),
            None => 0.0,
        };
        let vh = self.state.v.max(current);
        let (v0, a0, period) = (vh, self.state.a.max(0.0), self.config.period);
        // Braking distance with the lowest limits seen so far, doubled. A piece's grip is
        // taken at the lower of the speed it allows and the state's: on a tight curve the
        // grip at the state's speed may be none at all (the curvature would take all of
        // the acceleration), but the path is never on it that fast, and an infinite reach
        // would pull the whole program into the window.
        let from = Motion {
            s: 0.0,
            v: v0,
            a: a0,
        };
        let reach_for = |grip: &Grip, jerk: f64| {
            2.0 * speed::brake_distance(&from, 0.0, grip, jerk) + 2.0 * v0 * period + 1e-9
        };
        let floor = Grip::constant(self.accel_floor);
        let mut range = reach_for(&floor, self.jerk_floor);
        // Pieces ahead that turn a rotary axis may allow far less than the floors (see
        // `deep`): the window reaches as far as braking with their limits needs.
        self.low_ahead.pass(s);
        if !self.low_ahead.is_empty() {
            let (accel, jerk) = self.low_ahead.lowest((self.accel_floor, self.jerk_floor));
            range = range.max(deep::reach(&from, accel, jerk, period));
        }
        let w = &mut self.window;
        w.limits.clear();
        // Acceleration and jerk for the next period: those of the current piece (the
        // limits ahead make the state arrive at each piece within its acceleration limit;
        // neighbouring pieces share the lower jerk limit near their joint, see `push_piece`).
        let none = Grip::constant(f64::INFINITY);
        w.grip = none;
        w.jerk = f64::INFINITY;
        let (mut pre_grip, mut pre_jerk) = (none, f64::INFINITY);
        let (mut low_speed, mut low_grip) = (f64::INFINITY, none);
        let mut low_jerk = f64::INFINITY;
        // Path distance the next period can reach: a piece starting within it shares its
        // jerk limit with the current one for that period.
        let next_reach = s + speed::period_travel(
            self.state.v,
            self.state.a,
            self.pieces.get(first).map_or(0.0, |p| p.jerk),
            period,
        );
        let (mut reach_accel, mut reach_jerk) = (f64::INFINITY, f64::INFINITY);
        for (k, p) in self.pieces.iter().skip(first).enumerate() {
            if p.start - s > range || p.start >= stop {
                break;
            }
            let limit = p.speed_limit(self.factor);
            let accel = p.grip.at(v0.min(limit));
            if accel < reach_accel || p.jerk < reach_jerk {
                reach_accel = reach_accel.min(accel);
                reach_jerk = reach_jerk.min(p.jerk);
                range = range.max(reach_for(&Grip::constant(reach_accel), reach_jerk));
            }
            if k == 0 {
                w.grip = p.grip;
                w.jerk = p.jerk;
                pre_grip = p.grip;
                pre_jerk = p.jerk;
            } else if p.start <= next_reach {
                w.jerk = w.jerk.min(p.jerk);
            }
            // A jerk below all before it in the window is a limit too: the state must
            // reach that piece able to go on with its jerk (a piece committed while the
            // path state moved on the piece before keeps its own, higher jerk, see
            // `push_piece`). Meeting the lowest one ahead prepares for all higher ones.
            let jerk_drops = p.jerk < low_jerk;
            low_jerk = low_jerk.min(p.jerk);
            // Likewise a grip below the lowest before it at some speed; the limit keeps the
            // lowest grip so far, which every piece up to the next limit allows.
            if limit < low_speed || low_grip.undercut_by(&p.grip) || (k > 0 && jerk_drops) {
                // Only a lower acceleration or jerk limit, or a speed that is no step down
                // (`Piece::drop`, decided as the piece was committed): a soft limit (see
                // `speed::Limit`), met on its own while it is ahead. So is the current
                // piece's own: the state is past its start, so the backward pass must not
                // lower it as if the path stood there; the limits ahead are met from the
                // state itself.
                let soft = k == 0 || !p.drop;
                // The running minima start after the current piece: the state is on it
                // already, and a piece ahead with a higher limit than the current one may
                // still be a step down from the pieces around it, settled lower by those
                // after it. Left out while the state is on a slower piece, it would turn up
                // as a limit below the state's braking curve as soon as the state moved on.
                if k > 0 {
                    low_speed = low_speed.min(limit);
                    low_grip = low_grip.min(p.grip);
                }
                match w.limits.last_mut() {
                    // A limit barely below one just before it (dense code, where the speed
                    // limits of the blends drift down piece by piece) joins that one: its
                    // limits then hold from the earlier place on, which is stricter, and the
                    // window stays short. Not a drop in jerk: where the jerk drops decides how
                    // far a positive acceleration may be eased with the higher jerk before
                    // it, and moving that place with the current piece would let one period's
                    // check accept what the next one's refuses.
                    Some(last)
                        if last.at > s
                            && p.start - last.at <= MERGE_DISTANCE
                            && limit >= last.speed * (1.0 - MERGE_SHARE)
                            && p.jerk >= last.jerk =>
                    {
                        last.speed = last.speed.min(limit);
                        last.own = last.own.min(limit);
                        last.soft &= soft;
                        last.grip_after = low_grip;
                        last.jerk = last.jerk.min(p.jerk);
                        pre_grip = pre_grip.min(p.grip);
                        pre_jerk = pre_jerk.min(p.jerk);
                    }
                    _ => {
                        // The ramp that meets this limit arrives in a state the piece's own
                        // jerk can continue from: it uses the lower of the two jerks.
                        w.limits.push(Limit {
                            at: p.start,
                            speed: limit,
                            own: limit,
                            grip_after: low_grip,
                            grip: pre_grip,
                            jerk: pre_jerk.min(p.jerk),
                            soft,
                        });
                        // Limits further on are checked from this one (see `speed::settle`).
                        pre_grip = p.grip;
                        pre_jerk = p.jerk;
                    }
                }
            }
            if pre_grip.undercut_by(&p.grip) || p.jerk < pre_jerk {
                pre_grip = pre_grip.min(p.grip);
                pre_jerk = pre_jerk.min(p.jerk);
            }
        }
        self.range = range;
        if !w.grip.most().is_finite() {
            w.grip = floor;
            w.jerk = self.jerk_floor;
        }
        if !pre_grip.most().is_finite() {
            pre_grip = w.grip;
            pre_jerk = w.jerk;
        }
        if stop - s <= range {
            w.limits.push(Limit {
                at: stop,
                speed: 0.0,
                own: 0.0,
                grip_after: none,
                grip: pre_grip,
                jerk: pre_jerk,
                soft: false,
            });
        }
        self.settled.settle(&mut w.limits);
    }
}

/// The limits of the last window before and after [`speed::settle`]. The window is scanned
/// every period, but its limits change only where a piece enters or leaves it: the backward
/// pass of an unchanged list gives the same result, so it is taken from here instead.
#[derive(Debug, Clone, Default)]
pub(super) struct SettleMemo {
    /// The limits as the last scan collected them.
    raw: Vec<Limit>,
    /// The same after the backward pass.
    settled: Vec<Limit>,
}

impl SettleMemo {
    /// Makes room for `n` limits in each list.
    pub(super) fn reserve(&mut self, n: usize) {
        self.raw.reserve(n);
        self.settled.reserve(n);
    }

    /// Settles `limits` (see [`speed::settle`]), reusing the last result when the list is
    /// the same as last time.
    fn settle(&mut self, limits: &mut Vec<Limit>) {
        if *limits == self.raw {
            limits.clone_from(&self.settled);
            return;
        }
        self.raw.clone_from(limits);
        speed::settle(limits);
        self.settled.clone_from(limits);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The backward pass on its own.
    fn settled(limits: &[Limit]) -> Vec<Limit> {
        let mut l = limits.to_vec();
        speed::settle(&mut l);
        l
    }

    #[test]
    fn the_memo_settles_as_the_backward_pass_does_whether_the_window_changed_or_not() {
        // Three windows in a row: 30 mm/s then a stop 0.4 mm ahead (the backward pass lowers
        // the first), the same again, then one whose stop has moved on.
        let first = vec![
            Limit::uniform(0.0, 50.0, 1000.0, 1e5, true),
            Limit::uniform(0.2, 30.0, 1000.0, 1e5, false),
            Limit::uniform(0.6, 0.0, 1000.0, 1e5, false),
        ];
        let mut moved = first.clone();
        moved[2].at = 5.0;
        let mut memo = SettleMemo::default();
        for raw in [&first, &first, &moved, &first] {
            let mut l = raw.clone();
            memo.settle(&mut l);
            assert_eq!(l, settled(raw));
        }
        // The pass did lower the 30 mm/s limit before the near stop, and not before the far
        // one: the windows really settle differently.
        assert!(settled(&first)[1].speed < 30.0);
        assert_eq!(settled(&moved)[1].speed, 30.0);
    }
}
