//! Face milling: cycles 232 and 233.
//!
//! Cycle 232: the area starts at Q225/Q226 and reaches Q218 along the first axis and
//! Q219 along the second (their signs give the directions); material is taken from the
//! height Q227 down to Q386. Cycle 233: the area of Q218 × Q219 lies at the tool position
//! as Q367 says (0 the tool is over its centre, 1 over its lower left corner, 2 lower
//! right, 3 upper right, 4 upper left); Q350 = 1 runs the passes along the first axis, 2
//! along the second; Q215 = 0 roughs and finishes, 1 only roughs, 2 only finishes.
//!
//! Passes run along the chosen axis; their centre lines are spread evenly across the
//! other side from one edge to the other, at most Q370 × tool diameter apart (the tool
//! overhangs each edge by its radius).
//!
//! Sequence:
//! 1. Rapid traverse up to the 2nd set-up clearance Q204 above Q227 when lower, over the
//!    starting point — outside the area by the tool radius plus the side clearance Q357 —
//!    and down to the set-up clearance Q200 above Q227.
//! 2. The depth Q227 − (Q386 + Q369) is split into equal infeeds of at most Q202; for each
//!    the tool goes down at the milling feed Q207 and mills the passes:
//!    - Q389 = 0: meander; every pass ends outside the area, Q357 plus the tool radius
//!      beyond the edge; the step to the next pass runs there at the positioning feed
//!      Q253;
//!    - Q389 = 1: meander; the passes end Q357 beyond the edge (the tool still over it);
//!    - 232 with Q389 = 2, 233 with Q389 = 2 or 3: one direction; after each pass the tool
//!      rises to the set-up clearance, returns to the start of the next pass (232: at
//!      Q253; 233: at rapid traverse) and goes down at Q207; the passes end as for 0
//!      (Q389 = 2) or 1 (Q389 = 3).
//!
//!    Successive levels run the passes in reverse order. With a floor allowance Q369 a
//!    last level at Q386 follows at the finishing feed Q385.
//! 3. Rapid traverse up to the 2nd set-up clearance.
//!
//! Not supported in 233: the helical strategy Q389 = 4 and the lateral limits Q347–Q349
//! (both are refused).

use super::super::{CycleContext, CycleError, CycleFeed, Move};
use super::geom::{EPS, Frame, Path, check_size, steps_even};
use super::params::{Params, modal_feed};

/// A face-milling job in plane terms.
struct Face {
    /// Corner where the passes start (working plane).
    origin: [f64; 2],
    /// Unit direction of the passes.
    ua: [f64; 2],
    /// Unit direction of the step between passes.
    ub: [f64; 2],
    /// Length along `ua`.
    la: f64,
    /// Length along `ub`.
    lb: f64,
    /// Meander (else one direction with retraction).
    meander: bool,
    /// Passes end the tool radius further out.
    overtravel: bool,
    /// Feed back to the next pass in one-direction machining.
    f_return: CycleFeed,
    /// Q215.
    op: u32,
}

/// Cycle 232.
pub(super) fn face_milling(
    p: &Params,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let strategy = p.choice(389, p.q_or(389, 0.0), 2, "0, 1 or 2")?;
    let a0 = p.q(225, "starting point in the first axis")?;
    let b0 = p.q(226, "starting point in the second axis")?;
    let l1 = p.q(218, "first side length")?;
    let l2 = p.q(219, "second side length")?;
    if l1.abs() < EPS || l2.abs() < EPS {
        return Err(p.geometry("the side lengths Q218 and Q219 must not be 0"));
    }
    let face = Face {
        origin: [a0, b0],
        ua: [l1.signum(), 0.0],
        ub: [0.0, l2.signum()],
        la: l1.abs(),
        lb: l2.abs(),
        meander: strategy != 2,
        overtravel: strategy != 1,
        f_return: p.feed_or(253, CycleFeed::Rapid)?,
        op: 0,
    };
    run(p, ctx, &face, out)
}

/// Cycle 233.
pub(super) fn face_milling_233(
    p: &Params,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let strategy = p.choice(389, p.q_or(389, 0.0), 4, "0 to 4")?;
    if strategy == 4 {
        return Err(p.geometry("the helical strategy Q389 = 4 is not supported"));
    }
    for q in [347, 348, 349] {
        if p.q_or(q, 0.0) != 0.0 {
            return Err(p.geometry(format!("lateral limits (Q{q}) are not supported")));
        }
    }
    let op = p.choice(215, p.q_or(215, 0.0), 2, "0, 1 or 2")?;
    let dir = p.choice(350, p.q_or(350, 1.0), 2, "1 or 2")?;
    if dir == 0 {
        return Err(p.range(super::super::ParamKey::Q(350), 0.0, "1 or 2"));
    }
    let l1 = p.q(218, "first side length")?;
    let l2 = p.q(219, "second side length")?;
    p.check(218, l1, EPS, f64::MAX, "greater than 0")?;
    p.check(219, l2, EPS, f64::MAX, "greater than 0")?;
    let pos = p.choice(367, p.q_or(367, 0.0), 4, "0 to 4")?;
    // Lower left corner of the area.
    let shift = match pos {
        0 => [-l1 / 2.0, -l2 / 2.0],
        2 => [-l1, 0.0],
        3 => [-l1, -l2],
        4 => [0.0, -l2],
        _ => [0.0, 0.0],
    };
    let origin = [ctx.pos[0] + shift[0], ctx.pos[1] + shift[1]];
    let (ua, ub, la, lb) = if dir == 1 {
        ([1.0, 0.0], [0.0, 1.0], l1, l2)
    } else {
        ([0.0, 1.0], [1.0, 0.0], l2, l1)
    };
    let face = Face {
        origin,
        ua,
        ub,
        la,
        lb,
        meander: strategy < 2,
        overtravel: strategy == 0 || strategy == 2,
        f_return: CycleFeed::Rapid,
        op,
    };
    run(p, ctx, &face, out)
}

