//! Step/dir on Linux boards through the GPIO character device (`linux-gpio` feature).

use linux_embedded_hal::CdevPin;
use linux_embedded_hal::gpio_cdev::{Chip, LineRequestFlags};

use super::axis::{SpinDelay, StepDirAxis, StepDirOutputs};
use super::config::StepDirConfig;
use super::inputs::{Switch, SwitchInputs};
use super::{StepDirError, config::to_ns};

/// A step/dir axis on GPIO character-device lines.
pub type GpioStepDirAxis = StepDirAxis<CdevPin, CdevPin, SpinDelay>;

const CONSUMER: &str = "klar";

fn line(chip: &mut Chip, n: u32, output: bool) -> Result<CdevPin, StepDirError> {
    let flags = if output {
        LineRequestFlags::OUTPUT
    } else {
        LineRequestFlags::INPUT
    };
    let handle = chip
        .get_line(n)
        .and_then(|l| l.request(flags, 0, CONSUMER))
        .map_err(|e| StepDirError::Pin(format!("GPIO line {n}: {e}")))?;
    CdevPin::new(handle).map_err(|e| StepDirError::Pin(format!("GPIO line {n}: {e}")))
}

/// Opens the GPIO lines named in `config.pins` and builds the axis with a spinning
/// wall-clock delay. Check [`super::limits::check`] first.
pub fn open_gpio_axis(
    config: &StepDirConfig,
    servo_period: f64,
) -> Result<GpioStepDirAxis, StepDirError> {
    let pins = config
        .pins
        .as_ref()
        .ok_or_else(|| StepDirError::Config("no [pins] table for a GPIO axis".into()))?;
    let mut chip =
        Chip::new(&pins.chip).map_err(|e| StepDirError::Pin(format!("{}: {e}", pins.chip)))?;
    let debounce = to_ns("debounce", config.debounce, true)?;
    let mut input = |n: Option<u32>| -> Result<Option<Switch<CdevPin>>, StepDirError> {
        n.map(|n| {
            line(&mut chip, n, false).map(|p| Switch::new(p, pins.inputs_active_low, debounce))
        })
        .transpose()
    };
    let switches = SwitchInputs {
        limit_negative: input(pins.limit_negative)?,
        limit_positive: input(pins.limit_positive)?,
        home: input(pins.home)?,
        estop: input(pins.estop)?,
    };
    let outputs = StepDirOutputs {
        step: line(&mut chip, pins.step, true)?,
        dir: line(&mut chip, pins.dir, true)?,
        enable: pins.enable.map(|n| line(&mut chip, n, true)).transpose()?,
        enable_active_low: pins.enable_active_low,
    };
    StepDirAxis::new(config, servo_period, outputs, switches, SpinDelay::new())
}
