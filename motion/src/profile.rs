//! Jerk-limited speed profile along a path: the 7-phase S-curve from rest to rest.
//!
//! Phases: jerk +J, constant acceleration, jerk −J (acceleration phase), cruise, then the
//! mirror image to stop. Short moves that cannot reach the cruise speed get a lower peak
//! speed (and, if needed, a lower peak acceleration) so the distance is still exact.

/// Path limits a profile must respect.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathLimits {
    /// Largest path speed (units/s).
    pub velocity: f64,
    /// Largest path acceleration (units/s²).
    pub acceleration: f64,
    /// Largest path jerk (units/s³).
    pub jerk: f64,
}

/// Path distance, speed and acceleration at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileState {
    /// Distance from the start.
    pub s: f64,
    /// Path speed.
    pub v: f64,
    /// Path acceleration.
    pub a: f64,
}

/// A symmetric rest-to-rest S-curve over a distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SCurve {
    distance: f64,
    /// Peak speed actually reached.
    peak_velocity: f64,
    /// Peak acceleration actually reached.
    peak_acceleration: f64,
    jerk: f64,
    /// Duration of each jerk phase.
    t_jerk: f64,
    /// Duration of the constant-acceleration phase.
    t_const: f64,
    /// Duration of the cruise phase.
    t_cruise: f64,
}

/// The acceleration phase to reach speed `v` from rest: (jerk time, constant-acceleration
/// time, peak acceleration).
fn ramp(v: f64, a: f64, j: f64) -> (f64, f64, f64) {
    if v * j >= a * a {
        (a / j, v / a - a / j, a)
    } else {
        let tj = (v / j).sqrt();
        (tj, 0.0, j * tj)
    }
}

impl SCurve {
    /// The time-optimal symmetric S-curve covering `distance` within `limits`. All inputs
    /// must be positive and finite (the planner checks them).
    pub fn new(distance: f64, limits: PathLimits) -> SCurve {
        let PathLimits {
            velocity: vmax,
            acceleration: a,
            jerk: j,
        } = limits;
        // Distance of a full rest → v → rest profile without cruise: v · (acceleration time).
        let stop_distance = |v: f64| {
            let (tj, tc, _) = ramp(v, a, j);
            v * (2.0 * tj + tc)
        };
        let v = if stop_distance(vmax) <= distance {
            vmax
        } else if distance >= 2.0 * a * a * a / (j * j) {
            // Peak acceleration reached: v²/a + v·a/j = distance.
            let b = a / j;
            0.5 * a * (-b + (b * b + 4.0 * distance / a).sqrt())
        } else {
            // Triangular acceleration: 2·v^{3/2}/√j = distance.
            (0.5 * distance * j.sqrt()).powf(2.0 / 3.0)
        };
        let v = v.min(vmax);
        let (t_jerk, t_const, peak_acceleration) = ramp(v, a, j);
        let t_cruise = ((distance - stop_distance(v)) / v).max(0.0);
        SCurve {
            distance,
            peak_velocity: v,
            peak_acceleration,
            jerk: j,
            t_jerk,
            t_const,
            t_cruise,
        }
    }

    /// Total duration.
    pub fn duration(&self) -> f64 {
        2.0 * self.ramp_time() + self.t_cruise
    }

    /// Distance covered.
    pub fn distance(&self) -> f64 {
        self.distance
    }

    /// Peak path speed reached.
    pub fn peak_velocity(&self) -> f64 {
        self.peak_velocity
    }

    /// Peak path acceleration reached.
    pub fn peak_acceleration(&self) -> f64 {
        self.peak_acceleration
    }

    fn ramp_time(&self) -> f64 {
        2.0 * self.t_jerk + self.t_const
    }

