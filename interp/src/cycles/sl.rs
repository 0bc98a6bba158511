//! SL contour cycles 20–24 on the contours of cycle 14.
//!
//! Cycle 20 CONTOUR DATA gives the machining data for the later cycles: Q1 milling depth
//! (negative), Q2 path overlap (stepover = Q2 × tool radius), Q3 side allowance, Q4 floor
//! allowance, Q5 surface coordinate, Q6 set-up clearance above the surface, Q7 clearance
//! height (absolute), Q8 inside rounding radius, Q9 milling direction (+1 climb, −1
//! up-cut, as Q351 of the pocket cycles).
//!
//! The contours of cycle 14 are sorted into pockets and islands: a contour is a pocket
//! when its radius compensation puts the tool inside it (counter-clockwise with RL,
//! clockwise with RR), an island otherwise; contours programmed without compensation
//! count as the pocket (the first) and islands (the others). The area to machine lies in
//! a pocket and outside every island.
//!
//! Cycle 22 ROUGH-OUT (Q10 plunging depth, Q11 plunging feed, Q12 milling feed): for each
//! infeed of at most Q10 from the surface Q5 down to Q1 less the floor allowance Q4, the
//! area is cleared on lines parallel to the first axis, at most the stepover apart,
//! keeping the tool centre the tool radius plus the side allowance Q3 away from every
//! contour. Neighbouring lines are joined in a zigzag at depth where the link keeps that
//! distance; otherwise the tool retracts to the set-up clearance, moves over at rapid
//! traverse and plunges again at Q11. Then the tool runs once along every wall at that
//! same distance, which takes off the ridges the lines leave. At the start and end the
//! tool travels at the clearance height Q7.
//!
//! Cycle 21 PILOT DRILLING (Q10 plunging depth, Q11 plunging feed, Q13 rough-out tool)
//! drills a hole at every point where cycle 22 with the rough-out tool will plunge: the
//! starts of its clearing lines and wall paths, worked out with the rough-out tool's radius
//! (the caller passes it as [`CycleContext::rough_out_radius`]). Each hole goes from the
//! set-up clearance down to the rough-out floor (Q1 less the floor allowance Q4) in infeeds
//! of at most Q10 at Q11, and the tool returns at rapid traverse to the set-up clearance.
//!
//! Cycle 23 FLOOR FINISHING (Q11, Q12) does the same in one cut at the depth Q1, the side
//! allowance still left.
//!
//! Cycle 24 SIDE FINISHING (Q9 direction, Q10 plunging depth, Q11, Q12, Q14 side
//! allowance left after finishing) runs along every wall at the tool radius plus Q14, for
//! each infeed of at most Q10 down to Q1. The parts of a wall path that would come closer
//! to another contour are left out.
//!
//! Milling direction (Q9 of cycle 24, else of cycle 20): +1 climb milling with M3, so
//! pocket walls run counter-clockwise and island walls clockwise; −1 the other way.
//!
//! Approximations: line-by-line clearing instead of contour-parallel rings inside; the
//! tool plunges straight down at the start of each path (no tangential approach, no
//! reciprocating plunge Q19); the rounding radius Q8, the coarse roughing tool Q18 and
//! the retraction feed Q208 are not used; arcs are replaced by chords within a
//! micrometre, and the clearances are widened by as much.

use super::pocket::geom::{Frame, Path, check_size, steps_down};
use super::pocket::params::{Params, pocket_ccw};
use super::{Contour, CycleContext, CycleError, CycleFeed, Move, ParamKey, ParamSource};

mod index;
mod offset;
mod raster;
mod region;
#[cfg(test)]
mod tests;

use offset::Polyline;
use region::{CHORD_TOL, RegionError};

