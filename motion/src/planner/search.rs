//! The search for the highest safe ramp of one period: the step of the speed generator that
//! rides a braking curve in front of a binding limit.
//!
//! The answer is defined by a bisection over the ramp's target speed between a ramp known to
//! be safe (`low`) and the highest speed worth trying (`high`): halvings, each keeping the
//! upper half when its lower end (the midpoint) is safe, and the state of the last safe
//! midpoint. They end after [`BISECTION_STEPS`], or sooner once the bracket is no wider than
//! [`SPEED_RESOLUTION`] of its lower end ([`resolved`]). A plain bisection judges every
//! midpoint (one safety check each).
//!
//! In about a quarter of the braking periods of dense CAM code no target above `low` is safe
//! (the state stands right on the braking curve of a limit a hair ahead), and the plain
//! bisection judges every one of its unsafe midpoints to find that out. [`highest_safe`] judges the
//! lowest midpoint the bisection can reach first: when it is unsafe, so is every midpoint
//! above it where the verdict switches from safe to unsafe once along the target speed,
//! and the ramp towards `low` is the answer after one check. Otherwise the bisection runs
//! as before (the probe's verdict is remembered, so it costs one check more).
//!
//! The state returned is always one the check judged safe; where the verdicts switch once
//! it is the plain bisection's own.

use super::speed::{Motion, Window};
use super::verdicts::Verdicts;

/// Halvings of the bracket of target speeds: the answer's resolution is the bracket over
/// 2¹⁸ (0.4 µm/s on a bracket as wide as 100 mm/s; those of braking periods are mostly below
/// 1 mm/s). Two halvings more change no program time of `bench/program_times.sh`; two fewer
/// lose 1 ms on the circle without a jerk limit.
pub(super) const BISECTION_STEPS: usize = 18;

/// Share of its own speed within which the answer is close enough: the bisection stops once
/// the bracket of target speeds is no wider than this share of its lower end (the highest
/// speed known to be safe). At 25 mm/s that is 2.5 µm/s, 2.5 nm of path over a 1 ms
/// period; the next period's search starts afresh from the state reached, so the shortfall
/// does not add up. In dense CAM code, where the speed follows the limits of short pieces
/// up and down every period, brackets are a few tenths of a mm/s wide, and the fixed count
/// of halvings resolved them to micrometres per second: two in five of the safety checks of
/// a long test run went on that. Near a stop (lower end zero) every halving is taken.
pub(super) const SPEED_RESOLUTION: f64 = 1e-4;

/// True when the bracket `[lo, hi]` of target speeds is narrow enough to stop halving.
fn resolved(lo: f64, hi: f64) -> bool {
    hi - lo <= SPEED_RESOLUTION * lo
}

/// The state after the period of the highest safe ramp from the current state towards a
/// target in `[low, high]` (the bisection's answer, see the module documentation), the ramp
/// towards `low` having given the safe state `at_low`. `trial` gives the state after the
/// period of the ramp towards a target.
pub(super) fn highest_safe(
    low: f64,
    high: f64,
    at_low: Motion,
    trial: impl Fn(f64) -> Motion,
    w: &Window,
    verdicts: &mut Verdicts,
) -> Motion {
    if resolved(low, high) {
        return at_low;
    }
    // The lowest midpoint: the one the bisection ends at when every verdict is unsafe.
    let mut lowest = high;
    for _ in 0..BISECTION_STEPS {
        if resolved(low, lowest) {
            break;
        }
        lowest = 0.5 * (low + lowest);
    }
    if lowest > low && !verdicts.check(&trial(lowest), w) {
        return at_low;
    }
    bisect(low, high, at_low, &trial, w, verdicts)
}

