//! Step generator throughput (edges per second of computation) and its edge timing error
//! against the ideal crossing times of a constant-velocity command.

use std::convert::Infallible;

use divan::{Bencher, counter::ItemsCount};
use embedded_hal::digital::{ErrorType, OutputPin};
use klar_drivers::stepdir::{Polarity, StepDirChannel, StepGenerator, StepTiming};

struct NullPin;

impl ErrorType for NullPin {
    type Error = Infallible;
}

impl OutputPin for NullPin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

fn timing() -> StepTiming {
    StepTiming {
        steps_per_unit: 400.0,
        min_step_period_ns: 10_000,
        pulse_width_ns: 2_000,
        dir_setup_ns: 2_000,
        dir_hold_ns: 2_000,
    }
}

/// Runs `ticks` ticks of `tick_ns` at velocity `v` (units/s) from a standstill and
/// returns the rising-edge times.
fn run(v: f64, tick_ns: u64, ticks: u64) -> Vec<u64> {
    let mut g = StepGenerator::new(timing(), 0);
    let end = ticks * tick_ns;
    g.set_target(0, v * end as f64 * 1e-9, end);
    let mut rises = Vec::new();
    for k in 0..ticks {
        let now = k * tick_ns;
        while let Some(a) = g.poll(now) {
            if a == klar_drivers::stepdir::StepAction::StepHigh {
                rises.push(now);
            }
        }
    }
    rises
}

#[divan::bench(args = [10_000u64, 1_000])]
fn ticks_at_max_rate(bencher: Bencher, tick_ns: u64) {
    // 100 mm/s x 400 steps/mm = 40000 steps/s: 80000 edges/s of motion.
    let ticks = 1_000_000_000 / tick_ns / 10; // 0.1 s of motion
    let edges = 2 * 4_000;
    bencher
        .counter(ItemsCount::new(edges as usize))
        .bench_local(|| {
            let mut ch = StepDirChannel::new(
                StepGenerator::new(timing(), 0),
                NullPin,
                NullPin,
                Polarity::default(),
            )
            .unwrap_or_else(|e| match e {});
            let end = ticks * tick_ns;
            ch.generator_mut().set_target(0, 10.0, end);
            for k in 0..ticks {
                let _ = ch.poll(k * tick_ns);
            }
            ch.counters().steps
        });
}

fn main() {
    for (v, tick_ns) in [
        (10.0, 25_000u64),
        (50.0, 10_000),
        (100.0, 10_000),
        (100.0, 1_000),
    ] {
        let ticks = 100_000_000 / tick_ns; // 0.1 s
        let rises = run(v, tick_ns, ticks);
        let rate = v * 400.0;
        let mut max_err: f64 = 0.0;
        let mut sum = 0.0;
        for (i, &t) in rises.iter().enumerate() {
            let ideal = (i as f64 + 0.5) / rate * 1e9;
            let err = t as f64 - ideal;
            max_err = max_err.max(err.abs());
            sum += err;
        }
        println!(
            "v = {v} mm/s ({rate:.0} steps/s), tick {} us: {} steps, edge error mean {:.2} us, max {:.2} us",
            tick_ns as f64 / 1e3,
            rises.len(),
            sum / rises.len().max(1) as f64 / 1e3,
            max_err / 1e3
        );
    }
    divan::main();
}
