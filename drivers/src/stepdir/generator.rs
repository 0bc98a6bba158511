//! The step generator: turns a commanded position, interpolated linearly over each servo
//! period, into step and direction edges that respect the drive's timing (maximum step
//! rate, step pulse width, direction setup and hold times).
//!
//! Core-only code: no heap, no std, no floating-point functions beyond `core` operators.
//! Time is an integer count of nanoseconds from an arbitrary origin.

/// Timing of the step/dir interface, in nanoseconds and steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepTiming {
    /// Steps per mm (or per degree). Negative reverses the direction output.
    pub steps_per_unit: f64,
    /// Shortest time between two rising step edges, ns (1e9 / maximum step rate).
    pub min_step_period_ns: u64,
    /// Step pulse high time, and the shortest low time between pulses, ns.
    pub pulse_width_ns: u64,
    /// Time from a direction change to the next rising step edge, ns.
    pub dir_setup_ns: u64,
    /// Time from a falling step edge to a direction change, ns.
    pub dir_hold_ns: u64,
}

/// Why a [`StepTiming`] cannot work.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepTimingError {
    /// `steps_per_unit` is zero or not a number.
    Scale,
    /// The pulse (high + low) does not fit in the minimum step period.
    PulseTooLong,
    /// The minimum step period is zero.
    ZeroPeriod,
}

impl core::fmt::Display for StepTimingError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StepTimingError::Scale => f.write_str("steps_per_unit must be a non-zero number"),
            StepTimingError::PulseTooLong => f.write_str(
                "pulse width high plus low exceeds the minimum step period (max step rate too high)",
            ),
            StepTimingError::ZeroPeriod => f.write_str("the minimum step period is zero"),
        }
    }
}

impl StepTiming {
    /// Checks that the timing describes a usable interface.
    pub fn validate(&self) -> Result<(), StepTimingError> {
        if !(self.steps_per_unit.is_finite()
            && (self.steps_per_unit > 1e-12 || self.steps_per_unit < -1e-12))
        {
            return Err(StepTimingError::Scale);
        }
        if self.min_step_period_ns == 0 {
            return Err(StepTimingError::ZeroPeriod);
        }
        if self.pulse_width_ns.saturating_mul(2) > self.min_step_period_ns {
            return Err(StepTimingError::PulseTooLong);
        }
        Ok(())
    }
}

/// One change the generator asks of the pins.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepAction {
    /// Set the direction output (true: positive).
    Direction(bool),
    /// Rising step edge (the step counts from here).
    StepHigh,
    /// Falling step edge.
    StepLow,
}

