//! The jerk-limited speed generator along the blended path.
//!
//! The path state is distance, speed and acceleration `(s, v, a)`. Each servo period it
//! moves on by the fastest admissible action, judged by whether the state after the period
//! is *safe*: for every speed limit ahead (the start of a piece with a lower limit, a stop
//! point, the end of the planned path), the time-optimal jerk-limited [`Ramp`] down to that
//! limit fits into the distance left, and the speed can be brought to a standstill without
//! reversing. Only the running minima of the limits ahead need checking (a higher limit
//! behind a lower one is met by the braking for the lower one), and only within the distance
//! the machine could need to brake.
//!
//! Checks and actions must agree: a state judged safe must have an action whose result is
//! judged safe again, or the generator falls behind a braking curve and can only be clamped
//! (a speed below zero, an acceleration step). So each speed limit is judged with the ramp
//! the generator then follows to meet it (the limit's own acceleration and jerk), and the
//! nearest limit ahead that the state must slow down for stands for everything behind it.
//!
//! The candidate actions are ramps ([`Ramp`]) towards a speed, best first:
//! 1. *go*: the ramp towards the speed limit (or the feed hold's zero) of the current piece;
//! 2. the ramp towards the highest speed, between a binding limit and the go target, whose
//!    result is safe (found by bisection, narrowed by probes: `search`): it rides the
//!    braking curve in front of a limit.
//!    Binding limits are tried worst first: those the state misses, those the go ramp
//!    would miss; then, with a deceleration, the ramp that eases it at once with the
//!    current jerk (the way to come to rest without reversing that the check assumes); then
//!    a stop. The search looks no higher than the speed above which all ramps move alike
//!    over the period, so it stays fine where the answer is;
//! 3. when none is safe (a state off a braking curve, by rounding or past limits it meets
//!    only by braking for one further on): of these ramps the one that leaves the lowest
//!    speed without turning the path back.
//!
//! A limit is met with zero acceleration unless the path passes it on the way to another:
//! braking through it towards a lower limit behind it (see `passes_under`: the parts of a
//! blend into a corner, whose limits step down piece by piece), or leaving the current
//! piece for a faster one while still speeding up (see `leaves_below`: out of a corner).
//! Then the state must cross the limit no faster than the limit's own speed and within
//! the acceleration limit after it, and the limits behind it are judged on their own.
//!
//! Each action has |jerk| ≤ J and |a| ≤ A, the window's smallest path limits, so the
//! per-axis limits of every piece in the window hold. Positions are integrated exactly for
//! piecewise constant jerk, so finite differences of the samples stay within the limits too.
//!
//! On curves the acceleration limit depends on the speed ([`Grip`]): it is all of the limit
//! at rest and shrinks as the curvature term κ·v² takes its share. A ramp that never goes
//! faster than `u` may use the grip at `u`, so every action uses the grip of the highest
//! speed it reaches. Speeding up, the generator picks the ramp whose own top speed gives the
//! most speed after the period. Braking, the checks let the ramp switch to the higher
//! acceleration of lower speeds at fixed knees of the grip ([`brake_distance`]).

use super::search::highest_safe;
use super::through::{CROSSING_SLACK, leaves_below, passes_under};
use super::verdicts::Verdicts;
use crate::limits::Grip;
use crate::profile::Ramp;

/// Path distance, speed and acceleration.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Motion {
    /// Path distance.
    pub s: f64,
    /// Path speed.
    pub v: f64,
    /// Path acceleration.
    pub a: f64,
}

/// Limits that start at a path position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limit {
    /// Where they start.
    pub at: f64,
    /// The speed limit from there on (0 for a stop), lowered by [`settle`] until the
    /// limits after it can be met from it.
    pub speed: f64,
    /// The speed limit of the pieces from there on as they allow it (before [`settle`]):
    /// what a state braking through the limit towards a lower one must not exceed.
    pub own: f64,
    /// The acceleration limit by speed from there on.
    pub grip_after: Grip,
    /// The smallest acceleration limit by speed between the current position and `at`.
    pub grip: Grip,
    /// The smallest jerk limit between the current position and `at`.
    pub jerk: f64,
    /// True when the speed does not drop here: the limit only carries a lower acceleration
    /// or jerk limit. [`settle`] never lowers such a limit's speed (it would stand as a
    /// step in a braking curve for a lower limit further on), and the nearest limit ahead
    /// that stands for all further ones is the nearest one that is not soft.
    pub soft: bool,
}

