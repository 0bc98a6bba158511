//! Lathe DIN PLUS programs (CNC PILOT / MANUALplus / smart.Turn, `.nc`): line syntax,
//! program sections, variables, control structures and local subprograms, the lathe's modal
//! state, face and lateral hole patterns with their drilling/milling cycles, the face contour
//! cycle G793, the FINISHED PART contour with its finishing, roughing and recessing cycles, and the
//! LATERAL_Y / SURFACE_Y working plane.
//!
//! Ops of lathe programs carry X as a **radius**: the interpreter halves the programmed
//! diameter, so the geometry in ops is machine-independent and the lathe kinematics maps
//! X/Z/C/Y/B without a diameter factor.

pub mod block;
pub(crate) mod contour;
pub(crate) mod control;
pub(crate) mod cycles;
pub(crate) mod exec;
pub mod expr;
pub(crate) mod external;
pub(crate) mod facemill;
pub mod flow;
pub(crate) mod grooving;
pub(crate) mod lateral;
pub(crate) mod lathe;
pub(crate) mod parallel;
pub mod pattern;
pub(crate) mod recess_offset;
pub(crate) mod recess_turn;
pub(crate) mod roughing;
pub(crate) mod run;
pub(crate) mod thread;
pub(crate) mod thread_cycle;
pub mod tilt;
pub mod unknown;

pub use cycles::{face_in_turned, face_pose};
pub use lathe::TOOL_CHANGE_POINT;
pub use pattern::{CircleLayout, PatternEnd};
pub use run::Section;
pub use tilt::LateralPlane;
