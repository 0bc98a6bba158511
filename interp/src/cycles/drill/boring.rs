//! Boring with a single-edge boring bar: 202 BORING and 204 BACK BORING.
//!
//! A boring bar must not drag its cutting edge over the finished wall on the way out. Both
//! cycles therefore stop the spindle *oriented* (at the angle Q336, so that the edge points
//! in a known direction) and move the tool sideways, away from the wall, before it travels
//! along the tool axis without cutting; once out of the hole the tool returns to the hole
//! centre and the spindle turns again as it did at the call.
//!
//! The oriented spindle stop is emitted as a spindle stop ([`Move::Spindle`] with
//! [`SpindleDir::Off`]): the moves carry no spindle angle, so Q336 is range-checked but has
//! no effect on the output. A stop is emitted only while the spindle turns.
//!
//! Q214 gives the direction of that sideways move in the working plane, the same for both
//! cycles: 1 towards the negative reference axis (−X for tool axis Z), 2 towards the negative
//! minor axis (−Y), 3 towards the positive reference axis (+X), 4 towards the positive minor
//! axis (+Y); 0 (cycle 202 only) means no sideways move. The programmer chooses Q214 and
//! Q336 together so that the move takes the edge away from the wall.

use super::common::{
    Common, Hole, HoleSequence, HoleSteps, LEN_MAX, Params, Path, common, cutting,
    set_up_clearance, surface_and_second,
};
use crate::cycles::{CycleContext, CycleError, CycleFeed, Move, ParamKey};
use crate::op::SpindleDir;

/// How far cycle 202 moves the edge off the wall at the bottom of the hole, mm (a fixed
/// value in the manual).
const DISENGAGE: f64 = 0.2;

/// Reads Q214: the unit vector `(a, b)` of the disengaging direction in the working plane,
/// `None` for 0 (allowed only when `allow_none`).
fn disengaging_direction(p: &Params<'_>, allow_none: bool) -> Result<Option<[f64; 2]>, CycleError> {
    let (lo, range) = if allow_none {
        (
            0,
            "0 (none), 1 (-ref. axis), 2 (-minor axis), 3 (+ref. axis), 4 (+minor axis)",
        )
    } else {
        (
            1,
            "1 (-ref. axis), 2 (-minor axis), 3 (+ref. axis), 4 (+minor axis)",
        )
    };
    let v = p.req_int(214, "disengaging direction", lo, 4, range)?;
    Ok(match v {
        1 => Some([-1.0, 0.0]),
        2 => Some([0.0, -1.0]),
        3 => Some([1.0, 0.0]),
        4 => Some([0.0, 1.0]),
        _ => None,
    })
}

/// Reads Q336, the angle of the oriented spindle stop (0 when absent: the parameter came
/// with later software versions).
fn orientation_angle(p: &Params<'_>) -> Result<f64, CycleError> {
    p.opt(336, 0.0, 0.0, 360.0, "0..=360")
}

/// The spindle and the sideways moves of a boring cycle at one hole centred at `centre`.
struct Bar {
    /// Hole centre in the working plane.
    centre: [f64; 2],
    /// Sideways offset from the centre while the edge is off the wall (zero: none).
    offset: [f64; 2],
    /// Feed of the sideways move at the bottom.
    feed: CycleFeed,
    /// Spindle direction at the call.
    call: SpindleDir,
    /// Spindle direction now.
    now: SpindleDir,
}

impl Bar {
    /// A bar at the call position of `ctx`, moved `dist` along `dir` (none when `None`).
    fn new(ctx: &CycleContext, dir: Option<[f64; 2]>, dist: f64, feed: CycleFeed) -> Self {
        let [da, db] = dir.unwrap_or([0.0, 0.0]);
        Bar {
            centre: [ctx.pos[0], ctx.pos[1]],
            offset: [da * dist, db * dist],
            feed,
            call: ctx.spindle,
            now: ctx.spindle,
        }
    }

    /// Switches the spindle to `d` unless it already runs (or stands) that way.
    fn spindle(&mut self, path: &mut Path<'_>, d: SpindleDir) {
        if d != self.now {
            path.spindle(d);
            self.now = d;
        }
    }

    /// Oriented spindle stop, then the sideways move off the wall at `feed`.
    fn disengage(&mut self, path: &mut Path<'_>, feed: CycleFeed) {
        self.spindle(path, SpindleDir::Off);
        let [ca, cb] = self.centre;
        path.plane(ca + self.offset[0], cb + self.offset[1], feed);
    }

    /// Back to the hole centre at `feed`.
    fn centre(&self, path: &mut Path<'_>, feed: CycleFeed) {
        path.plane(self.centre[0], self.centre[1], feed);
    }
}

impl HoleSteps for Bar {
    fn at_bottom(&mut self, path: &mut Path<'_>) {
        self.disengage(path, self.feed);
    }

    fn before_top(&mut self, path: &mut Path<'_>) {
        self.centre(path, CycleFeed::Rapid);
        self.spindle(path, self.call);
    }
}

