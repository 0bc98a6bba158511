//! SL contour cycles 20–24 on the contours of cycle 14.

use super::{Contour, CycleContext, CycleError, Move, ParamSource};

/// True when `number` is an SL machining cycle this module generates.
pub(super) fn knows(number: u32) -> bool {
    let _ = number;
    false
}

/// See [`super::generate_sl`].
pub(super) fn generate(
    cycle: u32,
    contours: &[Contour],
    p20: &dyn ParamSource,
    p: &dyn ParamSource,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let _ = (contours, p20, p, ctx, out);
    Err(CycleError::Unknown(cycle))
}