/// Rounds to the nearest integer (halves away from zero) without `std`; saturates.
pub fn round_to_steps(x: f64) -> i64 {
    if x.is_nan() {
        return 0;
    }
    let t = x as i64;
    let frac = x - t as f64;
    if frac >= 0.5 {
        t.saturating_add(1)
    } else if frac <= -0.5 {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// The step generator state.
#[derive(Debug, Clone, PartialEq)]
pub struct StepGenerator {
    timing: StepTiming,
    /// Steps issued (rising edges), signed.
    position: i64,
    /// Interpolation segment, in steps (fractional) and ns.
    seg_from: f64,
    seg_to: f64,
    seg_t0: u64,
    seg_t1: u64,
    step_high: bool,
    forward: bool,
    last_rise: Option<u64>,
    last_fall: Option<u64>,
    dir_changed_at: Option<u64>,
}

impl StepGenerator {
    /// A generator at `position` steps, direction output positive (set at time 0).
    pub fn new(timing: StepTiming, position: i64) -> Self {
        Self {
            timing,
            position,
            seg_from: position as f64,
            seg_to: position as f64,
            seg_t0: 0,
            seg_t1: 0,
            step_high: false,
            forward: true,
            last_rise: None,
            last_fall: None,
            dir_changed_at: Some(0),
        }
    }

    /// The timing in use.
    pub fn timing(&self) -> &StepTiming {
        &self.timing
    }

    /// Steps issued so far (the open-loop position in steps).
    pub fn position(&self) -> i64 {
        self.position
    }

    /// The open-loop position in machine units.
    pub fn position_units(&self) -> f64 {
        self.position as f64 / self.timing.steps_per_unit
    }

    /// The direction output (true: positive).
    pub fn forward(&self) -> bool {
        self.forward
    }

    /// True while a step pulse is high.
    pub fn step_high(&self) -> bool {
        self.step_high
    }

    /// Redefines the present position (homing): no steps are issued.
    pub fn set_position_units(&mut self, position: f64) {
        self.position = round_to_steps(position * self.timing.steps_per_unit);
        self.seg_from = self.position as f64;
        self.seg_to = self.seg_from;
        self.seg_t1 = self.seg_t0;
    }

    /// The interpolated command at `now`, in (fractional) steps.
    pub fn command_steps(&self, now: u64) -> f64 {
        if now >= self.seg_t1 || self.seg_t1 <= self.seg_t0 {
            return self.seg_to;
        }
        let s = now.saturating_sub(self.seg_t0) as f64 / (self.seg_t1 - self.seg_t0) as f64;
        self.seg_from + (self.seg_to - self.seg_from) * s
    }

    /// Steps still to issue at `now` (positive: forward), before timing constraints.
    pub fn pending_steps(&self, now: u64) -> i64 {
        round_to_steps(self.command_steps(now)).saturating_sub(self.position)
    }

    /// Commands `position` (machine units) to be reached `duration_ns` after `now`,
    /// moving linearly from the command in force at `now`.
    pub fn set_target(&mut self, now: u64, position: f64, duration_ns: u64) {
        let to = position * self.timing.steps_per_unit;
        if !to.is_finite() {
            return;
        }
        self.seg_from = self.command_steps(now);
        self.seg_to = to;
        self.seg_t0 = now;
        self.seg_t1 = now.saturating_add(duration_ns);
    }

    /// Stops commanding motion: the command becomes the steps already issued.
    pub fn hold(&mut self, now: u64) {
        self.seg_from = self.position as f64;
        self.seg_to = self.seg_from;
        self.seg_t0 = now;
        self.seg_t1 = now;
    }

    /// The next pin change due at `now`, if any (call again until `None`).
    pub fn poll(&mut self, now: u64) -> Option<StepAction> {
        let t = &self.timing;
        if self.step_high {
            let rise = self.last_rise.unwrap_or(0);
            if now >= rise.saturating_add(t.pulse_width_ns) {
                self.step_high = false;
                self.last_fall = Some(now);
                return Some(StepAction::StepLow);
            }
            return None;
        }
        let wanted = round_to_steps(self.command_steps(now));
        if wanted == self.position {
            return None;
        }
        let forward = wanted > self.position;
        if forward != self.forward {
            let hold_ok = self
                .last_fall
                .is_none_or(|f| now >= f.saturating_add(t.dir_hold_ns));
            if !hold_ok {
                return None;
            }
            self.forward = forward;
            self.dir_changed_at = Some(now);
            return Some(StepAction::Direction(forward));
        }
        if let Some(d) = self.dir_changed_at
            && now < d.saturating_add(t.dir_setup_ns)
        {
            return None;
        }
        if let Some(r) = self.last_rise
            && now < r.saturating_add(t.min_step_period_ns)
        {
            return None;
        }
        if let Some(f) = self.last_fall
            && now < f.saturating_add(t.pulse_width_ns)
        {
            return None;
        }
        self.step_high = true;
        self.last_rise = Some(now);
        self.position += if forward { 1 } else { -1 };
        Some(StepAction::StepHigh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timing() -> StepTiming {
        StepTiming {
            steps_per_unit: 100.0,
            min_step_period_ns: 10_000,
            pulse_width_ns: 2_000,
            dir_setup_ns: 3_000,
            dir_hold_ns: 1_000,
        }
    }

    #[test]
    fn rounding_without_std() {
        assert_eq!(round_to_steps(2.5), 3);
        assert_eq!(round_to_steps(2.49), 2);
        assert_eq!(round_to_steps(-2.5), -3);
        assert_eq!(round_to_steps(-0.4), 0);
        assert_eq!(round_to_steps(f64::NAN), 0);
        assert_eq!(round_to_steps(1e300), i64::MAX);
    }

    #[test]
    fn validation_names_the_problem() {
        assert_eq!(timing().validate(), Ok(()));
        let t = StepTiming {
            pulse_width_ns: 6_000,
            ..timing()
        };
        assert_eq!(t.validate(), Err(StepTimingError::PulseTooLong));
        let t = StepTiming {
            steps_per_unit: 0.0,
            ..timing()
        };
        assert_eq!(t.validate(), Err(StepTimingError::Scale));
    }

    #[test]
    fn reversal_waits_for_pulse_end_hold_and_setup() {
        let mut g = StepGenerator::new(timing(), 0);
        g.set_target(0, 0.01, 0); // one step forward, immediately
        assert_eq!(g.poll(0), None, "direction setup from t = 0 not elapsed");
        assert_eq!(g.poll(3_000), Some(StepAction::StepHigh));
        g.set_target(3_000, -0.01, 0); // now one step back: two steps of reversal
        assert_eq!(g.poll(4_000), None, "pulse still high");
        assert_eq!(g.poll(5_000), Some(StepAction::StepLow));
        assert_eq!(g.poll(5_500), None, "direction hold after the falling edge");
        assert_eq!(g.poll(6_000), Some(StepAction::Direction(false)));
        assert_eq!(g.poll(8_999), None, "direction setup");
        // Setup done at 9000 but the step period (10 us from 3000) ends at 13000.
        assert_eq!(g.poll(9_000), None);
        assert_eq!(g.poll(13_000), Some(StepAction::StepHigh));
        assert_eq!(g.position(), 0);
    }
}
