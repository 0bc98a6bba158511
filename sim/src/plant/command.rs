//! The drive's internal command generator: fine interpolation of servo-cycle setpoints
//! and the velocity profile of the homing moves, both sampled at the drive's substep rate.

use klar_motion::Setpoint;

/// Quintic Hermite interpolation between two setpoints one servo cycle apart.
///
/// The polynomial matches position, velocity and acceleration at both ends, so it
/// reproduces every polynomial path of degree ≤ 5 (in particular the cubic pieces of a
/// jerk-limited profile) exactly between the servo samples. Evaluation works in the
/// normalised time `s = τ / T ∈ [0, 1]` to keep the coefficients well scaled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct QuinticSegment {
    /// Coefficients of `s⁰ … s⁵` in position units.
    coefficients: [f64; 6],
    /// Duration `T` of the segment in seconds (> 0).
    duration: f64,
}

impl QuinticSegment {
    /// The segment from `start` (τ = 0) to `end` (τ = `duration`); `duration` must be > 0.
    pub(crate) fn new(start: Setpoint, end: Setpoint, duration: f64) -> Self {
        let t = duration;
        let (p0, v0, a0) = (
            start.position,
            start.velocity * t,
            start.acceleration * t * t,
        );
        let (p1, v1, a1) = (end.position, end.velocity * t, end.acceleration * t * t);
        let h = p1 - p0;
        Self {
            coefficients: [
                p0,
                v0,
                0.5 * a0,
                0.5 * (20.0 * h - (8.0 * v1 + 12.0 * v0) - (3.0 * a0 - a1)),
                0.5 * (-30.0 * h + (14.0 * v1 + 16.0 * v0) + (3.0 * a0 - 2.0 * a1)),
                0.5 * (12.0 * h - 6.0 * (v1 + v0) + (a1 - a0)),
            ],
            duration: t,
        }
    }

    /// Position at time `tau` seconds after the segment start.
    pub(crate) fn position(&self, tau: f64) -> f64 {
        let s = tau / self.duration;
        let c = &self.coefficients;
        c[0] + s * (c[1] + s * (c[2] + s * (c[3] + s * (c[4] + s * c[5]))))
    }

    /// Velocity at time `tau`.
    pub(crate) fn velocity(&self, tau: f64) -> f64 {
        let s = tau / self.duration;
        let c = &self.coefficients;
        (c[1] + s * (2.0 * c[2] + s * (3.0 * c[3] + s * (4.0 * c[4] + s * 5.0 * c[5]))))
            / self.duration
    }

    /// Acceleration at time `tau`.
    pub(crate) fn acceleration(&self, tau: f64) -> f64 {
        let s = tau / self.duration;
        let c = &self.coefficients;
        (2.0 * c[2] + s * (6.0 * c[3] + s * (12.0 * c[4] + s * 20.0 * c[5])))
            / (self.duration * self.duration)
    }
}

/// Where a homing move is heading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum HomingGoal {
    /// Searching for the home switch edge at constant speed in this direction (±1).
    Search {
        /// +1 or −1.
        direction: f64,
    },
    /// Returning to the reference position after the edge was latched.
    Return {
        /// Target in (referenced) measured coordinates.
        target: f64,
    },
}

/// A velocity- and acceleration-limited command profile for the homing moves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct HomingProfile {
    /// The current goal.
    pub(crate) goal: HomingGoal,
    /// Commanded position (measured coordinates).
    pub(crate) position: f64,
    /// Commanded velocity.
    pub(crate) velocity: f64,
    /// Speed limit.
    max_velocity: f64,
    /// Acceleration limit.
    max_acceleration: f64,
}

impl HomingProfile {
    /// A profile at rest at `position` searching in `direction`.
    pub(crate) fn search(
        position: f64,
        direction: f64,
        max_velocity: f64,
        max_acceleration: f64,
    ) -> Self {
        Self {
            goal: HomingGoal::Search { direction },
            position,
            velocity: 0.0,
            max_velocity,
            max_acceleration,
        }
    }

    /// True once a return move has reached its target and stopped.
    pub(crate) fn finished(&self) -> bool {
        matches!(self.goal, HomingGoal::Return { target } if self.position == target && self.velocity == 0.0)
    }

