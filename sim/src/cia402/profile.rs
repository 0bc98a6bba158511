//! The simulated drive's own motion generators: the profile position move (trapezoidal
//! velocity towards a target position) and the profile velocity ramp (constant
//! acceleration towards a target velocity).

/// The state of a profile position move (drive coordinates, units and units/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Profile {
    pub(crate) target: f64,
    pub(crate) position: f64,
    pub(crate) velocity: f64,
}

impl Profile {
    /// One cycle of `dt` seconds: accelerate at `accel` towards `v_max`, and brake in time
    /// to stop at the target (v ≤ √(2·a·distance)); `resolution` is one count in units (the
    /// move snaps to the target once within half of it at a crawl).
    pub(crate) fn step(&mut self, v_max: f64, accel: f64, resolution: f64, dt: f64) {
        let to_go = self.target - self.position;
        let stop_speed = (2.0 * accel * to_go.abs()).sqrt();
        let wanted = to_go.signum() * v_max.min(stop_speed);
        let dv = (wanted - self.velocity).clamp(-accel * dt, accel * dt);
        let v = self.velocity + dv;
        self.position += 0.5 * (self.velocity + v) * dt;
        self.velocity = v;
        let remaining = self.target - self.position;
        if remaining.abs() <= 0.5 * resolution && v.abs() <= accel * dt
            || remaining.signum() != to_go.signum() && to_go != 0.0
        {
            self.position = self.target;
            self.velocity = 0.0;
        }
    }
}

/// The profile velocity ramp: the drive's velocity demand moving towards the target
/// velocity at the profile acceleration while the speed grows, and at the profile
/// deceleration while it shrinks (including through zero on a reversal).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct VelocityRamp {
    /// Velocity demand, units/s.
    pub(crate) velocity: f64,
    /// Position reference integrated from the demand, units.
    pub(crate) position: f64,
}

impl VelocityRamp {
    /// One cycle of `dt` seconds towards `target` (units/s) with `accel` and `decel`
    /// (units/s², positive); returns true once the demand equals the target.
    pub(crate) fn step(&mut self, target: f64, accel: f64, decel: f64, dt: f64) -> bool {
        let v = self.velocity;
        let speeding_up = v * target >= 0.0 && target.abs() > v.abs();
        let rate = if speeding_up { accel } else { decel };
        // Slowing through zero towards the opposite sign: decelerate to zero first.
        let goal = if v * target < 0.0 { 0.0 } else { target };
        let next = v + (goal - v).clamp(-rate * dt, rate * dt);
        self.position += 0.5 * (v + next) * dt;
        self.velocity = next;
        next == target
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_takes_the_time_the_acceleration_implies() {
        // 0 → 100 units/s at 1000 units/s² takes 0.1 s: 100 cycles of 1 ms, covering
        // v²/(2a) = 5 units.
        let mut r = VelocityRamp {
            velocity: 0.0,
            position: 0.0,
        };
        let mut cycles = 0;
        while !r.step(100.0, 1000.0, 500.0, 0.001) {
            cycles += 1;
            assert!(cycles < 1000);
        }
        assert_eq!(cycles + 1, 100);
        assert!((r.position - 5.0).abs() < 1e-9, "{}", r.position);
        // Down to -50 decelerates at 500 all the way: 150 units/s at 500 units/s² = 0.3 s.
        let mut cycles = 0;
        while !r.step(-50.0, 1000.0, 500.0, 0.001) {
            cycles += 1;
            assert!(cycles < 1000);
        }
        // Down to zero at the deceleration (0.2 s), then up to -50 at the acceleration
        // (0.05 s).
        assert_eq!(cycles + 1, 250);
    }
}
