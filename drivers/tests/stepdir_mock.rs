//! The step/dir axis against embedded-hal-mock pins (exact edge sequences) and against
//! recording pins on a test clock (edge timing versus the commanded positions).

use std::cell::{Cell, RefCell};
use std::convert::Infallible;
use std::rc::Rc;

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{ErrorType, InputPin, OutputPin};
use embedded_hal_mock::eh1::delay::NoopDelay;
use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as T};
use klar_drivers::stepdir::{StepDirAxis, StepDirConfig, StepDirOutputs, Switch, SwitchInputs};
use klar_motion::{AxisBackend, AxisFault, AxisFeedback, AxisState, Setpoint};

const PERIOD: f64 = 0.001;

fn config() -> StepDirConfig {
    let mut c = StepDirConfig::new(100.0, 20_000.0);
    c.pulse_width = 5e-6;
    c.dir_setup = 5e-6;
    c.dir_hold = 5e-6;
    c.tick = 25e-6;
    c.debounce = 100e-6;
    c
}

fn sp(position: f64) -> [Setpoint; 1] {
    [Setpoint {
        position,
        ..Setpoint::default()
    }]
}

fn run<A: AxisBackend>(axis: &mut A, positions: impl IntoIterator<Item = f64>) -> AxisFeedback {
    let mut fb = [AxisFeedback::default()];
    for (n, p) in positions.into_iter().enumerate() {
        axis.cycle(n as f64 * PERIOD, &sp(p), &mut fb)
            .expect("cycle");
    }
    fb[0].clone()
}

#[test]
fn mock_pins_see_exactly_the_commanded_steps_and_one_reversal() {
    // 0 → 0.5 mm in 50 cycles (50 steps forward), then → 0.2 mm (30 steps back).
    let forward = 50;
    let back = 30;
    let mut step_tx = vec![T::set(State::Low)];
    for _ in 0..forward + back {
        step_tx.push(T::set(State::High));
        step_tx.push(T::set(State::Low));
    }
    let dir_tx = [T::set(State::High), T::set(State::Low)];
    let enable_tx = [T::set(State::Low), T::set(State::High)];
    let mut step = PinMock::new(&step_tx);
    let mut dir = PinMock::new(&dir_tx);
    let mut enable = PinMock::new(&enable_tx);
    let outputs = StepDirOutputs {
        step: step.clone(),
        dir: dir.clone(),
        enable: Some(enable.clone()),
        enable_active_low: false,
    };
    let mut axis = StepDirAxis::new(
        &config(),
        PERIOD,
        outputs,
        SwitchInputs::<PinMock>::default(),
        NoopDelay,
    )
    .expect("axis");
    axis.enable().expect("enable");
    let path = (1..=50)
        .map(|n| 0.01 * n as f64)
        .chain((1..=30).map(|n| 0.5 - 0.01 * n as f64))
        .chain(std::iter::repeat_n(0.2, 5));
    let fb = run(&mut axis, path);
    assert!((fb.position - 0.2).abs() < 1e-12, "{fb:?}");
    assert!(fb.following_error.abs() < 1e-12);
    assert_eq!(axis.counters().steps, 80);
    assert_eq!(axis.counters().reversals, 1);
    step.done();
    dir.done();
    enable.done();
}

/// A pin that records (time, level) on a shared test clock.
#[derive(Clone)]
struct Recorder {
    clock: Rc<Cell<u64>>,
    log: Rc<RefCell<Vec<(u64, bool)>>>,
}

impl ErrorType for Recorder {
    type Error = Infallible;
}

impl OutputPin for Recorder {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.log.borrow_mut().push((self.clock.get(), false));
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.log.borrow_mut().push((self.clock.get(), true));
        Ok(())
    }
}

/// A delay that advances the test clock.
struct ClockDelay(Rc<Cell<u64>>);

impl DelayNs for ClockDelay {
    fn delay_ns(&mut self, ns: u32) {
        self.0.set(self.0.get() + u64::from(ns));
    }
}

/// An input pin whose level is a function of the test clock.
#[derive(Clone)]
struct ScriptedInput {
    clock: Rc<Cell<u64>>,
    high_from: Rc<Cell<Option<u64>>>,
    glitches: Rc<Vec<(u64, u64)>>,
}

impl ErrorType for ScriptedInput {
    type Error = Infallible;
}

impl InputPin for ScriptedInput {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        let t = self.clock.get();
        let glitch = self.glitches.iter().any(|(a, b)| t >= *a && t < *b);
        Ok(glitch || self.high_from.get().is_some_and(|h| t >= h))
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        self.is_high().map(|h| !h)
    }
}

