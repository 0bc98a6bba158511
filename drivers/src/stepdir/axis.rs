//! A step/dir axis behind [`AxisBackend`]: the step channel, an enable output and the
//! switch inputs, advanced tick by tick through each servo period with an embedded-hal
//! delay between ticks (a no-op delay for simulated time, a spinning wall-clock delay on
//! a Linux thread).

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{InputPin, OutputPin};
use klar_motion::{AxisBackend, AxisFault, AxisFeedback, AxisState, BackendError, Setpoint};
use tracing::warn;

use super::StepDirError;
use super::channel::{ChannelCounters, Polarity, StepDirChannel};
use super::config::{StepDirConfig, to_ns};
use super::generator::StepGenerator;
use super::inputs::{SwitchInputs, SwitchState};

/// The output pins of a step/dir axis.
#[derive(Debug)]
pub struct StepDirOutputs<O: OutputPin> {
    /// Step output.
    pub step: O,
    /// Direction output.
    pub dir: O,
    /// Enable output, if wired.
    pub enable: Option<O>,
    /// The enable output is active low.
    pub enable_active_low: bool,
}

/// An open-loop step/dir axis.
#[derive(Debug)]
pub struct StepDirAxis<O: OutputPin, I: InputPin, D: DelayNs> {
    channel: StepDirChannel<O>,
    enable: Option<O>,
    enable_active_low: bool,
    switches: SwitchInputs<I>,
    delay: D,
    tick_ns: u64,
    period_ns: u64,
    now_ns: u64,
    state: AxisState,
    fault: Option<AxisFault>,
    homed: bool,
    homing_velocity: Option<f64>,
    home_position: f64,
    last_switches: SwitchState,
}

fn pin_error<E: core::fmt::Debug>(what: &str, e: E) -> BackendError {
    BackendError::Communication(format!("{what} pin: {e:?}"))
}

impl<O: OutputPin, I: InputPin, D: DelayNs> StepDirAxis<O, I, D> {
    /// Builds the axis at position 0 for a runtime with `servo_period` seconds; the
    /// enable output starts inactive.
    pub fn new(
        config: &StepDirConfig,
        servo_period: f64,
        outputs: StepDirOutputs<O>,
        switches: SwitchInputs<I>,
        delay: D,
    ) -> Result<Self, StepDirError> {
        let timing = config.timing()?;
        let tick_ns = to_ns("tick", config.tick, false)?;
        let period_ns = to_ns("servo period", servo_period, false)?;
        if period_ns < tick_ns {
            return Err(StepDirError::Config(format!(
                "servo period {servo_period} s is shorter than the tick {} s",
                config.tick
            )));
        }
        if let Some(v) = config.homing_velocity
            && !(v.is_finite() && v != 0.0)
        {
            return Err(StepDirError::Config(format!(
                "homing_velocity must be a non-zero speed, not {v}"
            )));
        }
        let polarity = Polarity {
            step_active_low: config.step_active_low,
            dir_invert: config.dir_invert,
        };
        let channel = StepDirChannel::new(
            StepGenerator::new(timing, 0),
            outputs.step,
            outputs.dir,
            polarity,
        )
        .map_err(|e| StepDirError::Pin(format!("step/dir: {e:?}")))?;
        let homing_possible = config.homing_velocity.is_some() && switches.home.is_some();
        let mut axis = Self {
            channel,
            enable: outputs.enable,
            enable_active_low: outputs.enable_active_low,
            switches,
            delay,
            tick_ns,
            period_ns,
            now_ns: 0,
            state: AxisState::Disabled,
            fault: None,
            homed: !homing_possible,
            homing_velocity: config.homing_velocity.filter(|_| homing_possible),
            home_position: config.home_position,
            last_switches: SwitchState::default(),
        };
        axis.set_enable(false)
            .map_err(|e| StepDirError::Pin(e.to_string()))?;
        Ok(axis)
    }

    /// Rising step edges and direction changes written so far.
    pub fn counters(&self) -> ChannelCounters {
        self.channel.counters()
    }

    /// Steps issued (open-loop position in steps).
    pub fn steps(&self) -> i64 {
        self.channel.generator().position()
    }

    /// The debounced switches at the end of the last cycle.
    pub fn switches(&self) -> SwitchState {
        self.last_switches
    }

    /// Time inside the axis, ns since it was built.
    pub fn now_ns(&self) -> u64 {
        self.now_ns
    }

    fn set_enable(&mut self, on: bool) -> Result<(), BackendError> {
        if let Some(pin) = self.enable.as_mut() {
            let high = on != self.enable_active_low;
            let r = if high { pin.set_high() } else { pin.set_low() };
            r.map_err(|e| pin_error("enable", e))?;
        }
        Ok(())
    }

    fn trip(&mut self, fault: AxisFault) {
        if self.fault.is_none() {
            warn!("step/dir axis stopped: {fault}");
        }
        let now = self.now_ns;
        self.channel.generator_mut().hold(now);
        self.fault = Some(fault);
        self.state = AxisState::Faulted;
    }

