//! Corner blending: curvature-continuous transition curves that replace a corner (or a jump
//! of curvature) between two path elements, inside the active path tolerance.
//!
//! A blend is a quintic Hermite curve ([`Quintic`]) that starts and ends with the position,
//! unit tangent and curvature vector of the path where it joins it, so position, direction
//! and curvature are continuous along the blended path (G2). [`corner`] builds one between
//! two elements and checks its distance from the programmed contour.

mod bounds;
pub mod corner;
pub mod memo;
pub mod pool;
pub mod quintic;

pub use corner::{ContourPart, blend_within, distance_to_part};
pub use memo::{BoundsMemo, MEMO_SLOTS};
pub use pool::{BLEND_SLOTS, BlendPool};
pub use quintic::Quintic;
