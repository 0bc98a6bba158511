//! Crossing a stop corner without standing still.
//!
//! A sharp corner whose blend would crawl is an exact stop (see `corner_stop`): the path
//! brakes to rest on the corner, then speeds up along the next element. The second motion
//! may begin before the first has ended, as long as the tool stays within the corner's
//! tolerance band and every axis within its limits: the samples of the last part of the
//! braking and of the first part of the speeding up are added together (each as a
//! displacement from the corner), and the time they overlap is saved.
//!
//! Only corners between elements on the linear axes are crossed so (no rotary axis turns on
//! either side: its degrees do not measure against a band in millimetres), and only where
//! no event or other stop lies on the corner and no feed hold is asked for. The rules,
//! checked on the samples themselves for each number of periods the departure may start
//! early, the largest that keeps them all being taken:
//! * **Band.** Every combined sample is the braking's point plus the departure's offset
//!   from the corner, and must lie within the share of the band a blend may use
//!   ([`TOLERANCE_SHARE`]: the rest covers the way between samples). Where the elements on
//!   either side are lines, its distance from them is computed; otherwise it is bounded:
//!   where the braking's point lies on a programmed element (not on a blend), the combined
//!   sample lies within the departure's distance from the corner of the contour, and where
//!   the departure's point does, within the braking's distance.
//! * **Axes.** Every axis keeps its velocity, acceleration and jerk limits judged as a
//!   trace is, by the first, second and third differences of the positions over the
//!   changed samples and three on either side. An axis that moves in only one of the two
//!   motions follows that motion shifted in time, within its limits as planned; an axis
//!   that moves in both (the slope of a finishing pass and the lift after it) gets the sum
//!   of the two, which `corner_share` makes room for when the corner is committed.
//! * **Feed.** Each block's own motion keeps its feed, as planned. A combined sample moves
//!   both blocks at once; its speed stays within the higher of their speed limits (feed
//!   with the override), and it belongs to that block (the departure's on a tie).
//! * **Turn.** The path turns by at most 150°: a line travelled back (a plunge and its
//!   retract) reaches its end.
//!
//! Nothing else changes: the braking and the departure are those the speed generator
//! planned. The combination needs the samples of the departure before the end of the
//! braking goes out, so as the path closes in on such a corner the planner steps ahead
//! (a few dozen periods at most, in one call) and gives the combined samples out one per
//! call. A feed hold asked for meanwhile acts after them; an event on the way (an op at
//! the corner) gives the samples out as planned, without overlap.

use super::path::Shape;
use super::{Marker, Planner, Sample, Step};
use crate::blend::corner::TOLERANCE_SHARE;
use crate::config::AxisLimits;
use klar_interp::Pose;
use std::collections::VecDeque;

/// Samples of the braking the planner keeps back at most before the corner (more: the
/// braking is given out as planned).
const TAIL_SAMPLES: usize = 256;

/// Samples of the departure taken at most to combine with the braking.
const HEAD_SAMPLES: usize = 64;

/// Periods of travel at the current speed, beyond the band, from which the planner starts
/// keeping the braking's samples back. Braking to rest takes about twice as many periods
/// as its remaining distance over its speed, so the braking's last 30 periods or so are
/// kept: more than the departure's part within the band (about 8 periods at the bench
/// machine's limits) and the braking's within it together with the three periods kept as
/// planned on either side. Fewer periods kept back means a feed hold asked for meanwhile
/// acts sooner.
const LEAD_PERIODS: f64 = 16.0;

/// Cosine of the sharpest turn that is overlapped (150°). A turn back on itself, or
/// nearly, is crossed standing still: the path's far end (the bottom of a plunge, the end
/// of a line before it is travelled back) must be reached, not cut short within the band.
const REVERSAL_COSINE: f64 = -0.866;

/// A sharp stop corner the path may cross without standing still.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StopCorner {
    /// Tolerance band around the programmed contour (mm).
    pub band: f64,
    /// Where the element before is a line: its unit direction (towards the corner) and the
    /// length of it that is travelled.
    pub before: Option<([f64; 9], f64)>,
    /// Where the element after is a line: its unit direction and length.
    pub after: Option<([f64; 9], f64)>,
}