/// True when `number` is an SL machining cycle this module generates.
pub(super) fn knows(number: u32) -> bool {
    matches!(number, 21..=24)
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
    if !knows(cycle) {
        return Err(CycleError::Unknown(cycle));
    }
    let d = Params::new(20, p20);
    let c = Params::new(cycle, p);
    let depth = d.q(1, "milling depth")?;
    if depth > 0.0 {
        return Err(d.range(ParamKey::Q(1), depth, "negative (0 skips the cycle)"));
    }
    let overlap = d.check(2, d.q_or(2, 1.0), 0.0001, 1.9999, "0.0001 to 1.9999")?;
    let side = d.check(3, d.q_or(3, 0.0), 0.0, f64::MAX, "0 or more")?;
    let floor = d.check(4, d.q_or(4, 0.0), 0.0, f64::MAX, "0 or more")?;
    let surface = d.q(5, "workpiece surface coordinate")?;
    let clear = d.check(6, d.q(6, "set-up clearance")?, 0.0, f64::MAX, "0 or more")?;
    let height = d.q(7, "clearance height")?;
    let (infeed, f_plunge, f_mill) = match cycle {
        21 => {
            let q10 = c.q(10, "plunging depth")?.abs();
            c.check(10, q10, 1e-6, f64::MAX, "not 0")?;
            let f11 = c.feed_or(11, super::pocket::params::modal_feed(ctx))?;
            (q10, f11, f11)
        }
        22 | 24 => {
            let q10 = c.q(10, "plunging depth")?.abs();
            c.check(10, q10, 1e-6, f64::MAX, "not 0")?;
            let f12 = c.feed_or(12, super::pocket::params::modal_feed(ctx))?;
            (q10, c.feed_or(11, f12)?, f12)
        }
        _ => {
            let f12 = c.feed_or(12, super::pocket::params::modal_feed(ctx))?;
            (f64::MAX, c.feed_or(11, f12)?, f12)
        }
    };
    // cycle 21 works out the plunge points of the rough-out tool
    let r = match cycle {
        21 => ctx.rough_out_radius.ok_or_else(|| {
            c.geometry("the rough-out tool Q13 is not in the tool table".to_string())
        })?,
        _ => ctx.tool_radius,
    };
    if !(r.is_finite() && r > 0.0) {
        return Err(CycleError::ToolRadius {
            cycle: c.cycle,
            radius: r,
        });
    }
    if depth == 0.0 {
        return Ok(());
    }
    if matches!(cycle, 21 | 22) && -depth < floor {
        return Err(d.geometry("the floor allowance Q4 is larger than the depth Q1"));
    }
    let region = region::build(contours).map_err(|e| {
        c.geometry(match e {
            RegionError::Empty => "no contour defined (cycle 14)".to_string(),
            RegionError::Degenerate(i) => format!("contour {} encloses no area", i + 1),
            RegionError::BadArc(i) => {
                format!("contour {} has an arc whose end is off its circle", i + 1)
            }
        })
    })?;
    if region.pockets.is_empty() {
        return Err(c.geometry("the contours define islands only, no pocket"));
    }
    let q9 = match cycle {
        24 => c
            .get(ParamKey::Q(9))
            .or_else(|| d.get(ParamKey::Q(9)))
            .unwrap_or(1.0),
        _ => d.q_or(9, 1.0),
    };
    let area_left = pocket_ccw(q9, ctx.spindle);
    let allowance = match cycle {
        24 => c.check(14, c.q_or(14, 0.0), 0.0, f64::MAX, "0 or more")?,
        _ => side,
    };
    let rho = r + allowance + CHORD_TOL;
    let index = index::Index::new(&region, rho);
    let walls = offset::wall_paths(&region, &index, rho, area_left);
    let levels = match cycle {
        21 | 22 => steps_down(surface, surface + depth + floor, infeed),
        23 => vec![surface + depth],
        _ => steps_down(surface, surface + depth, infeed),
    };
    let (ymin, ymax) = region
        .pockets
        .iter()
        .flat_map(|q| &q.pts)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p[1]), hi.max(p[1]))
        });
    if cycle != 24 {
        check_size(
            cycle,
            2.0 * levels.len() as f64 * ((ymax - ymin) / (overlap * r)).max(1.0),
        )?;
    }
    let mut passes: Vec<Polyline> = Vec::new();
    if cycle != 24 {
        let spans = raster::spans(&region, &index, rho, overlap * r);
        for run in raster::link(&index, &spans, rho) {
            let mut line = Vec::with_capacity(2 * run.len());
            for (s, up) in run {
                let (a, b) = if up { (s.lo, s.hi) } else { (s.hi, s.lo) };
                line.push([a, s.y]);
                line.push([b, s.y]);
            }
            passes.push(line);
        }
    }
    passes.extend(walls);
    if passes.is_empty() {
        return Err(c.geometry(format!(
            "the tool (diameter {}) does not fit into the contour",
            2.0 * r
        )));
    }
    if cycle == 21 {
        return pilot_holes(
            &passes,
            &levels,
            surface + clear,
            height,
            f_plunge,
            ctx,
            out,
        );
    }
    let points: usize = passes.iter().map(|p| p.len() + 4).sum();
    check_size(cycle, (levels.len() * points) as f64)?;
    let top = surface + clear;
    let safe = height.max(top);
    let mut path = Path::new(out, Frame::new([0.0, 0.0], 0.0), ctx.pos);
    if ctx.pos[2] < safe {
        path.line_abs([ctx.pos[0], ctx.pos[1], safe], CycleFeed::Rapid);
    }
    let mut first = true;
    for z in levels {
        for pass in &passes {
            let Some(&start) = pass.first() else { continue };
            let h = if first { ctx.pos[2].max(safe) } else { top };
            path.line(start, h, CycleFeed::Rapid);
            path.line(start, top, CycleFeed::Rapid);
            path.line(start, z, f_plunge);
            first = false;
            for p in pass {
                path.line(*p, z, f_mill);
            }
            let here = [path.cur[0], path.cur[1]];
            path.line(here, top, CycleFeed::Rapid);
        }
    }
    let here = [path.cur[0], path.cur[1]];
    path.line(here, safe, CycleFeed::Rapid);
    Ok(())
}

/// Cycle 21: a hole at the start of every pass of the rough-out, in infeeds `levels`.
fn pilot_holes(
    passes: &[Polyline],
    levels: &[f64],
    top: f64,
    height: f64,
    feed: CycleFeed,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let mut holes: Vec<[f64; 2]> = Vec::new();
    for start in passes.iter().filter_map(|p| p.first()) {
        if !holes
            .iter()
            .any(|h| (h[0] - start[0]).hypot(h[1] - start[1]) < 1e-6)
        {
            holes.push(*start);
        }
    }
    check_size(21, (holes.len() * (levels.len() + 3)) as f64)?;
    let safe = height.max(top);
    let mut path = Path::new(out, Frame::new([0.0, 0.0], 0.0), ctx.pos);
    if ctx.pos[2] < safe {
        path.line_abs([ctx.pos[0], ctx.pos[1], safe], CycleFeed::Rapid);
    }
    for (k, h) in holes.iter().enumerate() {
        let over = if k == 0 { ctx.pos[2].max(safe) } else { top };
        path.line(*h, over, CycleFeed::Rapid);
        path.line(*h, top, CycleFeed::Rapid);
        for z in levels {
            path.line(*h, *z, feed);
        }
        path.line(*h, top, CycleFeed::Rapid);
    }
    let here = [path.cur[0], path.cur[1]];
    path.line(here, safe, CycleFeed::Rapid);
    Ok(())
}