struct Rig {
    clock: Rc<Cell<u64>>,
    step: Rc<RefCell<Vec<(u64, bool)>>>,
    dir: Rc<RefCell<Vec<(u64, bool)>>>,
    enable: Rc<RefCell<Vec<(u64, bool)>>>,
}

impl Rig {
    fn new() -> Self {
        Self {
            clock: Rc::new(Cell::new(0)),
            step: Rc::default(),
            dir: Rc::default(),
            enable: Rc::default(),
        }
    }
    fn pin(&self, log: &Rc<RefCell<Vec<(u64, bool)>>>) -> Recorder {
        Recorder {
            clock: self.clock.clone(),
            log: log.clone(),
        }
    }
    fn input(&self, high_from: Option<u64>, glitches: Vec<(u64, u64)>) -> ScriptedInput {
        ScriptedInput {
            clock: self.clock.clone(),
            high_from: Rc::new(Cell::new(high_from)),
            glitches: Rc::new(glitches),
        }
    }
    fn axis(
        &self,
        config: &StepDirConfig,
        switches: SwitchInputs<ScriptedInput>,
    ) -> StepDirAxis<Recorder, ScriptedInput, ClockDelay> {
        let outputs = StepDirOutputs {
            step: self.pin(&self.step),
            dir: self.pin(&self.dir),
            enable: Some(self.pin(&self.enable)),
            enable_active_low: true,
        };
        StepDirAxis::new(
            config,
            PERIOD,
            outputs,
            switches,
            ClockDelay(self.clock.clone()),
        )
        .expect("axis")
    }
    fn rises(&self) -> Vec<u64> {
        edges(&self.step.borrow(), true)
    }
}

fn edges(log: &[(u64, bool)], rising: bool) -> Vec<u64> {
    log.windows(2)
        .filter(|w| w[0].1 != w[1].1 && w[1].1 == rising)
        .map(|w| w[1].0)
        .collect()
}

#[test]
fn edges_follow_the_commanded_velocity_within_one_tick() {
    let rig = Rig::new();
    let mut axis = rig.axis(&config(), SwitchInputs::default());
    axis.enable().unwrap();
    // Constant velocity v = 37 mm/s = 3700 steps/s: the setpoint of cycle n is the
    // position for the end of that cycle, v (n + 1) T, so the command is p(t) = v t.
    let v = 37.0;
    let cycles = 200;
    run(&mut axis, (0..cycles).map(|n| v * (n + 1) as f64 * PERIOD));
    let rises = rig.rises();
    let expected_steps = (v * cycles as f64 * PERIOD * 100.0).round() as usize;
    assert_eq!(rises.len(), expected_steps);
    let tick = 25_000u64;
    for (i, &t) in rises.iter().enumerate() {
        // Step k = i + 1 is due when p(t) * 100 crosses k - 0.5.
        let ideal = ((i as f64 + 0.5) / (v * 100.0) * 1e9).ceil() as u64;
        // The first step also waits for the direction setup after enabling.
        let late = t.saturating_sub(ideal);
        assert!(t + 1 >= ideal, "step {i} early: {t} < {ideal}");
        assert!(late < tick, "step {i} late by {late} ns");
    }
    // Every pulse is high for at least the pulse width, low at least as long.
    let log = rig.step.borrow();
    for w in log.windows(2) {
        assert!(w[1].0 - w[0].0 >= 5_000, "{w:?}");
    }
}

#[test]
fn step_rate_is_limited_and_no_step_is_lost() {
    let rig = Rig::new();
    let mut c = config();
    c.max_step_rate = 4_000.0; // 250 us between rising edges
    let mut axis = rig.axis(&c, SwitchInputs::default());
    axis.enable().unwrap();
    // Ask for 1 mm (100 steps) at once: it cannot go faster than 4000 steps/s.
    let fb = run(&mut axis, std::iter::repeat_n(1.0, 30));
    assert!((fb.position - 1.0).abs() < 1e-12, "{fb:?}");
    let rises = rig.rises();
    assert_eq!(rises.len(), 100);
    for w in rises.windows(2) {
        assert!(w[1] - w[0] >= 250_000, "{w:?}");
    }
    // At the limit: 100 steps take 99 periods after the first.
    assert_eq!(rises[99] - rises[0], 99 * 250_000);
}

