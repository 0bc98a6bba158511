//! The machine the planner's unit tests plan on: X, Y and Z at 100 mm/s, 1000 mm/s² and
//! 1e5 mm/s³, a 1 ms period and a 0.01 mm tolerance (the benchmark machine's limits).

use super::Planner;
use crate::config::{AxisLimits, PlannerConfig};
use klar_interp::Pose;

/// The test machine's axis limits.
pub(super) fn limits() -> [Option<AxisLimits>; 9] {
    let l = AxisLimits {
        max_velocity: 100.0,
        max_acceleration: 1000.0,
        max_jerk: 1e5,
    };
    let mut limits = [None; 9];
    limits[..3].fill(Some(l));
    limits
}

/// A planner for the test machine, standing at the origin.
pub(super) fn planner() -> Planner {
    let config = PlannerConfig {
        limits: limits(),
        period: 0.001,
        tolerance: 0.01,
    };
    match Planner::new(config, Pose::ZERO) {
        Ok(p) => p,
        Err(e) => panic!("the test machine is valid: {e}"),
    }
}
