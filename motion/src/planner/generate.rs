//! The per-period step: markers and events due on the path, advancing the path state and
//! sampling the pose for the servo loop.

use super::speed::{self, Motion};
use super::{Marker, Planner, ROUNDING, SNAP_SHARE, STOP_SNAP, Sample, Step};
use klar_interp::{OpKind, Pose};

impl Planner {
    pub(super) fn at_rest(&self) -> bool {
        self.state.v <= 1e-9 && self.state.a.abs() <= 1e-3
    }

    /// The next sample or event; `None` once finished and drained (or, before
    /// [`Planner::finish`], when it needs input first).
    pub fn next_step(&mut self) -> Option<Step> {
        self.overlapped_step(false)
    }

    /// The next sample or event when the caller has no input to give though the planner
    /// wants some (its source has fallen behind): the path goes on with what is committed.
    /// That is safe because the speed profile always brakes for the end of the committed
    /// path (it counts as a stop, see `next_stop`): a starved path slows down and comes to
    /// rest there, and holds until input arrives. `None` once finished and drained.
    pub fn next_step_starved(&mut self) -> Option<Step> {
        self.overlapped_step(true)
    }

    /// The next step of the planned motion, before corners are overlapped.
    pub(super) fn step(&mut self, starved: bool) -> Option<Step> {
        self.place_move_hold();
        loop {
            match self.markers.front() {
                Some(Marker::Event { at, .. }) if *at <= self.reached + STOP_SNAP => {
                    if let Some(Marker::Event { op, .. }) = self.markers.pop_front() {
                        if let OpKind::Tcpm {
                            reframe: Some(p), ..
                        } = &op.kind
                        {
                            self.reframe(*p);
                        }
                        return Some(Step::Event(op));
                    }
                }
                Some(Marker::Stop { at, .. })
                    if self.stash.is_none()
                        && self.at_rest()
                        && (*at - self.state.s).abs() <= ROUNDING =>
                {
                    let at = *at;
                    self.state = Motion {
                        s: at,
                        v: 0.0,
                        a: 0.0,
                    };
                    self.reached = at;
                    self.reached_stop(at);
                    self.overlap.passed_stop(at);
                    if let Some(Marker::Stop { op, dwell, .. }) = self.markers.pop_front() {
                        if dwell > 0.0 {
                            let loc = op.as_ref().map_or(self.rest_loc, |o| o.loc);
                            // Holds at the same point add up (two dwells, a dwell and
                            // a machine function's wait).
                            let now = self.cycles as f64 * self.config.period;
                            let from = self.hold_until.map_or(now, |(end, _)| end.max(now));
                            self.hold_until = Some((from + dwell, loc));
                        }
                        if let Some(op) = op {
                            if let Some((_, to)) = op.kind.geared_ends() {
                                // The servo loop moves the axes to `to` during the event.
                                self.reframe(to);
                            }
                            return Some(Step::Event(op));
                        }
                    }
                    continue;
                }
                _ => {}
            }
            if let Some(sample) = self.stash.take() {
                return Some(Step::Sample(sample));
            }
            let t = (self.cycles + 1) as f64 * self.config.period;
            if let Some((end, loc)) = self.hold_until {
                if t <= end + 1e-9 {
                    self.cycles += 1;
                    let pose = self.pose_here();
                    return Some(Step::Sample(Sample {
                        t,
                        pose,
                        velocity: [0.0; 9],
                        acceleration: [0.0; 9],
                        loc,
                    }));
                }
                self.hold_until = None;
            }
            if !self.finished && !starved && self.needs_input() {
                return None;
            }
            if self.finished
                && self.markers.is_empty()
                && self.at_rest()
                && self.state.s >= self.committed_end - ROUNDING
            {
                return None;
            }
            let sample = self.advance(t);
            self.cycles += 1;
            if matches!(self.markers.front(), Some(Marker::Event { at, .. }) if *at <= self.reached + STOP_SNAP)
            {
                self.stash = Some(sample);
                continue;
            }
            return Some(Step::Sample(sample));
        }
    }

