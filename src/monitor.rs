//! Run-time monitors and stop reactions: what the runtime watches each servo cycle besides
//! the drives' own fault reports, how it brings axes to rest when the path cannot be kept
//! (a jerk-limited quick stop per axis, [`AxisStop`]), and what it reports about a stop
//! ([`StopReport`]).
//!
//! The braking distance of an axis moving at `v` with acceleration limit `a` and jerk limit
//! `j`, starting from zero acceleration, is `v²/(2a) + v·a/(2j)` when `v ≥ a²/j` (the
//! acceleration ramps to `−a` in `a/j`, holds, and ramps back), and `v·√(v/j)` otherwise
//! (a triangular acceleration profile that never reaches `a`).

use klar_interp::AxisLetter;
use klar_motion::{AxisFault, Setpoint};
use std::fmt;

/// Braking distance from speed `v` at zero acceleration with acceleration limit `a_max` and
/// jerk limit `j_max` (see the module doc for the formula).
pub fn braking_distance(v: f64, a_max: f64, j_max: f64) -> f64 {
    let v = v.abs();
    if v * j_max >= a_max * a_max {
        v * v / (2.0 * a_max) + v * a_max / (2.0 * j_max)
    } else {
        v * (v / j_max).sqrt()
    }
}

/// A jerk-limited stop of one axis from its current commanded state, one servo cycle at a
/// time: the acceleration ramps toward `−a_max` against the motion and back to zero so that
/// the velocity reaches zero with it.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisStop {
    position: f64,
    velocity: f64,
    acceleration: f64,
    a_max: f64,
    j_max: f64,
}

impl AxisStop {
    /// A stop from commanded position, velocity and acceleration with the axis limits.
    pub fn new(setpoint: Setpoint, a_max: f64, j_max: f64) -> Self {
        let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
        Self {
            position: finite(setpoint.position),
            velocity: finite(setpoint.velocity),
            acceleration: finite(setpoint.acceleration),
            a_max: a_max.abs().max(f64::MIN_POSITIVE),
            j_max: j_max.abs().max(f64::MIN_POSITIVE),
        }
    }

    /// True once the commanded motion has stopped.
    pub fn at_rest(&self) -> bool {
        self.velocity == 0.0 && self.acceleration == 0.0
    }

    /// Advances by `dt` and returns the setpoint for the end of the step.
    pub fn step(&mut self, dt: f64) -> Setpoint {
        if self.at_rest() || !(dt.is_finite() && dt > 0.0) {
            return self.setpoint();
        }
        // Work in the direction of motion: u ≥ 0 is the speed, b the acceleration along it.
        let s = if self.velocity != 0.0 {
            self.velocity.signum()
        } else {
            -self.acceleration.signum()
        };
        let (u, b) = (self.velocity * s, self.acceleration * s);
        let (u1, b1, d) = advance(u, b, dt, self.a_max, self.j_max);
        self.position += s * d.max(0.0);
        if u1 > 0.0 {
            self.velocity = s * u1;
            self.acceleration = s * b1;
        } else {
            self.velocity = 0.0;
            self.acceleration = 0.0;
        }
        self.setpoint()
    }

    /// The current commanded state.
    pub fn setpoint(&self) -> Setpoint {
        Setpoint {
            position: self.position,
            velocity: self.velocity,
            acceleration: self.acceleration,
        }
    }
}

/// One step `dt` of a stop along the direction of motion from speed `u ≥ 0` and acceleration
/// `b`: returns the speed, the acceleration and the distance at its end (speed and
/// acceleration zero once at rest). The stop brakes harder ([`press`]) until the landing
/// curve `u = b²/(2j)` is reached, then ramps the acceleration back to zero with jerk `j` so
/// that both reach zero together ([`ramp_to_rest`]). The switch falls inside the step where
/// it is due (found by bisection): a switch a step late would have to end with the
/// acceleration cut from hundreds of mm/s² to zero, a step early would stop longer than the
/// braking distance.
fn advance(u: f64, b: f64, dt: f64, a: f64, j: f64) -> (f64, f64, f64) {
    // On or past the landing curve: past it when the stop began too late to land with j.
    let landing = |u: f64, b: f64| u <= 0.0 || (b < 0.0 && b * b >= 2.0 * j * u);
    if landing(u, b) {
        return ramp_to_rest(u, b, dt, j);
    }
    let (up, bp, dp) = press(u, b, dt, a, j);
    if !landing(up, bp) {
        return (up, bp, dp);
    }
    let (mut lo, mut hi) = (0.0, dt);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        let (um, bm, _) = press(u, b, mid, a, j);
        if landing(um, bm) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let (ut, bt, dpt) = press(u, b, hi, a, j);
    let (u2, b2, d2) = ramp_to_rest(ut, bt, dt - hi, j);
    (u2, b2, dpt + d2)
}

