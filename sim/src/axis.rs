//! Simulated axes behind the axis boundary trait: [`SimBackend`] runs one [`ServoPlant`]
//! per axis, advancing each by the configured servo period every cycle.

use crate::faults::{EncoderNoise, FaultSchedule, InjectedFault, ScheduledFault};
use crate::plant::{PlantError, ServoPlant, SimAxisParams, SimParamsError};
use klar_motion::{AxisBackend, AxisFault, AxisFeedback, BackendError, Setpoint};

/// Why a [`SimBackend`] cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimBackendError {
    /// The servo period is not a finite positive number of seconds.
    #[error("servo period must be finite and > 0 s, got {0}")]
    InvalidPeriod(f64),
    /// The start position of an axis is not finite.
    #[error("axis {axis}: start position {position} is not finite")]
    InvalidStart {
        /// Index of the axis.
        axis: usize,
        /// The position given.
        position: f64,
    },
    /// The parameters of an axis are invalid.
    #[error("axis {axis}: {source}")]
    InvalidParams {
        /// Index of the axis.
        axis: usize,
        /// What is wrong.
        source: SimParamsError,
    },
}

/// Simulated servo axes as an [`AxisBackend`]: every [`AxisBackend::cycle`] advances each
/// plant by one servo period.
#[derive(Debug, Clone)]
pub struct SimBackend {
    /// One plant per axis, in the runtime's axis order.
    plants: Vec<ServoPlant>,
    /// Servo period in seconds.
    servo_period: f64,
    /// A configuration error found by [`SimBackend::new`]: every request then fails with it.
    config_error: Option<SimBackendError>,
    /// Injected faults waiting for their time.
    schedule: FaultSchedule,
    /// Per axis: the feedback frozen when its link was lost (`None` while the link is up).
    link_lost: Vec<Option<AxisFeedback>>,
}

impl SimBackend {
    /// Axes from `(parameters, start position)` pairs, advanced by `servo_period` seconds per
    /// cycle. Never panics: with an invalid servo period every request fails with
    /// [`BackendError::InvalidState`], an axis with invalid parameters starts Faulted (see
    /// [`ServoPlant::new`]). [`SimBackend::try_new`] reports these problems up front.
    pub fn new(axes: Vec<(SimAxisParams, f64)>, servo_period: f64) -> Self {
        let config_error = (!(servo_period.is_finite() && servo_period > 0.0))
            .then_some(SimBackendError::InvalidPeriod(servo_period));
        if let Some(e) = &config_error {
            tracing::error!("simulated backend: {e}");
        }
        let plants: Vec<ServoPlant> = axes
            .into_iter()
            .map(|(params, start)| ServoPlant::new(params, start))
            .collect();
        Self {
            link_lost: vec![None; plants.len()],
            plants,
            servo_period,
            config_error,
            schedule: FaultSchedule::default(),
        }
    }

    /// Like [`SimBackend::new`], but refuses an invalid period, start position or
    /// parameter set.
    pub fn try_new(
        axes: Vec<(SimAxisParams, f64)>,
        servo_period: f64,
    ) -> Result<Self, SimBackendError> {
        if !(servo_period.is_finite() && servo_period > 0.0) {
            return Err(SimBackendError::InvalidPeriod(servo_period));
        }
        for (axis, (params, position)) in axes.iter().enumerate() {
            if !position.is_finite() {
                return Err(SimBackendError::InvalidStart {
                    axis,
                    position: *position,
                });
            }
            params
                .validate()
                .map_err(|source| SimBackendError::InvalidParams { axis, source })?;
        }
        Ok(Self::new(axes, servo_period))
    }

    /// The servo period in seconds.
    pub fn servo_period(&self) -> f64 {
        self.servo_period
    }

    /// All plants, in axis order.
    pub fn plants(&self) -> &[ServoPlant] {
        &self.plants
    }

    /// The plant of one axis.
    pub fn plant(&self, axis: usize) -> Option<&ServoPlant> {
        self.plants.get(axis)
    }

    /// The plant of one axis, for fault injection and inspection in tests.
    pub fn plant_mut(&mut self, axis: usize) -> Option<&mut ServoPlant> {
        self.plants.get_mut(axis)
    }

    /// Sets the shared e-stop input of all axes (see [`ServoPlant::set_estop`]).
    pub fn set_estop(&mut self, active: bool) {
        for plant in &mut self.plants {
            plant.set_estop(active);
        }
    }

    /// Faults one axis with `fault` (see [`ServoPlant::inject_fault`]).
    pub fn inject_fault(&mut self, axis: usize, fault: AxisFault) -> Result<(), BackendError> {
        self.plant_checked(axis)?.inject_fault(fault);
        Ok(())
    }

    /// Replaces the schedule of injected faults; each strikes at the start of the first cycle
    /// whose time reaches it.
    pub fn set_fault_schedule(&mut self, schedule: FaultSchedule) {
        self.schedule = schedule;
    }