#[cfg(test)]
impl Limit {
    /// A limit at `at` with speed `speed` (its own too), acceleration `accel` at every
    /// speed and jerk `jerk` on the way to it and after it.
    pub(super) fn uniform(at: f64, speed: f64, accel: f64, jerk: f64, soft: bool) -> Limit {
        let grip = Grip::constant(accel);
        Limit {
            at,
            speed,
            own: speed,
            grip_after: grip,
            grip,
            jerk,
            soft,
        }
    }
}

/// What the generator needs to know about the path ahead.
#[derive(Debug, Clone)]
pub struct Window {
    /// Running minima of the limits ahead, in path order (the first is the current piece).
    pub limits: Vec<Limit>,
    /// Acceleration limit by speed for the next period.
    pub grip: Grip,
    /// Jerk limit for the next period.
    pub jerk: f64,
    /// The servo period (s): a piece starting within one period's travel of the state
    /// lends its jerk limit to the period's action.
    pub period: f64,
}

impl Default for Window {
    fn default() -> Self {
        Window {
            limits: Vec::new(),
            grip: Grip::constant(f64::INFINITY),
            jerk: f64::INFINITY,
            period: 0.0,
        }
    }
}

/// Share of a limit's acceleration and jerk that the braking ramps of the checks assume.
/// The actions brake with the full limits, so a state judged safe always has an action
/// whose result is judged safe again, with room for rounding and for limits that follow
/// each other closer than one period travels (dense CAM code).
pub(super) const JUDGE: f64 = 0.98;

/// Slack for rounding: relative, when comparing an acceleration with a limit; absolute
/// (mm/s), for the speed left when a deceleration is eased.
pub(super) const SPEED_SLACK: f64 = 1e-9;

/// Relative slack above a speed limit that a state may have and still meet it (rounding),
/// and the absolute slack above a stop's zero. The search for the highest safe ramp can land
/// anywhere within it, so it is kept well below what a trace would notice.
pub(super) const LIMIT_SLACK: f64 = 1e-11;

/// Distance slack when comparing braking distances (rounding), mm.
const DISTANCE_SLACK: f64 = 1e-12;

/// Shares of the grip's peak at which a braking ramp switches to the higher acceleration
/// of lower speeds (see [`brake_distance`]), highest speed first.
const KNEE_SHARES: [f64; 2] = [0.35, 0.7];

/// Relative change of the grip over a speed range below which it counts as constant.
const GRIP_CHANGE: f64 = 0.02;

/// Golden-section steps for the ramp's top speed when speeding up on a curve.
const TOP_STEPS: usize = 14;

/// Distance one servo period of `period` seconds can cover at most from speed `v` with
/// acceleration `a` under jerk `jerk` (a bound: `v·T + |a|·T² + j·T³`). A piece that starts
/// within it may be reached in the next period.
pub fn period_travel(v: f64, a: f64, jerk: f64, period: f64) -> f64 {
    v * period + a.abs() * period * period + jerk * period.powi(3)
}

/// The speed `x` settles at when its acceleration is brought to zero at once with jerk
/// `jerk`: above its speed when it speeds up, below when it slows down.
pub(super) fn settled_speed(x: &Motion, jerk: f64) -> f64 {
    x.v + x.a * x.a.abs() / (2.0 * jerk)
}

/// The highest speed `x` reaches when its acceleration is brought to zero at once.
pub fn peak_speed(x: &Motion, jerk: f64) -> f64 {
    let a = x.a.max(0.0);
    x.v + a * a / (2.0 * jerk)
}

/// Distance the path needs from `x` to slow down to `target` (ending with zero
/// acceleration) with the acceleration `grip` allows and jerk `jerk`: the shorter of one
/// ramp with the grip of the highest speed, and a chain of ramps that switches to the grip
/// of each knee (`KNEE_SHARES`) once the speed is below it. Each ramp of the chain ends at
/// its knee with zero acceleration, so the chain is a motion the actions can follow.
/// Infinite when the grip leaves no acceleration at the start.
pub fn brake_distance(x: &Motion, target: f64, grip: &Grip, jerk: f64) -> f64 {
    brake_distance_within(x, target, grip, jerk, f64::NEG_INFINITY)
}

