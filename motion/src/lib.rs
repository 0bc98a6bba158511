//! klar-motion: geometry, planning, trajectory sampling and kinematics, and the axis
//! boundary trait ([`axis::AxisBackend`]) that backends implement.

pub mod axis;

pub use axis::{
    AxisBackend, AxisFault, AxisFeedback, AxisState, BackendError, Setpoint, SpindleBackend,
    SpindleFeedback,
};
