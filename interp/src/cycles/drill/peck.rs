//! Drilling with several infeeds: 200 DRILLING, 203 UNIVERSAL DRILLING, 205 UNIVERSAL
//! PECKING and the old cycle 1 PECKING.

use super::common::{
    EPS, HoleSequence, LEN_MAX, MAX_INFEEDS, Params, Path, deepened_start, depth_reference_tip,
    infeed_depths, old_common, old_dwell, old_key, plunged,
};
use crate::cycles::{CycleContext, CycleError, CycleFeed, Move, ParamKey};

/// Reads Q202 (plunging depth), which must be positive.
fn plunging_depth(p: &Params<'_>) -> Result<f64, CycleError> {
    const RANGE: &str = "0 < Q202 <= 99999.9999";
    let v = p.req(202, "plunging depth", 0.0, LEN_MAX, RANGE)?;
    if v <= 0.0 {
        return Err(p.range_err(ParamKey::Q(202), v, RANGE));
    }
    Ok(v)
}

/// Cycle 200 DRILLING.
///
/// Sequence: rapid to the set-up clearance Q200 above the surface Q203; drill at Q206 by
/// one plunging depth Q202; rapid back to the set-up clearance, dwell Q210 there, rapid down
/// again to the set-up clearance above the depth just reached, and drill the next infeed;
/// repeat until the depth Q201 is reached (a plunging depth of at least the full depth drills
/// in one move). Dwell Q211 at the bottom, then rapid out to the set-up clearance or the 2nd
/// set-up clearance Q204.
pub(super) fn drilling(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let seq = plunged(p)?;
    let plunge = plunging_depth(p)?;
    let dwell_top = p.dwell(210)?;
    let dwell_bottom = p.dwell(211)?;
    depth_reference_tip(p)?;
    let Some(seq) = seq else { return Ok(()) };
    let (c, feed) = (seq.c, seq.feed);
    let depths = infeed_depths(p, 0.0, c.hole.depth, plunge, 0.0, 0.0)?;
    let seq = seq.dwell(dwell_bottom);
    let mut path = Path::new(out, ctx.pos);
    seq.enter(&mut path, &mut ());
    for (i, &d) in depths.iter().enumerate() {
        path.axis(c.hole.at(d), feed);
        if i + 1 == depths.len() {
            break;
        }
        path.rapid_axis(c.safe);
        path.dwell(dwell_top);
        path.rapid_axis(c.hole.at(d - c.clearance));
    }
    seq.finish(&mut path, &mut ());
    Ok(())
}

/// Cycle 203 UNIVERSAL DRILLING.
///
/// Like 200, with three additions. Each infeed after the first is smaller by the decrement
/// Q212, but not smaller than the minimum plunging depth Q205. With Q213 > 0 the tool does
/// not leave the hole after every infeed: after an infeed it backs off by Q256 (chip
/// breaking) and drills on, and only after Q213 such chip breaks the next retraction goes
/// all the way to the set-up clearance (dwell Q210 there, rapid down to the set-up
/// clearance above the depth reached). Retractions inside the hole and out of it run at
/// Q208 (0 or absent: at the plunging feed Q206, FMAX allowed). At the bottom: dwell Q211,
/// retract at Q208 to the set-up clearance, then rapid to the 2nd set-up clearance.
pub(super) fn universal_drilling(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let seq = plunged(p)?;
    let plunge = plunging_depth(p)?;
    let dwell_top = p.dwell(210)?;
    let decrement = p.opt(212, 0.0, 0.0, LEN_MAX, "0..=99999.9999")?;
    let breaks = p.opt_int(213, 0, 0, 99_999, "0..=99999")?;
    let min_plunge = p.opt(205, 0.0, 0.0, LEN_MAX, "0..=99999.9999")?;
    let dwell_bottom = p.dwell(211)?;
    let retract = p.move_feed(208)?.flatten();
    let chip = p.opt(256, 0.2, 0.0, LEN_MAX, "0..=99999.9999")?;
    depth_reference_tip(p)?;
    let Some(seq) = seq else { return Ok(()) };
    let (c, feed) = (seq.c, seq.feed);
    let retract = retract.unwrap_or(feed);
    let depths = infeed_depths(p, 0.0, c.hole.depth, plunge, decrement, min_plunge)?;
    let seq = seq.dwell(dwell_bottom).retract(retract);
    let mut path = Path::new(out, ctx.pos);
    seq.enter(&mut path, &mut ());
    let mut done_breaks = 0;
    for (i, &d) in depths.iter().enumerate() {
        path.axis(c.hole.at(d), feed);
        if i + 1 == depths.len() {
            break;
        }
        if done_breaks < breaks {
            done_breaks += 1;
            path.axis(c.hole.at(d - chip), retract);
        } else {
            done_breaks = 0;
            path.axis(c.safe, retract);
            path.dwell(dwell_top);
            path.rapid_axis(c.hole.at(d - c.clearance));
        }
    }
    seq.finish(&mut path, &mut ());
    Ok(())
}