/// [`brake_distance`], or, when that is at most `enough`, possibly a larger value that is
/// still at most `enough`: the single ramp is tried first and the chain skipped when it
/// already fits (a check against the distance left needs no more).
fn brake_distance_within(x: &Motion, target: f64, grip: &Grip, jerk: f64, enough: f64) -> f64 {
    let top = peak_speed(x, jerk);
    let first = grip.at(top);
    if first <= 0.0 {
        return f64::INFINITY;
    }
    let single = Ramp::new(x.v, x.a, target, first, jerk).distance();
    if single <= enough {
        return single;
    }
    let mut knees = KNEE_SHARES
        .iter()
        .filter_map(|&f| grip.knee(f))
        .filter(|&u| u > target && u < x.v.min(top));
    let Some(knee) = knees.next() else {
        return single;
    };
    let mut chain = Ramp::new(x.v, x.a, knee, first, jerk).distance();
    let mut from = knee;
    for u in knees {
        chain += Ramp::new(from, 0.0, u, grip.at(from), jerk).distance();
        from = u;
    }
    chain += Ramp::new(from, 0.0, target, grip.at(from), jerk).distance();
    single.min(chain)
}

/// Distance travelled while |a| is brought down to `limit` with jerk `jerk`.
pub(super) fn easing_distance(x: &Motion, limit: f64, jerk: f64) -> f64 {
    let t = (x.a.abs() - limit).max(0.0) / jerk;
    let j = -x.a.signum() * jerk;
    (x.v * t + 0.5 * x.a * t * t + j * t * t * t / 6.0).max(0.0)
}

/// The jerk with which `x` may start bringing a positive acceleration down to zero on its way
/// to limit `l` ahead, and how far it holds: the window's jerk when that is higher than the
/// limit's, up to one period's travel before the nearest limit ahead with a lower jerk
/// (where the jerk drops: a piece with a lower jerk than the current one is always a limit
/// of its own; `l` itself when none is nearer). From there on the period's action already
/// has the lower jerk (see `Planner::scan`). `None` when the limit's own jerk applies from
/// the start.
///
/// Past that place the easing goes on with the lower jerk. A rule that eased with the higher
/// jerk only when the whole easing ended before the drop would be a cliff: one period
/// closer to the drop the braking need would jump to the one with the low jerk throughout,
/// and a state judged safe would have no safe successor.
fn easing_for(x: &Motion, l: &Limit, w: &Window) -> Option<(f64, f64)> {
    if x.a <= 0.0 || l.at <= x.s || w.jerk <= l.jerk {
        return None;
    }
    let nearest = w
        .limits
        .iter()
        .find(|m| m.at > x.s && m.jerk < w.jerk)
        .map_or(l.at, |m| m.at.min(l.at));
    // The travel of one period, at the highest speed the easing reaches.
    let reach = period_travel(peak_speed(x, w.jerk), x.a, w.jerk, w.period);
    Some((w.jerk, (nearest - reach).max(x.s)))
}

/// Newton steps for the time at which an easing reaches a given distance.
const EASING_STEPS: usize = 16;

/// The state after `x` has moved on by `distance` while its acceleration is brought towards
/// zero with jerk `jerk`, when it gets that far before the acceleration reaches zero (and,
/// for a negative acceleration, before the speed does).
///
/// The distance after time τ is `v·τ + a·τ²/2 − sign(a)·j·τ³/6`, increasing while the speed
/// is positive. With a positive acceleration it is convex until the acceleration is zero, so
/// Newton's method started there falls to the root without overshooting it; with a
/// negative one it is concave, and Newton's method started at zero climbs to it.
pub(super) fn eased_by(x: &Motion, distance: f64, jerk: f64) -> Motion {
    let end = x.a.abs() / jerk;
    let j = -x.a.signum() * jerk;
    let at = |t: f64| x.v * t + 0.5 * x.a * t * t + j * t * t * t / 6.0;
    let mut t = if x.a > 0.0 { end } else { 0.0 };
    for _ in 0..EASING_STEPS {
        let speed = x.v + x.a * t + 0.5 * j * t * t;
        if speed <= 0.0 {
            break;
        }
        let next = (t - (at(t) - distance) / speed).clamp(0.0, end);
        let done = (t - next).abs() <= 1e-15 * end;
        t = next;
        if done {
            break;
        }
    }
    Motion {
        s: x.s + distance,
        v: x.v + x.a * t + 0.5 * j * t * t,
        a: x.a + j * t,
    }
}

/// Distance `x` needs to slow down to the speed of limit `l` ahead ([`brake_distance`] with
/// `share` of its grip and jerk); where [`easing_for`] allows, a positive acceleration is
/// first brought down with the window's jerk, as far as that jerk holds.
///
/// When the need is at most `enough`, the value returned may be any at most `enough`: the
/// first estimate that fits ends the search (see [`brake_distance_within`]).
fn brake_need(x: &Motion, l: &Limit, w: &Window, share: f64, enough: f64) -> f64 {
    let (grip, jerk) = (l.grip.scaled(share), l.jerk * share);
    let single = brake_distance_within(x, l.speed, &grip, jerk, enough);
    if single <= enough {
        return single;
    }
    let Some((fast, until)) = easing_for(x, l, w) else {
        return single;
    };
    let fast = fast * share;
    let ease = easing_distance(x, 0.0, fast);
    let room = until - x.s;
    if ease > room {
        // The jerk drops before the acceleration is zero: the rest eases with the lower one.
        let there = eased_by(x, room, fast);
        return single.min(room + brake_distance(&there, l.speed, &grip, jerk));
    }
    let eased = Motion {
        s: x.s + ease,
        v: peak_speed(x, fast),
        a: 0.0,
    };
    single.min(ease + brake_distance(&eased, l.speed, &grip, jerk))
}

