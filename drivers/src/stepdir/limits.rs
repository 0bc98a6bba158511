//! Honest limits of step/dir: the step rate an axis needs against what the drive, the
//! generator tick and (on Linux) thread jitter allow; a configuration that cannot keep
//! up is refused with the reason.

use super::config::{StepClock, StepDirConfig};

/// Why a step/dir configuration cannot meet its axis or servo period.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepDirLimitError {
    /// The axis is faster than the drive's step rate allows.
    #[error(
        "max velocity {velocity} units/s needs {needed:.0} steps/s at {steps_per_unit} steps/unit, \
         but max_step_rate is {max_rate:.0} steps/s"
    )]
    StepRate {
        /// Axis velocity limit, units/s.
        velocity: f64,
        /// Steps per unit.
        steps_per_unit: f64,
        /// Steps/s needed.
        needed: f64,
        /// Configured maximum.
        max_rate: f64,
    },
    /// The generator tick is too coarse for the step rate: a pulse needs a high and a
    /// low tick.
    #[error(
        "a tick of {tick_us:.1} us allows at most {tick_rate:.0} steps/s (one high and one \
         low tick per step), below the {needed:.0} steps/s needed"
    )]
    TickTooCoarse {
        /// Tick, microseconds.
        tick_us: f64,
        /// Highest rate at this tick.
        tick_rate: f64,
        /// Steps/s needed.
        needed: f64,
    },
    /// The servo period is not a whole number of ticks.
    #[error("servo period {servo_us:.1} us is not a whole number of {tick_us:.1} us ticks")]
    PeriodNotMultiple {
        /// Servo period, microseconds.
        servo_us: f64,
        /// Tick, microseconds.
        tick_us: f64,
    },
    /// A Linux thread cannot keep a tick shorter than its wake-up jitter.
    #[error(
        "from a Linux thread, edges jitter by up to {jitter_us:.0} us, but the tick is \
         {tick_us:.1} us and the fastest step period is {period_us:.1} us: use a tick of at \
         least the jitter and step rates below {rate:.0} steps/s, or a step generator in \
         hardware (PRU, FPGA, microcontroller)"
    )]
    Jitter {
        /// Assumed jitter, microseconds.
        jitter_us: f64,
        /// Tick, microseconds.
        tick_us: f64,
        /// Shortest step period needed, microseconds.
        period_us: f64,
        /// Highest rate that tolerates the jitter.
        rate: f64,
    },
    /// The configuration itself is invalid.
    #[error("{0}")]
    Config(String),
}

/// What a step/dir axis will achieve, for reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepDirTiming {
    /// Step rate needed at the axis's maximum velocity, steps/s.
    pub needed_rate: f64,
    /// Ticks per servo period.
    pub ticks_per_period: u64,
    /// Worst edge timing error: one tick, plus the jitter on a Linux thread, s.
    pub edge_error: f64,
}

impl std::fmt::Display for StepDirTiming {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "step/dir: up to {:.0} steps/s, {} generator ticks per servo period, edges within \
             {:.1} us of their ideal time",
            self.needed_rate,
            self.ticks_per_period,
            self.edge_error * 1e6
        )
    }
}

/// Accepts a step/dir axis with velocity limit `max_velocity` (units/s) for a machine
/// with `servo_period` (s), or says why not.
pub fn check(
    config: &StepDirConfig,
    servo_period: f64,
    max_velocity: f64,
) -> Result<StepDirTiming, StepDirLimitError> {
    let timing = config
        .timing()
        .map_err(|e| StepDirLimitError::Config(e.to_string()))?;
    let tick_ns = super::config::to_ns("tick", config.tick, false)
        .map_err(|e| StepDirLimitError::Config(e.to_string()))?;
    let period_ns = super::config::to_ns("servo period", servo_period, false)
        .map_err(|e| StepDirLimitError::Config(e.to_string()))?;
    if !(max_velocity.is_finite() && max_velocity >= 0.0) {
        return Err(StepDirLimitError::Config(format!(
            "max velocity {max_velocity} is not a speed"
        )));
    }
    let needed = max_velocity * timing.steps_per_unit.abs();
    if needed > config.max_step_rate {
        return Err(StepDirLimitError::StepRate {
            velocity: max_velocity,
            steps_per_unit: timing.steps_per_unit,
            needed,
            max_rate: config.max_step_rate,
        });
    }
    let tick_rate = 1.0 / (2.0 * config.tick);
    if needed > tick_rate {
        return Err(StepDirLimitError::TickTooCoarse {
            tick_us: config.tick * 1e6,
            tick_rate,
            needed,
        });
    }
    if period_ns < tick_ns || period_ns % tick_ns != 0 {
        return Err(StepDirLimitError::PeriodNotMultiple {
            servo_us: servo_period * 1e6,
            tick_us: config.tick * 1e6,
        });
    }
    let mut edge_error = config.tick;
    if config.clock == StepClock::LinuxThread {
        let jitter = config.linux_jitter;
        if !(jitter.is_finite() && jitter >= 0.0) {
            return Err(StepDirLimitError::Config(format!(
                "linux_jitter {jitter} is not a time"
            )));
        }
        // Each edge may come `jitter` late: a step period must hold a pulse, its low time
        // and the jitter of both edges; the tick must not be shorter than the jitter.
        let rate = 1.0 / (2.0 * (config.pulse_width + jitter));
        let period = if needed > 0.0 {
            1.0 / needed
        } else {
            f64::INFINITY
        };
        if config.tick < jitter || needed > rate {
            return Err(StepDirLimitError::Jitter {
                jitter_us: jitter * 1e6,
                tick_us: config.tick * 1e6,
                period_us: period * 1e6,
                rate,
            });
        }
        edge_error += jitter;
    }
    Ok(StepDirTiming {
        needed_rate: needed,
        ticks_per_period: period_ns / tick_ns,
        edge_error,
    })
}
