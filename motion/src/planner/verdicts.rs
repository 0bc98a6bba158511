//! The verdicts of the safety check ([`speed::check`]) already given within one period's
//! search for the next state.
//!
//! The check is a pure function of the trial state and the window, and the search of one
//! period often tries the same state twice: ramps towards different speeds move alike over
//! the period while their first phase of constant jerk outlasts it (braking with the full
//! jerk, or holding the acceleration limit), so several steps of the bisection, or a
//! candidate ramp and a bisection step, land on the very same state. Such a state is judged
//! once and its verdict reused; states are compared bit for bit (−0 and +0 differ: the sign
//! of an acceleration steers the easing), so every verdict is the one the check would give.

use super::speed::{self, Motion, Window};

/// Verdicts given within one period, by the trial state's bits.
#[derive(Debug, Clone)]
pub(super) struct Verdicts {
    seen: Vec<([u64; 3], bool)>,
}

/// Room for the verdicts of one period, reserved when the planner is built so that the
/// servo loop does not grow it: a period's search judges about two dozen states (the
/// bisection's steps and the candidate ramps); more only grow it once.
const RESERVED_VERDICTS: usize = 128;

impl Default for Verdicts {
    fn default() -> Self {
        Verdicts {
            seen: Vec::with_capacity(RESERVED_VERDICTS),
        }
    }
}

impl Verdicts {
    /// Forgets the verdicts: a new period, or a new window.
    pub(super) fn clear(&mut self) {
        self.seen.clear();
    }

    /// How many states were judged since the last [`Verdicts::clear`].
    #[cfg(test)]
    pub(super) fn len(&self) -> usize {
        self.seen.len()
    }

    /// [`speed::check`] of `x` in `w`, judged only the first time `x` is seen since the
    /// last [`Verdicts::clear`] (the window must not have changed in between).
    pub(super) fn check(&mut self, x: &Motion, w: &Window) -> bool {
        let key = [x.s.to_bits(), x.v.to_bits(), x.a.to_bits()];
        if let Some(&(_, safe)) = self.seen.iter().find(|(k, _)| *k == key) {
            return safe;
        }
        let safe = speed::check(x, w);
        self.seen.push((key, safe));
        safe
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planner::speed::Limit;

    /// A window with one stop 1 mm ahead, 1000 mm/s² and 1e5 mm/s³.
    fn stop_ahead() -> Window {
        Window {
            limits: vec![
                Limit::uniform(0.0, 100.0, 1000.0, 1e5, true),
                Limit::uniform(1.0, 0.0, 1000.0, 1e5, false),
            ],
            grip: crate::limits::Grip::constant(1000.0),
            jerk: 1e5,
            period: 0.001,
        }
    }

    #[test]
    fn a_remembered_verdict_is_the_checks_own_for_safe_and_unsafe_states_and_signed_zeros() {
        let w = stop_ahead();
        // At rest anything is safe; at 100 mm/s braking from 1 mm ahead is not: a braking
        // ramp with 1000 mm/s² needs v²/(2A) = 5 mm and more.
        let states = [
            Motion {
                s: 0.0,
                v: 0.0,
                a: 0.0,
            },
            Motion {
                s: 0.0,
                v: 100.0,
                a: 0.0,
            },
            Motion {
                s: 0.0,
                v: 1.0,
                a: -0.0,
            },
            Motion {
                s: 0.0,
                v: 1.0,
                a: 0.0,
            },
        ];
        assert!(speed::check(&states[0], &w));
        assert!(!speed::check(&states[1], &w));
        let mut memo = Verdicts::default();
        for round in 0..2 {
            for x in &states {
                assert_eq!(
                    memo.check(x, &w),
                    speed::check(x, &w),
                    "round {round}: {x:?}"
                );
            }
        }
        // Each state judged once: −0 and +0 are two states.
        assert_eq!(memo.seen.len(), states.len());
        memo.clear();
        assert!(memo.seen.is_empty());
    }
}