/// How far limit `l` is missed from state `x` in window `w`: the distance needed to meet it
/// over the distance left (0 when it is met), for its speed and for its acceleration.
fn misses(x: &Motion, l: &Limit, w: &Window) -> (f64, f64) {
    let slack = (l.at - x.s).max(0.0);
    let ratio = |need: f64| {
        if need > slack + DISTANCE_SLACK {
            need / slack.max(DISTANCE_SLACK)
        } else {
            0.0
        }
    };
    let slowing = slows_for(x, l);
    let too_fast = if slowing {
        // A stop is judged with the full limits: the path arrives there exactly.
        let share = if l.speed > 0.0 { JUDGE } else { 1.0 };
        ratio(brake_need(x, l, w, share, slack + DISTANCE_SLACK))
    } else {
        0.0
    };
    // While the speed must still come down to the limit, its ramp (ending with zero
    // acceleration there) meets the acceleration limit too.
    let after = arrival_accel(x, l);
    let too_hard = if !slowing && x.a.abs() > after * (1.0 + SPEED_SLACK) {
        ratio(easing_distance(x, after, l.jerk))
    } else {
        0.0
    };
    (too_fast, too_hard)
}

/// The acceleration limit `x` must be within when it reaches limit `l` without slowing
/// down for it: the grip after the limit at the highest speed `x` can arrive with.
fn arrival_accel(x: &Motion, l: &Limit) -> f64 {
    l.grip_after.at(x.v.max(peak_speed(x, l.jerk)))
}

/// Makes the limits consistent backwards (the backward pass of the look-ahead): each
/// limit's speed is lowered until the next limit can be met from it, braking with the
/// acceleration and jerk limits of the pieces between the two. Soft limits are left as they
/// are and passed over: the next limit after them brakes with their acceleration and jerk
/// limits too. Afterwards meeting the nearest limit ahead that is not soft is enough to meet
/// all the others.
pub fn settle(limits: &mut [Limit]) {
    let none = Grip::constant(f64::INFINITY);
    let (mut grip, mut jerk) = (none, f64::INFINITY);
    for l in limits.iter_mut() {
        if l.soft {
            grip = grip.min(l.grip);
            jerk = jerk.min(l.jerk);
        } else {
            l.grip = l.grip.min(grip);
            l.jerk = l.jerk.min(jerk);
            (grip, jerk) = (none, f64::INFINITY);
        }
    }
    let mut next = None;
    for k in (0..limits.len()).rev() {
        if limits[k].soft {
            continue;
        }
        if let Some(n) = next {
            limits[k].speed = settled(&limits[k], &limits[n]);
        }
        next = Some(k);
    }
}

