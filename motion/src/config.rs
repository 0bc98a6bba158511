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

/// A configuration value the planner cannot work with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// A limit of an axis is not a positive finite number.
    #[error("axis {axis}: {what} must be a positive finite number, got {value}")]
    BadLimit {
        /// The axis.
        axis: AxisLetter,
        /// Which limit.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// The servo period is not a positive finite number.
    #[error("servo period must be a positive finite number of seconds, got {0}")]
    BadPeriod(f64),
    /// The path tolerance is negative or not finite.
    #[error("path tolerance must be a finite number >= 0 mm, got {0}")]
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
        if !(self.period.is_finite() && self.period > 0.0) {
            return Err(ConfigError::BadPeriod(self.period));
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return Err(ConfigError::BadTolerance(self.tolerance));
        }
        if self.limits.iter().all(Option::is_none) {
            return Err(ConfigError::NoAxes);
        }
        for (axis, limits) in AxisLetter::ALL.into_iter().zip(&self.limits) {
            let Some(l) = limits else { continue };
            for (what, value) in [
                ("max_velocity", l.max_velocity),
                ("max_acceleration", l.max_acceleration),
                ("max_jerk", l.max_jerk),
            ] {
                if !(value.is_finite() && value > 0.0) {
                    return Err(ConfigError::BadLimit { axis, what, value });
                }
            }
        }
        Ok(())
    }
}
