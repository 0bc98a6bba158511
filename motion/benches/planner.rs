//! Look-ahead planner costs: planning throughput on dense CAM code (segments per second,
//! corners blended) and the cost of one servo cycle of the speed generator.

use klar_interp::{Feed, Op, OpKind, Pose, SourceLoc};
use klar_motion::{Planner, PlannerConfig, Step};
use std::f64::consts::PI;

#[path = "support/machine.rs"]
mod machine;

fn main() {
    divan::main();
}

fn config() -> PlannerConfig {
    machine::xyz(100.0, 1000.0, 1e5)
}

/// `n` chords of a circle of radius 25 mm (2000 chords per turn) at 50 mm/s.
fn polyline(n: usize) -> Vec<Op> {
    let p = |k: usize| {
        let phi = 2.0 * PI * k as f64 / 2000.0;
        Pose::xyz(25.0 * phi.cos(), 25.0 * phi.sin(), 0.0)
    };
    (0..n)
        .map(|k| Op {
            kind: OpKind::Line {
                from: p(k),
                to: p(k + 1),
                feed: Feed::Rate(50.0),
            },
            loc: SourceLoc::default(),
        })
        .collect()
}

/// Planning: pushing (cutting, blending, limiting) 10 000 dense segments.
#[divan::bench]
fn plan_dense_segments(bencher: divan::Bencher) {
    let ops = polyline(10_000);
    let start = Pose::xyz(25.0, 0.0, 0.0);
    bencher
        .counter(divan::counter::ItemsCount::new(ops.len()))
        .with_inputs(|| ops.clone())
        .bench_local_values(|ops| {
            let mut planner = Planner::new(config(), start).expect("valid config");
            for op in ops {
                planner.push(op).expect("valid op");
            }
            divan::black_box(planner.planned_pose())
        });
}

/// One servo cycle: `next_step` on dense code at speed (the planner already filled).
#[divan::bench(sample_count = 2000, sample_size = 1)]
fn servo_cycle(bencher: divan::Bencher) {
    let ops = polyline(4_000);
    let start = Pose::xyz(25.0, 0.0, 0.0);
    let mut planner = Planner::new(config(), start).expect("valid config");
    for op in ops {
        planner.push(op).expect("valid op");
    }
    planner.finish();
    // Run up to speed first.
    for _ in 0..200 {
        planner.next_step();
    }
    bencher.bench_local(|| {
        let step = planner.next_step();
        divan::black_box(matches!(step, Some(Step::Sample(_))))
    });
}