/// The speed of limit `here` lowered until limit `next` can be met from it.
fn settled(here: &Limit, next: &Limit) -> f64 {
    let room = (next.at - here.at).max(0.0);
    let (grip, jerk) = (next.grip.scaled(JUDGE), next.jerk * JUDGE);
    let brake = |v: f64| brake_distance(&Motion { s: 0.0, v, a: 0.0 }, next.speed, &grip, jerk);
    if here.speed <= next.speed || brake(here.speed) <= room {
        return here.speed;
    }
    // With the grip of the highest speed the closed form is on the safe side.
    let fast = braking_speed(next.speed, room, grip.at(here.speed), jerk);
    let hi = fast.min(here.speed);
    // The highest speed in [lo, hi] whose braking fits, by bisection.
    let highest = |mut lo: f64, mut hi: f64, steps: usize| {
        for _ in 0..steps {
            let mid = 0.5 * (lo + hi);
            if brake(mid) <= room {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    };
    let varies = grip.at(next.speed) > grip.at(here.speed) * (1.0 + GRIP_CHANGE);
    if varies && brake(hi) <= room {
        // The grip grows as the speed falls: search above the closed form.
        highest(hi, here.speed, 30)
    } else if brake(hi) > room {
        // Rounding put the closed form a hair too high: settle it by bisection.
        highest(next.speed, hi, 40)
    } else {
        hi
    }
}

/// The highest speed from which a jerk-limited ramp (starting and ending with zero
/// acceleration, limits `accel` and `jerk`) slows down to `target` within `room`.
///
/// The ramp takes `T = 2·√(Δv/J)` while `Δv ≤ A²/J` and `T = Δv/A + A/J` beyond, and covers
/// the mean of its end speeds times `T`. The first case is the cubic `u³ + 2w·u = room·√J`
/// in `u = √Δv` (one real root, Cardano), the second a quadratic in the speed.
pub fn braking_speed(target: f64, room: f64, accel: f64, jerk: f64) -> f64 {
    let (w, a, j) = (target.max(0.0), accel, jerk);
    let corner = a * a / j;
    if room >= (2.0 * w + corner) * a / j {
        // v² + (A²/J)·v + (w·A²/J − w² − 2A·room) = 0.
        let c = w * corner - w * w - 2.0 * a * room;
        return 0.5 * (-corner + (corner * corner - 4.0 * c).max(0.0).sqrt());
    }
    let (p, q) = (2.0 * w, room * j.sqrt());
    let r = (0.25 * q * q + p * p * p / 27.0).sqrt();
    let u = (0.5 * q + r).cbrt() + (0.5 * q - r).cbrt();
    w + u.max(0.0) * u.max(0.0)
}

/// The limits that bind state `x`, each with its index in the window and how far it
/// misses them (see [`misses`]).
///
/// Limits the state stands in are always checked. A limit ahead is judged with the lowest
/// acceleration and jerk limits of all pieces between the state and it (its own cover only
/// the pieces since the limit before it). Once the state must slow down for a limit that is
/// not soft, that limit stands for all further ones: after [`settle`] its speed lets the path
/// meet them, and its ramp ends with zero acceleration there, so it stands for the
/// acceleration limits further on too. Checking those further ones with their own (lower)
/// jerk would judge a state on the nearest limit's braking curve unsafe although following
/// that curve meets them all: the checks would contradict the actions. A limit the state
/// need not slow down for stands for nothing: [`settle`] vouches for the limits after it
/// only from a state that reaches it without speeding up, and a state below its speed may
/// still be speeding up when it gets there (one braking down to it that eases its
/// deceleration at once before it arrives as [`settle`] assumes, and stands for them). Nor
/// does a limit met on the way through (see `through`), nor one the state is still below but
/// misses (it must slow down for it only because its acceleration could no longer be eased
/// in time): the ramp for it speeds up towards its speed, and the limits behind it must
/// be judged, and bind, on their own.
fn relevant<'a>(
    x: &'a Motion,
    w: &'a Window,
) -> impl Iterator<Item = (usize, Limit, f64, f64)> + 'a {
    let mut covered = false;
    let (mut grip, mut jerk) = (Grip::constant(f64::INFINITY), f64::INFINITY);
    w.limits.iter().enumerate().filter_map(move |(k, l)| {
        if covered {
            return None;
        }
        let mut l = *l;
        if l.at > x.s {
            grip = grip.min(l.grip);
            jerk = jerk.min(l.jerk);
            l.grip = grip;
            l.jerk = jerk;
        }
        let (mut fast, hard) = misses(x, &l, w);
        // A limit missed with the zero-acceleration ramp may still be met on the way
        // through: passed braking towards a lower one behind it, or, the current piece's,
        // left still speeding up before the speed gets above it. Then it stands for nothing
        // behind it: the limits after it are judged on their own.
        let rest = w.limits.get(k + 1..).unwrap_or(&[]);
        let through = fast > 0.0
            && (l.at > x.s && !l.soft && passes_under(x, &l, rest).is_some()
                || k == 0 && l.at <= x.s && leaves_below(x, &l, rest.first(), w));
        if through {
            fast = 0.0;
        }
        // A limit ahead of the window's start that the state has crossed (a trial state one
        // period on): braking through limits, the state must have crossed it no faster
        // than its speed, whatever it settles at, and be within the acceleration limit
        // after it.
        if k > 0 && l.at <= x.s {
            if x.v > l.own * (1.0 + CROSSING_SLACK) {
                fast = fast.max(x.v / l.own.max(f64::MIN_POSITIVE));
            }
            let grip = l.grip_after.at(x.v);
            if x.a.abs() > grip * (1.0 + CROSSING_SLACK) {
                fast = fast.max(x.a.abs() / grip.max(f64::MIN_POSITIVE));
            }
        }
        if l.at > x.s && !l.soft && !through {
            // A state braking down to the limit's speed that gets there with its
            // deceleration eased at once arrives as the backward pass assumes too.
            let arrives =
                x.a < 0.0 && x.v >= l.speed && easing_distance(x, 0.0, l.jerk) <= l.at - x.s;
            covered = if slows_for(x, &l) {
                x.v >= l.speed || fast == 0.0 && hard == 0.0
            } else {
                arrives
            };
        }
        Some((k, l, fast, hard))
    })
}

