//! Pocket, stud and face-milling cycles.

use super::{CycleContext, CycleError, Move, ParamSource};

/// True when this module generates cycle `number`.
pub(super) fn knows(number: u32) -> bool {
    let _ = number;
    false
}

/// Appends the motion of cycle `number` to `out` (see [`super::generate`]).
pub(super) fn generate(
    number: u32,
    p: &dyn ParamSource,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let _ = (p, ctx, out);
    Err(CycleError::Unknown(number))
}
