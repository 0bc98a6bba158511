//! Cruising: periods at constant speed far from every limit ahead, taken without the speed
//! generator.
//!
//! Most of a long program's periods run at a piece's speed limit with zero acceleration and
//! nothing to slow down for within several braking distances. There the generator would
//! check every limit in the window each period only to find the same answer: speed held. So
//! after a period the generator ended cruising, the planner works out how far the state may
//! go on at that speed: up to twice the braking distance (with the limits' own acceleration
//! and jerk) before every lower limit in the window, half the window's reach beyond which
//! it has not looked, the first piece ahead with another speed limit, the point where a
//! piece could hand over to a faster next one (`Planner::go_target`), and four periods'
//! travel short of each. Pieces with the same limit follow each other without a handover,
//! so a cruise goes on over their joints (the short chords of CAM code). Until then each
//! period moves the state on by `v·T`; a feed override, a feed hold or a new window ends it
//! (the next period is the generator's again).

use super::Planner;
use super::speed::{self, Motion};

/// The cruise the state is on, if any.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Cruising {
    /// The stretch found after the last period of the generator.
    stretch: Option<Cruise>,
    /// True when every period goes through the generator (tests compare the two).
    off: bool,
    /// Periods taken cruising so far.
    taken: u64,
}

/// A stretch the state may cruise over without the generator.
#[derive(Debug, Clone, Copy)]
struct Cruise {
    /// Path position the state may reach at most this way.
    until: f64,
    /// The speed it holds.
    speed: f64,
    /// The feed override it was found for.
    factor: f64,
}

/// Periods' travel kept short of every limit and of the handover to the next piece.
const CRUISE_MARGIN: f64 = 4.0;

impl Planner {
    /// The next state when the state may cruise on for one more period.
    pub(super) fn cruise_step(&mut self) -> Option<Motion> {
        let c = self.cruise.stretch?;
        let x = self.state;
        let dt = self.config.period;
        let ok = !self.held
            && self.factor == c.factor
            && x.a == 0.0
            && x.v == c.speed
            && x.s + x.v * dt <= c.until;
        if !ok {
            self.cruise.stretch = None;
            return None;
        }
        self.cruise.taken += 1;
        Some(Motion {
            s: x.s + x.v * dt,
            v: x.v,
            a: 0.0,
        })
    }

