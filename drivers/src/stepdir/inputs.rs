//! Switch inputs (limits, home, e-stop) over embedded-hal input pins, with debounce.
//! Core-only code (no heap).

use embedded_hal::digital::InputPin;

/// A debounced binary signal: the output changes only after the raw level has stayed
/// the same for the debounce time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Debounce {
    window_ns: u64,
    stable: bool,
    candidate: bool,
    since: u64,
}

impl Debounce {
    /// A debouncer that starts at `initial` and needs `window_ns` of a stable level.
    pub fn new(window_ns: u64, initial: bool) -> Self {
        Self {
            window_ns,
            stable: initial,
            candidate: initial,
            since: 0,
        }
    }

    /// Feeds the raw level sampled at `now`; returns the debounced level.
    pub fn update(&mut self, raw: bool, now: u64) -> bool {
        if raw != self.candidate {
            self.candidate = raw;
            self.since = now;
        }
        if self.candidate != self.stable && now.saturating_sub(self.since) >= self.window_ns {
            self.stable = self.candidate;
        }
        self.stable
    }

    /// The debounced level.
    pub fn level(&self) -> bool {
        self.stable
    }
}

/// The debounced state of the switches (true: active).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SwitchState {
    /// Negative limit switch.
    pub limit_negative: bool,
    /// Positive limit switch.
    pub limit_positive: bool,
    /// Home switch.
    pub home: bool,
    /// Emergency stop (a broken chain reads as active when wired active-low).
    pub estop: bool,
}

/// One optional input with its polarity and debouncer.
#[derive(Debug)]
pub struct Switch<I: InputPin> {
    pin: I,
    active_low: bool,
    debounce: Debounce,
}

impl<I: InputPin> Switch<I> {
    /// A switch on `pin`; `active_low` for normally-closed wiring to ground.
    pub fn new(pin: I, active_low: bool, debounce_ns: u64) -> Self {
        Self {
            pin,
            active_low,
            debounce: Debounce::new(debounce_ns, false),
        }
    }

    /// Samples the pin at `now`; returns the debounced active state.
    pub fn sample(&mut self, now: u64) -> Result<bool, I::Error> {
        let high = self.pin.is_high()?;
        Ok(self.debounce.update(high != self.active_low, now))
    }

    /// Gives the pin back.
    pub fn release(self) -> I {
        self.pin
    }
}

/// The switch inputs of one axis; each is optional.
#[derive(Debug)]
pub struct SwitchInputs<I: InputPin> {
    /// Negative limit.
    pub limit_negative: Option<Switch<I>>,
    /// Positive limit.
    pub limit_positive: Option<Switch<I>>,
    /// Home.
    pub home: Option<Switch<I>>,
    /// Emergency stop.
    pub estop: Option<Switch<I>>,
}

impl<I: InputPin> Default for SwitchInputs<I> {
    fn default() -> Self {
        Self {
            limit_negative: None,
            limit_positive: None,
            home: None,
            estop: None,
        }
    }
}

impl<I: InputPin> SwitchInputs<I> {
    /// Samples every configured switch at `now`.
    pub fn sample(&mut self, now: u64) -> Result<SwitchState, I::Error> {
        fn one<I: InputPin>(s: &mut Option<Switch<I>>, now: u64) -> Result<bool, I::Error> {
            match s {
                Some(s) => s.sample(now),
                None => Ok(false),
            }
        }
        Ok(SwitchState {
            limit_negative: one(&mut self.limit_negative, now)?,
            limit_positive: one(&mut self.limit_positive, now)?,
            home: one(&mut self.home, now)?,
            estop: one(&mut self.estop, now)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glitches_shorter_than_the_window_are_ignored() {
        let mut d = Debounce::new(1_000, false);
        assert!(!d.update(true, 0));
        assert!(!d.update(false, 500), "a 500 ns glitch");
        assert!(!d.update(true, 2_000));
        assert!(!d.update(true, 2_999));
        assert!(d.update(true, 3_000), "stable for 1000 ns");
        assert!(d.update(false, 3_100));
        assert!(!d.update(false, 4_100));
    }
}