    /// Injects one fault now (see [`InjectedFault`] for what each does).
    pub fn inject(&mut self, axis: usize, fault: &InjectedFault) -> Result<(), BackendError> {
        if let InjectedFault::EStop = fault {
            self.set_estop(true);
            return Ok(());
        }
        let last = self.plant_checked(axis)?.feedback();
        let plant = self.plant_checked(axis)?;
        match fault {
            InjectedFault::Drive { code } => {
                plant.inject_fault(InjectedFault::drive_fault(*code));
            }
            InjectedFault::CommunicationLost => {
                plant.inject_fault(AxisFault::CommunicationLost);
                if let Some(slot) = self.link_lost.get_mut(axis) {
                    *slot = Some(AxisFeedback {
                        fault: Some(AxisFault::CommunicationLost),
                        ..last
                    });
                }
            }
            InjectedFault::EncoderNoise { amplitude } => {
                let seed = 0x5EED_0000 + axis as u64;
                plant.set_encoder_noise(Some(EncoderNoise::new(*amplitude, seed)));
            }
            InjectedFault::Stuck => plant.set_stuck(true),
            InjectedFault::LimitSwitch => {
                let positive = plant.actual_velocity() >= 0.0;
                plant.inject_fault(AxisFault::LimitSwitch { positive });
            }
            InjectedFault::EStop => {}
        }
        tracing::warn!(axis, fault = fault.name(), "sim: fault injected");
        Ok(())
    }

    /// Removes the causes of injected faults on one axis (frees a jammed slide, quiets the
    /// encoder, restores the link) so that [`AxisBackend::reset_fault`] can clear the fault.
    /// The e-stop is released separately with [`SimBackend::set_estop`].
    pub fn repair(&mut self, axis: usize) -> Result<(), BackendError> {
        let plant = self.plant_checked(axis)?;
        plant.set_stuck(false);
        plant.set_encoder_noise(None);
        if let Some(slot) = self.link_lost.get_mut(axis) {
            *slot = None;
        }
        Ok(())
    }

    /// True while the link to `axis` is lost.
    pub fn link_lost(&self, axis: usize) -> bool {
        self.link_lost.get(axis).is_some_and(Option::is_some)
    }

    /// The configuration error as a backend error, if any.
    fn check_config(&self) -> Result<(), BackendError> {
        match &self.config_error {
            Some(e) => Err(BackendError::InvalidState(e.to_string())),
            None => Ok(()),
        }
    }

    /// The plant of `axis`, or [`BackendError::NoSuchAxis`].
    fn plant_checked(&mut self, axis: usize) -> Result<&mut ServoPlant, BackendError> {
        self.plants
            .get_mut(axis)
            .ok_or(BackendError::NoSuchAxis(axis))
    }
}

/// A plant refusal as a backend error naming the axis.
fn refused(axis: usize, e: PlantError) -> BackendError {
    BackendError::InvalidState(format!("axis {axis}: {e}"))
}

impl AxisBackend for SimBackend {
    fn axis_count(&self) -> usize {
        self.plants.len()
    }

    /// Enables every axis; all are tried, the first refusal is returned.
    fn enable(&mut self) -> Result<(), BackendError> {
        self.check_config()?;
        let mut first = Ok(());
        for (axis, plant) in self.plants.iter_mut().enumerate() {
            if let Err(e) = plant.enable()
                && first.is_ok()
            {
                first = Err(refused(axis, e));
            }
        }
        first
    }

    fn disable(&mut self) -> Result<(), BackendError> {
        self.check_config()?;
        for plant in &mut self.plants {
            plant.disable();
        }
        Ok(())
    }

    fn start_homing(&mut self, axis: usize) -> Result<(), BackendError> {
        self.check_config()?;
        self.plant_checked(axis)?
            .start_homing()
            .map_err(|e| refused(axis, e))
    }

    fn reset_fault(&mut self, axis: usize) -> Result<(), BackendError> {
        self.check_config()?;
        if self.link_lost(axis) {
            return Err(BackendError::Communication(format!(
                "axis {axis}: no link to the drive"
            )));
        }
        self.plant_checked(axis)?
            .reset_fault()
            .map_err(|e| refused(axis, e))
    }

    fn cycle(
        &mut self,
        t: f64,
        setpoints: &[Setpoint],
        feedback: &mut [AxisFeedback],
    ) -> Result<(), BackendError> {
        self.check_config()?;
        let expected = self.plants.len();
        for got in [setpoints.len(), feedback.len()] {
            if got != expected {
                return Err(BackendError::AxisCount { expected, got });
            }
        }
        for ScheduledFault { axis, fault, .. } in self.schedule.take_due(t) {
            if let Err(e) = self.inject(axis, &fault) {
                tracing::warn!("sim: scheduled fault not injected: {e}");
            }
        }
        let period = self.servo_period;
        for (((plant, setpoint), out), frozen) in self
            .plants
            .iter_mut()
            .zip(setpoints)
            .zip(feedback)
            .zip(&self.link_lost)
        {
            let fresh = plant.step(*setpoint, period);
            // Without a link the drive keeps running on its own, but the control only sees
            // what it last received.
            *out = frozen.clone().unwrap_or(fresh);
        }
        Ok(())
    }
}
