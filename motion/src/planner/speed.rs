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
//! The candidate actions, best first:
//! 1. *go*: the ramp towards the speed limit (or the feed hold's zero) of the current piece;
//! 2. the largest constant jerk in [−J, J] whose result is safe (found by bisection), which
//!    rides the braking curve in front of a lower limit;
//! 3. *brake*: the ramp down to the lowest limit that the state cannot otherwise meet.
//!
//! Each action has |jerk| ≤ J and |a| ≤ A, the window's smallest path limits, so the
//! per-axis limits of every piece in the window hold. Positions are integrated exactly for
//! piecewise constant jerk, so finite differences of the samples stay within the limits too.

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

/// A speed limit starting at a path position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limit {
    /// Where it starts.
    pub at: f64,
    /// The speed limit from there on (0 for a stop).
    pub speed: f64,
}

/// What the generator needs to know about the path ahead.
#[derive(Debug, Clone, Default)]
pub struct Window {
    /// Running minima of the speed limits ahead, in path order.
    pub limits: Vec<Limit>,
    /// Path acceleration limit over the window.
    pub accel: f64,
    /// Path jerk limit over the window.
    pub jerk: f64,
}

/// Bisection steps for the constant-jerk action.
const BISECTION_STEPS: usize = 18;

/// Relative speed slack when comparing with a limit (rounding).
const SPEED_SLACK: f64 = 1e-9;

/// Distance slack when comparing braking distances (rounding), mm.
const DISTANCE_SLACK: f64 = 1e-12;

/// Why a state is not safe: the lowest speed limit it cannot meet, if any (`None`: the
/// acceleration is so negative that the speed would reverse).
type Unsafe = Option<f64>;

/// Checks a state against the window.
pub fn check(x: &Motion, w: &Window) -> Result<(), Unsafe> {
    let j = w.jerk;
    if x.a < 0.0 && x.v - x.a * x.a / (2.0 * j) < -SPEED_SLACK {
        return Err(None);
    }
    let zeroed = x.v + x.a * x.a.abs() / (2.0 * j);
    let mut lowest: Option<f64> = None;
    for l in &w.limits {
        if zeroed <= l.speed * (1.0 + SPEED_SLACK) + SPEED_SLACK {
            continue;
        }
        let slack = (l.at - x.s).max(0.0);
        let need = Ramp::new(x.v, x.a, l.speed, w.accel, j).distance();
        if need > slack + DISTANCE_SLACK {
            lowest = Some(lowest.map_or(l.speed, |m: f64| m.min(l.speed)));
        }
    }
    match lowest {
        Some(m) => Err(Some(m)),
        None => Ok(()),
    }
}

/// State after `dt` with constant jerk `j`.
fn constant_jerk(x: &Motion, j: f64, dt: f64) -> Motion {
    Motion {
        s: x.s + x.v * dt + 0.5 * x.a * dt * dt + j * dt * dt * dt / 6.0,
        v: x.v + x.a * dt + 0.5 * j * dt * dt,
        a: x.a + j * dt,
    }
}

/// State after following the ramp to `target` for `dt`.
fn ramp_step(x: &Motion, target: f64, w: &Window, dt: f64) -> Motion {
    let r = Ramp::new(x.v, x.a, target, w.accel, w.jerk).state(dt);
    Motion {
        s: x.s + r.s,
        v: r.v,
        a: r.a,
    }
}

/// The state one period `dt` on, heading for `target` speed.
pub fn advance(x: &Motion, target: f64, w: &Window, dt: f64) -> Motion {
    let go = ramp_step(x, target, w, dt);
    let go_fail = match check(&go, w) {
        Ok(()) => return go,
        Err(e) => e,
    };
    let j = w.jerk;
    let low = constant_jerk(x, -j, dt);
    match check(&low, w) {
        Ok(()) => {
            let (mut lo, mut hi) = (-j, j);
            for _ in 0..BISECTION_STEPS {
                let mid = 0.5 * (lo + hi);
                if check(&constant_jerk(x, mid, dt), w).is_ok() {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            constant_jerk(x, lo, dt)
        }
        Err(low_fail) => {
            let to = match (low_fail, go_fail) {
                (Some(p), Some(q)) => p.min(q),
                (Some(p), None) | (None, Some(p)) => p,
                (None, None) => target.min(x.v),
            };
            ramp_step(x, to.min(target).max(0.0), w, dt)
        }
    }
}
