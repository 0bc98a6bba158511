//! Single-infeed cycles: 201 REAMING, 240 CENTERING, 241 SINGLE-LIP DEEP-HOLE DRILLING.

use super::common::{LEN_MAX, Params, Path, common};
use crate::cycles::{CycleContext, CycleError, CycleFeed, Move, ParamKey};
use crate::op::SpindleDir;

/// Cycle 201 REAMING.
///
/// Rapid to the set-up clearance Q200; ream at Q206 to the depth Q201 in one move; dwell
/// Q211 at the bottom; retract at Q208 to the set-up clearance (Q208 = 0 or absent: at the
/// reaming feed, FMAX allowed); rapid to the 2nd set-up clearance Q204 when that is larger.
pub(super) fn reaming(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let c = common(p, 201)?;
    let feed = CycleFeed::Rate(p.cut_feed(206, "feed rate for plunging")?);
    let dwell = p.dwell(211)?;
    let retract = p.move_feed(208)?.flatten().unwrap_or(feed);
    let Some(c) = c else { return Ok(()) };
    let mut path = Path::new(out, ctx.pos);
    path.rapid_axis(c.safe);
    path.axis(c.hole.at(c.hole.depth), feed);
    path.dwell(dwell);
    path.axis(c.safe, retract);
    path.rapid_axis(c.top);
    Ok(())
}

/// Cycle 240 CENTERING.
///
/// Rapid to the set-up clearance; center at Q206 to the depth Q201; dwell Q211; rapid to
/// the set-up clearance or the 2nd set-up clearance. Q343 = 1 (depth from the countersink
/// diameter Q344) needs the tool's point angle, which the cycle context does not carry, so it
/// is refused with a clear message.
pub(super) fn centering(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let by_diameter = p.opt_int(343, 0, 0, 1, "0 (depth) or 1 (diameter)")?;
    if by_diameter == 1 {
        return Err(p.geometry(
            "Q343=1 (centering to a diameter) needs the tool's point angle, which is not known; program the depth (Q343=0)",
        ));
    }
    let c = common(p, 201)?;
    let feed = CycleFeed::Rate(p.cut_feed(206, "feed rate for plunging")?);
    let dwell = p.dwell(211)?;
    let Some(c) = c else { return Ok(()) };
    let mut path = Path::new(out, ctx.pos);
    path.rapid_axis(c.safe);
    path.axis(c.hole.at(c.hole.depth), feed);
    path.dwell(dwell);
    path.rapid_axis(c.top);
    Ok(())
}

/// Cycle 241 SINGLE-LIP DEEP-HOLE DRILLING (main parameters).
///
/// Rapid to the set-up clearance; switch the spindle to the entry/exit direction Q426
/// (3 = M3, 4 = M4, 5 = stopped; absent: unchanged). With a deepened starting point Q379
/// move at the pre-positioning feed Q253 (FMAX allowed; absent: Q206) to the set-up
/// clearance above it. Switch the spindle to the drilling direction (the direction at the
/// call, M3 when the spindle was stopped) and drill at Q206 to the depth Q201, with a dwell
/// Q211 at the dwell depth Q435 when one is given and at the bottom. Switch back to the exit
/// direction, retract at Q208 (0 or absent: Q206) to the set-up clearance, rapid to the 2nd
/// set-up clearance and restore the spindle direction of the call.
///
/// Left out: the spindle speeds Q427/Q428 (a [`Move::Spindle`] carries only the direction),
/// the coolant M functions Q429/Q430, and the pecking parameters of later versions
/// (Q202/Q212/Q205: the hole is drilled in one infeed).
pub(super) fn single_lip(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    const LEN: &str = "0..=99999.9999";
    let c = common(p, 201)?;
    let feed = CycleFeed::Rate(p.cut_feed(206, "feed rate for plunging")?);
    let dwell = p.dwell(211)?;
    let deep_start = p.opt(379, 0.0, 0.0, LEN_MAX, LEN)?;
    let pre = p.move_feed(253)?.flatten().unwrap_or(feed);
    let retract = p.move_feed(208)?.flatten().unwrap_or(feed);
    let entry = match p.raw(ParamKey::Q(426)) {
        None => None,
        Some(_) => match p.opt_int(426, 3, 3, 5, "3 (M3), 4 (M4) or 5 (stopped)")? {
            3 => Some(SpindleDir::Cw),
            4 => Some(SpindleDir::Ccw),
            _ => Some(SpindleDir::Off),
        },
    };
    p.opt(427, 0.0, 0.0, 99_999.0, "0..=99999 rpm")?;
    p.opt(428, 0.0, 0.0, 99_999.0, "0..=99999 rpm")?;
    p.opt(429, 0.0, 0.0, 999.0, "0..=999")?;
    p.opt(430, 0.0, 0.0, 999.0, "0..=999")?;
    let dwell_depth = p.opt(435, 0.0, 0.0, LEN_MAX, LEN)?;
    let Some(c) = c else { return Ok(()) };
    if deep_start >= c.hole.depth {
        return Err(p.geometry(format!(
            "the deepened starting point Q379={deep_start} is not above the depth {}",
            c.hole.depth
        )));
    }
    let entry = entry.unwrap_or(ctx.spindle);
    let drill = if ctx.spindle == SpindleDir::Off {
        SpindleDir::Cw
    } else {
        ctx.spindle
    };
    let mut spindle = ctx.spindle;
    let mut path = Path::new(out, ctx.pos);
    let mut set = |path: &mut Path<'_>, d: SpindleDir| {
        if d != spindle {
            path.spindle(d);
            spindle = d;
        }
    };
    path.rapid_axis(c.safe);
    set(&mut path, entry);
    if deep_start > 0.0 {
        path.axis(c.hole.at(deep_start - c.clearance), pre);
    }
    set(&mut path, drill);
    if dwell_depth > deep_start && dwell_depth < c.hole.depth {
        path.axis(c.hole.at(dwell_depth), feed);
        path.dwell(dwell);
    }
    path.axis(c.hole.at(c.hole.depth), feed);
    path.dwell(dwell);
    set(&mut path, entry);
    path.axis(c.safe, retract);
    path.rapid_axis(c.top);
    set(&mut path, ctx.spindle);
    Ok(())
}