/// Braking harder for `t`: the acceleration ramps toward `−a` with jerk `−j` and holds there.
/// Returns speed, acceleration and distance.
fn press(u: f64, b: f64, t: f64, a: f64, j: f64) -> (f64, f64, f64) {
    let t1 = if b > -a { ((b + a) / j).min(t) } else { 0.0 };
    let u1 = u + b * t1 - 0.5 * j * t1 * t1;
    let b1 = b - j * t1;
    let d1 = u * t1 + 0.5 * b * t1 * t1 - j * t1 * t1 * t1 / 6.0;
    let t2 = t - t1;
    (u1 + b1 * t2, b1, d1 + u1 * t2 + 0.5 * b1 * t2 * t2)
}

/// Ramping the acceleration `b < 0` back to zero for `t` with the constant jerk that brings
/// speed and acceleration to zero together, at most `j` (with `j`, a stop that began too late
/// reaches zero speed first and ends there). Returns speed, acceleration and distance; zero
/// speed and acceleration once at rest.
fn ramp_to_rest(u: f64, b: f64, t: f64, j: f64) -> (f64, f64, f64) {
    if u <= 0.0 || b >= 0.0 {
        return (0.0, 0.0, 0.0);
    }
    let jerk = (b * b / (2.0 * u)).min(j);
    let t_flat = -b / jerk;
    let end = zero_crossing(u, b, jerk, t.min(t_flat));
    let d = u * end + 0.5 * b * end * end + jerk * end * end * end / 6.0;
    if end < t {
        (0.0, 0.0, d)
    } else {
        (u + b * t + 0.5 * jerk * t * t, b + jerk * t, d)
    }
}

/// First time in `[0, dt]` where `u + b·t + jerk·t²/2` reaches zero (`dt` when it does not).
fn zero_crossing(u: f64, b: f64, jerk: f64, dt: f64) -> f64 {
    let (qa, qb, qc) = (0.5 * jerk, b, u);
    let roots: [f64; 2] = if qa.abs() < 1e-300 {
        if qb != 0.0 {
            [-qc / qb, f64::NAN]
        } else {
            [f64::NAN; 2]
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc < 0.0 {
            [f64::NAN; 2]
        } else {
            let r = disc.sqrt();
            [(-qb - r) / (2.0 * qa), (-qb + r) / (2.0 * qa)]
        }
    };
    roots
        .into_iter()
        .filter(|t| t.is_finite() && *t >= 0.0 && *t <= dt)
        .fold(dt, f64::min)
}

/// Why a run stopped early.
#[derive(Debug, Clone, PartialEq)]
pub enum StopCause {
    /// An axis reported a fault (drive, limit switch, e-stop, lost link, its own following
    /// error window).
    AxisFault(AxisFault),
    /// The control's following-error monitor tripped.
    FollowingError {
        /// Commanded − measured when it tripped.
        error: f64,
        /// The configured limit.
        limit: f64,
    },
    /// The backend could not be reached (a transport error).
    Communication(String),
    /// The spindle faulted or did not reach speed.
    Spindle(String),
    /// An error of the program reached at run time.
    Program(String),
    /// Setpoints reached the axes too late.
    Underrun {
        /// How late, s.
        late: f64,
        /// The machine's limit, s.
        limit: f64,
    },
    /// The setpoint guard refused a commanded setpoint (it was not sent).
    Setpoint(crate::runtime::guard::Violation),
    /// The operator asked for a stop.
    Requested,
    /// The operator stopped the run from outside (a signal to `klar run` or `klar serve`).
    Operator,
}

impl fmt::Display for StopCause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StopCause::AxisFault(fault) => write!(f, "{fault}"),
            StopCause::FollowingError { error, limit } => {
                write!(f, "following error {error:.4} beyond the monitor's {limit}")
            }
            StopCause::Communication(m) => write!(f, "communication: {m}"),
            StopCause::Spindle(m) => write!(f, "spindle: {m}"),
            StopCause::Program(m) => write!(f, "program: {m}"),
            StopCause::Underrun { late, limit } => write!(
                f,
                "setpoint underrun: {:.1} ms late (limit {:.1} ms)",
                late * 1e3,
                limit * 1e3
            ),
            StopCause::Setpoint(v) => write!(f, "setpoint refused: {v}"),
            StopCause::Requested => write!(f, "stop requested"),
            StopCause::Operator => write!(f, "stopped by the operator"),
        }
    }
}

