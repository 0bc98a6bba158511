//! Helpers shared by the planner tests: building ops, driving the planner like the runtime
//! does, and checking sampled motion by finite differences.
#![allow(dead_code)]

use klar_interp::{Feed, Op, OpKind, Plane, Pose, SourceLoc};
use klar_motion::{AxisLimits, Planner, PlannerConfig, Sample, Step};

/// An op on a given program line.
pub fn op(line: u32, kind: OpKind) -> Op {
    Op {
        kind,
        loc: SourceLoc {
            file: 0,
            line,
            col: 1,
            block: Some(u64::from(line)),
        },
    }
}

/// A line op.
pub fn line(n: u32, from: Pose, to: Pose, feed: Feed) -> Op {
    op(n, OpKind::Line { from, to, feed })
}

/// An arc op.
pub fn arc(
    n: u32,
    from: Pose,
    to: Pose,
    center: [f64; 2],
    plane: Plane,
    sweep: f64,
    feed: Feed,
) -> Op {
    op(
        n,
        OpKind::Arc {
            from,
            to,
            center,
            plane,
            sweep,
            feed,
        },
    )
}

/// Limits for X Y Z (and optionally more axes).
pub fn limits_xyz(v: f64, a: f64, j: f64) -> [Option<AxisLimits>; 9] {
    let l = AxisLimits {
        max_velocity: v,
        max_acceleration: a,
        max_jerk: j,
    };
    [
        Some(l),
        Some(l),
        Some(l),
        None,
        None,
        None,
        None,
        None,
        None,
    ]
}

/// A configuration with the given limits and a 1 ms period.
pub fn config(limits: [Option<AxisLimits>; 9]) -> PlannerConfig {
    PlannerConfig {
        limits,
        period: 0.001,
        tolerance: 0.01,
    }
}

/// What a run produced, in order.
#[derive(Debug, Default)]
pub struct Run {
    /// Samples in order.
    pub samples: Vec<Sample>,
    /// Events with the number of samples emitted before each.
    pub events: Vec<(usize, Op)>,
    /// Largest planned time seen.
    pub planned_time: f64,
}

/// Drives a planner the way the runtime does: push while it needs input, then step.
pub fn run(config: PlannerConfig, start: Pose, ops: Vec<Op>) -> Run {
    run_controlled(config, start, ops, |_, _| {})
}

/// [`run`], calling `control` before every step with the planner and the samples so far
/// (an operator changing the feed override or holding the feed).
pub fn run_controlled(
    config: PlannerConfig,
    start: Pose,
    ops: Vec<Op>,
    mut control: impl FnMut(&mut Planner, &[Sample]),
) -> Run {
    let mut planner = Planner::new(config, start).expect("valid config");
    let mut ops = ops.into_iter();
    let mut out = Run::default();
    let mut guard = 0u64;
    loop {
        while planner.needs_input() {
            match ops.next() {
                Some(o) => planner.push(o).expect("op accepted"),
                None => planner.finish(),
            }
        }
        out.planned_time = planner.planned_time();
        control(&mut planner, &out.samples);
        match planner.next_step() {
            Some(Step::Sample(s)) => out.samples.push(s),
            Some(Step::Event(e)) => out.events.push((out.samples.len(), e)),
            None => break,
        }
        guard += 1;
        assert!(guard < 50_000_000, "planner does not terminate");
    }
    out
}

/// Positions of one axis at t = -2p, -p, 0, samples..., then held three more periods: the
/// machine is at rest before and after.
pub fn padded(start: &Pose, samples: &[Sample], axis: usize) -> Vec<f64> {
    let mut x = vec![start.0[axis]; 3];
    x.extend(samples.iter().map(|s| s.pose.0[axis]));
    let last = *x.last().unwrap_or(&start.0[axis]);
    x.extend([last; 3]);
    x
}

/// Largest |first|, |second|, |third| finite difference of a sequence, divided by p, p², p³.
pub fn max_differences(x: &[f64], p: f64) -> (f64, f64, f64) {
    let mut m = (0.0f64, 0.0f64, 0.0f64);
    for w in x.windows(2) {
        m.0 = m.0.max(((w[1] - w[0]) / p).abs());
    }
    for w in x.windows(3) {
        m.1 = m.1.max(((w[2] - 2.0 * w[1] + w[0]) / (p * p)).abs());
    }
    for w in x.windows(4) {
        m.2 =
            m.2.max(((w[3] - 3.0 * w[2] + 3.0 * w[1] - w[0]) / (p * p * p)).abs());
    }
    m
}

/// Asserts that every configured axis stays within its limits (with `slack`, e.g. 1.01)
/// by finite differences of the sampled positions.
pub fn assert_within_limits(config: &PlannerConfig, start: &Pose, samples: &[Sample], slack: f64) {
    for (i, l) in config.limits.iter().enumerate() {
        let Some(l) = l else { continue };
        let x = padded(start, samples, i);
        let (v, a, j) = max_differences(&x, config.period);
        assert!(
            v <= l.max_velocity * slack,
            "axis {i}: velocity {v} above {}",
            l.max_velocity
        );
        assert!(
            a <= l.max_acceleration * slack,
            "axis {i}: acceleration {a} above {}",
            l.max_acceleration
        );
        assert!(
            j <= l.max_jerk * slack,
            "axis {i}: jerk {j} above {}",
            l.max_jerk
        );
    }
}

/// Distance over X Y Z U V W.
pub fn linear_distance(a: &Pose, b: &Pose) -> f64 {
    [0usize, 1, 2, 6, 7, 8]
        .iter()
        .map(|&i| (a.0[i] - b.0[i]).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Distance in X Y Z from `p` to the segment from `a` to `b` (to `a` where the two are one
/// point).
pub fn segment_distance(p: &Pose, a: &Pose, b: &Pose) -> f64 {
    let d: Vec<f64> = (0..3).map(|i| b.0[i] - a.0[i]).collect();
    let w: Vec<f64> = (0..3).map(|i| p.0[i] - a.0[i]).collect();
    let dd: f64 = d.iter().map(|x| x * x).sum();
    let t = if dd > 0.0 {
        (d.iter().zip(&w).map(|(x, y)| x * y).sum::<f64>() / dd).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (0..3)
        .map(|i| (w[i] - t * d[i]).powi(2))
        .sum::<f64>()
        .sqrt()
}
