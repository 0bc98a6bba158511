//! The servo plant shared by every simulated axis and drive.
//!
//! Placeholder contract: a perfect follower. Replaced by the full model.

use klar_motion::{AxisFeedback, AxisState, Setpoint};

/// Parameters of one simulated servo axis.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SimAxisParams {}

/// A simulated servo axis: plant plus position controller plus encoder.
#[derive(Debug, Clone)]
pub struct ServoPlant {
    position: f64,
}

impl ServoPlant {
    /// A plant at rest at `position`.
    pub fn new(_params: SimAxisParams, position: f64) -> Self {
        Self { position }
    }

    /// Advances the plant by `dt` seconds following `setpoint`.
    pub fn step(&mut self, setpoint: Setpoint, _dt: f64) -> AxisFeedback {
        self.position = setpoint.position;
        AxisFeedback {
            position: self.position,
            following_error: 0.0,
            state: AxisState::Enabled,
            homed: true,
            fault: None,
        }
    }
}
