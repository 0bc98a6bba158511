//! The simulated spindle motor behind a VFD: speed ramps at a fixed acceleration toward
//! the commanded speed, so waiting for at-speed takes real (simulated) time.
//!
//! The motor also carries an incremental encoder with an index, and feels the cut
//! ([`LoadDip`] with `load_droop` and `load_time_constant`): under a chip of cross-section
//! `A` mm² its speed sinks below the ramped speed by `load_droop · A` (at most half).
//! The shaft angle is the integral of that speed; the encoder reports it in whole counts.

use klar_motion::{AxisFault, BackendError, SpindleBackend, SpindleFeedback};

use crate::load::LoadDip;

/// Parameters of a simulated spindle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpindleParams {
    /// Highest speed, rpm.
    pub max_rpm: f64,
    /// Ramp rate, rpm per second (the VFD's acceleration/deceleration time over the speed
    /// range).
    pub acceleration: f64,
    /// At-speed window as a fraction of the command.
    pub at_speed_fraction: f64,
    /// Smallest at-speed window, rpm.
    pub at_speed_min_rpm: f64,
    /// Encoder counts per revolution (the resolution of the measured angle).
    pub encoder_counts: u32,
    /// Fraction of the speed lost per mm² of chip cross-section under cut.
    pub load_droop: f64,
    /// Time constant of the speed dip under load, s.
    pub load_time_constant: f64,
}

impl Default for SpindleParams {
    fn default() -> Self {
        Self {
            max_rpm: 24_000.0,
            acceleration: 8_000.0,
            at_speed_fraction: 0.02,
            at_speed_min_rpm: 10.0,
            encoder_counts: 4096,
            load_droop: 0.0,
            load_time_constant: 0.05,
        }
    }
}

/// A spindle motor with a linear speed ramp. Time advances only through
/// [`SpindleModel::advance`].
#[derive(Debug, Clone, PartialEq)]
pub struct SpindleModel {
    params: SpindleParams,
    commanded: f64,
    /// The ramped speed without load, rpm.
    rpm: f64,
    fault: Option<u16>,
    /// The shaft angle, degrees, unwrapped (0 at the index).
    angle: f64,
    /// The speed dip under cut.
    load: LoadDip,
}

impl SpindleModel {
    /// A stopped spindle.
    pub fn new(params: SpindleParams) -> Self {
        Self {
            params,
            commanded: 0.0,
            rpm: 0.0,
            fault: None,
            angle: 0.0,
            load: LoadDip::new(params.load_droop, params.load_time_constant),
        }
    }

    /// The parameters.
    pub fn params(&self) -> &SpindleParams {
        &self.params
    }

    /// Sets the target speed (signed rpm), clamped to ±`max_rpm`; non-numbers stop.
    pub fn set_command(&mut self, rpm: f64) {
        self.commanded = if rpm.is_finite() {
            rpm.clamp(-self.params.max_rpm, self.params.max_rpm)
        } else {
            0.0
        };
    }

    /// The target speed in force (0 while faulted).
    pub fn command(&self) -> f64 {
        if self.fault.is_some() {
            0.0
        } else {
            self.commanded
        }
    }

    /// The present speed, rpm, signed (under load: below the ramped speed by the dip).
    pub fn rpm(&self) -> f64 {
        self.rpm * self.load.factor()
    }

    /// The true shaft angle, degrees, unwrapped.
    pub fn angle(&self) -> f64 {
        self.angle
    }

    /// The angle the encoder reports: the shaft angle in whole counts (toward −∞), degrees.
    pub fn encoder_angle(&self) -> f64 {
        let counts = f64::from(self.params.encoder_counts.max(1));
        (self.angle / 360.0 * counts).floor() * 360.0 / counts
    }

    /// Sets the chip cross-section under cut, mm² (0 out of the cut; non-numbers and
    /// negative values count as 0).
    pub fn set_load(&mut self, section_mm2: f64) {
        self.load.set_load(section_mm2);
    }

    /// The active fault code.
    pub fn fault(&self) -> Option<u16> {
        self.fault
    }

    /// Faults the VFD with `code`: it ramps down to a stop and ignores commands until
    /// [`SpindleModel::reset_fault`].
    pub fn inject_fault(&mut self, code: u16) {
        self.fault = Some(code);
    }

    /// Clears the fault; the command is forgotten (the spindle stays stopped).
    pub fn reset_fault(&mut self) {
        if self.fault.take().is_some() {
            self.commanded = 0.0;
        }
    }

    /// True when the speed is within the at-speed window of the command.
    pub fn at_speed(&self) -> bool {
        let target = self.command();
        let window =
            (target.abs() * self.params.at_speed_fraction).max(self.params.at_speed_min_rpm);
        self.fault.is_none() && (self.rpm - target).abs() <= window
    }

    /// Advances the ramp by `dt` seconds.
    pub fn advance(&mut self, dt: f64) {
        if !(dt.is_finite() && dt > 0.0) {
            return;
        }
        let target = self.command();
        let step = self.params.acceleration * dt;
        let diff = target - self.rpm;
        let before = self.rpm();
        self.rpm = if diff.abs() <= step {
            target
        } else {
            self.rpm + step.copysign(diff)
        };
        self.load.advance(dt);
        // rpm → degrees per second: · 360 / 60; the mean speed over the step.
        self.angle += 0.5 * (before + self.rpm()) * 6.0 * dt;
    }
}

/// A simulated spindle directly behind [`SpindleBackend`] (no bus), for the built-in
/// machines. Time comes from the `t` of each cycle.
#[derive(Debug, Clone)]
pub struct SimSpindle {
    model: SpindleModel,
    last_t: Option<f64>,
}

impl SimSpindle {
    /// A stopped spindle.
    pub fn new(params: SpindleParams) -> Self {
        Self {
            model: SpindleModel::new(params),
            last_t: None,
        }
    }

    /// The motor model (for fault injection in tests).
    pub fn model_mut(&mut self) -> &mut SpindleModel {
        &mut self.model
    }
}

impl SpindleBackend for SimSpindle {
    fn command(&mut self, rpm: f64) -> Result<(), BackendError> {
        if !rpm.is_finite() {
            return Err(BackendError::InvalidState(format!(
                "spindle speed {rpm} is not a number"
            )));
        }
        if rpm.abs() > self.model.params.max_rpm {
            return Err(BackendError::InvalidState(format!(
                "spindle speed {rpm} rpm beyond max_rpm {}",
                self.model.params.max_rpm
            )));
        }
        self.model.set_command(rpm);
        Ok(())
    }

    fn set_load(&mut self, section_mm2: f64) {
        self.model.set_load(section_mm2);
    }

    fn cycle(&mut self, t: f64) -> Result<SpindleFeedback, BackendError> {
        if let Some(last) = self.last_t {
            self.model.advance(t - last);
        }
        self.last_t = Some(t);
        Ok(SpindleFeedback {
            position: Some(self.model.encoder_angle()),
            rpm: self.model.rpm(),
            at_speed: self.model.at_speed(),
            fault: self.model.fault().map(|code| AxisFault::Drive {
                code: u32::from(code),
                text: format!("simulated VFD fault code {code}"),
            }),
        })
    }
}