/// The common sequence.
fn run(p: &Params, ctx: &CycleContext, f: &Face, out: &mut Vec<Move>) -> Result<(), CycleError> {
    let top = p.q(227, "starting point in the tool axis")?;
    let end = p.q(386, "end point in the tool axis")?;
    let infeed = p.q(202, "maximum plunging depth")?;
    p.check(202, infeed, EPS, f64::MAX, "greater than 0")?;
    let floor = p.check(369, p.q_or(369, 0.0), 0.0, f64::MAX, "0 or more")?;
    let overlap = p.check(370, p.q_or(370, 1.0), 0.1, 1.0, "0.1 to 1")?;
    let f_mill = p.feed_or(207, modal_feed(ctx))?;
    let f_finish = p.feed_or(385, f_mill)?;
    let f_pos = p.feed_or(253, CycleFeed::Rapid)?;
    let clear = p.check(200, p.q_or(200, 2.0), 0.0, f64::MAX, "0 or more")?;
    let side = p.check(357, p.q_or(357, 2.0), 0.0, f64::MAX, "0 or more")?;
    let clear2 = p
        .check(204, p.q_or(204, 50.0), 0.0, f64::MAX, "0 or more")?
        .max(clear);
    if end > top {
        return Err(p.geometry(format!(
            "the end point Q386 = {end} lies above the starting point Q227 = {top}"
        )));
    }
    if top - end < floor {
        return Err(p.geometry("the floor allowance Q369 is larger than the depth"));
    }
    let r = ctx.tool_radius;
    if !(r.is_finite() && r > 0.0) {
        return Err(CycleError::ToolRadius {
            cycle: p.cycle,
            radius: r,
        });
    }

    let to_plane = |x: f64, y: f64| {
        [
            f.origin[0] + f.ua[0] * x + f.ub[0] * y,
            f.origin[1] + f.ua[1] * x + f.ub[1] * y,
        ]
    };
    let x_start = -(r + side);
    let x_end = if f.overtravel {
        f.la + side + r
    } else {
        f.la + side
    };
    let step = overlap * 2.0 * r;
    let n = (f.lb / step - 1e-9).ceil().clamp(1.0, 100_000.0);
    // n is a small positive whole number.
    let count = n as usize;
    let lines: Vec<f64> = (0..=count).map(|j| f.lb * j as f64 / n).collect();

    let mut levels: Vec<(f64, CycleFeed)> = Vec::new();
    if f.op != 2 && top - end - floor > EPS {
        levels.extend(
            steps_even(top, end + floor, infeed)
                .into_iter()
                .map(|z| (z, f_mill)),
        );
    }
    if f.op != 1 && (floor > 0.0 || f.op == 2) {
        levels.push((end, f_finish));
    }
    check_size(p.cycle, 4.0 * (levels.len() * lines.len()) as f64)?;
    let mut path = Path::new(out, Frame::new([0.0, 0.0], 0.0), ctx.pos);
    let high = top + clear;
    let safe = top + clear2;
    if ctx.pos[2] < safe {
        path.line_abs([ctx.pos[0], ctx.pos[1], safe], CycleFeed::Rapid);
    }
    let first = to_plane(x_start, 0.0);
    path.line(first, ctx.pos[2].max(safe), CycleFeed::Rapid);
    path.line(first, high, CycleFeed::Rapid);
    let mut forward = true;
    for (k, (z, feed)) in levels.iter().enumerate() {
        let order: Vec<f64> = if k % 2 == 0 {
            lines.clone()
        } else {
            lines.iter().rev().copied().collect()
        };
        for (i, y) in order.iter().enumerate() {
            let (from, to) = if !f.meander || forward {
                (x_start, x_end)
            } else {
                (x_end, x_start)
            };
            if !f.meander {
                let here = [path.cur[0], path.cur[1]];
                path.line(here, high, CycleFeed::Rapid);
                path.line(to_plane(from, *y), high, f.f_return);
                path.line(to_plane(from, *y), *z, f_mill);
            } else if i == 0 {
                path.line(to_plane(from, *y), path.cur[2], f_pos);
                path.line(to_plane(from, *y), *z, f_mill);
            } else {
                path.line(to_plane(from, *y), *z, f_pos);
            }
            path.line(to_plane(to, *y), *z, *feed);
            if f.meander {
                forward = !forward;
            }
        }
    }
    path.line([path.cur[0], path.cur[1]], safe, CycleFeed::Rapid);
    Ok(())
}