    /// State of the acceleration phase `tau` seconds after the start.
    fn ramp_state(&self, tau: f64) -> ProfileState {
        let (j, tj, tc, ap) = (self.jerk, self.t_jerk, self.t_const, self.peak_acceleration);
        let tau = tau.clamp(0.0, self.ramp_time());
        if tau <= tj {
            return ProfileState {
                s: j * tau.powi(3) / 6.0,
                v: 0.5 * j * tau * tau,
                a: j * tau,
            };
        }
        let (s1, v1) = (j * tj.powi(3) / 6.0, 0.5 * j * tj * tj);
        if tau <= tj + tc {
            let d = tau - tj;
            return ProfileState {
                s: s1 + v1 * d + 0.5 * ap * d * d,
                v: v1 + ap * d,
                a: ap,
            };
        }
        let (s2, v2) = (s1 + v1 * tc + 0.5 * ap * tc * tc, v1 + ap * tc);
        let d = tau - tj - tc;
        ProfileState {
            s: s2 + v2 * d + 0.5 * ap * d * d - j * d.powi(3) / 6.0,
            v: v2 + ap * d - 0.5 * j * d * d,
            a: ap - j * d,
        }
    }

    /// State `t` seconds after the start (clamped to the profile): exactly the distance at
    /// and after the end.
    pub fn state(&self, t: f64) -> ProfileState {
        let ramp = self.ramp_time();
        let total = self.duration();
        if t >= total {
            return ProfileState {
                s: self.distance,
                v: 0.0,
                a: 0.0,
            };
        }
        if t <= ramp {
            return self.ramp_state(t);
        }
        if t <= ramp + self.t_cruise {
            let up = self.ramp_state(ramp);
            return ProfileState {
                s: up.s + self.peak_velocity * (t - ramp),
                v: self.peak_velocity,
                a: 0.0,
            };
        }
        // Braking is the acceleration phase mirrored in time and distance.
        let m = self.ramp_state(total - t);
        ProfileState {
            s: (self.distance - m.s).clamp(0.0, self.distance),
            v: m.v,
            a: -m.a,
        }
    }
}

/// Path distance, speed, acceleration and jerk at one instant of a [`Ramp`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RampState {
    /// Distance from where the ramp started.
    pub s: f64,
    /// Path speed.
    pub v: f64,
    /// Path acceleration.
    pub a: f64,
}

/// The time-optimal jerk-limited change of path speed from any state `(v₀, a₀)` to a target
/// speed `w` with zero acceleration: at most three phases of constant jerk (±J, 0, ±J) with
/// |a| ≤ A in between, then cruise at `w` for ever.
///
/// Whether it speeds up or slows down follows from the speed reached by bringing the
/// acceleration to zero at once, `v₀ + a₀·|a₀|/(2J)`: below `w` it speeds up, above it slows
/// down. An acceleration above A (limits that dropped) is first brought back to A.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ramp {
    v0: f64,
    a0: f64,
    target: f64,
    /// (jerk, duration) of the three phases.
    phases: [(f64, f64); 3],
}

/// One constant-jerk phase of a [`Ramp`] as it starts: distance `s`, speed `v` and
/// acceleration `a` at its start, its jerk `j` and duration `d`.
#[derive(Debug, Clone, Copy)]
struct PhaseStart {
    s: f64,
    v: f64,
    a: f64,
    j: f64,
    d: f64,
}

impl PhaseStart {
    /// Distance covered `h` seconds into the phase, from the ramp's start.
    fn distance(&self, h: f64) -> f64 {
        self.s + self.v * h + 0.5 * self.a * h * h + self.j * h * h * h / 6.0
    }

    /// Speed `h` seconds into the phase.
    fn speed(&self, h: f64) -> f64 {
        self.v + self.a * h + 0.5 * self.j * h * h
    }

    /// Lowest and highest speed over `[lo, hi]` within the phase: the ends and, where it
    /// lies between them, the turning point of the quadratic.
    fn speed_range(&self, lo: f64, hi: f64) -> (f64, f64) {
        let (u, w) = (self.speed(lo), self.speed(hi));
        let (mut low, mut high) = (u.min(w), u.max(w));
        if self.j != 0.0 {
            let turn = -self.a / self.j;
            if turn > lo && turn < hi {
                low = low.min(self.speed(turn));
                high = high.max(self.speed(turn));
            }
        }
        (low, high)
    }

