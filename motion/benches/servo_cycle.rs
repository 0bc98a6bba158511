//! Cost of one servo cycle of the look-ahead planner, as a distribution: `next_step` timed
//! one call at a time over a long dense program (0.05 mm chords of an R25 circle at
//! F3000 with the planner fed as the runtime feeds it), printed as percentiles up to
//! p99.99 and the maximum; and the same over laps of the benchmark square (50 × 50 mm,
//! 1 mm corner arcs, F6000), where the path brakes into and speeds up out of blends four
//! times a lap. divan then measures the mean and median of the dense program's call.
//!
//! On a shared machine single timings carry the machine's own interruptions (a fixed task
//! of ~2 µs shows tails of tens of µs), so three distributions are printed: the single
//! timings, the same fixed task timed alike (the machine's noise), and each cycle's cost as
//! the least of three runs of that same cycle on copies of the planner (an interruption
//! would have to hit all three: what is left is the planner's own cost).

use klar_interp::{Feed, Op, OpKind, Plane, Pose, SourceLoc};
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

/// The `k`-th move of endless laps of the benchmark square from (−24, 0): edges and 1 mm
/// corner arcs turning left, at F6000.
fn square_move(k: usize) -> Op {
    let xy = |x: f64, y: f64| Pose::xyz(x, y, 0.0);
    let feed = Feed::Rate(100.0);
    let corner = |from: Pose, to: Pose, center: [f64; 2]| OpKind::Arc {
        from,
        to,
        center,
        plane: Plane::XY,
        sweep: 90.0,
        feed,
    };
    let edge = |from: Pose, to: Pose| OpKind::Line { from, to, feed };
    let kind = match k % 8 {
        0 => edge(xy(-24.0, 0.0), xy(24.0, 0.0)),
        1 => corner(xy(24.0, 0.0), xy(25.0, 1.0), [24.0, 1.0]),
        2 => edge(xy(25.0, 1.0), xy(25.0, 49.0)),
        3 => corner(xy(25.0, 49.0), xy(24.0, 50.0), [24.0, 49.0]),
        4 => edge(xy(24.0, 50.0), xy(-24.0, 50.0)),
        5 => corner(xy(-24.0, 50.0), xy(-25.0, 49.0), [-24.0, 49.0]),
        6 => edge(xy(-25.0, 49.0), xy(-25.0, 1.0)),
        _ => corner(xy(-25.0, 1.0), xy(-24.0, 0.0), [-24.0, 1.0]),
    };
    Op {
        kind,
        loc: SourceLoc::default(),
    }
}

/// Runs `cycles` servo cycles on the endless program `source` (its moves by index, from
/// `start`) and returns each `next_step` duration in nanoseconds (input pushed between
/// cycles is not counted). With `repeats` > 1 each cycle is also run on that many copies
/// of the planner first and the least time counts.
fn cycle_times(cycles: usize, repeats: usize, start: Pose, source: fn(usize) -> Op) -> Vec<u64> {
    let mut planner = Planner::new(config(), start).expect("valid config");
    let mut next = 0usize;
    let mut times = Vec::with_capacity(cycles);
    while times.len() < cycles {
        while planner.needs_input() {
            planner.push(source(next)).expect("valid op");
            next += 1;
        }
        let mut least = u64::MAX;
        for _ in 1..repeats {
            let mut copy = planner.clone();
            let t0 = Instant::now();
            divan::black_box(copy.next_step());
            least = least.min(nanos(t0));
        }
        let t0 = Instant::now();
        let step = planner.next_step();
        least = least.min(nanos(t0));
        if matches!(step, Some(Step::Sample(_))) {
            times.push(least);
        }
    }
    times
}

fn nanos(t0: Instant) -> u64 {
    u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX)
}

/// A fixed task of about the servo cycle's median cost timed `count` times: the timing
/// noise of the machine itself.
fn noise_times(count: usize) -> Vec<u64> {
    let mut x = 1.0f64;
    (0..count)
        .map(|_| {
            let t0 = Instant::now();
            for k in 0..100 {
                x = (x * 1.000_001 + f64::from(k)).sqrt();
            }
            divan::black_box(x);
            nanos(t0)
        })
        .collect()
}

/// Prints p50, p99, p99.9, p99.99 and the maximum of 200 000 cycles (200 s of motion):
/// single timings, the machine's noise, and the least of three runs per cycle, on the
/// dense program and on the square's laps.
fn print_percentiles() {
    let cycles = 200_000;
    print_row(
        "servo cycle, single timings",
        cycle_times(cycles, 1, point(0), chord),
    );
    print_row("fixed task (machine noise)", noise_times(cycles));
    print_row(
        "servo cycle, least of 3 runs",
        cycle_times(cycles, 3, point(0), chord),
    );
    let corner = Pose::xyz(-24.0, 0.0, 0.0);
    print_row(
        "square laps, least of 3 runs",
        cycle_times(cycles, 3, corner, square_move),
    );
}

fn print_row(what: &str, mut t: Vec<u64>) {
    t.sort_unstable();
    let at = |q: f64| {
        let i = ((t.len() as f64 - 1.0) * q).round() as usize;
        t.get(i).copied().unwrap_or(0) as f64 / 1000.0
    };
    println!(
        "{what} ({} cycles): p50 {:.2} µs, p99 {:.2} µs, p99.9 {:.2} µs, p99.99 {:.2} µs, max {:.2} µs",
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
