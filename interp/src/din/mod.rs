//! Lathe DIN PLUS programs (CNC PILOT / MANUALplus / smart.Turn, `.nc`): line syntax,
//! program sections, the lathe's modal state, face patterns and drilling/milling cycles, and
//! the LATERAL_Y / SURFACE_Y working plane.
//!
//! Ops of lathe programs carry X as a **radius**: the interpreter halves the programmed
//! diameter, so the geometry in ops is machine-independent and the lathe kinematics maps
//! X/Z/C/Y/B without a diameter factor.

pub mod block;
pub(crate) mod contour;
pub(crate) mod cycles;
pub(crate) mod exec;
pub(crate) mod lathe;
pub mod pattern;
pub(crate) mod run;
pub mod tilt;

pub use cycles::{face_in_turned, face_pose};
pub use lathe::TOOL_CHANGE_POINT;
pub use pattern::{CircleLayout, PatternEnd};
pub use run::Section;
pub use tilt::LateralPlane;