    /// One tick: switches, safety reactions, edges.
    fn tick(&mut self) -> Result<(), BackendError> {
        let now = self.now_ns;
        let sw = self
            .switches
            .sample(now)
            .map_err(|e| pin_error("switch", e))?;
        self.last_switches = sw;
        if sw.estop && self.state != AxisState::Faulted {
            self.trip(AxisFault::EStop);
            self.set_enable(false)?;
        }
        let generator = self.channel.generator();
        let pending = generator.pending_steps(now);
        let (moving_up, moving_down) = (pending > 0, pending < 0);
        let positive_scale = generator.timing().steps_per_unit > 0.0;
        let (up, down) = if positive_scale {
            (moving_up, moving_down)
        } else {
            (moving_down, moving_up)
        };
        if matches!(self.state, AxisState::Enabled | AxisState::Homing) {
            if sw.limit_positive && up {
                self.trip(AxisFault::LimitSwitch { positive: true });
            } else if sw.limit_negative && down {
                self.trip(AxisFault::LimitSwitch { positive: false });
            }
        }
        if self.state == AxisState::Homing && sw.home {
            let home = self.home_position;
            let g = self.channel.generator_mut();
            g.hold(now);
            g.set_position_units(home);
            self.homed = true;
            self.state = AxisState::Enabled;
        }
        self.channel
            .poll(now)
            .map_err(|e| pin_error("step/dir", e))?;
        Ok(())
    }
}

impl<O: OutputPin, I: InputPin, D: DelayNs> AxisBackend for StepDirAxis<O, I, D> {
    fn axis_count(&self) -> usize {
        1
    }

    fn enable(&mut self) -> Result<(), BackendError> {
        if self.state == AxisState::Faulted {
            return Err(BackendError::InvalidState(
                "the axis is faulted: reset the fault first".into(),
            ));
        }
        let now = self.now_ns;
        self.channel.generator_mut().hold(now);
        self.set_enable(true)?;
        if self.state == AxisState::Disabled {
            self.state = AxisState::Enabled;
        }
        Ok(())
    }

    fn disable(&mut self) -> Result<(), BackendError> {
        let now = self.now_ns;
        self.channel.generator_mut().hold(now);
        self.set_enable(false)?;
        if self.state != AxisState::Faulted {
            self.state = AxisState::Disabled;
        }
        Ok(())
    }

    fn start_homing(&mut self, axis: usize) -> Result<(), BackendError> {
        if axis != 0 {
            return Err(BackendError::NoSuchAxis(axis));
        }
        if self.homing_velocity.is_none() {
            return Err(BackendError::InvalidState(
                "homing needs a home input and homing_velocity".into(),
            ));
        }
        if self.state != AxisState::Enabled {
            return Err(BackendError::InvalidState(format!(
                "homing needs an enabled axis, it is {:?}",
                self.state
            )));
        }
        self.homed = false;
        self.state = AxisState::Homing;
        Ok(())
    }

    fn reset_fault(&mut self, axis: usize) -> Result<(), BackendError> {
        if axis != 0 {
            return Err(BackendError::NoSuchAxis(axis));
        }
        if self.last_switches.estop {
            return Err(BackendError::InvalidState(
                "the e-stop is still active".into(),
            ));
        }
        if self.state == AxisState::Faulted {
            self.fault = None;
            self.state = AxisState::Disabled;
            self.set_enable(false)?;
        }
        Ok(())
    }

    fn cycle(
        &mut self,
        _t: f64,
        setpoints: &[Setpoint],
        feedback: &mut [AxisFeedback],
    ) -> Result<(), BackendError> {
        let lengths = (setpoints.len(), feedback.len());
        let (Some(sp), Some(fb), (1, 1)) = (setpoints.first(), feedback.first_mut(), lengths)
        else {
            return Err(BackendError::AxisCount {
                expected: 1,
                got: if lengths.0 == 1 { lengths.1 } else { lengths.0 },
            });
        };
        let now = self.now_ns;
        match self.state {
            AxisState::Enabled if sp.position.is_finite() => {
                self.channel
                    .generator_mut()
                    .set_target(now, sp.position, self.period_ns);
            }
            AxisState::Homing => {
                let v = self.homing_velocity.unwrap_or(0.0);
                let g = self.channel.generator_mut();
                let from = g.command_steps(now) / g.timing().steps_per_unit;
                let step = v * self.period_ns as f64 * 1e-9;
                g.set_target(now, from + step, self.period_ns);
            }
            _ => {}
        }
        let ticks = self.period_ns / self.tick_ns;
        for _ in 0..ticks {
            self.tick()?;
            self.delay
                .delay_ns(u32::try_from(self.tick_ns).unwrap_or(u32::MAX));
            self.now_ns = self.now_ns.saturating_add(self.tick_ns);
        }
        let position = self.channel.generator().position_units();
        *fb = AxisFeedback {
            position,
            following_error: sp.position - position,
            state: self.state,
            homed: self.homed,
            fault: self.fault.clone(),
        };
        Ok(())
    }
}

/// A wall-clock [`DelayNs`] that spins to absolute deadlines, so ticks do not drift:
/// each call waits until the previous deadline plus `ns`. Preemption still adds jitter
/// (see [`super::limits`]).
#[derive(Debug, Clone)]
pub struct SpinDelay {
    next: Option<std::time::Instant>,
}

impl SpinDelay {
    /// A delay whose first deadline counts from its first use.
    pub fn new() -> Self {
        Self { next: None }
    }
}

impl Default for SpinDelay {
    fn default() -> Self {
        Self::new()
    }
}

impl DelayNs for SpinDelay {
    fn delay_ns(&mut self, ns: u32) {
        let now = std::time::Instant::now();
        let base = self.next.unwrap_or(now);
        let deadline = base + std::time::Duration::from_nanos(u64::from(ns));
        // After a long stall, restart from now instead of racing to catch up.
        let deadline = if deadline + std::time::Duration::from_millis(5) < now {
            now
        } else {
            deadline
        };
        while std::time::Instant::now() < deadline {
            std::hint::spin_loop();
        }
        self.next = Some(deadline);
    }
}
