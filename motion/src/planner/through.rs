//! Limits met on the way through rather than with zero acceleration: braking through a
//! limit towards a lower one behind it, and leaving the current piece for a faster one
//! while still speeding up (see the notes of [`super::speed`]).

use super::speed::{
    JUDGE, LIMIT_SLACK, Limit, Motion, SPEED_SLACK, Window, eased_by, easing_distance,
    settled_speed,
};
use crate::limits::Grip;
use crate::profile::Ramp;

/// Relative slack above a limit's speed with which a trial state may have crossed it
/// (rounding).
pub(super) const CROSSING_SLACK: f64 = 1e-9;

/// Hard limits behind a missed one that [`passes_under`] tries to brake towards.
const THROUGH_LIMITS: usize = 4;

/// The lower limit behind limit `l` ahead towards which the state may brake through `l`
/// (its speed, and the acceleration and jerk limits of all pieces up to it), where `l` is
/// missed by the ramp that meets it with zero acceleration; `None` where there is none.
///
/// Braking through meets `l` when a braking ramp from `x` towards one of the next
/// [`THROUGH_LIMITS`] hard limits `m` behind it in `rest` that is lower than `l`, with the
/// lowest acceleration and jerk limits of all pieces up to `m` (shared by [`JUDGE`]), meets
/// `m` and passes `l` no faster than `l`'s own speed (not the speed
/// [`settle`](super::speed::settle) lowered it to for an arrival without acceleration).
/// Where the speed limits step down piece after piece (the parts of a blend running into a
/// corner), meeting each with zero acceleration makes the braking stop and start again at
/// every step; braking through them follows the steps' lower corners instead.
///
/// Only a plain braking ramp counts: one whose state is within those acceleration limits
/// and never speeds up again (its speed falls all the way, so it is below `l`'s on all of
/// `l`'s stretch once it is at its start). A state braking harder than the pieces ahead
/// allow would ease with their low jerk and could dip far below `m`'s speed before coming
/// back up: no way to meet `l`. Nor is a stop a target: stops are met exactly with the
/// full limits (`speed::misses`), from the zero-acceleration ramps of the limits before
/// them. The limits between `l` and `m` are judged on their own.
pub(super) fn passes_under(x: &Motion, l: &Limit, rest: &[Limit]) -> Option<(f64, Grip, f64)> {
    if x.a > 0.0 {
        return None;
    }
    let (mut grip, mut jerk) = (l.grip, l.jerk);
    let mut hard = 0;
    for m in rest {
        // Soft limits on the way lend their acceleration and jerk limits.
        grip = grip.min(m.grip);
        jerk = jerk.min(m.jerk);
        if m.soft {
            continue;
        }
        hard += 1;
        if hard > THROUGH_LIMITS {
            return None;
        }
        // A stop is met with the full limits, exactly (see `misses`): it is left to the
        // ramps that meet the limits before it with zero acceleration.
        if m.speed >= l.speed || m.speed <= 0.0 {
            continue;
        }
        let (full, judged) = (grip.at(x.v), jerk * JUDGE);
        let accel = JUDGE * full;
        if accel <= 0.0 || -x.a > full * (1.0 + SPEED_SLACK) || settled_speed(x, judged) < m.speed {
            continue;
        }
        let ramp = Ramp::new(x.v, x.a, m.speed, accel, judged);
        // The ramp's speed only falls: already within `l`'s speed, it passes below it.
        let below = |r: &Ramp| {
            x.v <= l.own || r.speed_after_at_most(l.at - x.s, l.own * (1.0 + LIMIT_SLACK))
        };
        if ramp.distance() <= m.at - x.s && below(&ramp) {
            return Some((m.speed, grip, jerk));
        }
    }
    None
}

/// True when `x`, speeding up on the piece of limit `l` (the current one), leaves it for
/// the piece of `next` no faster than `l`'s own speed. A trial state one period on that is
/// past `next`'s start already crossed the joint no faster than it is now, as long as it
/// is still speeding up. A state before it must still be speeding up at `next`, a faster
/// piece, and no faster than `l` there when it eases its acceleration at once, with the
/// lowest jerk of the period's action, the current piece and the next one (shared by
/// [`JUDGE`]). Past `next` its limits judge the state. So the path can leave a slow piece
/// for a faster one (out of a corner) with the acceleration it has, instead of easing it
/// to zero at the slow piece's speed first.
pub(super) fn leaves_below(x: &Motion, l: &Limit, next: Option<&Limit>, w: &Window) -> bool {
    let Some(n) = next else {
        return false;
    };
    let room = n.at - x.s;
    if room <= 0.0 {
        return x.a >= 0.0 && x.v <= l.own * (1.0 + CROSSING_SLACK);
    }
    if x.a <= 0.0 || n.speed <= l.own {
        return false;
    }
    let jerk = l.jerk.min(n.jerk).min(w.jerk) * JUDGE;
    easing_distance(x, 0.0, jerk) >= room
        && eased_by(x, room, jerk).v <= l.own * (1.0 + LIMIT_SLACK)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hard limit at `at` with speed `speed`, grip `accel` and jerk `jerk`.
    fn limit(at: f64, speed: f64, accel: f64, jerk: f64) -> Limit {
        Limit::uniform(at, speed, accel, jerk, false)
    }

    #[test]
    fn braking_through_needs_a_plain_braking_ramp_to_a_lower_limit_that_is_no_stop() {
        // A limit of 24 mm/s 0.3 mm ahead, one of 21.6 mm/s 0.6 mm ahead.
        let l = limit(0.3, 24.0, 1000.0, 1e5);
        let lower = limit(0.6, 21.6, 1000.0, 1e5);
        let state = |a: f64| Motion { s: 0.0, v: 30.0, a };
        // Braking at 300 mm/s² the ramp towards the lower limit meets it and passes the
        // first below its speed; the ramp meeting the first with zero acceleration cannot.
        let x = state(-300.0);
        let zero = Ramp::new(x.v, x.a, l.speed, JUDGE * 1000.0, JUDGE * 1e5);
        assert!(zero.distance() > l.at);
        assert_eq!(
            passes_under(&x, &l, &[lower]).map(|t| t.0),
            Some(lower.speed)
        );
        // Not when the pieces up to the lower limit have so low a jerk that easing the
        // deceleration would take the speed below the lower limit's (a dip, not a ramp).
        let hard = state(-800.0);
        let low_jerk = limit(0.6, 21.6, 1000.0, 2e4);
        assert!(settled_speed(&hard, JUDGE * 2e4) < low_jerk.speed);
        assert!(passes_under(&hard, &l, &[low_jerk]).is_none());
        // Nor when the state brakes harder than those pieces allow.
        let low_grip = limit(0.6, 21.6, 200.0, 1e5);
        assert!(passes_under(&x, &l, &[low_grip]).is_none());
        // Nor towards a stop, nor while speeding up.
        let stop = limit(0.6, 0.0, 1000.0, 1e5);
        assert!(passes_under(&x, &l, &[stop]).is_none());
        assert!(passes_under(&state(100.0), &l, &[lower]).is_none());
    }
}