    /// Advances the profile by `h` seconds and returns the acceleration applied during the
    /// interval (for feed-forward). The speed follows the braking curve `√(2·a·d)` toward a
    /// return target so that it arrives without overshoot.
    pub(crate) fn advance(&mut self, h: f64) -> f64 {
        let a_max = self.max_acceleration;
        let desired = match self.goal {
            HomingGoal::Search { direction } => direction * self.max_velocity,
            HomingGoal::Return { target } => {
                let d = target - self.position;
                let remaining = d.abs();
                if remaining <= 0.5 * a_max * h * h && self.velocity.abs() <= a_max * h {
                    self.position = target;
                    self.velocity = 0.0;
                    return 0.0;
                }
                // Speed from which braking at a_max stops exactly at the target, evaluated
                // one half interval ahead so the discrete profile does not overshoot.
                let braking = (2.0 * a_max * remaining).sqrt() - 0.5 * a_max * h;
                d.signum() * self.max_velocity.min(braking.max(0.0))
            }
        };
        let a = ((desired - self.velocity) / h).clamp(-a_max, a_max);
        self.position += self.velocity * h + 0.5 * a * h * h;
        self.velocity += a * h;
        a
    }

    /// Moves the whole profile by `delta` (used when the reference changes).
    pub(crate) fn shift(&mut self, delta: f64) {
        self.position += delta;
        if let HomingGoal::Return { target } = &mut self.goal {
            *target += delta;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An arbitrary quintic p(τ) = Σ kᵢ τⁱ with its exact derivatives.
    fn quintic(k: [f64; 6], t: f64) -> Setpoint {
        let p = k.iter().rev().fold(0.0, |acc, c| acc * t + c);
        let v = k[1]
            + 2.0 * k[2] * t
            + 3.0 * k[3] * t * t
            + 4.0 * k[4] * t.powi(3)
            + 5.0 * k[5] * t.powi(4);
        let a = 2.0 * k[2] + 6.0 * k[3] * t + 12.0 * k[4] * t * t + 20.0 * k[5] * t.powi(3);
        Setpoint {
            position: p,
            velocity: v,
            acceleration: a,
        }
    }

    #[test]
    fn quintic_segment_reproduces_a_quintic_path() {
        let k = [12.5, -40.0, 900.0, 3.0e4, -2.0e6, 5.0e7];
        let t0 = 0.013;
        let dt = 0.002;
        let seg = QuinticSegment::new(quintic(k, t0), quintic(k, t0 + dt), dt);
        for i in 0..=20 {
            let tau = dt * f64::from(i) / 20.0;
            let exact = quintic(k, t0 + tau);
            assert!((seg.position(tau) - exact.position).abs() < 1e-10);
            assert!((seg.velocity(tau) - exact.velocity).abs() < 1e-7);
            assert!((seg.acceleration(tau) - exact.acceleration).abs() < 1e-3);
        }
    }

    #[test]
    fn homing_return_reaches_the_target_without_overshoot() {
        let mut profile = HomingProfile::search(0.0, 1.0, 10.0, 500.0);
        for _ in 0..2000 {
            profile.advance(1e-4);
        }
        // Accelerated to 10 mm/s in 0.02 s, then cruised: 0.2 s total.
        assert!((profile.velocity - 10.0).abs() < 1e-9);
        let expected = 10.0 * 0.2 - 0.5 * 10.0 * 0.02;
        assert!((profile.position - expected).abs() < 1e-9);
        let target = 0.5;
        profile.goal = HomingGoal::Return { target };
        let mut furthest: f64 = f64::NEG_INFINITY;
        let mut steps = 0;
        while !profile.finished() && steps < 100_000 {
            profile.advance(1e-4);
            furthest = furthest.max(profile.position);
            steps += 1;
        }
        assert!(profile.finished());
        assert_eq!(profile.position, target);
        // Braking from 10 mm/s at 500 mm/s² needs 0.1 mm: it turns at ≈ expected + 0.1.
        assert!(furthest <= expected + 0.1 + 1e-6, "overshoot {furthest}");
        assert!(furthest >= expected + 0.1 - 1e-3);
    }
}
