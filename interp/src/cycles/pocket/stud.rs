//! Studs milled from the outside in: cycles 256 RECTANGULAR STUD and 257 CIRCULAR STUD.
//!
//! Sequence (both cycles):
//! 1. The tool goes at rapid traverse up to the 2nd set-up clearance Q204 when it is
//!    lower, then to the starting point beside the blank: on the first axis of the stud
//!    (256: on the negative side of the stud turned by Q224; 257: in the direction of the
//!    start angle Q376, measured from the first axis), the set-up clearance Q200 outside
//!    the first ring; then down to Q200 above the surface Q203.
//! 2. Roughing (Q215 = 0 or 1; studs without Q215 rough and finish): for each infeed of
//!    at most Q202 down to Q201 the tool plunges at the starting point with feed Q206,
//!    moves straight onto the first ring and runs once round it, then steps in by at most
//!    Q370 × tool diameter to the next ring, until the ring that leaves the side allowance
//!    Q368 on the stud; it then goes back to the starting point. The first ring takes off
//!    the blank (Q424 × Q425 for 256, diameter Q222 for 257) no deeper than one stepover.
//!    Rings run clockwise for climb milling (Q351 = +1 with M3: the stud lies on the
//!    right of the travel), counter-clockwise for up-cut milling.
//! 3. Finishing (Q215 = 0 or 2, when Q368 > 0 or Q215 = 2): at the infeeds of Q338 (all at
//!    once when 0) one ring on the finished contour offset by the tool radius at feed Q385.
//! 4. Rapid traverse up to the set-up clearance and to the 2nd set-up clearance.
//!
//! Approximation: the tool enters each ring on a straight line from outside instead of a
//! tangential approach.

use super::super::{CycleContext, CycleError, CycleFeed, Move};
use super::geom::{EPS, Frame, Path, RoundedRect, check_size, steps_down};
use super::milled::{rect_outline, rect_sides};
use super::params::{Params, pocket_ccw};

/// A stud in its frame, with the blank around it.
struct Stud {
    shape: RoundedRect,
    /// How far the blank reaches beyond the finished stud at most.
    extra: f64,
    frame: Frame,
}

/// Cycle 256: finished sides Q218 × Q219 from blank sides Q424 × Q425, corner radius Q220,
/// turned by Q224, placed by Q367 like cycle 251.
pub(super) fn rect_stud(
    p: &Params,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let (l1, l2) = rect_sides(p)?;
    let b1 = p.q(424, "workpiece blank side length 1")?;
    let b2 = p.q(425, "workpiece blank side length 2")?;
    p.check(424, b1, l1, f64::MAX, "at least the first side length Q218")?;
    p.check(
        425,
        b2,
        l2,
        f64::MAX,
        "at least the second side length Q219",
    )?;
    let (shape, rot, centre) = rect_outline(p, ctx, l1, l2)?;
    // Turned half a revolution so that the rings start on the negative first axis.
    let frame = Frame::new(centre, rot + 180.0);
    let extra = ((b1 - l1) / 2.0).max((b2 - l2) / 2.0);
    run(
        p,
        ctx,
        &Stud {
            shape,
            extra,
            frame,
        },
        out,
    )
}

/// Cycle 257: finished diameter Q223 from blank diameter Q222 about the tool position,
/// starting at angle Q376 (−1 or missing: 0).
pub(super) fn circ_stud(
    p: &Params,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let d = p.q(223, "finished part diameter")?;
    p.check(223, d, EPS, f64::MAX, "greater than 0")?;
    let blank = p.q(222, "workpiece blank diameter")?;
    p.check(
        222,
        blank,
        d,
        f64::MAX,
        "at least the finished diameter Q223",
    )?;
    let start = p.q_or(376, 0.0);
    let start = if start == -1.0 {
        0.0
    } else {
        p.check(376, start, -360.0, 360.0, "-360 to 360")?
    };
    let shape = RoundedRect {
        ha: d / 2.0,
        hb: d / 2.0,
        rc: d / 2.0,
    };
    let frame = Frame::new([ctx.pos[0], ctx.pos[1]], start);
    run(
        p,
        ctx,
        &Stud {
            shape,
            extra: (blank - d) / 2.0,
            frame,
        },
        out,
    )
}

/// The common sequence.
fn run(p: &Params, ctx: &CycleContext, stud: &Stud, out: &mut Vec<Move>) -> Result<(), CycleError> {
    let op = p.choice(215, p.q_or(215, 0.0), 2, "0, 1 or 2")?;
    let h = p.heights()?;
    let side = p.check(368, p.q_or(368, 0.0), 0.0, f64::MAX, "0 or more")?;
    let overlap = p.check(370, p.q_or(370, 1.0), 0.1, 1.9999, "0.1 to 1.9999")?;
    let ccw = !pocket_ccw(p.q_or(351, 1.0), ctx.spindle);
    let feeds = p.feeds(ctx)?;
    if h.depth == 0.0 {
        return Ok(());
    }
    let r = p.tool_radius(ctx)?;
    let step = overlap * 2.0 * r;
    let material = (stud.extra - side).max(0.0);
    let n = (material / step - 1e-9).ceil().clamp(1.0, 100_000.0);
    // n is a small positive whole number.
    let count = n as usize;
    let rings: Vec<RoundedRect> = (1..=count)
        .map(|k| {
            stud.shape
                .offset(r + side + material * (count - k) as f64 / n)
        })
        .collect();
    let fin = stud.shape.offset(r);
    let reach = rings.first().map_or(fin.ha, |g| g.ha).max(fin.ha);
    let start = [reach + h.clear, 0.0];

    let mut path = Path::new(out, stud.frame, ctx.pos);
    let top = h.surface + h.clear;
    let safe = h.surface + h.clear2;
    let bottom = h.surface + h.depth;
    if ctx.pos[2] < safe {
        path.line_abs([ctx.pos[0], ctx.pos[1], safe], CycleFeed::Rapid);
    }
    path.line(start, ctx.pos[2].max(safe), CycleFeed::Rapid);
    path.line(start, top, CycleFeed::Rapid);
    let levels = steps_down(h.surface, bottom, h.infeed);
    check_size(p.cycle, 10.0 * (levels.len() * (rings.len() + 1)) as f64)?;
    let finish_levels = steps_down(h.surface, bottom, h.finish_infeed);
    check_size(p.cycle, 10.0 * finish_levels.len() as f64)?;
    if op != 2 {
        for z in levels {
            path.line(start, z, feeds.plunge);
            for ring in &rings {
                path.ring(*ring, ccw, z, feeds.mill);
            }
            path.line(start, z, feeds.mill);
        }
    }
    if op != 1 && (side > 0.0 || op == 2) {
        for z in finish_levels {
            path.line(start, z, feeds.plunge);
            path.ring(fin, ccw, z, feeds.finish);
            path.line(start, z, feeds.finish);
        }
    }
    path.line(start, top, CycleFeed::Rapid);
    path.line(start, safe, CycleFeed::Rapid);
    Ok(())
}
