//! The bench machine shared by the planner benchmarks: X Y Z with equal limits, 1 ms servo
//! period, 0.01 mm path tolerance.

use klar_motion::{AxisLimits, PlannerConfig};

/// X Y Z at velocity `v`, acceleration `a` and jerk `j`.
pub fn xyz(v: f64, a: f64, j: f64) -> PlannerConfig {
    let l = AxisLimits {
        max_velocity: v,
        max_acceleration: a,
        max_jerk: j,
    };
    let mut limits = [None; 9];
    limits[..3].fill(Some(l));
    PlannerConfig {
        limits,
        period: 0.001,
        tolerance: 0.01,
    }
}