/// True when `x` must slow down to meet limit `l` (or stop there: a stop is a point, not a
/// region, so the distance to come to rest always counts). A state that is braking settles
/// below its speed only once its deceleration is eased: where the limit comes first, it
/// must slow down for it unless easing at once gets there slow enough.
fn slows_for(x: &Motion, l: &Limit) -> bool {
    if (l.speed <= 0.0 && x.v > 0.0)
        || settled_speed(x, l.jerk) > l.speed * (1.0 + LIMIT_SLACK) + LIMIT_SLACK
    {
        return true;
    }
    let room = l.at - x.s;
    let above = |v: f64| v > l.own * (1.0 + CROSSING_SLACK);
    x.a < 0.0
        && room > 0.0
        && above(x.v)
        && easing_distance(x, 0.0, l.jerk) > room
        && above(eased_by(x, room, l.jerk).v)
}

/// True when the state is safe: every limit in the window can still be met, and the speed
/// can come to rest without reversing.
pub fn check(x: &Motion, w: &Window) -> bool {
    if !rests_forwards(x, w) {
        return false;
    }
    relevant(x, w).all(|(_, _, fast, hard)| fast == 0.0 && hard == 0.0)
}

/// A ramp towards a speed: (target, acceleration limit, jerk limit).
type Action = (f64, f64, f64);

/// Buffers [`advance_with`] works in, kept by its caller from one period to the next so
/// that a period's step allocates nothing once they have grown to the window's needs.
#[derive(Debug, Clone, Default)]
pub struct Scratch {
    /// Ramps found with their urgency, while sorting.
    found: Vec<(Action, f64)>,
    /// Candidate ramps, in the order they are tried.
    candidates: Vec<Action>,
    /// The check's verdicts on the states tried this period.
    verdicts: Verdicts,
}

impl Scratch {
    /// Makes room for the ramps of `n` limits.
    pub fn reserve(&mut self, n: usize) {
        self.found.reserve(2 * n);
        self.candidates.reserve(2 * n + 2);
    }
}

/// The ramps from state `from` for the limits that `x` misses (`from` itself, or where the
/// plain action from it would lead), the worst first (the largest ratio of distance needed
/// to distance left); empty when it misses none.
fn bindings(
    from: &Motion,
    x: &Motion,
    w: &Window,
    found: &mut Vec<(Action, f64)>,
    out: &mut Vec<Action>,
) {
    found.clear();
    for (k, limit, too_fast, too_hard) in relevant(x, w) {
        let l = &limit;
        let urgency = if too_fast > 0.0 { too_fast } else { too_hard };
        if urgency <= 0.0 {
            continue;
        }
        // The speed ramp is the one the check judges (its acceleration and jerk), so
        // following it keeps the limit met; it ends with zero acceleration at the limit,
        // so it meets the acceleration limit there too: prefer it whenever the speed is
        // missed. Easing the acceleration uses the current piece's jerk (at least the
        // limit's), which eases no later than the check assumes.
        let ramp = if too_fast > 0.0 {
            // The ramp starts from `from`: where the check there lets a positive
            // acceleration be eased with the window's jerk, the ramp eases with it too. A
            // limit still above the speed binds only because the acceleration could not be
            // eased with the limit's own jerk in time; the ramp that keeps it met is the one
            // that eases with that jerk into its speed (unless the window's jerk eases all
            // of the acceleration before it drops).
            let eases = |m: &Motion| {
                easing_for(m, l, w)
                    .filter(|&(fast, until)| {
                        m.v >= l.speed || m.s + easing_distance(m, 0.0, JUDGE * fast) <= until
                    })
                    .map(|(fast, _)| fast)
            };
            let jerk = eases(from)
                .or_else(|| eases(x))
                .unwrap_or(l.jerk.min(w.jerk));
            (l.speed, l.grip.min(w.grip).at(peak_speed(x, jerk)), jerk)
        } else {
            let accel = arrival_accel(x, l).min(w.grip.at(peak_speed(x, w.jerk)));
            (l.speed.min(x.v), accel, w.jerk)
        };
        found.push((ramp, urgency));
        // The ramp that brakes through the limit towards a lower one behind it, where the
        // check lets `from` do so: next, should the ramp ending at this limit's speed cross
        // it too fast.
        if too_fast > 0.0 && l.at > from.s && !l.soft {
            let rest = w.limits.get(k + 1..).unwrap_or(&[]);
            if let Some((speed, grip, jerk)) = passes_under(from, l, rest) {
                let jerk = jerk.min(w.jerk);
                let accel = grip.min(w.grip).at(peak_speed(from, jerk));
                found.push(((speed, accel, jerk), urgency));
            }
        }
    }
    // Worst first; ties keep the order found (a stable insertion sort: the list is short,
    // and std's stable sort would allocate).
    for i in 1..found.len() {
        let mut j = i;
        while j > 0 && found[j - 1].1.total_cmp(&found[j].1).is_lt() {
            found.swap(j - 1, j);
            j -= 1;
        }
    }
    out.extend(found.iter().map(|f| f.0));
}

