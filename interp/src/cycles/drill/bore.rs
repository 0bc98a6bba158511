//! 208 BORE MILLING: a hole milled on a helix.

use std::f64::consts::PI;

use super::common::{EPS, HoleSequence, LEN_MAX, MAX_INFEEDS, Params, Path, common};
use crate::cycles::{CycleContext, CycleError, CycleFeed, Move, ParamKey};
use crate::op::SpindleDir;

/// Cycle 208 BORE MILLING.
///
/// The hole is centred at the call position. Rapid to the set-up clearance Q200; move at
/// the milling feed Q206 from the centre to the helix start (the manual approaches on a
/// rounding arc where there is room; here a straight move at the set-up clearance, above
/// the material). The tool centre then runs on a helix of radius Q335/2 − tool radius from
/// the set-up clearance down to the depth Q201, descending Q334 per revolution. At the
/// depth one more full circle removes what the descent left, the tool returns to the centre
/// and rapids to the set-up clearance or the 2nd set-up clearance.
///
/// Direction: Q351 = +1 climb milling, −1 up-cut, for a spindle turning M3 (counter-
/// clockwise on the inside of a bore for climb milling); with M4 the direction flips. When
/// the bore diameter equals the tool diameter the tool drills straight to depth at Q206; a
/// tool wider than the bore is an error.
///
/// The helix is emitted as arcs of at most half a turn so that no arc has the same start
/// and end point in the plane. Accepted without effect on the path: Q342 (pre-drilled
/// diameter), Q370 (path overlap).
pub(super) fn bore_milling(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    const LEN: &str = "0..=99999.9999";
    const PITCH: &str = "0 < Q334 <= 99999.9999";
    let c = common(p, 201)?;
    let feed = CycleFeed::Rate(p.cut_feed(206, "feed rate for milling")?);
    let pitch = p.req(334, "infeed per helix", 0.0, LEN_MAX, PITCH)?;
    let diameter = p.req(335, "nominal diameter", 0.0, LEN_MAX, LEN)?;
    p.opt(342, 0.0, 0.0, LEN_MAX, LEN)?;
    let climb = p.opt_int(351, 1, -1, 1, "+1 (climb) or -1 (up-cut)")?;
    if climb == 0 {
        return Err(p.range_err(ParamKey::Q(351), 0.0, "+1 (climb) or -1 (up-cut)"));
    }
    p.opt(370, 1.0, 0.0001, 1.999, "0.0001..=1.999")?;
    let Some(c) = c else { return Ok(()) };
    let radius = diameter / 2.0 - ctx.tool_radius;
    if radius < -EPS {
        return Err(p.geometry(format!(
            "the tool (diameter {}) is larger than the bore Q335={diameter}",
            2.0 * ctx.tool_radius
        )));
    }
    let [ca, cb, _] = ctx.pos;
    let seq = HoleSequence::new(&c, feed);
    let bottom = seq.bottom();
    let mut path = Path::new(out, ctx.pos);
    seq.enter(&mut path, &mut ());
    if radius <= EPS {
        path.axis(bottom, feed);
        seq.finish(&mut path, &mut ());
        return Ok(());
    }
    if pitch <= 0.0 {
        return Err(p.range_err(ParamKey::Q(334), pitch, PITCH));
    }
    let ccw = (climb > 0) == (ctx.spindle != SpindleDir::Ccw);
    let sign = if ccw { 1.0 } else { -1.0 };
    let drop = (c.safe - bottom).abs();
    let turns = drop / pitch;
    let pieces = (turns * 2.0).ceil().max(1.0);
    if pieces > (2 * MAX_INFEEDS) as f64 {
        return Err(p.geometry(format!(
            "more than {MAX_INFEEDS} helix turns; increase Q334"
        )));
    }
    let pieces = pieces as usize;
    let sweep = sign * 2.0 * PI * turns / pieces as f64;
    let centre = [ca, cb];
    let on = |angle: f64, t: f64| [ca + radius * angle.cos(), cb + radius * angle.sin(), t];
    path.line(on(0.0, c.safe), feed);
    for j in 1..=pieces {
        let frac = j as f64 / pieces as f64;
        let t = c.safe + (bottom - c.safe) * frac;
        path.arc(centre, on(sweep * j as f64, t), ccw, feed);
    }
    let end = sweep * pieces as f64;
    path.arc(centre, on(end + sign * PI, bottom), ccw, feed);
    path.arc(centre, on(end + sign * 2.0 * PI, bottom), ccw, feed);
    path.line([ca, cb, bottom], feed);
    seq.finish(&mut path, &mut ());
    Ok(())
}