    /// Whether the speed where the phase covers `distance` is at most `bound`, decided from
    /// a narrow bracket round the time it gets there, found by Newton's method; `None` when
    /// the bracket does not decide it (or the speed is not positive all phase long, so the
    /// distance might not grow with time).
    ///
    /// The answer is the one of [`Ramp::speed_after_at_most`]'s bisection, whose final
    /// lower end `lo` lies within one last bracket width `δ = d/2²⁴` before a time at
    /// which the distance is reached: with a time `t_lo` before which the distance is
    /// certainly not yet reached and `t_hi` after which it certainly is (each clear of the
    /// target distance by far more than the rounding of evaluating it), `lo` lies in
    /// `[t_lo − δ, t_hi]`, and when every speed there clears `bound` by `margin` on one
    /// side, so does the speed at `lo`.
    fn decide_near_root(&self, distance: f64, bound: f64, margin: f64) -> Option<bool> {
        let (low, _) = self.speed_range(0.0, self.d);
        if low.is_nan() || low <= 0.0 {
            return None;
        }
        let size = self.s.abs()
            + self.v.abs() * self.d
            + 0.5 * self.a.abs() * self.d * self.d
            + self.j.abs() * self.d * self.d * self.d / 6.0;
        let gap = ROOT_GAP * size;
        let mut t = ((distance - self.s) / self.v.max(low)).clamp(0.0, self.d);
        for _ in 0..NEWTON_STEPS {
            t = (t - (self.distance(t) - distance) / self.speed(t)).clamp(0.0, self.d);
        }
        let width = ROOT_WIDTH * self.d;
        let (t_lo, t_hi) = ((t - width).max(0.0), (t + width).min(self.d));
        let before = t_lo <= 0.0 || self.distance(t_lo) < distance - gap;
        let after = self.distance(t_hi) > distance + gap;
        if !(before && after) {
            return None;
        }
        // Twice the last bracket's width: the halving rounds.
        let last = 2.0 * self.d / f64::from(1u32 << SPEED_AFTER_STEPS);
        let (low, high) = self.speed_range((t_lo - last).max(0.0), t_hi);
        if high <= bound - margin {
            Some(true)
        } else if low > bound + margin {
            Some(false)
        } else {
            None
        }
    }
}

/// Newton steps for the time at which a phase reaches a distance in
/// [`PhaseStart::decide_near_root`].
const NEWTON_STEPS: usize = 5;

/// Half-width of the bracket round Newton's time, as a share of the phase's duration.
const ROOT_WIDTH: f64 = 1e-9;

/// How far the distance at the bracket's ends must clear the target, as a share of the
/// size of the distance's terms over the phase: far above the rounding of evaluating it.
const ROOT_GAP: f64 = 1e-12;

impl Ramp {
    /// The ramp from speed `v0` and acceleration `a0` to speed `target`, with path
    /// acceleration limit `accel` and jerk limit `jerk` (both positive and finite).
    pub fn new(v0: f64, a0: f64, target: f64, accel: f64, jerk: f64) -> Ramp {
        let zeroed = v0 + a0 * a0.abs() / (2.0 * jerk);
        let phases = if target >= zeroed {
            speed_up(target - v0, a0, accel, jerk)
        } else {
            speed_up(v0 - target, -a0, accel, jerk).map(|(j, t)| (-j, t))
        };
        Ramp {
            v0,
            a0,
            target,
            phases,
        }
    }

    /// Time until the target speed is reached.
    pub fn duration(&self) -> f64 {
        self.phases.iter().map(|p| p.1).sum()
    }

    /// The target speed.
    pub fn target(&self) -> f64 {
        self.target
    }

    /// Distance covered until the target speed is reached.
    pub fn distance(&self) -> f64 {
        self.state(self.duration()).s
    }

    /// The jerk applied at time `t` (zero after the ramp).
    pub fn jerk_at(&self, t: f64) -> f64 {
        let mut t0 = 0.0;
        for &(j, d) in &self.phases {
            if t < t0 + d {
                return j;
            }
            t0 += d;
        }
        0.0
    }

    /// The phase in which the ramp covers `distance`, with the distance, speed and
    /// acceleration at its start; `None` when the ramp ends before (the target speed holds
    /// beyond). Phases of no length are skipped.
    fn phase_reaching(&self, distance: f64) -> Option<PhaseStart> {
        let (mut s, mut v, mut a) = (0.0, self.v0, self.a0);
        for &(j, d) in &self.phases {
            if d <= 0.0 {
                continue;
            }
            let p = PhaseStart { s, v, a, j, d };
            if p.distance(d) >= distance {
                return Some(p);
            }
            s = p.distance(d);
            v += a * d + 0.5 * j * d * d;
            a += j * d;
        }
        None
    }

