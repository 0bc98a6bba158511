//! One step/dir output channel: the step generator driving two embedded-hal output pins.
//! Core-only code (no heap).

use embedded_hal::digital::OutputPin;

use super::generator::{StepAction, StepGenerator};

/// Electrical polarity of the step and direction outputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Polarity {
    /// The step pulse is a low level (the idle level is high).
    pub step_active_low: bool,
    /// Positive direction is a low level.
    pub dir_invert: bool,
}

/// Counters of a channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ChannelCounters {
    /// Rising step edges written.
    pub steps: u64,
    /// Direction changes written.
    pub reversals: u64,
}

/// A step generator with its two pins.
#[derive(Debug)]
pub struct StepDirChannel<O: OutputPin> {
    generator: StepGenerator,
    step: O,
    dir: O,
    polarity: Polarity,
    counters: ChannelCounters,
}

impl<O: OutputPin> StepDirChannel<O> {
    /// Takes the pins and drives them to idle: step inactive, direction positive.
    pub fn new(
        generator: StepGenerator,
        mut step: O,
        mut dir: O,
        polarity: Polarity,
    ) -> Result<Self, O::Error> {
        set(&mut step, polarity.step_active_low)?;
        set(&mut dir, generator.forward() != polarity.dir_invert)?;
        Ok(Self {
            generator,
            step,
            dir,
            polarity,
            counters: ChannelCounters::default(),
        })
    }

    /// The generator (for commands and position).
    pub fn generator(&self) -> &StepGenerator {
        &self.generator
    }

    /// The generator, mutable.
    pub fn generator_mut(&mut self) -> &mut StepGenerator {
        &mut self.generator
    }

    /// Edges written so far.
    pub fn counters(&self) -> ChannelCounters {
        self.counters
    }

    /// Applies every pin change due at `now`. Returns the number of changes.
    pub fn poll(&mut self, now: u64) -> Result<u32, O::Error> {
        let mut changes = 0;
        // At most: falling edge, direction change, rising edge.
        for _ in 0..3 {
            let Some(action) = self.generator.poll(now) else {
                break;
            };
            match action {
                StepAction::StepHigh => {
                    set(&mut self.step, !self.polarity.step_active_low)?;
                    self.counters.steps += 1;
                }
                StepAction::StepLow => set(&mut self.step, self.polarity.step_active_low)?,
                StepAction::Direction(forward) => {
                    set(&mut self.dir, forward != self.polarity.dir_invert)?;
                    self.counters.reversals += 1;
                }
            }
            changes += 1;
        }
        Ok(changes)
    }

    /// Gives the pins back.
    pub fn release(self) -> (O, O) {
        (self.step, self.dir)
    }
}

fn set<O: OutputPin>(pin: &mut O, high: bool) -> Result<(), O::Error> {
    if high { pin.set_high() } else { pin.set_low() }
}
