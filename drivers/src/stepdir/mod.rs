//! Step/direction outputs and switch inputs over embedded-hal 1.0.
//!
//! - [`generator`], [`channel`], [`inputs`]: the core, written against `core` and
//!   embedded-hal only (no heap, no std): step generation with maximum step rate, pulse
//!   width and direction setup/hold times, no lost steps at reversal; debounced limit,
//!   home and e-stop inputs.
//! - [`StepDirAxis`]: the axis behind [`klar_motion::AxisBackend`], generic over the pins
//!   and the delay that paces the ticks.
//! - [`limits`]: what step/dir can do (step rate, tick, Linux thread jitter) and the check
//!   that refuses a configuration that cannot keep up.
//! - `linux` (feature `linux-gpio`): the axis on GPIO character-device lines.

mod axis;
pub mod channel;
mod config;
pub mod generator;
pub mod inputs;
pub mod limits;
#[cfg(feature = "linux-gpio")]
pub mod linux;

pub use axis::{SpinDelay, StepDirAxis, StepDirOutputs};
pub use channel::{ChannelCounters, Polarity, StepDirChannel};
pub use config::{GpioPins, StepClock, StepDirConfig};
pub use generator::{StepAction, StepGenerator, StepTiming, StepTimingError};
pub use inputs::{Debounce, Switch, SwitchInputs, SwitchState};

/// What went wrong setting up a step/dir axis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepDirError {
    /// The configuration is not usable.
    #[error("invalid step/dir configuration: {0}")]
    Config(String),
    /// A pin could not be opened or driven.
    #[error("step/dir pin: {0}")]
    Pin(String),
}
