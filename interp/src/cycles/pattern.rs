//! Point patterns: cycles 220 and 221, and the points of PATTERN DEF.

use super::{CycleContext, CycleError, Move, P3, ParamSource};

/// True when `number` is a pattern cycle.
pub(super) fn knows(number: u32) -> bool {
    let _ = number;
    false
}

/// See [`super::generate_pattern`].
pub(super) fn generate(
    pattern: u32,
    pp: &dyn ParamSource,
    machining: u32,
    mp: &dyn ParamSource,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let _ = (pp, machining, mp, ctx, out);
    Err(CycleError::Unknown(pattern))
}

/// See [`super::generate_at_points`].
pub(super) fn at_points(
    points: &[P3],
    machining: u32,
    mp: &dyn ParamSource,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let _ = (points, mp, ctx, out);
    Err(CycleError::Unknown(machining))
}