impl StopCorner {
    /// An upper bound of the distance of `p` from the programmed contour around the corner
    /// `c`: the distance from the lines on either side where they are known.
    fn distance(&self, p: &Pose, c: &Pose) -> f64 {
        let w: Vec9 = std::array::from_fn(|i| p.0[i] - c.0[i]);
        let from_line = |dir: &Vec9, sign: f64, length: f64| {
            let along = (0..9).map(|i| w[i] * dir[i] * sign).sum::<f64>();
            let t = along.clamp(0.0, length);
            (0..9)
                .map(|i| (w[i] - sign * dir[i] * t).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        let before = self
            .before
            .map_or(f64::INFINITY, |(d, l)| from_line(&d, -1.0, l));
        let after = self
            .after
            .map_or(f64::INFINITY, |(d, l)| from_line(&d, 1.0, l));
        before.min(after)
    }
}

/// Nine axis values.
type Vec9 = [f64; 9];

/// One sample kept back, with its path distance from the corner (left before it for the
/// braking, travelled after it for the departure).
#[derive(Debug, Clone, Copy)]
struct Kept {
    sample: Sample,
    distance: f64,
    /// True when the sample lies on a programmed element (not on a blend, which may lie
    /// anywhere within the band of the contour).
    on_contour: bool,
    /// Speed limit (programmed feed with the override, and the piece's own) of the piece
    /// it lies on, mm/s.
    limit: f64,
}

/// Where the combination stands.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    /// No corner close.
    Idle,
    /// Braking into the corner at `at` (path position).
    Braking { at: f64, corner: StopCorner },
    /// The planner stood on the corner and departs from it; `within` of the braking's
    /// samples kept back lie within the band.
    Departing {
        at: f64,
        corner: StopCorner,
        within: usize,
    },
}

/// The state of the overlap at corners (see the module documentation).
#[derive(Debug, Clone)]
pub(super) struct Overlap {
    phase: Phase,
    tail: Vec<Kept>,
    head: Vec<Kept>,
    /// Steps ready to go out, oldest first.
    out: VecDeque<Step>,
    /// Set when the planner has passed the stop marker of the corner being braked for.
    passed: bool,
    /// Departure samples kept back that lie beyond the band.
    beyond: usize,
    /// Periods saved at corners so far.
    saved: u64,
}

impl Default for Overlap {
    fn default() -> Self {
        Self {
            phase: Phase::Idle,
            tail: Vec::with_capacity(TAIL_SAMPLES),
            head: Vec::with_capacity(HEAD_SAMPLES),
            out: VecDeque::with_capacity(TAIL_SAMPLES + HEAD_SAMPLES + 2),
            passed: false,
            beyond: 0,
            saved: 0,
        }
    }
}

impl Overlap {
    /// True when nothing is kept back or waiting to go out.
    pub(super) fn is_empty(&self) -> bool {
        self.phase == Phase::Idle && self.out.is_empty()
    }

    /// Samples computed but not given out yet.
    pub(super) fn samples_ahead(&self) -> u64 {
        let waiting = self
            .out
            .iter()
            .filter(|s| matches!(s, Step::Sample(_)))
            .count();
        (waiting + self.tail.len() + self.head.len()) as u64
    }

    /// The planner passed a stop marker at `at`.
    pub(super) fn passed_stop(&mut self, at: f64) {
        if let Phase::Braking { at: corner, .. } = self.phase
            && (corner - at).abs() <= 1e-9
        {
            self.passed = true;
        }
    }

    /// Periods saved at corners so far.
    pub(super) fn saved_periods(&self) -> u64 {
        self.saved
    }

    /// Gives out what was kept back unchanged, then `next` (if any).
    fn give_out_as_planned(&mut self, next: Option<Step>) {
        for k in self.tail.drain(..).chain(self.head.drain(..)) {
            self.out.push_back(Step::Sample(k.sample));
        }
        if let Some(step) = next {
            self.out.push_back(step);
        }
        self.phase = Phase::Idle;
        self.passed = false;
        self.beyond = 0;
    }

