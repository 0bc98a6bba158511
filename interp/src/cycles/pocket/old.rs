//! Old-format pocket cycles: 4 POCKET MILLING and 5 CIRCULAR POCKET.
//!
//! Both work about the tool position, which the program has placed over the pocket centre
//! at the set-up clearance above the workpiece surface (so the surface lies the set-up
//! clearance below the tool; the sign of the depth gives the working direction, only
//! downwards is supported). Sequence:
//! 1. The tool plunges at the centre to the first plunging depth with the feed of the
//!    cycle (straight down).
//! 2. It clears the level from the inside out at the milling feed, in closed rings whose
//!    spacing is at most the tool radius (the old cycles' stepover is the overlap factor
//!    of the machine, taken as 1, times the tool radius), the outer ring touching the
//!    wall; DR+ runs counter-clockwise, DR− clockwise. Cycle 4 rings follow the rectangle
//!    (corner radius from sub-block 4.7 when given), cycle 5 rings are circles. The tool
//!    returns to the centre.
//! 3. Steps 1–2 repeat until the depth is reached; then the tool goes at rapid traverse
//!    back up to its starting height.
//!
//! Sub-blocks: 4.1/5.1 set-up clearance, 4.2/5.2 depth, 4.3/5.3 plunging depth and
//! feed, 4.4 side length along the first axis (X word), 4.5 side length along the second
//! axis (Y word), 4.6 F and DR, 4.7 corner radius; 5.4 radius, 5.5 F and DR. The F of
//! sub-block 3 is the plunging feed, the F of 4.6 / 5.5 the milling feed; a definition
//! with one F uses it for both. Approximation: concentric rings stand in for
//! the spiral of the original cycle.

use super::super::{CycleContext, CycleError, CycleFeed, Move, ParamKey};
use super::geom::{Frame, RoundedRect};
use super::milled::{Plunge, Pocket, run};
use super::params::Params;

/// A value of sub-block `line`, position `index`.
fn old(line: u8, index: u8) -> ParamKey {
    ParamKey::Old { line, index }
}

/// A side length given as a word (`X+80`) or as the plain value of its sub-block.
fn side(p: &Params, word: &'static str, line: u8) -> Result<f64, CycleError> {
    match p.get(ParamKey::OldWord(word)) {
        Some(v) => Ok(v),
        None => p.req(old(line, 0), "side length"),
    }
}

/// Cycle 4.
pub(super) fn pocket(
    p: &Params,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let l1 = side(p, "X", 4)?.abs();
    let l2 = side(p, "Y", 5)?.abs();
    if !(l1 > 0.0 && l2 > 0.0) {
        return Err(p.geometry("the side lengths must be greater than 0"));
    }
    let rc = p.get(old(7, 0)).unwrap_or(0.0).abs();
    if rc > l1.min(l2) / 2.0 {
        return Err(p.range(old(7, 0), rc, "0 to half the shorter side"));
    }
    let shape = RoundedRect {
        ha: l1 / 2.0,
        hb: l2 / 2.0,
        rc,
    };
    common(p, ctx, shape, out)
}

/// Cycle 5.
pub(super) fn circular_pocket(
    p: &Params,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let radius = p.req(old(4, 0), "circle radius")?.abs();
    if radius.is_nan() || radius <= 0.0 {
        return Err(p.range(old(4, 0), radius, "greater than 0"));
    }
    let shape = RoundedRect {
        ha: radius,
        hb: radius,
        rc: radius,
    };
    common(p, ctx, shape, out)
}

/// The part shared by cycles 4 and 5.
fn common(
    p: &Params,
    ctx: &CycleContext,
    shape: RoundedRect,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let clear = p.req(old(1, 0), "set-up clearance")?.abs();
    let depth = p.req(old(2, 0), "depth")?;
    if depth > 0.0 {
        return Err(p.range(old(2, 0), depth, "negative (working downwards)"));
    }
    let infeed = p.req(old(3, 0), "plunging depth")?.abs();
    if infeed.is_nan() || infeed <= 0.0 {
        return Err(p.range(old(3, 0), infeed, "greater than 0"));
    }
    let f = p
        .get(ParamKey::OldWord("F"))
        .ok_or_else(|| CycleError::Missing {
            cycle: p.cycle,
            param: "F".to_string(),
            what: "feed rate",
        })?;
    let feed = p.feed_value(ParamKey::OldWord("F"), f, true)?;
    let feed_of = |line: u8| -> Result<CycleFeed, CycleError> {
        let key = ParamKey::OldFeed { line };
        match p.get(key) {
            Some(v) => p.feed_value(key, v, true),
            None => Ok(feed),
        }
    };
    let f_plunge = feed_of(3)?;
    let f_mill = feed_of(if p.cycle == 4 { 6 } else { 5 })?;
    let ccw = p.get(ParamKey::OldWord("DR")).unwrap_or(1.0) >= 0.0;
    if depth == 0.0 {
        return Ok(());
    }
    let r = ctx.tool_radius;
    if !(r.is_finite() && r > 0.0) {
        return Err(CycleError::ToolRadius {
            cycle: p.cycle,
            radius: r,
        });
    }
    if shape.half_min() < r {
        return Err(p.geometry(format!(
            "the tool (diameter {}) is larger than the pocket (width {})",
            2.0 * r,
            2.0 * shape.half_min()
        )));
    }
    let pk = Pocket {
        cycle: p.cycle,
        shape,
        frame: Frame::new([ctx.pos[0], ctx.pos[1]], 0.0),
        op: 1,
        surface: ctx.pos[2] - clear,
        depth,
        infeed,
        finish_infeed: 0.0,
        clear,
        clear2: clear,
        side: 0.0,
        floor: 0.0,
        stepover: r,
        ccw,
        plunge: Plunge::Vertical,
        f_plunge,
        f_mill,
        f_finish: CycleFeed::Rapid,
    };
    run(&pk, ctx, out)
}
