//! Configuration of a step/dir axis as it appears in the machine TOML (seconds, steps,
//! mm or degrees).

use serde::Deserialize;

use super::StepDirError;
use super::generator::StepTiming;

/// Where the step generator's ticks come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StepClock {
    /// Simulated time: a servo cycle's ticks are computed at once (tests, simulation).
    #[default]
    Virtual,
    /// Wall clock from an ordinary Linux thread (spinning between ticks): wake-up and
    /// preemption jitter limit the step rate.
    LinuxThread,
}

/// GPIO lines of a step/dir axis on a Linux board (GPIO character device).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GpioPins {
    /// GPIO chip device, e.g. `/dev/gpiochip0`.
    pub chip: String,
    /// Step output line.
    pub step: u32,
    /// Direction output line.
    pub dir: u32,
    /// Enable output line.
    #[serde(default)]
    pub enable: Option<u32>,
    /// The enable output is active low (most stepper drives).
    #[serde(default)]
    pub enable_active_low: bool,
    /// Negative limit switch input line.
    #[serde(default)]
    pub limit_negative: Option<u32>,
    /// Positive limit switch input line.
    #[serde(default)]
    pub limit_positive: Option<u32>,
    /// Home switch input line.
    #[serde(default)]
    pub home: Option<u32>,
    /// E-stop input line.
    #[serde(default)]
    pub estop: Option<u32>,
    /// Inputs are active low: an active switch (or an open e-stop chain wired that way)
    /// reads as a low level.
    #[serde(default)]
    pub inputs_active_low: bool,
}

/// A step/dir axis.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepDirConfig {
    /// Steps per mm or per degree (microstepping included). Negative reverses.
    pub steps_per_unit: f64,
    /// Highest step rate the drive accepts, steps/s.
    pub max_step_rate: f64,
    /// Step pulse width (high time, also the minimum low time), s.
    #[serde(default = "default_pulse")]
    pub pulse_width: f64,
    /// Direction setup time before a step edge, s.
    #[serde(default = "default_pulse")]
    pub dir_setup: f64,
    /// Direction hold time after a step edge, s.
    #[serde(default = "default_pulse")]
    pub dir_hold: f64,
    /// Step generator tick, s.
    #[serde(default = "default_tick")]
    pub tick: f64,
    /// Step pulses are low-going.
    #[serde(default)]
    pub step_active_low: bool,
    /// Positive direction is a low level.
    #[serde(default)]
    pub dir_invert: bool,
    /// Switch debounce time, s.
    #[serde(default = "default_debounce")]
    pub debounce: f64,
    /// Homing speed toward the home switch (signed: the direction), units/s. Without
    /// it (or without a home input) the axis is taken as referenced where it starts.
    #[serde(default)]
    pub homing_velocity: Option<f64>,
    /// Position assigned at the home switch, mm or degrees.
    #[serde(default)]
    pub home_position: f64,
    /// Clock of the step generator.
    #[serde(default)]
    pub clock: StepClock,
    /// Assumed worst wake-up/preemption jitter of a Linux thread, s.
    #[serde(default = "default_jitter")]
    pub linux_jitter: f64,
    /// GPIO lines (Linux boards, with the `linux-gpio` feature).
    #[serde(default)]
    pub pins: Option<GpioPins>,
}

fn default_pulse() -> f64 {
    5e-6
}
fn default_tick() -> f64 {
    25e-6
}
fn default_debounce() -> f64 {
    0.005
}
fn default_jitter() -> f64 {
    100e-6
}

/// Converts seconds to whole nanoseconds, refusing non-numbers, negatives and absurd values.
pub(crate) fn to_ns(name: &str, seconds: f64, allow_zero: bool) -> Result<u64, StepDirError> {
    let ok = seconds.is_finite()
        && seconds < 3600.0
        && (seconds > 0.0 || (allow_zero && seconds == 0.0));
    if !ok {
        return Err(StepDirError::Config(format!(
            "{name} must be a time {} 3600 s, not {seconds}",
            if allow_zero {
                "from 0 to"
            } else {
                "between 0 and"
            }
        )));
    }
    Ok((seconds * 1e9).round() as u64)
}

impl StepDirConfig {
    /// A configuration with the defaults for the optional values.
    pub fn new(steps_per_unit: f64, max_step_rate: f64) -> Self {
        Self {
            steps_per_unit,
            max_step_rate,
            pulse_width: default_pulse(),
            dir_setup: default_pulse(),
            dir_hold: default_pulse(),
            tick: default_tick(),
            step_active_low: false,
            dir_invert: false,
            debounce: default_debounce(),
            homing_velocity: None,
            home_position: 0.0,
            clock: StepClock::Virtual,
            linux_jitter: default_jitter(),
            pins: None,
        }
    }

    /// The generator timing; errors name the bad value.
    pub fn timing(&self) -> Result<StepTiming, StepDirError> {
        if !(self.max_step_rate.is_finite() && self.max_step_rate > 0.0) {
            return Err(StepDirError::Config(format!(
                "max_step_rate must be positive, not {}",
                self.max_step_rate
            )));
        }
        let timing = StepTiming {
            steps_per_unit: self.steps_per_unit,
            min_step_period_ns: to_ns("1 / max_step_rate", 1.0 / self.max_step_rate, false)?,
            pulse_width_ns: to_ns("pulse_width", self.pulse_width, false)?,
            dir_setup_ns: to_ns("dir_setup", self.dir_setup, true)?,
            dir_hold_ns: to_ns("dir_hold", self.dir_hold, true)?,
        };
        timing
            .validate()
            .map_err(|e| StepDirError::Config(e.to_string()))?;
        Ok(timing)
    }
}