    /// The largest number of periods by which the departure may start before the braking
    /// ends (see the module documentation), 0 when it may not.
    fn best_shift(&self, sc: &StopCorner, limits: &[Option<AxisLimits>; 9], period: f64) -> usize {
        let Some(rest) = self.tail.last() else {
            return 0;
        };
        // The braking must end at rest on the corner.
        if rest.distance.abs() > 1e-9 || rest.sample.velocity.iter().any(|v| *v != 0.0) {
            return 0;
        }
        let m = self.tail.len() - 1;
        let corner = rest.sample.pose;
        if self.turn_cosine() < REVERSAL_COSINE {
            return 0;
        }
        // Three samples of the braking before the overlap and three of the departure after
        // it stay as planned (the differences that judge the limits reach over them).
        let most = m.saturating_sub(3).min(self.head.len().saturating_sub(3));
        (1..=most)
            .rev()
            .find(|&k| {
                self.tail[m - k + 1..].iter().zip(&self.head).all(|(b, d)| {
                    let band = TOLERANCE_SHARE * sc.band;
                    let within = (b.on_contour && offset(d, &corner) <= band)
                        || (d.on_contour && offset(b, &corner) <= band)
                        || sc.distance(&combined(b, d, &corner), &corner) <= band;
                    within && speed(b, d) <= b.limit.max(d.limit) * (1.0 + 1e-9)
                }) && self.keeps_limits(k, limits, period)
            })
            .unwrap_or(0)
    }

    /// Cosine of the turn at the corner: between the direction of the braking's last moving
    /// sample and the departure's first (−1 when either has none).
    fn turn_cosine(&self) -> f64 {
        let moving = |k: &&Kept| k.sample.velocity.iter().any(|v| *v != 0.0);
        let (Some(b), Some(d)) = (
            self.tail.iter().rev().find(moving),
            self.head.iter().find(moving),
        ) else {
            return -1.0;
        };
        let (u, w) = (&b.sample.velocity, &d.sample.velocity);
        let dot: f64 = u.iter().zip(w).map(|(x, y)| x * y).sum();
        let norm = |v: &[f64; 9]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        dot / (norm(u) * norm(w))
    }

    /// The `n`-th sample given out when the departure starts `k` periods early (indexed as
    /// the braking's samples, the departure's following them).
    fn shifted(&self, k: usize, n: usize) -> Sample {
        let m = self.tail.len() - 1;
        let corner = self.tail[m].sample.pose.0;
        if n + k <= m {
            return self.tail[n].sample;
        }
        let kept = &self.head[n + k - m - 1];
        let d = kept.sample;
        if n > m {
            return d;
        }
        let b = &self.tail[n];
        let mut s = b.sample;
        s.pose = combined(b, kept, &Pose(corner));
        for (v, w) in s.velocity.iter_mut().zip(&d.velocity) {
            *v += w;
        }
        for (a, w) in s.acceleration.iter_mut().zip(&d.acceleration) {
            *a += w;
        }
        if kept.limit >= b.limit {
            s.loc = d.loc;
        }
        s
    }

    /// True when every axis keeps its limits where the shift by `k` periods changes the
    /// samples given out, judged as a trace is: velocity, acceleration and jerk by the first,
    /// second and third differences of the positions over the periods. A limit the planned
    /// samples already reach there counts as that limit (rounding).
    fn keeps_limits(&self, k: usize, limits: &[Option<AxisLimits>; 9], period: f64) -> bool {
        let m = self.tail.len() - 1;
        let total = self.tail.len() + self.head.len();
        // Three samples before the first changed one, three after the braking's end.
        let lo = m + 1 - k - 3;
        let hi = m + 3;
        let planned = |n: usize| {
            if n <= m {
                self.tail[n].sample.pose
            } else {
                self.head[n - m - 1].sample.pose
            }
        };
        for (i, axis) in limits.iter().enumerate() {
            let Some(l) = axis else { continue };
            let own = peaks(
                (lo..=(hi + k).min(total - 1)).map(|n| planned(n).0[i]),
                period,
            );
            let shifted = peaks((lo..=hi).map(|n| self.shifted(k, n).pose.0[i]), period);
            let most = [l.max_velocity, l.max_acceleration, l.max_jerk];
            for d in 0..3 {
                if shifted[d] > most[d].max(own[d]) * (1.0 + 1e-9) {
                    return false;
                }
            }
        }
        true
    }