    /// After a period of the generator that ended at `next` from the state before it, with
    /// speed target `target`: the stretch it may cruise over from there, if any.
    pub(super) fn find_cruise(&mut self, before: &Motion, next: &Motion, target: f64) {
        self.cruise.stretch = None;
        if self.cruise.off
            || self.held
            || next.a != 0.0
            || before.a != 0.0
            || next.v != before.v
            || next.v != target
        {
            return;
        }
        let v = next.v;
        if v <= 0.0 {
            return;
        }
        let margin = CRUISE_MARGIN * v * self.config.period;
        let from = Motion { s: 0.0, v, a: 0.0 };
        let mut until = next.s + 0.5 * self.range;
        for l in &self.window.limits {
            if l.at <= next.s {
                continue;
            }
            if l.speed < v {
                let brake = speed::brake_distance(&from, l.speed, &l.grip, l.jerk);
                if !brake.is_finite() {
                    return;
                }
                until = until.min(l.at - 2.0 * brake);
            }
        }
        // The speed target (`go_target`) stays the speed held while the state is on pieces
        // whose limit is that speed: the cruise may go on over the joints between them (dense
        // code), and ends at the first piece with another limit (a lower one is a limit of
        // the window, met above). The handover to a faster next piece starts within this
        // reach of the end of the piece before it.
        let k = self.current_index();
        for (i, p) in self.pieces.iter().enumerate().skip(k) {
            if p.start >= until {
                break;
            }
            if p.speed_limit(self.factor) != v {
                until = until.min(p.start);
                break;
            }
            let faster = self
                .pieces
                .get(i + 1)
                .is_some_and(|q| q.speed_limit(self.factor) > v);
            if faster {
                let accel = p.grip.most();
                let ease = if accel.is_finite() {
                    accel / p.jerk
                } else {
                    0.0
                };
                let reach = (v + accel.min(1e12) * ease) * ease + 2.0 * v * self.config.period;
                until = until.min(p.end() - reach);
                break;
            }
        }
        until -= margin;
        if until > next.s + v * self.config.period {
            self.cruise.stretch = Some(Cruise {
                until,
                speed: v,
                factor: self.factor,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Step;
    use klar_interp::{Feed, Op, OpKind, Pose, SourceLoc};

    fn line(from: Pose, to: Pose, feed: f64) -> Op {
        Op {
            kind: OpKind::Line {
                from,
                to,
                feed: Feed::Rate(feed),
            },
            loc: SourceLoc::default(),
        }
    }

    fn samples(ops: &[Op], off: bool) -> (Vec<(f64, Pose)>, u64) {
        let mut p = super::super::test_machine::planner();
        p.cruise.off = off;
        let mut ops = ops.iter().cloned();
        let mut out = Vec::new();
        loop {
            while p.needs_input() {
                match ops.next() {
                    Some(o) => p.push(o).expect("op accepted"),
                    None => p.finish(),
                }
            }
            match p.next_step() {
                Some(Step::Sample(s)) => out.push((s.t, s.pose)),
                Some(Step::Event(_)) => {}
                None => break,
            }
        }
        (out, p.cruise.taken)
    }

    #[test]
    fn cruising_gives_the_generators_samples() {
        // Long lines at two feeds, a slow stretch, corners and a stop in between: the
        // samples with cruising are those of the generator alone, bit for bit.
        let p = |x: f64, y: f64| Pose::xyz(x, y, 0.0);
        let ops = vec![
            line(p(0.0, 0.0), p(80.0, 0.0), 60.0),
            line(p(80.0, 0.0), p(83.0, 0.001), 10.0),
            line(p(83.0, 0.001), p(150.0, 0.001), 90.0),
            line(p(150.0, 0.001), p(150.0, 60.0), 40.0),
            line(p(150.0, 60.0), p(10.0, 20.0), 100.0),
        ];
        let (with, cruised) = samples(&ops, false);
        let (without, none) = samples(&ops, true);
        assert!(with.len() > 4000);
        assert!(
            cruised > with.len() as u64 / 2,
            "{cruised} of {}",
            with.len()
        );
        assert_eq!(none, 0);
        assert_eq!(with, without);
    }

    #[test]
    fn cruising_goes_on_over_the_joints_of_short_chords_at_one_feed() {
        // 200 chords of 0.3 mm along X at 40 mm/s, then a turn into Y: each chord is shorter
        // than the reach within which a piece could hand over to a faster one (about 0.58 mm
        // at 40 mm/s with 1000 mm/s² and 1e5 mm/s³), so only cruising over the joints lets
        // most periods skip the generator. The samples stay the generator's, bit for bit.
        let mut ops = Vec::new();
        for k in 0..200 {
            let x = |k: i32| 0.3 * f64::from(k);
            ops.push(line(
                Pose::xyz(x(k), 0.0, 0.0),
                Pose::xyz(x(k + 1), 0.0, 0.0),
                40.0,
            ));
        }
        ops.push(line(
            Pose::xyz(60.0, 0.0, 0.0),
            Pose::xyz(60.0, 30.0, 0.0),
            40.0,
        ));
        let (with, cruised) = samples(&ops, false);
        let (without, _) = samples(&ops, true);
        // 90 mm at 40 mm/s: a little over 2.25 s.
        assert!(with.len() > 2250, "{}", with.len());
        assert!(
            cruised > with.len() as u64 * 3 / 4,
            "{cruised} of {}",
            with.len()
        );
        assert_eq!(with, without);
    }
}