/// How the axes were brought to rest.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopKind {
    /// Feed hold along the programmed path (the axes could still follow).
    OnPath,
    /// Each axis stopped on its own (jerk-limited) while the faulted ones braked in their
    /// drives: the path is left.
    Quick,
}

/// What happened to one axis during a stop.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisStopFigures {
    /// The axis.
    pub axis: AxisLetter,
    /// Commanded velocity when the fault was seen, units/s.
    pub velocity: f64,
    /// Commanded acceleration when the fault was seen, units/s².
    pub acceleration: f64,
    /// Measured position when the fault was seen.
    pub position_at_fault: f64,
    /// Measured position at rest.
    pub position_at_rest: f64,
    /// |following error| when the fault was seen.
    pub following_error: f64,
}

impl AxisStopFigures {
    /// Distance the axis travelled from the fault to rest (measured).
    pub fn stop_distance(&self) -> f64 {
        (self.position_at_rest - self.position_at_fault).abs()
    }
}

/// The report of a stop: cause, where in the program, which axis, and the figures.
#[derive(Debug, Clone, PartialEq)]
pub struct StopReport {
    /// Why.
    pub cause: StopCause,
    /// The axis that caused it, if one did.
    pub axis: Option<AxisLetter>,
    /// Program line being executed.
    pub line: u32,
    /// Block number being executed, if the block has one.
    pub block: Option<u64>,
    /// Machine time the fault was seen, s.
    pub t_fault: f64,
    /// Machine time all axes were at rest, s.
    pub t_rest: f64,
    /// How the axes were stopped.
    pub kind: StopKind,
    /// Per machine axis.
    pub axes: Vec<AxisStopFigures>,
}

