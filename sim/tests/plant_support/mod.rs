//! Test support: reference motion profiles computed in closed form, independently of the
//! plant's own interpolation, and small helpers to drive a plant cycle by cycle.

#![allow(dead_code)]

use klar_motion::Setpoint;

/// Servo period used by the tests (1 ms, the built-in machine's).
pub const PERIOD: f64 = 0.001;

/// A rest-to-rest jerk-limited (seven-phase) move of `distance` that reaches both the
/// acceleration and the velocity limit, as a list of constant-jerk phases.
#[derive(Debug, Clone)]
pub struct SCurve {
    /// Start position.
    start: f64,
    /// (duration, jerk) of each phase.
    phases: Vec<(f64, f64)>,
}

impl SCurve {
    /// Plans the move; panics in the test if the limits do not allow all seven phases.
    pub fn new(start: f64, distance: f64, v: f64, a: f64, j: f64) -> Self {
        let t_jerk = a / j;
        let t_const_acc = v / a - t_jerk;
        assert!(
            t_const_acc >= 0.0,
            "velocity limit reached before acceleration limit"
        );
        let t_ramp = v / a + t_jerk;
        let t_cruise = distance / v - t_ramp;
        assert!(
            t_cruise >= 0.0,
            "move too short to reach the velocity limit"
        );
        let phases = vec![
            (t_jerk, j),
            (t_const_acc, 0.0),
            (t_jerk, -j),
            (t_cruise, 0.0),
            (t_jerk, -j),
            (t_const_acc, 0.0),
            (t_jerk, j),
        ];
        Self { start, phases }
    }

    /// Total duration.
    pub fn duration(&self) -> f64 {
        self.phases.iter().map(|(d, _)| d).sum()
    }

    /// Position, velocity and acceleration at time `t` (held at the end after the move).
    pub fn at(&self, t: f64) -> Setpoint {
        let (mut p, mut v, mut a) = (self.start, 0.0, 0.0);
        let mut left = t.max(0.0);
        for &(d, j) in &self.phases {
            let dt = left.min(d);
            p += v * dt + a * dt * dt / 2.0 + j * dt * dt * dt / 6.0;
            v += a * dt + j * dt * dt / 2.0;
            a += j * dt;
            left -= dt;
            if left <= 0.0 {
                break;
            }
        }
        if t >= self.duration() {
            v = 0.0;
            a = 0.0;
        }
        Setpoint {
            position: p,
            velocity: v,
            acceleration: a,
        }
    }
}

/// A jerk-limited run-up from rest to constant velocity `v` (either sign): jerk `j`, then
/// constant acceleration (at most `a`, less if `v` is too small to reach it), then jerk
/// `−j`, then cruise for ever.
pub fn ramp_to_velocity(start: f64, v: f64, a: f64, j: f64, t: f64) -> Setpoint {
    let sign = v.signum();
    let speed = v.abs();
    let a = a.min((speed * j).sqrt());
    let t_jerk = a / j;
    let t_const = speed / a - t_jerk;
    let phases = [
        (t_jerk, sign * j),
        (t_const.max(0.0), 0.0),
        (t_jerk, -sign * j),
        (f64::INFINITY, 0.0),
    ];
    let (mut p, mut vel, mut acc) = (start, 0.0, 0.0);
    let mut left = t.max(0.0);
    for (d, jerk) in phases {
        let dt = left.min(d);
        p += vel * dt + acc * dt * dt / 2.0 + jerk * dt * dt * dt / 6.0;
        vel += acc * dt + jerk * dt * dt / 2.0;
        acc += jerk * dt;
        left -= dt;
        if left <= 0.0 {
            break;
        }
    }
    Setpoint {
        position: p,
        velocity: vel,
        acceleration: acc,
    }
}

/// A setpoint at rest at `position`.
pub fn rest(position: f64) -> Setpoint {
    Setpoint {
        position,
        velocity: 0.0,
        acceleration: 0.0,
    }
}

/// Simulation time of cycle `k` (the setpoint of cycle k belongs to the end of the cycle).
pub fn time_of(k: u32) -> f64 {
    f64::from(k) * PERIOD
}