    /// Speed once the ramp has covered `distance` (the target speed beyond its end), for a
    /// ramp whose speed stays positive until then. Within the phase where the distance is
    /// reached the time is found by bisection (the distance grows with time while the
    /// speed is positive); the speed is that at the bracket's earlier end, a hair before
    /// the distance is reached.
    pub fn speed_after(&self, distance: f64) -> f64 {
        let Some(p) = self.phase_reaching(distance) else {
            return self.target;
        };
        let (mut lo, mut hi) = (0.0, p.d);
        for _ in 0..SPEED_AFTER_STEPS {
            let mid = 0.5 * (lo + hi);
            if p.distance(mid) < distance {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        p.speed(lo)
    }

    /// True when [`Ramp::speed_after`] of `distance` is at most `bound`, found with as few
    /// bisection steps as decide it: the bisection's answer is the speed at some time in the
    /// bracket, so once every speed in the bracket (the ends and the turning point of the
    /// quadratic between them) is clearly on one side of `bound` the answer is too. Where
    /// the bracket never decides (the speed within rounding of `bound`), the full
    /// bisection's speed is compared, as `speed_after` gives it.
    pub fn speed_after_at_most(&self, distance: f64, bound: f64) -> bool {
        let Some(p) = self.phase_reaching(distance) else {
            return self.target <= bound;
        };
        let margin = DECIDE_MARGIN * (p.v.abs() + bound.abs() + p.a.abs() * p.d);
        if let Some(side) = p.decide_near_root(distance, bound, margin) {
            return side;
        }
        let (mut lo, mut hi) = (0.0, p.d);
        for _ in 0..SPEED_AFTER_STEPS {
            let (low, high) = p.speed_range(lo, hi);
            if high <= bound - margin {
                return true;
            }
            if low > bound + margin {
                return false;
            }
            let mid = 0.5 * (lo + hi);
            if p.distance(mid) < distance {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        p.speed(lo) <= bound
    }

    /// State `t ≥ 0` seconds after the start; cruise at the target after the ramp.
    pub fn state(&self, t: f64) -> RampState {
        let (mut s, mut v, mut a) = (0.0, self.v0, self.a0);
        let mut left = t.max(0.0);
        for &(j, d) in &self.phases {
            let h = left.min(d);
            if h <= 0.0 {
                continue;
            }
            s += v * h + 0.5 * a * h * h + j * h * h * h / 6.0;
            v += a * h + 0.5 * j * h * h;
            a += j * h;
            left -= h;
        }
        let total = self.duration();
        if t >= total {
            s += self.target * (t - total);
            v = self.target;
            a = 0.0;
        }
        RampState { s, v, a }
    }
}

/// Bisection steps in [`Ramp::speed_after`]: a phase lasts at most a few tenths of a second
/// at the speeds and limits of a machine, so 2⁻²⁴ of it is below 0.1 µs.
const SPEED_AFTER_STEPS: usize = 24;

/// Relative margin (of the speeds involved) by which the speeds in a bracket must clear the
/// bound before [`Ramp::speed_after_at_most`] decides from them: far above the rounding of
/// evaluating the speed at a time, so the early answer is the full bisection's.
const DECIDE_MARGIN: f64 = 1e-12;

/// Phases raising the speed by `dv` from acceleration `a0`, where `dv ≥ a0·|a0|/(2J)`.
fn speed_up(dv: f64, a0: f64, accel: f64, jerk: f64) -> [(f64, f64); 3] {
    let dv = dv.max(a0 * a0.abs() / (2.0 * jerk));
    if a0 > accel {
        // Bring the acceleration back to the limit, hold it, then to zero.
        let hold = ((dv - a0 * a0 / (2.0 * jerk)) / accel).max(0.0);
        return [
            (-jerk, (a0 - accel) / jerk),
            (0.0, hold),
            (-jerk, accel / jerk),
        ];
    }
    // Peak acceleration without a hold: (2·ap² − a0²)/(2J) = dv.
    let peak = ((2.0 * jerk * dv + a0 * a0) / 2.0).max(0.0).sqrt();
    if peak <= accel {
        [
            (jerk, ((peak - a0) / jerk).max(0.0)),
            (0.0, 0.0),
            (-jerk, peak / jerk),
        ]
    } else {
        let hold = ((dv - (2.0 * accel * accel - a0 * a0) / (2.0 * jerk)) / accel).max(0.0);
        [
            (jerk, ((accel - a0) / jerk).max(0.0)),
            (0.0, hold),
            (-jerk, accel / jerk),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_speed_after_a_distance_is_the_speed_of_the_state_that_reaches_it() {
        // Braking from 40 mm/s at −300 mm/s² to 10 mm/s (A 800, J 2e4), a ramp with all
        // three phases, and speeding up from rest; checked against the state by time.
        for r in [
            Ramp::new(40.0, -300.0, 10.0, 800.0, 2e4),
            Ramp::new(0.0, 0.0, 50.0, 1000.0, 1e5),
        ] {
            let total = r.duration();
            for k in 1..40 {
                let t = total * f64::from(k) / 40.0;
                let x = r.state(t);
                let v = r.speed_after(x.s);
                assert!((v - x.v).abs() < 1e-5, "{t}: {v} against {}", x.v);
            }
            // Beyond the end: the target.
            assert_eq!(r.speed_after(r.distance() + 1.0), r.target());
        }
        // Braking from 40 mm/s already at the limit of 800 mm/s² holds it first: there the
        // speed after d is √(40² − 2·800·d) (down to 10 mm/s plus the easing's 3.2 mm/s).
        let r = Ramp::new(40.0, -800.0, 10.0, 800.0, 1e5);
        for d in [0.05f64, 0.2, 0.4, 0.6] {
            let want = (1600.0 - 1600.0 * d).sqrt();
            assert!(want > 13.2, "{d}");
            let v = r.speed_after(d);
            assert!((v - want).abs() < 1e-5, "{d}: {v} against {want}");
        }
    }

    #[test]
    fn deciding_the_speed_after_a_distance_agrees_with_the_full_bisection() {
        // Braking, speeding up and easing ramps; distances inside every phase and beyond
        // the end; bounds across the speed range, and the full bisection's answer itself
        // with the neighbouring floats.
        let ramps = [
            Ramp::new(40.0, -300.0, 10.0, 800.0, 2e4),
            Ramp::new(40.0, -800.0, 10.0, 800.0, 1e5),
            Ramp::new(0.0, 0.0, 50.0, 1000.0, 1e5),
            Ramp::new(12.0, 400.0, 3.0, 1000.0, 5e4),
            Ramp::new(25.0, 0.0, 24.9, 500.0, 1e5),
        ];
        let mut decided = 0;
        for r in ramps {
            let total = r.distance();
            for k in 0..=60 {
                let d = total * f64::from(k) / 50.0;
                let v = r.speed_after(d);
                let mut bounds = vec![v, v.next_up(), v.next_down(), 0.0, 60.0];
                bounds.extend((0..=40).map(|i| 1.25 * f64::from(i)));
                for b in bounds {
                    assert_eq!(r.speed_after_at_most(d, b), v <= b, "{r:?} {d} {b}");
                    decided += 1;
                }
            }
        }
        assert!(decided > 10_000);
    }

    #[test]
    fn the_bracket_round_the_root_decides_clear_bounds_and_leaves_the_close_ones() {
        // Braking from 40 mm/s at 1000 mm/s² (after the jerk phase): the speed falls all
        // along the hold, so a distance inside it has one time and one speed.
        let r = Ramp::new(40.0, -1000.0, 10.0, 1000.0, 1e5);
        let total = r.distance();
        let d = 0.5 * total;
        let p = r.phase_reaching(d).expect("inside the ramp");
        let v = r.speed_after(d);
        let margin = DECIDE_MARGIN * (p.v.abs() + v + p.a.abs() * p.d);
        assert_eq!(p.decide_near_root(d, v + 0.01, margin), Some(true));
        assert_eq!(p.decide_near_root(d, v - 0.01, margin), Some(false));
        // At the bisection's own speed the bracket cannot tell: the full bisection decides.
        assert_eq!(p.decide_near_root(d, v, margin), None);
        assert!(r.speed_after_at_most(d, v));
        assert!(!r.speed_after_at_most(d, v.next_down()));
    }
}