#[test]
fn reversal_respects_hold_and_setup_times() {
    let rig = Rig::new();
    let mut c = config();
    c.dir_setup = 60e-6; // more than two ticks
    c.dir_hold = 30e-6;
    let mut axis = rig.axis(&c, SwitchInputs::default());
    axis.enable().unwrap();
    let path = [0.05, 0.05, -0.05, -0.05, -0.05, 0.02, 0.02, 0.02];
    let fb = run(&mut axis, path);
    assert!((fb.position - 0.02).abs() < 1e-12);
    let dir_changes: Vec<u64> = rig.dir.borrow().iter().skip(1).map(|e| e.0).collect();
    assert_eq!(dir_changes.len(), 2, "two reversals");
    let falls = edges(&rig.step.borrow(), false);
    let rises = rig.rises();
    for d in dir_changes {
        let last_fall = falls
            .iter()
            .filter(|&&f| f <= d)
            .max()
            .copied()
            .unwrap_or(0);
        let next_rise = rises
            .iter()
            .find(|&&r| r > d)
            .copied()
            .expect("steps after reversal");
        assert!(d - last_fall >= 30_000, "hold: {d} - {last_fall}");
        assert!(next_rise - d >= 60_000, "setup: {next_rise} - {d}");
    }
    // 5 + 10 + 7 steps.
    assert_eq!(rises.len(), 22);
}

#[test]
fn limit_switch_debounce_and_trip() {
    let rig = Rig::new();
    // A 50 us glitch at 2 ms (shorter than the 100 us debounce), then the switch closes
    // for real at 10 ms.
    let limit = rig.input(Some(10_000_000), vec![(2_000_000, 2_050_000)]);
    let switches = SwitchInputs {
        limit_positive: Some(Switch::new(limit, false, 100_000)),
        ..SwitchInputs::default()
    };
    let mut axis = rig.axis(&config(), switches);
    axis.enable().unwrap();
    // Move at 20 mm/s for 20 ms: the switch stops it near 10 ms + debounce.
    let fb = run(&mut axis, (0..20).map(|n| 20.0 * (n + 1) as f64 * PERIOD));
    assert_eq!(fb.state, AxisState::Faulted);
    assert_eq!(fb.fault, Some(AxisFault::LimitSwitch { positive: true }));
    let rises = rig.rises();
    let last = *rises.last().unwrap();
    assert!(last < 10_100_000 + 25_000, "stepped after the trip: {last}");
    // It passed the glitch: steps continued after 2.05 ms.
    assert!(rises.iter().any(|&r| r > 2_100_000 && r < 10_000_000));
    // Moving away from the switch is allowed after a reset.
    axis.reset_fault(0).unwrap();
    axis.enable().unwrap();
    let here = fb.position;
    let fb = run(&mut axis, (0..10).map(|n| here - 0.01 * (n + 1) as f64));
    assert_eq!(fb.state, AxisState::Enabled, "{fb:?} from {here}");
    assert!((fb.position - (here - 0.1)).abs() < 1e-9);
}

#[test]
fn estop_disables_and_blocks_reset_while_active() {
    let rig = Rig::new();
    let estop = rig.input(Some(3_000_000), vec![]);
    let switches = SwitchInputs {
        estop: Some(Switch::new(estop.clone(), false, 100_000)),
        ..SwitchInputs::default()
    };
    let mut axis = rig.axis(&config(), switches);
    axis.enable().unwrap();
    let fb = run(&mut axis, (0..6).map(|n| 10.0 * (n + 1) as f64 * PERIOD));
    assert_eq!(fb.fault, Some(AxisFault::EStop));
    // Enable output is active low: high = off after the trip.
    assert_eq!(rig.enable.borrow().last().map(|e| e.1), Some(true));
    assert!(axis.reset_fault(0).is_err());
    estop.high_from.set(None);
    run(&mut axis, [fb.position]);
    axis.reset_fault(0).expect("reset after release");
    assert!(axis.enable().is_ok());
}

#[test]
fn homing_sets_the_reference_at_the_switch() {
    let rig = Rig::new();
    let home = rig.input(Some(5_000_000), vec![]);
    let switches = SwitchInputs {
        home: Some(Switch::new(home, false, 100_000)),
        ..SwitchInputs::default()
    };
    let mut c = config();
    c.homing_velocity = Some(-10.0);
    c.home_position = -2.0;
    let mut axis = rig.axis(&c, switches);
    axis.enable().unwrap();
    let fb = run(&mut axis, [0.0]);
    assert!(!fb.homed);
    axis.start_homing(0).unwrap();
    let mut fb = AxisFeedback::default();
    for _ in 0..20 {
        fb = run(&mut axis, [0.0]);
        if fb.homed {
            break;
        }
    }
    assert!(fb.homed && fb.state == AxisState::Enabled, "{fb:?}");
    assert!((fb.position + 2.0).abs() < 1e-12);
    // Homing moved in the negative direction (direction output low).
    assert_eq!(rig.dir.borrow().last().map(|e| e.1), Some(false));
}
