//! Planner configuration: per-axis dynamic limits, servo period and path tolerance.

use klar_interp::AxisLetter;

/// Dynamic limits of one program axis (mm or degrees, per second).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisLimits {
    /// Largest speed, mm/s or °/s.
    pub max_velocity: f64,
    /// Largest acceleration, mm/s² or °/s².
    pub max_acceleration: f64,
    /// Largest jerk, mm/s³ or °/s³.
    pub max_jerk: f64,
}

/// Everything the planner needs to know about the machine.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannerConfig {
    /// Limits per program axis, indexed by [`AxisLetter::index`]; `None` means the machine
    /// has no such axis, and a move of it is refused.
    pub limits: [Option<AxisLimits>; 9],
    /// Servo period in seconds: the sampler emits one sample per period.
    pub period: f64,
    /// Default path tolerance in mm (for corner blending; the exact-stop planner keeps it
    /// only for later use).
    pub tolerance: f64,
}

/// Servo periods the planner works with, s (50 µs … 100 ms): a shorter period makes the
/// sample count of a move grow beyond what a control can compute in time, a longer one is no
/// longer a servo loop.
pub const PERIOD_RANGE: [f64; 2] = [50e-6, 0.1];

/// Axis speeds the planner works with, mm/s or °/s (0.01 … 100 000).
pub const VELOCITY_RANGE: [f64; 2] = [0.01, 1e5];

/// Axis accelerations the planner works with, mm/s² or °/s² (0.1 … 10 000 000).
pub const ACCELERATION_RANGE: [f64; 2] = [0.1, 1e7];

/// Axis jerks the planner works with, mm/s³ or °/s³ (1 … 10 000 000 000).
pub const JERK_RANGE: [f64; 2] = [1.0, 1e10];

/// Largest path tolerance the planner works with, mm.
pub const MAX_TOLERANCE: f64 = 10.0;

/// Whether `v` lies within `[lo, hi]` (false for NaN).
pub fn within(v: f64, [lo, hi]: [f64; 2]) -> bool {
    v >= lo && v <= hi
}

/// A configuration value the planner cannot work with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// A limit of an axis is not a number within its range.
    #[error("axis {axis}: {what} must lie in {} … {}, got {value}", range[0], range[1])]
    BadLimit {
        /// The axis.
        axis: AxisLetter,
        /// Which limit.
        what: &'static str,
        /// The value given.
        value: f64,
        /// The range it must lie in.
        range: [f64; 2],
    },
    /// The servo period is not within [`PERIOD_RANGE`].
    #[error("servo period must lie in {lo} … {hi} s, got {0}", lo = PERIOD_RANGE[0], hi = PERIOD_RANGE[1])]
    BadPeriod(f64),
    /// The path tolerance is negative, not finite or above [`MAX_TOLERANCE`].
    #[error("path tolerance must lie in 0 … {MAX_TOLERANCE} mm, got {0}")]
    BadTolerance(f64),
    /// The start pose has a value that is not finite.
    #[error("start position of axis {0} is not a finite number")]
    BadStart(AxisLetter),
    /// No axis is configured.
    #[error("no axis is configured")]
    NoAxes,
}

impl PlannerConfig {
    /// Checks every value; the planner refuses a configuration that fails here.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if !within(self.period, PERIOD_RANGE) {
            return Err(ConfigError::BadPeriod(self.period));
        }
        if !within(self.tolerance, [0.0, MAX_TOLERANCE]) {
            return Err(ConfigError::BadTolerance(self.tolerance));
        }
        if self.limits.iter().all(Option::is_none) {
            return Err(ConfigError::NoAxes);
        }
        for (axis, limits) in AxisLetter::ALL.into_iter().zip(&self.limits) {
            let Some(l) = limits else { continue };
            for (what, value, range) in [
                ("max_velocity", l.max_velocity, VELOCITY_RANGE),
                ("max_acceleration", l.max_acceleration, ACCELERATION_RANGE),
                ("max_jerk", l.max_jerk, JERK_RANGE),
            ] {
                if !within(value, range) {
                    return Err(ConfigError::BadLimit {
                        axis,
                        what,
                        value,
                        range,
                    });
                }
            }
        }
        Ok(())
    }
}