/// The plain bisection: every midpoint judged.
fn bisect(
    low: f64,
    high: f64,
    at_low: Motion,
    trial: &impl Fn(f64) -> Motion,
    w: &Window,
    verdicts: &mut Verdicts,
) -> Motion {
    let (mut lo, mut hi) = (low, high);
    let mut best = at_low;
    for _ in 0..BISECTION_STEPS {
        if resolved(lo, hi) {
            break;
        }
        let mid = 0.5 * (lo + hi);
        let t = trial(mid);
        if verdicts.check(&t, w) {
            lo = mid;
            best = t;
        } else {
            hi = mid;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planner::speed::{self, Limit};

    /// A window with one stop `at` mm ahead, 1000 mm/s² and 1e5 mm/s³, 1 ms period.
    fn stop_at(at: f64) -> Window {
        Window {
            limits: vec![
                Limit::uniform(0.0, 100.0, 1000.0, 1e5, true),
                Limit::uniform(at, 0.0, 1000.0, 1e5, false),
            ],
            grip: crate::limits::Grip::constant(1000.0),
            jerk: 1e5,
            period: 0.001,
        }
    }

    /// The state after one period cruising at target `u` from the start: a stand-in
    /// trial whose verdict switches once along `u`.
    fn cruise(u: f64) -> Motion {
        Motion {
            s: 0.001 * u,
            v: u,
            a: 0.0,
        }
    }

    /// The plain bisection's and [`highest_safe`]'s answers for `trial` between `low` and
    /// `high` in `w`, each with the number of states it judged.
    fn both(
        low: f64,
        high: f64,
        trial: impl Fn(f64) -> Motion,
        w: &Window,
    ) -> ((Motion, usize), (Motion, usize)) {
        let mut plain = Verdicts::default();
        let expected = bisect(low, high, trial(low), &trial, w, &mut plain);
        let mut probed = Verdicts::default();
        let got = highest_safe(low, high, trial(low), &trial, w, &mut probed);
        ((expected, plain.len()), (got, probed.len()))
    }

    #[test]
    fn a_target_inside_the_bracket_is_the_plain_bisections_at_one_check_more() {
        // Cruising at u towards a stop ahead: safe below the speed whose braking fits the
        // distance left, found by both searches alike (and well above rest).
        for at in [0.5, 2.0, 5.0] {
            let w = stop_at(at);
            let ((expected, plain), (got, probed)) = both(0.0, 99.0, cruise, &w);
            assert_eq!(got, expected, "stop at {at} mm");
            assert!(expected.v > 10.0, "stop at {at} mm: {expected:?}");
            assert!(speed::check(&got, &w));
            assert_eq!(probed, plain + 1, "stop at {at} mm");
        }
    }

    #[test]
    fn when_no_target_above_the_safe_ramp_is_safe_one_check_finds_it() {
        // A stop 1 nm ahead: only the ramp towards rest stays short of it; every other
        // target's state has crossed the stop still moving.
        let w = stop_at(1e-9);
        let ((expected, plain), (got, probed)) = both(0.0, 99.0, cruise, &w);
        assert_eq!(expected, Motion::default());
        assert_eq!(got, expected);
        assert_eq!((plain, probed), (BISECTION_STEPS, 1));
    }

    #[test]
    fn a_narrow_bracket_is_halved_only_down_to_the_resolution() {
        // Cruising towards a stop 0.35 mm ahead: the highest safe cruise is about 21 mm/s
        // (v²/2A + v·A/2J and the period's travel). In a bracket 0.3 mm/s wide round it the answer is that speed
        // less at most the resolution, found with no more checks than halving 0.3 mm/s
        // down to the resolution takes.
        let w = stop_at(0.35);
        // The highest safe cruising speed, to 1e-12 mm/s by a fine bisection on the check.
        let (mut lo, mut hi) = (0.0, 100.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if speed::check(&cruise(mid), &w) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let best = lo;
        // In closed form: after the period at u the state is 0.001·u on, and braking from u
        // (above A²/J = 10 mm/s, so with a held deceleration) needs u²/2A + u·A/2J; both
        // fill the 0.35 mm where u²/2000 + 0.006·u = 0.35.
        let closed = (-0.006 + (0.006f64.powi(2) + 4.0 / 2000.0 * 0.35).sqrt()) * 1000.0;
        assert!((best - closed).abs() <= 1e-6, "{best} against {closed}");
        let (low, high) = (best - 0.2, best + 0.1);
        let ((got, checks), _) = both(low, high, cruise, &w);
        assert!(got.v <= best + 1e-9, "{got:?} above {best}");
        assert!(
            best - got.v <= SPEED_RESOLUTION * low,
            "{got:?}: {} short of {best}",
            best - got.v
        );
        // 0.3 mm/s halved to 1e-4 of 21 mm/s (2.1 µm/s): 8 halvings.
        let halvings = ((high - low) / (SPEED_RESOLUTION * low)).log2().ceil() as usize;
        assert!(checks <= halvings, "{checks} checks, {halvings} halvings");
        assert!(checks < BISECTION_STEPS);
    }

    #[test]
    fn a_verdict_that_does_not_switch_once_still_ends_in_a_safe_state() {
        // The stop 1 nm ahead again, but the targets between 60 and 61 mm/s stand for a
        // trial that stays at rest (safe): the bisection may land in the band, the probe
        // keeps the ramp towards `low`; either answer is judged safe.
        let w = stop_at(1e-9);
        let trial = |u: f64| {
            if (60.0..61.0).contains(&u) {
                Motion::default()
            } else {
                cruise(u)
            }
        };
        let ((expected, _), (got, _)) = both(0.0, 99.0, trial, &w);
        assert!(speed::check(&expected, &w), "{expected:?}");
        assert!(speed::check(&got, &w), "{got:?}");
        assert_eq!(got, Motion::default());
    }
}
