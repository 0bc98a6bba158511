//! Pocket, stud and face-milling cycles.
//!
//! - 251 rectangular pocket, 252 circular pocket, 253 slot: [`milled`];
//! - 254 circular slot: [`arcslot`];
//! - 256 rectangular stud, 257 circular stud: [`stud`];
//! - old cycles 4 pocket milling and 5 circular pocket: [`old`];
//! - 232 and 233 face milling: [`face`].

use super::{CycleContext, CycleError, Move, ParamSource};

mod arcslot;
mod face;
pub(super) mod geom;
mod milled;
mod old;
pub(super) mod params;
mod stud;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_more;
#[cfg(test)]
pub(super) mod testutil;

use params::Params;

/// True when this module generates cycle `number`.
pub(super) fn knows(number: u32) -> bool {
    matches!(
        number,
        4 | 5 | 232 | 233 | 251 | 252 | 253 | 254 | 256 | 257
    )
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
        4 => old::pocket(&p, ctx, out),
        5 => old::circular_pocket(&p, ctx, out),
        232 => face::face_milling(&p, ctx, out),
        233 => face::face_milling_233(&p, ctx, out),
        251 => milled::rect_pocket(&p, ctx, out),
        252 => milled::circ_pocket(&p, ctx, out),
        253 => milled::slot(&p, ctx, out),
        254 => arcslot::circular_slot(&p, ctx, out),
        256 => stud::rect_stud(&p, ctx, out),
        257 => stud::circ_stud(&p, ctx, out),
        _ => Err(CycleError::Unknown(number)),
    }
}