/// State after following the ramp to `target` for `dt`.
fn ramp_step(x: &Motion, target: f64, accel: f64, jerk: f64, dt: f64) -> Motion {
    let r = Ramp::new(x.v, x.a, target, accel, jerk).state(dt);
    Motion {
        s: x.s + r.s,
        v: r.v,
        a: r.a,
    }
}

/// The ramp towards `target` that gains most speed within the period `dt`. Where the grip
/// shrinks between the speed `x` reaches anyway and the target, a ramp that stops at a
/// lower speed may use more acceleration: its top speed is chosen by golden section.
fn go_step(x: &Motion, target: f64, w: &Window, dt: f64) -> Motion {
    let top = peak_speed(x, w.jerk);
    let toward = |u: f64| ramp_step(x, u, w.grip.at(u.max(top)), w.jerk, dt);
    let plain = toward(target);
    if target <= top || w.grip.at(top) <= w.grip.at(target) * (1.0 + GRIP_CHANGE) {
        return plain;
    }
    let gain = |m: &Motion| m.v + 1e-6 * m.s;
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    let (mut lo, mut hi) = (top, target);
    let mut c = hi - ratio * (hi - lo);
    let mut d = lo + ratio * (hi - lo);
    let (mut fc, mut fd) = (toward(c), toward(d));
    for _ in 0..TOP_STEPS {
        if gain(&fc) >= gain(&fd) {
            hi = d;
            d = c;
            fd = fc;
            c = hi - ratio * (hi - lo);
            fc = toward(c);
        } else {
            lo = c;
            c = d;
            fc = fd;
            d = lo + ratio * (hi - lo);
            fd = toward(d);
        }
    }
    [plain, fc, fd]
        .into_iter()
        .max_by(|a, b| gain(a).total_cmp(&gain(b)))
        .unwrap_or(plain)
}

/// True when `x` can come to rest without reversing: a negative acceleration, brought to
/// zero at once, leaves the speed at least zero. The easing has the window's jerk up to
/// one period's travel before the next limit ahead with a lower jerk (from there on the
/// period's action may already have that jerk, see `Planner::scan`), then that lower jerk up
/// to one period's travel before the next drop, and so on. So a state that slows down to a
/// standstill well before a piece with a lower jerk (a feed hold) is judged with the jerk it
/// brakes with, one whose easing runs over a staircase of falling jerk limits (dense code)
/// with each of them, and the judgement moves smoothly with the state as the drops come
/// near.
fn rests_forwards(x: &Motion, w: &Window) -> bool {
    let rests = |m: &Motion, jerk: f64| settled_speed(m, jerk) >= -SPEED_SLACK;
    if x.a >= 0.0 {
        return true;
    }
    let (mut m, mut jerk) = (*x, w.jerk);
    if !rests(&m, jerk) {
        return false;
    }
    let reach = period_travel(x.v, x.a, w.jerk, w.period);
    for l in w.limits.iter().filter(|l| l.at > x.s) {
        if l.jerk >= jerk {
            continue;
        }
        let room = (l.at - reach - m.s).max(0.0);
        if easing_distance(&m, 0.0, jerk) <= room {
            return true;
        }
        m = eased_by(&m, room, jerk);
        jerk = l.jerk;
        if !rests(&m, jerk) {
            return false;
        }
    }
    true
}

/// The speed above which every ramp from `x` with jerk `jerk` moves alike over the next
/// `dt`: the acceleration rises with the full jerk all period long, as the speed it would
/// reach by easing at once is still below the target at the period's end (with a little
/// room for rounding).
fn reachable_speed(x: &Motion, jerk: f64, dt: f64) -> f64 {
    let a = x.a + jerk * dt;
    let v = x.v + x.a * dt + 0.5 * jerk * dt * dt;
    (v + a.max(0.0).powi(2) / (2.0 * jerk)).max(x.v) * (1.0 + 1e-6) + 1e-9
}