/// Cycle 205 UNIVERSAL PECKING.
///
/// Rapid to the set-up clearance. With a deepened starting point Q379 (a pre-drilled pilot
/// hole) the tool moves at the pre-positioning feed Q253 (FMAX allowed; absent: Q206) to
/// the set-up clearance above that point and the infeeds count from there. Each infeed runs
/// at Q206; infeeds shrink by Q212 down to Q205 as in 203. With Q257 > 0 the tool backs off
/// by Q256 after every Q257 of drilling inside one infeed (chip breaking). After each infeed
/// the tool leaves the hole to the set-up clearance and comes back at FMAX to an advanced
/// stop distance above the depth reached: Q258 before the first re-entry, Q259 before the
/// last, changing evenly in between. At the bottom: dwell Q211, retract to the set-up
/// clearance, rapid to the 2nd set-up clearance. Retractions run at Q208 (absent: FMAX as
/// in the first versions of the cycle; 0: at Q206).
///
/// Approximations: how the control spreads the advanced stop distance over the re-entries
/// is not specified beyond "evenly"; the even spread is per re-entry.
pub(super) fn universal_pecking(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    const LEN: &str = "0..=99999.9999";
    let seq = plunged(p)?;
    let plunge = plunging_depth(p)?;
    let decrement = p.opt(212, 0.0, 0.0, LEN_MAX, LEN)?;
    let min_plunge = p.opt(205, 0.0, 0.0, LEN_MAX, LEN)?;
    let upper = p.req(258, "upper advanced stop distance", 0.0, LEN_MAX, LEN)?;
    let lower = p.req(259, "lower advanced stop distance", 0.0, LEN_MAX, LEN)?;
    let chip_every = p.opt(257, 0.0, 0.0, LEN_MAX, LEN)?;
    let chip = p.opt(256, 0.2, 0.0, LEN_MAX, LEN)?;
    let dwell_bottom = p.dwell(211)?;
    let deep_start = p.opt(379, 0.0, 0.0, LEN_MAX, LEN)?;
    let pre = p.move_feed(253)?.flatten();
    let retract = p.move_feed(208)?;
    depth_reference_tip(p)?;
    let Some(seq) = seq else { return Ok(()) };
    let (c, feed) = (seq.c, seq.feed);
    let pre = pre.unwrap_or(feed);
    let retract = match retract {
        None => CycleFeed::Rapid,
        Some(None) => feed,
        Some(Some(f)) => f,
    };
    deepened_start(p, deep_start, &c)?;
    if chip_every > 0.0 && c.hole.depth / chip_every > MAX_INFEEDS as f64 {
        return Err(p.geometry(format!(
            "more than {MAX_INFEEDS} chip breaks for one hole; increase Q257"
        )));
    }
    let depths = infeed_depths(p, deep_start, c.hole.depth, plunge, decrement, min_plunge)?;
    let reentries = depths.len().saturating_sub(1);
    let seq = seq.dwell(dwell_bottom).retract(retract);
    let mut path = Path::new(out, ctx.pos);
    seq.enter(&mut path, &mut ());
    if deep_start > 0.0 {
        path.axis(c.hole.at(deep_start - c.clearance), pre);
    }
    let mut reached = deep_start;
    for (i, &d) in depths.iter().enumerate() {
        if chip_every > 0.0 {
            let mut next_break = reached + chip_every;
            while next_break < d - EPS {
                path.axis(c.hole.at(next_break), feed);
                path.axis(c.hole.at(next_break - chip), retract);
                next_break += chip_every;
            }
        }
        path.axis(c.hole.at(d), feed);
        reached = d;
        if i + 1 == depths.len() {
            break;
        }
        let advance = if reentries > 1 {
            upper + (lower - upper) * i as f64 / (reentries - 1) as f64
        } else {
            upper
        };
        path.axis(c.safe, retract);
        path.rapid_axis(c.hole.at(d - advance));
    }
    seq.finish(&mut path, &mut ());
    Ok(())
}

