//! A simulated stepper motor behind step/dir pins, for running step/dir axes with no
//! hardware: the output pins count step edges into a motor position, the input pins report
//! limit and home switches from that position.
//!
//! The motor is ideal (it never loses a step): what is simulated is the wiring, so the step
//! generator, its timing rules and the switch handling run exactly as on a board.

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{ErrorType, InputPin, OutputPin};
use std::cell::RefCell;
use std::convert::Infallible;
use std::rc::Rc;

/// The state of the simulated motor and its switches.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StepperMotor {
    /// Steps counted so far (positive with the direction pin high).
    pub steps: i64,
    /// Level of the direction pin.
    pub dir_high: bool,
    /// Level of the step pin.
    pub step_high: bool,
    /// Level of the enable pin.
    pub enabled_high: bool,
    /// Rising step edges seen.
    pub edges: u64,
    /// Switch positions in steps: (negative limit, positive limit, home). A limit is active
    /// at or beyond its position; the home switch is active at or above its position.
    pub switches: SwitchPositions,
}

/// Where the simulated switches sit, in steps.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SwitchPositions {
    /// Negative limit switch.
    pub limit_negative: Option<i64>,
    /// Positive limit switch.
    pub limit_positive: Option<i64>,
    /// Home switch (a cam, active from here upwards).
    pub home: Option<i64>,
}

/// Which pin of the motor a [`SimPin`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PinRole {
    /// Step output.
    Step,
    /// Direction output.
    Dir,
    /// Enable output.
    Enable,
    /// Negative limit input.
    LimitNegative,
    /// Positive limit input.
    LimitPositive,
    /// Home input.
    Home,
}

/// One pin wired to a shared [`StepperMotor`].
#[derive(Debug, Clone)]
pub struct SimPin {
    motor: Rc<RefCell<StepperMotor>>,
    role: PinRole,
}

/// A new motor and a function making its pins.
pub fn stepper(
    switches: SwitchPositions,
) -> (Rc<RefCell<StepperMotor>>, impl Fn(PinRole) -> SimPin) {
    let motor = Rc::new(RefCell::new(StepperMotor {
        switches,
        ..StepperMotor::default()
    }));
    let m = Rc::clone(&motor);
    (motor, move |role| SimPin {
        motor: Rc::clone(&m),
        role,
    })
}

impl ErrorType for SimPin {
    type Error = Infallible;
}

impl SimPin {
    fn set(&mut self, high: bool) {
        let mut m = self.motor.borrow_mut();
        match self.role {
            PinRole::Step => {
                if high && !m.step_high {
                    m.edges += 1;
                    m.steps += if m.dir_high { 1 } else { -1 };
                }
                m.step_high = high;
            }
            PinRole::Dir => m.dir_high = high,
            PinRole::Enable => m.enabled_high = high,
            // Inputs ignore writes.
            PinRole::LimitNegative | PinRole::LimitPositive | PinRole::Home => {}
        }
    }

    fn level(&self) -> bool {
        let m = self.motor.borrow();
        let s = m.switches;
        match self.role {
            PinRole::LimitNegative => s.limit_negative.is_some_and(|p| m.steps <= p),
            PinRole::LimitPositive => s.limit_positive.is_some_and(|p| m.steps >= p),
            PinRole::Home => s.home.is_some_and(|p| m.steps >= p),
            PinRole::Step => m.step_high,
            PinRole::Dir => m.dir_high,
            PinRole::Enable => m.enabled_high,
        }
    }
}

impl OutputPin for SimPin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.set(false);
        Ok(())
    }

    fn set_high(&mut self) -> Result<(), Infallible> {
        self.set(true);
        Ok(())
    }
}

impl InputPin for SimPin {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(self.level())
    }

    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(!self.level())
    }
}

/// A delay that returns at once: simulated time advances only through the servo cycles.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoDelay;

impl DelayNs for NoDelay {
    fn delay_ns(&mut self, _ns: u32) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rising_step_edges_count_in_the_direction_of_the_dir_pin() {
        let (motor, pin) = stepper(SwitchPositions::default());
        let (mut step, mut dir) = (pin(PinRole::Step), pin(PinRole::Dir));
        dir.set_high().unwrap();
        for _ in 0..5 {
            step.set_high().unwrap();
            step.set_high().unwrap(); // a level held high is not a second edge
            step.set_low().unwrap();
        }
        dir.set_low().unwrap();
        for _ in 0..2 {
            step.set_high().unwrap();
            step.set_low().unwrap();
        }
        let m = motor.borrow();
        assert_eq!((m.steps, m.edges), (3, 7));
    }

    #[test]
    fn switches_follow_the_motor_position() {
        let (motor, pin) = stepper(SwitchPositions {
            limit_negative: Some(-10),
            limit_positive: Some(10),
            home: Some(4),
        });
        let (mut neg, mut pos, mut home) = (
            pin(PinRole::LimitNegative),
            pin(PinRole::LimitPositive),
            pin(PinRole::Home),
        );
        motor.borrow_mut().steps = 4;
        assert_eq!(
            (neg.is_high(), pos.is_high(), home.is_high()),
            (Ok(false), Ok(false), Ok(true))
        );
        motor.borrow_mut().steps = 10;
        assert_eq!(pos.is_high(), Ok(true));
        motor.borrow_mut().steps = -11;
        assert_eq!((neg.is_high(), home.is_low()), (Ok(true), Ok(true)));
    }
}