impl fmt::Display for StopReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let how = match self.kind {
            StopKind::OnPath => "controlled stop on the path",
            StopKind::Quick => "quick stop",
        };
        write!(f, "{how} at t = {:.3} s: {}", self.t_fault, self.cause)?;
        if let Some(a) = self.axis {
            write!(f, ", axis {a}")?;
        }
        match self.block {
            Some(b) => write!(f, ", block {b} (line {})", self.line)?,
            None => write!(f, ", line {}", self.line)?,
        }
        write!(f, "; at rest after {:.3} s", self.t_rest - self.t_fault)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Simulates a stop with a tiny step and returns (distance, peak |a|, peak |jerk|).
    fn run_stop(v: f64, a0: f64, a_max: f64, j_max: f64, dt: f64) -> (f64, f64, f64) {
        let mut stop = AxisStop::new(
            Setpoint {
                position: 0.0,
                velocity: v,
                acceleration: a0,
            },
            a_max,
            j_max,
        );
        let (mut peak_a, mut peak_j) = (0.0f64, 0.0f64);
        let mut last_a = a0;
        let mut n = 0;
        while !stop.at_rest() {
            let sp = stop.step(dt);
            peak_a = peak_a.max(sp.acceleration.abs());
            if !stop.at_rest() {
                peak_j = peak_j.max((sp.acceleration - last_a).abs() / dt);
            }
            last_a = sp.acceleration;
            n += 1;
            assert!(n < 10_000_000, "stop never ends");
        }
        (stop.setpoint().position, peak_a, peak_j)
    }

    #[test]
    fn a_stop_from_cruise_matches_the_trapezoidal_closed_form() {
        // 100 mm/s, a = 2000, j = 50000: ramp 0.04 s, v ≥ a²/j = 80, so the
        // trapezoidal case: 100²/4000 + 100·2000/100000 = 2.5 + 2 = 4.5 mm.
        let (d, peak_a, peak_j) = run_stop(100.0, 0.0, 2000.0, 50_000.0, 1e-5);
        assert!((d - 4.5).abs() < 2e-3, "distance {d}");
        assert!(peak_a <= 2000.0 * (1.0 + 1e-9), "peak a {peak_a}");
        assert!(peak_j <= 50_000.0 * 1.001, "peak jerk {peak_j}");
        assert!((braking_distance(100.0, 2000.0, 50_000.0) - 4.5).abs() < 1e-12);
    }

    #[test]
    fn a_slow_stop_matches_the_triangular_closed_form() {
        // v = 20 < a²/j = 80: d = v·sqrt(v/j) = 20·sqrt(0.0004) = 0.4 mm.
        let (d, peak_a, _) = run_stop(-20.0, 0.0, 2000.0, 50_000.0, 1e-5);
        assert!((d + 0.4).abs() < 1e-3, "distance {d}");
        // Peak deceleration sqrt(v·j) = 1000.
        assert!((peak_a - 1000.0).abs() < 5.0, "peak a {peak_a}");
        assert!((braking_distance(20.0, 2000.0, 50_000.0) - 0.4).abs() < 1e-12);
    }

    #[test]
    fn a_stop_while_accelerating_first_removes_the_acceleration() {
        // a0 = +1000 along the motion: the speed still grows by a0²/(2j) = 10 mm/s while the
        // acceleration ramps to zero, then the cruise stop from 110 mm/s follows.
        let (d, _, _) = run_stop(100.0, 1000.0, 2000.0, 50_000.0, 1e-5);
        let t1: f64 = 1000.0 / 50_000.0;
        let d1 = 100.0 * t1 + 0.5 * 1000.0 * t1 * t1 - 50_000.0 * t1.powi(3) / 6.0;
        let expected = d1 + braking_distance(110.0, 2000.0, 50_000.0);
        assert!(
            (d - expected).abs() < 5e-3,
            "distance {d}, expected {expected}"
        );
    }

    #[test]
    fn a_stop_taken_over_while_braking_lands_without_an_acceleration_step() {
        // Taken over mid-way through another deceleration (as when a quick stop cuts a feed
        // hold short), at the servo period: by finite differences of the positions, as a
        // trace shows it, the jerk stays within the limit up to rest.
        let (a_max, j_max, dt) = (2000.0, 50_000.0, 1e-3);
        let mut stop = AxisStop::new(
            Setpoint {
                position: 0.0,
                velocity: 43.99,
                acceleration: -800.0,
            },
            a_max,
            j_max,
        );
        let mut x = vec![0.0];
        let mut n = 0;
        while !stop.at_rest() {
            x.push(stop.step(dt).position);
            n += 1;
            assert!(n < 1000, "stop never ends");
        }
        let last = *x.last().unwrap();
        x.extend([last; 4]);
        let d: Vec<f64> = x.windows(2).map(|w| (w[1] - w[0]) / dt).collect();
        let acc: Vec<f64> = d.windows(2).map(|w| (w[1] - w[0]) / dt).collect();
        let jerk: Vec<f64> = acc.windows(2).map(|w| (w[1] - w[0]) / dt).collect();
        let peak_a = acc.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        // the first differences need the positions before the take-over: left out
        let peak_j = jerk.iter().skip(1).fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(peak_a <= a_max, "peak a {peak_a}");
        assert!(peak_j <= j_max * 1.05, "peak jerk {peak_j}");
    }

    #[test]
    fn a_coarse_step_still_stops_within_one_step_of_the_closed_form() {
        let v = 166.0;
        let (d, _, _) = run_stop(v, 0.0, 2000.0, 50_000.0, 1e-3);
        let exact = braking_distance(v, 2000.0, 50_000.0);
        assert!(
            (d - exact).abs() <= v * 1e-3,
            "distance {d}, closed form {exact}"
        );
    }
}