/// The state one period `dt` on, heading for `target` speed.
pub fn advance(x: &Motion, target: f64, w: &Window, dt: f64) -> Motion {
    advance_with(x, target, w, dt, &mut Scratch::default())
}

/// [`advance`] working in the caller's `scratch` buffers (no allocation once they have
/// grown).
pub fn advance_with(x: &Motion, target: f64, w: &Window, dt: f64, scratch: &mut Scratch) -> Motion {
    let Scratch {
        found,
        candidates,
        verdicts,
    } = scratch;
    verdicts.clear();
    let go = go_step(x, target, w, dt);
    if verdicts.check(&go, w) {
        return go;
    }
    // Candidate ramps: towards the limits the state itself misses, worst first, then
    // towards those the go ramp would miss, then a stop. The first whose result is safe
    // bounds a bisection for the highest safe speed between it and the go target: the
    // ramp rides the braking curve in front of the binding limit.
    candidates.clear();
    bindings(x, x, w, found, candidates);
    bindings(x, &go, w, found, candidates);
    for c in candidates.iter_mut() {
        c.0 = c.0.min(target);
    }
    if x.a < 0.0 {
        // Holding the deceleration: towards the lowest target so far with the current
        // deceleration as the limit (or the window's grip, where that is lower). Before a
        // drop in jerk a ramp for a limit ahead with the full jerk may brake harder than the
        // lower jerk can ease (it could not come to rest without reversing), while easing
        // at once leaves the braking curve for that limit: the state on the curve between
        // the two holds its deceleration.
        let low = candidates.iter().map(|c| c.0).fold(target, f64::min);
        candidates.push((low, (-x.a).min(w.grip.at(x.v)), w.jerk));
        // Easing a deceleration at once with the window's jerk: the way to come to rest
        // without reversing that the check assumes (see `rests_forwards`). Easing ends below
        // the current speed, so where the state is faster than the target (a feed hold's
        // zero, a lower feed override) the ramp aims where easing ends: a state that may not
        // brake any harder before a drop in jerk eases first and stays above the new target
        // a little longer rather than turning back (the speed limits of the pieces ahead are
        // limits of the window). Below the target, the current piece's speed limit, nothing
        // goes above it.
        let eased = settled_speed(x, w.jerk).min(target.max(x.v));
        candidates.push((eased, w.grip.at(x.v), w.jerk));
    }
    candidates.push((0.0, w.grip.at(peak_speed(x, w.jerk)), w.jerk));
    let mut fallback: Option<(Motion, bool)> = None;
    for &(low, accel, jerk) in candidates.iter() {
        let low = low.max(0.0);
        let brake = ramp_step(x, low, accel, jerk, dt);
        if !verdicts.check(&brake, w) {
            // Kept for the fallback below: the slowest of the ramps that go on forwards (the
            // speed can still come to rest without reversing), else the first.
            let forwards = brake.v >= 0.0 && rests_forwards(&brake, w);
            match fallback {
                None => fallback = Some((brake, forwards)),
                Some((f, f_forwards)) => {
                    if forwards && (!f_forwards || brake.v < f.v) {
                        fallback = Some((brake, forwards));
                    }
                }
            }
            continue;
        }
        // Ramps towards any speed above what one period can reach with the full jerk move
        // alike over the period: searching only below that keeps the search fine where the
        // answer is (a stop approached with a search over the whole feed ended 50 nm short).
        let hi = target.min(reachable_speed(x, jerk, dt));
        if low >= hi {
            return brake;
        }
        // Above the speed the state reaches anyway the grip of the target applies.
        let trial = |u: f64| {
            let grip = w.grip.at(u.max(peak_speed(x, jerk)));
            ramp_step(x, u, accel.min(grip), jerk, dt)
        };
        return highest_safe(low, hi, brake, trial, w, verdicts);
    }
    // No ramp keeps every limit: the state is off a braking curve, by rounding, or because it
    // passes limits the backward pass settled for arriving without acceleration while it
    // brakes for one further on, faster than they allow and yet in time for that one. The
    // ramp for the worst miss would follow the curve of a limit that does not bind and leave
    // the one that does behind (an end stop came 0.3 µm late): take the ramp that leaves the
    // lowest speed, the nearest to all of those curves at once, among those that go on
    // forwards (a plain stop from a state braking hard can overshoot below zero: the path
    // would turn back).
    fallback.map_or(go, |(f, _)| f)
}

#[cfg(test)]
#[path = "speed_tests.rs"]
mod tests;
