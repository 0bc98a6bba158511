//! Planning and sampling throughput: how long one program of lines, arcs and splines takes
//! to plan and sample at a 1 ms servo period.

use klar_interp::op::SplineAxis;
use klar_interp::{AxisLetter, Feed, Op, OpKind, Plane, Pose, SourceLoc};
use klar_motion::{Planner, PlannerConfig, Step};

#[path = "support/machine.rs"]
mod machine;

fn main() {
    divan::main();
}

fn config() -> PlannerConfig {
    machine::xyz(200.0, 2000.0, 50_000.0)
}

fn op(kind: OpKind) -> Op {
    Op {
        kind,
        loc: SourceLoc::default(),
    }
}

/// A square pocket pass per level: four lines, a full circle and a spline, repeated.
fn program(levels: usize) -> Vec<Op> {
    let mut ops = Vec::new();
    let mut p = Pose::ZERO;
    for _ in 0..levels {
        for q in [
            Pose::xyz(40.0, 0.0, p.0[2]),
            Pose::xyz(40.0, 40.0, p.0[2]),
            Pose::xyz(0.0, 40.0, p.0[2]),
            Pose::xyz(0.0, 0.0, p.0[2]),
        ] {
            ops.push(op(OpKind::Line {
                from: p,
                to: q,
                feed: Feed::Rate(50.0),
            }));
            p = q;
        }
        ops.push(op(OpKind::Arc {
            from: p,
            to: p,
            center: [10.0, 0.0],
            plane: Plane::XY,
            sweep: 360.0,
            feed: Feed::Rate(40.0),
        }));
        let q = Pose::xyz(0.0, 0.0, p.0[2] - 1.0);
        ops.push(op(OpKind::Spline {
            from: p,
            to: q,
            axes: vec![
                SplineAxis {
                    axis: AxisLetter::X,
                    k: [1.0, -1.0, 0.0],
                },
                SplineAxis {
                    axis: AxisLetter::Z,
                    k: [0.0, 0.0, 1.0],
                },
            ],
            feed: Feed::Rate(30.0),
        }));
        p = q;
    }
    ops
}

/// Plans and samples `ops` to the end; returns the number of samples.
fn plan_and_count(ops: &[Op]) -> usize {
    let mut planner = Planner::new(config(), Pose::ZERO).expect("valid config");
    let mut input = ops.iter().cloned();
    let mut samples = 0usize;
    loop {
        while planner.needs_input() {
            match input.next() {
                Some(o) => planner.push(o).expect("valid op"),
                None => planner.finish(),
            }
        }
        match planner.next_step() {
            Some(Step::Sample(_)) => samples += 1,
            Some(Step::Event(_)) => {}
            None => break,
        }
    }
    samples
}

/// Whole program, planned and sampled; throughput in samples (servo cycles).
#[divan::bench(args = [1, 10])]
fn plan_and_sample(bencher: divan::Bencher, levels: usize) {
    let ops = program(levels);
    let samples = plan_and_count(&ops);
    bencher
        .counter(divan::counter::ItemsCount::new(samples))
        .bench_local(|| divan::black_box(plan_and_count(divan::black_box(&ops))));
}