    /// Combines the braking and the departure kept back, shifted by the best number of
    /// periods, and queues the result (then `next`, if any). Returns the periods saved.
    fn combine(
        &mut self,
        corner: &StopCorner,
        limits: &[Option<AxisLimits>; 9],
        period: f64,
        next: Option<Step>,
    ) -> usize {
        let k = self.best_shift(corner, limits, period);
        if k == 0 {
            self.give_out_as_planned(next);
            return 0;
        }
        let m = self.tail.len() - 1;
        let shift = k as f64;
        for n in 0..self.tail.len() + self.head.len() - k {
            let mut s = self.shifted(k, n);
            if n > m {
                s.t = ((s.t / period).round() - shift) * period;
            }
            self.out.push_back(Step::Sample(s));
        }
        if let Some(step) = next {
            self.out.push_back(step);
        }
        self.tail.clear();
        self.head.clear();
        self.phase = Phase::Idle;
        self.passed = false;
        self.beyond = 0;
        self.saved += k as u64;
        k
    }
}

/// Largest first, second and third differences of `x` over `period`, `period²` and
/// `period³` (velocity, acceleration and jerk as a trace is judged).
fn peaks(x: impl Iterator<Item = f64>, period: f64) -> [f64; 3] {
    let mut out = [0.0f64; 3];
    let mut w = [f64::NAN; 4];
    for (n, v) in x.enumerate() {
        w = [w[1], w[2], w[3], v];
        if n >= 1 {
            out[0] = out[0].max(((w[3] - w[2]) / period).abs());
        }
        if n >= 2 {
            out[1] = out[1].max(((w[3] - 2.0 * w[2] + w[1]) / (period * period)).abs());
        }
        if n >= 3 {
            let third = w[3] - 3.0 * w[2] + 3.0 * w[1] - w[0];
            out[2] = out[2].max((third / (period * period * period)).abs());
        }
    }
    out
}

/// The pose of the braking's sample `b` plus the departure's `d` offset from the corner `c`.
fn combined(b: &Kept, d: &Kept, c: &Pose) -> Pose {
    Pose(std::array::from_fn(|i| {
        b.sample.pose.0[i] + d.sample.pose.0[i] - c.0[i]
    }))
}

/// Path speed of the braking's sample `b` and the departure's `d` combined (mm/s).
fn speed(b: &Kept, d: &Kept) -> f64 {
    b.sample
        .velocity
        .iter()
        .zip(&d.sample.velocity)
        .map(|(x, y)| (x + y) * (x + y))
        .sum::<f64>()
        .sqrt()
}

/// Straight-line distance of a kept sample from the corner `c`.
fn offset(k: &Kept, c: &Pose) -> f64 {
    k.sample
        .pose
        .0
        .iter()
        .zip(&c.0)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

impl Planner {
    /// True when the path state lies on a programmed element rather than on a blend.
    fn on_contour(&self) -> bool {
        self.pieces
            .front()
            .is_some_and(|p| matches!(p.shape, Shape::Element(_)))
    }

    /// Speed limit of the piece the path state lies on (mm/s).
    fn piece_limit(&self) -> f64 {
        self.pieces
            .front()
            .map_or(0.0, |p| p.speed_limit(self.factor))
    }

    /// The next step for the servo loop, with sharp corners crossed without standing still
    /// where that is allowed (see the module documentation).
    pub(super) fn overlapped_step(&mut self, starved: bool) -> Option<Step> {
        loop {
            if let Some(step) = self.overlap.out.pop_front() {
                return Some(step);
            }
            // While samples are kept back the path goes on with what is committed, as when
            // the caller has no input to give: a caller that gives input whenever the planner
            // asks for it before each call gets `None` only at the end, as without overlap.
            // The look-ahead reaches far beyond the few dozen periods kept back.
            let collecting = self.overlap.phase != Phase::Idle;
            let next = self.step(starved || collecting);
            if next.is_none() {
                // The path ended (a departure that ends the program): what was kept back
                // goes out, combined where it may be.
                if collecting {
                    if let Phase::Braking { corner, .. } | Phase::Departing { corner, .. } =
                        self.overlap.phase
                    {
                        self.end_overlap(&corner, None);
                    }
                    if let Some(step) = self.overlap.out.pop_front() {
                        return Some(step);
                    }
                }
                return None;
            }
            // A step as planned goes out in its option as it came (a sample is hundreds of
            // bytes, and this runs every servo period: no move out of the option and back).
            match self.overlap.phase {
                Phase::Idle => {
                    if let Some(Step::Sample(sample)) = &next
                        && let Some((at, corner)) = self.corner_close()
                    {
                        self.overlap.phase = Phase::Braking { at, corner };
                        self.overlap.tail.push(Kept {
                            sample: *sample,
                            distance: at - self.state.s,
                            on_contour: self.on_contour(),
                            limit: self.piece_limit(),
                        });
                        continue;
                    }
                    return next;
                }
                Phase::Braking { at, corner } => match next {
                    Some(Step::Sample(sample)) if self.overlap.passed => {
                        let band = corner.band;
                        let within = self
                            .overlap
                            .tail
                            .iter()
                            .filter(|k| k.distance <= band)
                            .count();
                        self.overlap.phase = Phase::Departing { at, corner, within };
                        self.keep_departure(sample, at, &corner, within);
                    }
                    Some(Step::Sample(sample)) if self.overlap.tail.len() < TAIL_SAMPLES => {
                        self.overlap.tail.push(Kept {
                            sample,
                            distance: at - self.state.s,
                            on_contour: self.on_contour(),
                            limit: self.piece_limit(),
                        });
                    }
                    other => self.overlap.give_out_as_planned(other),
                },
                Phase::Departing { at, corner, within } => match next {
                    Some(Step::Sample(sample)) => {
                        self.keep_departure(sample, at, &corner, within);
                    }
                    event => self.end_overlap(&corner, event),
                },
            }
        }
    }

    /// Keeps a sample of the departure from the corner at `at`; combines once more would
    /// not help.
    ///
    /// Departure samples beyond the band pair only with the `within` braking samples within
    /// it, and three more stay as planned after the overlap (see `best_shift`).
    fn keep_departure(&mut self, sample: Sample, at: f64, corner: &StopCorner, within: usize) {
        let distance = self.state.s - at;
        let (on_contour, limit) = (self.on_contour(), self.piece_limit());
        self.overlap.head.push(Kept {
            sample,
            distance,
            on_contour,
            limit,
        });
        if distance > corner.band {
            self.overlap.beyond += 1;
        }
        if self.overlap.beyond >= within + 3 || self.overlap.head.len() >= HEAD_SAMPLES {
            self.end_overlap(corner, None);
        }
    }

    /// Combines what was kept back; the planner's clock moves back by the periods saved.
    fn end_overlap(&mut self, corner: &StopCorner, next: Option<Step>) {
        let saved = self
            .overlap
            .combine(corner, &self.config.limits, self.config.period, next);
        self.cycles -= saved as u64;
    }

    /// The corner ahead (path position and band) when the state closes in on a stop that
    /// may be overlapped: the next marker is such a stop, no feed hold is asked for, TCPM is
    /// off, no other marker lies on the corner, and the stop is within the band plus
    /// [`LEAD_PERIODS`] periods' travel.
    fn corner_close(&self) -> Option<(f64, StopCorner)> {
        if self.held || self.hold_pending() || self.tcpm || self.hold_until.is_some() {
            return None;
        }
        match self.markers.front() {
            Some(Marker::Stop {
                at,
                op: None,
                dwell,
                corner: Some(corner),
            }) if *dwell == 0.0
                && !matches!(self.markers.get(1), Some(m) if m.at() <= at + 1e-9) =>
            {
                let left = at - self.state.s;
                let lead = LEAD_PERIODS * self.config.period * self.state.v;
                (left > 0.0 && left <= corner.band + lead).then_some((*at, *corner))
            }
            _ => None,
        }
    }
}