/// Cycle 202 BORING.
///
/// Rapid to the set-up clearance Q200 above the surface Q203; bore at the plunging feed Q206
/// to the depth Q201; dwell Q211 with the spindle turning (to cut free); oriented spindle
/// stop at the angle Q336; move the edge [`DISENGAGE`] mm off the wall in the direction
/// Q214 (none with Q214 = 0: the edge then stays on the wall on the way out); retract at
/// Q208 to the set-up clearance (Q208 = 0 or absent: at Q206; FMAX allowed); back to the
/// hole centre; the spindle turns again as at the call; rapid to the 2nd set-up clearance
/// Q204 when that is larger. The sideways move at the bottom runs at the retraction feed.
pub(super) fn boring(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let c = common(p, 201)?;
    let feed = p.plunge_feed()?;
    let dwell = p.dwell(211)?;
    let retract = p.move_feed(208)?.flatten().unwrap_or(feed);
    let dir = disengaging_direction(p, true)?;
    orientation_angle(p)?;
    let Some(c) = c else { return Ok(()) };
    HoleSequence::new(&c, feed)
        .dwell(dwell)
        .retract(retract)
        .run(
            &mut Path::new(out, ctx.pos),
            &mut Bar::new(ctx, dir, DISENGAGE, retract),
        );
    Ok(())
}

/// Cycle 204 BACK BORING: a counterbore cut upwards from the far side of the workpiece
/// through an existing hole, with a boring bar whose edge sticks out sideways.
///
/// Geometry along the tool axis: the surface Q203 is the face the tool comes from, the
/// far face lies the material thickness Q250 behind it, and the counterbore goes the depth
/// Q249 from the far face back into the material. The tool length is measured to the
/// underside of the bar; its edge sits the tool edge height Q252 above that. The sign of
/// Q249 gives the direction the counterbore is cut in: positive towards the positive tool
/// axis (the tool comes from above), negative mirrors everything, like a positive depth in
/// the other drilling cycles.
///
/// Sequence: rapid to the set-up clearance Q200 above the surface; oriented spindle stop
/// (Q336) and a rapid sideways move by the off-centre distance Q251 in the direction Q214;
/// through the hole at the pre-positioning feed Q253 (FMAX allowed) until the edge is the
/// set-up clearance beyond the far face; back to the centre at Q253; spindle on (as at the
/// call, M3 when it was stopped); counterbore at Q254 until the edge is Q249 deep; dwell
/// Q255; oriented stop again and the sideways move by Q251 at Q253; out of the hole at Q253
/// to the set-up clearance; back to the centre; the spindle as at the call; rapid to the
/// 2nd set-up clearance Q204 when that is larger.
///
/// Ranges: Q250, Q251 and Q252 must be positive, Q249 not 0 and smaller in size than Q250
/// (the counterbore ends inside the material), Q214 1..4 (without a sideways move the bar
/// cannot pass the hole), Q253 positive or FMAX, Q254 positive.
pub(super) fn back_boring(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    const POS: &str = "0.0001..=99999.9999";
    const DEPTH: &str = "-99999.9999..=99999.9999, not 0";
    const PRE: &str = "0 < Q253 <= 99999.999 mm/min or FMAX";
    let clearance = set_up_clearance(p)?;
    let depth = p.req(249, "depth of counterbore", -LEN_MAX, LEN_MAX, DEPTH)?;
    if depth == 0.0 {
        return Err(p.range_err(ParamKey::Q(249), depth, DEPTH));
    }
    let thickness = p.req(250, "material thickness", 0.0001, LEN_MAX, POS)?;
    let off_centre = p.req(251, "off-center distance", 0.0001, LEN_MAX, POS)?;
    let edge = p.req(252, "tool edge height", 0.0001, LEN_MAX, POS)?;
    let pre = match p.move_feed(253)? {
        Some(Some(f)) => f,
        Some(None) => return Err(p.range_err(ParamKey::Q(253), 0.0, PRE)),
        None => {
            return Err(CycleError::Missing {
                cycle: p.cycle,
                param: "Q253".into(),
                what: "feed rate for pre-positioning",
            });
        }
    };
    let cut = CycleFeed::Rate(p.cut_feed(254, "feed rate for counterboring")?);
    let dwell = p.dwell(255)?;
    let (surface, second) = surface_and_second(p)?;
    let dir = disengaging_direction(p, false)?;
    orientation_angle(p)?;
    if depth.abs() >= thickness {
        return Err(p.geometry(format!(
            "the counterbore depth Q249={depth} does not end inside the material thickness Q250={thickness}"
        )));
    }
    // "into the material" is against the direction the counterbore is cut in; the far
    // face lies `thickness` into the material, the tool tip `edge` beyond the edge
    let hole = Hole {
        surface,
        dir: -depth.signum(),
        depth: thickness,
    };
    let c = Common::new(hole, clearance, second);
    let through = hole.at(thickness + clearance + edge);
    let counterbore = hole.at(thickness - depth.abs() + edge);
    let seq = HoleSequence::new(&c, cut).dwell(dwell).retract(pre);
    let mut bar = Bar::new(ctx, dir, off_centre, pre);
    let mut path = Path::new(out, ctx.pos);
    seq.enter(&mut path, &mut ());
    bar.disengage(&mut path, CycleFeed::Rapid);
    path.axis(through, pre);
    bar.centre(&mut path, pre);
    bar.spindle(&mut path, cutting(ctx.spindle));
    path.axis(counterbore, cut);
    seq.finish(&mut path, &mut bar);
    Ok(())
}
