//! Cost of one servo cycle of the look-ahead planner, as a distribution: `next_step` timed
//! one call at a time over a long dense program (0.05 mm chords of an R25 circle at
//! F3000 with the planner fed as the runtime feeds it), printed as percentiles up to
//! p99.99 and the maximum. divan then measures the mean and median of the same call.

use klar_interp::{Feed, Op, OpKind, Pose, SourceLoc};
use klar_motion::{Planner, PlannerConfig, Step};
use std::f64::consts::PI;
use std::time::Instant;

#[path = "support/machine.rs"]
mod machine;

fn main() {
    print_percentiles();
    divan::main();
}

fn config() -> PlannerConfig {
    machine::xyz(100.0, 1000.0, 1e5)
}

/// Chords per turn of the R25 circle: 0.05 mm each.
const CHORDS_PER_TURN: usize = 3142;

/// The `k`-th point of the dense circle.
fn point(k: usize) -> Pose {
    let phi = 2.0 * PI * k as f64 / CHORDS_PER_TURN as f64;
    Pose::xyz(25.0 * phi.cos(), 25.0 * phi.sin(), 0.0)
}

/// An endless source of chords at F3000.
fn chord(k: usize) -> Op {
    Op {
        kind: OpKind::Line {
            from: point(k),
            to: point(k + 1),
            feed: Feed::Rate(50.0),
        },
        loc: SourceLoc::default(),
    }
}

/// Runs `cycles` servo cycles on the dense program and returns each `next_step` duration
/// in nanoseconds (input pushed between cycles is not counted).
fn cycle_times(cycles: usize) -> Vec<u64> {
    let mut planner = Planner::new(config(), point(0)).expect("valid config");
    let mut next = 0usize;
    let mut times = Vec::with_capacity(cycles);
    while times.len() < cycles {
        while planner.needs_input() {
            planner.push(chord(next)).expect("valid op");
            next += 1;
        }
        let t0 = Instant::now();
        let step = planner.next_step();
        let dt = t0.elapsed();
        if matches!(step, Some(Step::Sample(_))) {
            times.push(u64::try_from(dt.as_nanos()).unwrap_or(u64::MAX));
        }
    }
    times
}

/// Prints p50, p99, p99.9, p99.99 and the maximum of 200 000 cycles (200 s of motion).
fn print_percentiles() {
    let mut t = cycle_times(200_000);
    t.sort_unstable();
    let at = |q: f64| {
        let i = ((t.len() as f64 - 1.0) * q).round() as usize;
        t.get(i).copied().unwrap_or(0) as f64 / 1000.0
    };
    println!(
        "servo cycle over {} cycles: p50 {:.2} µs, p99 {:.2} µs, p99.9 {:.2} µs, p99.99 {:.2} µs, max {:.2} µs",
        t.len(),
        at(0.5),
        at(0.99),
        at(0.999),
        at(0.9999),
        at(1.0)
    );
}

/// One servo cycle on the dense program at speed (divan's mean and median).
#[divan::bench(sample_count = 5000, sample_size = 1)]
fn dense_cycle(bencher: divan::Bencher) {
    let mut planner = Planner::new(config(), point(0)).expect("valid config");
    let mut next = 0usize;
    bencher.bench_local(|| {
        while planner.needs_input() {
            planner.push(chord(next)).expect("valid op");
            next += 1;
        }
        divan::black_box(planner.next_step())
    });
}
