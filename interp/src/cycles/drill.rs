//! Drilling, boring and tapping cycles.
//!
//! Every generator starts where the caller positioned the tool (`ctx.pos`; the hole is at
//! its `a, b`) and works along the tool axis. Shared rules, from the HEIDENHAIN cycle
//! descriptions:
//!
//! - Q200 set-up clearance is measured from the surface Q203; Q204 2nd set-up clearance too,
//!   and it only takes effect when it is larger than Q200. The cycle first moves at FMAX to
//!   the set-up clearance and ends at the set-up clearance or, when larger, at the 2nd
//!   set-up clearance.
//! - The sign of the depth gives the working direction. With a positive depth the clearance
//!   heights are mirrored as well (the manual warns that the tool then rapids to the set-up
//!   clearance *below* the surface). A depth of 0 means the cycle is not run: no motion.
//! - Feeds are mm/min in the definition, dwell times seconds. See [`common`] for FMAX and
//!   FAUTO.
//! - The only rapid moves below the set-up clearance re-enter a hole that is already cut,
//!   stopping short of the depth reached so far (pecking), follow a deepened starting
//!   point the programmer declared pre-drilled, or pass through the existing hole of a back
//!   boring (204) when its pre-positioning feed is FMAX.
//!
//! Old-format cycles 1 and 2 have no surface parameter: they start at the current tool
//! position, which the program puts at the set-up clearance above the surface.

use super::{CycleContext, CycleError, Move, ParamSource};

mod bore;
mod boring;
pub(super) mod common;
mod peck;
mod simple;
mod tap;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_boring;
#[cfg(test)]
mod tests_program;
#[cfg(test)]
pub(super) mod testutil;

use common::Params;

/// True when this module generates cycle `number`.
pub(super) fn knows(number: u32) -> bool {
    matches!(
        number,
        1 | 2 | 200 | 201 | 202 | 203 | 204 | 205 | 206 | 207 | 208 | 209 | 240 | 241
    )
}

/// True when `number` is an old-format cycle (sub-blocks `n.1`, `n.2`, … instead of Q
/// parameters) that starts at the current tool position.
pub(super) fn is_old_format(number: u32) -> bool {
    number < 200
}

/// Appends the motion of cycle `number` to `out` (see [`super::generate`]).
pub(super) fn generate(
    number: u32,
    p: &dyn ParamSource,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let p = Params::new(number, p);
    match number {
        1 => peck::old_pecking(&p, ctx, out),
        2 => tap::old_tapping(&p, ctx, out),
        200 => peck::drilling(&p, ctx, out),
        201 => simple::reaming(&p, ctx, out),
        202 => boring::boring(&p, ctx, out),
        203 => peck::universal_drilling(&p, ctx, out),
        204 => boring::back_boring(&p, ctx, out),
        205 => peck::universal_pecking(&p, ctx, out),
        206 => tap::tapping(&p, ctx, out),
        207 => tap::rigid_tapping(&p, ctx, out),
        208 => bore::bore_milling(&p, ctx, out),
        209 => tap::tapping_chip_breaking(&p, ctx, out),
        240 => simple::centering(&p, ctx, out),
        241 => simple::single_lip(&p, ctx, out),
        _ => Err(CycleError::Unknown(number)),
    }
}
