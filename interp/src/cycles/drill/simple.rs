//! Single-infeed cycles: 201 REAMING, 240 CENTERING, 241 SINGLE-LIP DEEP-HOLE DRILLING.

use super::common::{HoleSteps, LEN_MAX, Params, Path, cutting, deepened_start, plunged};
use crate::cycles::{CycleContext, CycleError, Move, ParamKey};
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
    let seq = plunged(p)?;
    let dwell = p.dwell(211)?;
    let retract = p.move_feed(208)?.flatten();
    let Some(seq) = seq else { return Ok(()) };
    seq.dwell(dwell)
        .retract(retract.unwrap_or(seq.feed))
        .run(&mut Path::new(out, ctx.pos), &mut ());
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
    let seq = plunged(p)?;
    let dwell = p.dwell(211)?;
    let Some(seq) = seq else { return Ok(()) };
    seq.dwell(dwell).run(&mut Path::new(out, ctx.pos), &mut ());
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
    let seq = plunged(p)?;
    let dwell = p.dwell(211)?;
    let deep_start = p.opt(379, 0.0, 0.0, LEN_MAX, LEN)?;
    let pre = p.move_feed(253)?.flatten();
    let retract = p.move_feed(208)?.flatten();
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
    let Some(seq) = seq else { return Ok(()) };
    let (c, feed) = (seq.c, seq.feed);
    deepened_start(p, deep_start, &c)?;
    let (pre, retract) = (pre.unwrap_or(feed), retract.unwrap_or(feed));
    let drill = cutting(ctx.spindle);
    let seq = seq.dwell(dwell).retract(retract);
    let mut spindle = EntrySpindle {
        now: ctx.spindle,
        entry: entry.unwrap_or(ctx.spindle),
    };
    let mut path = Path::new(out, ctx.pos);
    seq.enter(&mut path, &mut spindle);
    if deep_start > 0.0 {
        path.axis(c.hole.at(deep_start - c.clearance), pre);
    }
    spindle.set(&mut path, drill);
    if dwell_depth > deep_start && dwell_depth < c.hole.depth {
        path.axis(c.hole.at(dwell_depth), feed);
        path.dwell(dwell);
    }
    path.axis(seq.bottom(), feed);
    seq.finish(&mut path, &mut spindle);
    spindle.set(&mut path, ctx.spindle);
    Ok(())
}

/// The spindle of cycle 241: switched to the entry/exit direction at the set-up clearance
/// and again at the bottom before the retraction; a switch to the direction it already
/// turns in emits nothing.
struct EntrySpindle {
    /// Direction now.
    now: SpindleDir,
    /// Entry/exit direction (Q426).
    entry: SpindleDir,
}

impl EntrySpindle {
    /// Switches to `d` unless the spindle already turns that way.
    fn set(&mut self, path: &mut Path<'_>, d: SpindleDir) {
        if d != self.now {
            path.spindle(d);
            self.now = d;
        }
    }
}

impl HoleSteps for EntrySpindle {
    fn at_clearance(&mut self, path: &mut Path<'_>) {
        self.set(path, self.entry);
    }

    fn at_bottom(&mut self, path: &mut Path<'_>) {
        self.set(path, self.entry);
    }
}
