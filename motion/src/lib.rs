//! klar-motion: geometry, planning, trajectory sampling and kinematics, and the axis
//! boundary trait ([`axis::AxisBackend`]) that backends implement.
//!
//! Flow: [`Planner::push`] takes canonical ops, turns motion ops into [`geom::Segment`]s,
//! blends their corners inside the path tolerance ([`blend`]), and [`Planner::next_step`]
//! moves along the blended path with a jerk-limited look-ahead speed profile under per-axis
//! limits ([`limits::path_limits`]), sampled at the servo period.
//! [`kinematics`] maps the sampled program poses to machine axes.

#![warn(missing_docs)]

pub mod axis;
pub mod blend;
pub mod comp;
pub mod config;
pub mod error;
pub mod geom;
pub mod kinematics;
pub mod limits;
pub mod planner;
pub mod profile;
pub mod tilt;

pub use axis::{
    AxisBackend, AxisFault, AxisFeedback, AxisState, BackendError, FaultOrigin, Setpoint,
    SpindleBackend, SpindleFeedback,
};
pub use config::{AxisLimits, ConfigError, PlannerConfig};
pub use error::MotionError;
pub use geom::Segment;
pub use planner::{Planner, Sample, Step};
pub use profile::{PathLimits, Ramp, SCurve};