/// Old cycle 1 PECKING (`1.1` set-up clearance, `1.2` total depth, `1.3` plunging depth,
/// `1.4` dwell, `1.5 F` feed).
///
/// The tool starts at the current position, which is the set-up clearance above the
/// surface. It drills at F by one plunging depth, rapids back to the starting position and
/// down again to the advanced stop distance t above the depth reached, then drills the next
/// infeed; t is computed by the control: 0.6 mm for holes up to 30 mm deep, depth/50 for
/// deeper ones, at most 7 mm. At the total depth it dwells and rapids back to the starting
/// position. The sign of the depth gives the direction; the clearance and plunging depth
/// are taken by magnitude (programs in the field mix `ABST+1` with `TIEFE-21`).
pub(super) fn old_pecking(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    const ANY: &str = "-99999.9999..=99999.9999";
    let c = old_common(p, ctx.pos[2])?;
    let plunge = p.req_key(old_key(3), "plunging depth", -LEN_MAX, LEN_MAX, ANY)?;
    if plunge == 0.0 {
        return Err(p.range_err(old_key(3), plunge, "a plunging depth other than 0"));
    }
    let dwell = old_dwell(p, 4)?;
    let feed = CycleFeed::Rate(old_feed(p, ctx, 5)?);
    let Some(c) = c else { return Ok(()) };
    let hole = c.hole;
    let advance = if hole.depth <= 30.0 {
        0.6
    } else {
        (hole.depth / 50.0).min(7.0)
    };
    let depths = infeed_depths(p, 0.0, hole.depth, plunge.abs(), 0.0, 0.0)?;
    let seq = HoleSequence::new(&c, feed).dwell(dwell);
    let mut path = Path::new(out, ctx.pos);
    for (i, &d) in depths.iter().enumerate() {
        path.axis(hole.at(d), feed);
        if i + 1 == depths.len() {
            break;
        }
        path.rapid_axis(c.safe);
        path.rapid_axis(hole.at(d - advance));
    }
    seq.finish(&mut path, &mut ());
    Ok(())
}

/// The feed of an old cycle: the `F` word (mm/s, converted by the caller), or the modal
/// feed when the definition has none.
pub(super) fn old_feed(p: &Params<'_>, ctx: &CycleContext, line: u8) -> Result<f64, CycleError> {
    let key = ParamKey::OldWord("F");
    let v = match p.raw(key).or(ctx.feed) {
        Some(v) => v,
        None => {
            return Err(CycleError::Missing {
                cycle: p.cycle,
                param: format!("{}.{line} F", p.cycle),
                what: "feed rate",
            });
        }
    };
    if !(v.is_finite() && v > 0.0) {
        return Err(p.range_err(key, v, "a feed rate > 0"));
    }
    Ok(v)
}