    /// The frame changed under the machine standing at the end of the path so far (a TCPM
    /// switch): the pieces behind it are done, and the pose it stands at is `p` from now on,
    /// so every sample after the switch event is in the new frame.
    pub(super) fn reframe(&mut self, p: Pose) {
        while self
            .pieces
            .front()
            .is_some_and(|piece| piece.end() <= self.reached + STOP_SNAP)
        {
            if let Some(piece) = self.pieces.pop_front() {
                self.rest_loc = piece.loc;
            }
        }
        self.rest_pose = p;
        if let Some(sample) = self.stash.as_mut() {
            sample.pose = p;
        }
    }

    /// Where the machine stands: on the current piece, or at rest after the last one.
    fn pose_here(&self) -> Pose {
        match self.pieces.front() {
            Some(p) => p.point(self.state.s).pose,
            None => self.rest_pose,
        }
    }

    /// The speed the period's action heads for: the current piece's limit (zero in a feed
    /// hold), or the next piece's where that is faster, the state may get there still
    /// speeding up (within the distance easing the largest acceleration of the current
    /// piece covers, plus two periods' travel) and the path does not stop in between. The
    /// checks keep the speed within the current piece's limit until its end (see
    /// `through::leaves_below`).
    pub(super) fn go_target(&self) -> f64 {
        let k = self.current_index();
        let Some(p) = self.pieces.get(k).filter(|_| !self.held) else {
            return 0.0;
        };
        let here = p.speed_limit(self.factor);
        let Some(q) = self.pieces.get(k + 1) else {
            return here;
        };
        let (v, accel) = (self.state.v, p.grip.most());
        let ease = accel / p.jerk;
        let reach = (v + accel * ease) * ease + 2.0 * v * self.config.period;
        if accel.is_finite() && p.end() - self.state.s <= reach && self.next_stop() > p.end() {
            here.max(q.speed_limit(self.factor))
        } else {
            here
        }
    }

    /// Moves the path state on by one period and samples it at time `t`.
    fn advance(&mut self, t: f64) -> Sample {
        let next = match self.cruise_step() {
            Some(next) => next,
            None => self.generate(),
        };
        self.state = next;
        self.reached = next.s;
        self.sample_at(t, next)
    }

    /// The next state from the speed generator.
    fn generate(&mut self) -> Motion {
        self.scan();
        let target = self.go_target();
        let before = self.state;
        let mut next = speed::advance_with(
            &self.state,
            target,
            &self.window,
            self.config.period,
            &mut self.scratch,
        );
        if let Some(split) = self.hand_over(&before, &next, target) {
            next = split;
        }
        // Never past the end of the committed path or the next stop.
        let stop = self.next_stop();
        if next.s > stop {
            if next.s - stop > STOP_SNAP {
                tracing::warn!(over = next.s - stop, "path state clamped at a stop point");
            }
            next = Motion {
                s: stop,
                v: 0.0,
                a: 0.0,
            };
        }
        if next.v < 0.0 {
            next.v = 0.0;
        }
        // On the stop point when getting there in one step costs a negligible acceleration
        // and jerk.
        let period = self.config.period;
        let step_accel = (stop - next.s) / (period * period) + next.v / period + next.a.abs();
        let negligible = next.s <= stop
            && step_accel / period <= SNAP_SHARE * self.window.jerk
            && step_accel <= SNAP_SHARE * self.window.grip.most();
        if negligible {
            next = Motion {
                s: stop,
                v: 0.0,
                a: 0.0,
            };
        }
        self.find_cruise(&before, &next, target);
        next
    }

    /// Moves past the pieces behind `next` and samples it at time `t`.
    fn sample_at(&mut self, t: f64, next: Motion) -> Sample {
        while self.pieces.len() > 1 && self.pieces.front().is_some_and(|p| p.end() < next.s) {
            if let Some(p) = self.pieces.pop_front() {
                self.rest_pose = p.point(p.end()).pose;
                self.rest_loc = p.loc;
            }
        }
        match self.pieces.front() {
            Some(p) => {
                let point = p.point(next.s);
                let mut velocity = [0.0; 9];
                let mut acceleration = [0.0; 9];
                for i in 0..9 {
                    velocity[i] = point.d1[i] * next.v;
                    acceleration[i] = point.d1[i] * next.a + point.d2[i] * next.v * next.v;
                }
                Sample {
                    t,
                    pose: point.pose,
                    velocity,
                    acceleration,
                    loc: p.loc,
                }
            }
            None => Sample {
                t,
                pose: self.rest_pose,
                velocity: [0.0; 9],
                acceleration: [0.0; 9],
                loc: self.rest_loc,
            },
        }
    }
}
