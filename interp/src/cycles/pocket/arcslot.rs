//! Cycle 254 CIRCULAR SLOT.
//!
//! The slot follows the circle of diameter Q375 about its centre from the start angle
//! Q376 over the angular length Q248 (counter-clockwise), width Q219, round ends. Where it
//! lies, by Q367: 0 the centre is Q216/Q217 and the tool position does not count; 1 the
//! tool is over the centre of the end circle at the start angle; 2 over the middle of
//! the slot's centre line; 3 over the centre of the end circle at the far end. With Q377
//! repetitions (Q377 > 1) further slots follow, each turned on by Q378 about the centre.
//!
//! Sequence for each slot, with the parameters of cycle 253 (Q215, Q368, Q207, Q351,
//! Q201, Q202, Q369, Q206, Q338, Q200, Q203, Q204, Q366, Q385, Q370):
//! 1. Rapid traverse at the 2nd set-up clearance over the centre of the start end circle,
//!    down to the set-up clearance.
//! 2. Roughing: for each infeed the tool plunges there (Q366 = 0 straight down, 1 or 2 on
//!    a ramp forth and back along the centre line) and clears the slot in closed paths
//!    from the centre line outwards — each an arc on the outer side, a half circle round
//!    the end, an arc back on the inner side and a half circle round the start — at most
//!    Q370 × tool diameter apart, the outer one leaving the side allowance; then back to
//!    the start of the centre line.
//! 3. Finishing as in cycle 253: walls at the Q338 infeeds on the path the tool radius
//!    inside the slot outline, then the floor (when Q369 > 0).
//! 4. Rapid traverse to the set-up clearance, then to the 2nd set-up clearance.
//!
//! Direction: counter-clockwise along the outline for climb milling (Q351 = +1 with M3).
//! Approximations: the finishing path is entered straight from the centre line; one ramp
//! forth and back per infeed. The meaning of Q367 = 1…3 is this module's reading of the
//! manual's "left/right slot circle".

use super::super::{CycleContext, CycleError, CycleFeed, Move};
use super::geom::{EPS, Frame, Path, Seg, check_size, steps_down};
use super::params::{Params, pocket_ccw};

/// A point on the circle of radius `r` about `c` at angle `a` (radians).
fn polar(c: [f64; 2], r: f64, a: f64) -> [f64; 2] {
    [c[0] + r * a.cos(), c[1] + r * a.sin()]
}

/// The slot in the plane.
#[derive(Debug, Clone, Copy)]
struct ArcSlot {
    /// Circle centre.
    c: [f64; 2],
    /// Centre-line radius.
    rm: f64,
    /// Start angle, radians.
    a0: f64,
    /// Angular length, radians.
    sweep: f64,
}

impl ArcSlot {
    /// The closed path of points at distance `h` from the centre line, starting and
    /// ending at the outer side of the start; counter-clockwise when `ccw`.
    fn ring(&self, h: f64, ccw: bool) -> Vec<Seg> {
        let (c, a0, a1) = (self.c, self.a0, self.a0 + self.sweep);
        let e0 = polar(c, self.rm, a0);
        let e1 = polar(c, self.rm, a1);
        let p0 = polar(c, self.rm + h, a0);
        let q0 = polar(c, self.rm - h, a0);
        // A full turn (360°) is a ring between two circles joined by radial moves.
        let full = self.sweep >= std::f64::consts::TAU - 1e-12;
        let (p1, q1) = if full {
            (p0, q0)
        } else {
            (polar(c, self.rm + h, a1), polar(c, self.rm - h, a1))
        };
        let arc = |from, to, centre, ccw| Seg {
            from,
            to,
            centre: Some(centre),
            ccw,
        };
        let line = |from, to| Seg {
            from,
            to,
            centre: None,
            ccw: true,
        };
        let mut segs = vec![arc(p0, p1, c, true)];
        if full {
            if h > 1e-6 {
                segs.push(line(p1, q1));
            }
        } else if h > 1e-6 {
            segs.push(arc(p1, q1, e1, true));
        }
        if h > 1e-6 || !full {
            segs.push(arc(q1, q0, c, false));
        }
        if full {
            if h > 1e-6 {
                segs.push(line(q0, p0));
            }
        } else if h > 1e-6 {
            segs.push(arc(q0, p0, e0, true));
        }
        if ccw {
            segs
        } else {
            segs.iter()
                .rev()
                .map(|s| Seg {
                    from: s.to,
                    to: s.from,
                    centre: s.centre,
                    ccw: !s.ccw,
                })
                .collect()
        }
    }
}

/// Cycle 254.
pub(super) fn circular_slot(
    p: &Params,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let op = p.choice(215, p.q_or(215, 0.0), 2, "0, 1 or 2")?;
    let width = p.q(219, "slot width")?;
    p.check(219, width, EPS, f64::MAX, "greater than 0")?;
    let side = p.check(368, p.q_or(368, 0.0), 0.0, f64::MAX, "0 or more")?;
    let dia = p.q(375, "pitch circle diameter")?;
    p.check(375, dia, EPS, f64::MAX, "greater than 0")?;
    let pos = p.choice(367, p.q_or(367, 0.0), 3, "0 to 3")?;
    let start = p.check(376, p.q_or(376, 0.0), -360.0, 360.0, "-360 to 360")?;
    let len = p.q(248, "angular length")?;
    p.check(248, len, EPS, 360.0, "greater than 0, at most 360")?;
    let step_angle = p.check(378, p.q_or(378, 0.0), -360.0, 360.0, "-360 to 360")?;
    let reps = p.q_or(377, 1.0);
    let reps = if reps <= 1.0 {
        1
    } else {
        p.choice(377, reps, 99_999, "1 to 99999")?
    };
    let heights = p.heights()?;
    let floor = p.check(369, p.q_or(369, 0.0), 0.0, f64::MAX, "0 or more")?;
    let overlap = p.check(370, p.q_or(370, 1.0), 0.1, 1.9999, "0.1 to 1.9999")?;
    let ramp = p.choice(366, p.q_or(366, 1.0), 2, "0, 1 or 2")? != 0;
    let ccw = pocket_ccw(p.q_or(351, 1.0), ctx.spindle);
    let feeds = p.feeds(ctx)?;
    if heights.depth == 0.0 {
        return Ok(());
    }
    let r = p.tool_radius(ctx)?;
    let w = width / 2.0;
    let rm = dia / 2.0;
    if w < r - EPS {
        return Err(p.geometry(format!(
            "the tool (diameter {}) is wider than the slot ({width})",
            2.0 * r
        )));
    }
    if op != 2 && w < r + side - EPS {
        return Err(p.geometry("the side allowance Q368 leaves no room for the tool"));
    }
    if w >= rm {
        return Err(p.geometry("the slot is wider than its pitch circle diameter"));
    }
    if op != 2 && -heights.depth < floor {
        return Err(p.geometry("the floor allowance Q369 is larger than the depth"));
    }
    let (a_start, sweep) = (start.to_radians(), len.to_radians());
    let tool = [ctx.pos[0], ctx.pos[1]];
    let ref_angle = match pos {
        1 => a_start,
        2 => a_start + sweep / 2.0,
        _ => a_start + sweep,
    };
    let centre = match pos {
        0 => [
            p.q(216, "centre in the first axis")?,
            p.q(217, "centre in the second axis")?,
        ],
        _ => polar(tool, -rm, ref_angle),
    };

    let rough_levels = steps_down(
        heights.surface,
        heights.surface + heights.depth + floor,
        heights.infeed,
    )
    .len();
    let finish_levels = steps_down(
        heights.surface,
        heights.surface + heights.depth,
        heights.finish_infeed,
    )
    .len();
    let ring_count = (w / (overlap * 2.0 * r)).ceil() + 2.0;
    check_size(
        p.cycle,
        f64::from(reps) * 6.0 * ((rough_levels + 1) as f64 * ring_count + finish_levels as f64),
    )?;
    let mut path = Path::new(out, Frame::new([0.0, 0.0], 0.0), ctx.pos);
    let top = heights.surface + heights.clear;
    let safe = heights.surface + heights.clear2;
    let bottom = heights.surface + heights.depth;
    if ctx.pos[2] < safe {
        path.line_abs([ctx.pos[0], ctx.pos[1], safe], CycleFeed::Rapid);
    }
    let mut high = ctx.pos[2].max(safe);
    let step = overlap * 2.0 * r;
    for k in 0..reps {
        let slot = ArcSlot {
            c: centre,
            rm,
            a0: a_start + f64::from(k) * step_angle.to_radians(),
            sweep,
        };
        let e0 = polar(centre, rm, slot.a0);
        path.line(e0, high, CycleFeed::Rapid);
        path.line(e0, top, CycleFeed::Rapid);
        high = top;
        let rings = |hmax: f64| -> Vec<f64> {
            let n = (hmax / step - 1e-9).ceil().clamp(0.0, 100_000.0);
            // n is a small whole number.
            let count = n as usize;
            (0..=count)
                .map(|i| {
                    if count == 0 {
                        hmax
                    } else {
                        hmax * i as f64 / n
                    }
                })
                .collect()
        };
        let emit_rings = |path: &mut Path, hs: &[f64], z: f64, feed: CycleFeed| {
            for &h in hs {
                path.line(polar(centre, rm + h, slot.a0), z, feed);
                path.segs(&slot.ring(h, ccw), z, feed);
            }
            path.line(e0, z, feed);
        };
        if op != 2 {
            let hs = rings(w - r - side);
            let mut from = top;
            for z in steps_down(heights.surface, bottom + floor, heights.infeed) {
                let delta = sweep.min(2.0 * r / rm);
                if ramp && delta > 1e-6 {
                    let mid = polar(centre, rm, slot.a0 + delta);
                    path.arc(centre, mid, (from + z) / 2.0, true, 0, feeds.plunge);
                    path.arc(centre, e0, z, false, 0, feeds.plunge);
                } else {
                    path.line(e0, z, feeds.plunge);
                }
                emit_rings(&mut path, &hs, z, feeds.mill);
                from = z;
            }
        }
        if op != 1 {
            if side > 0.0 || op == 2 {
                for z in steps_down(heights.surface, bottom, heights.finish_infeed) {
                    path.line(e0, z, feeds.plunge);
                    emit_rings(&mut path, &[w - r], z, feeds.finish);
                }
            }
            if floor > 0.0 {
                path.line(e0, bottom, feeds.plunge);
                emit_rings(&mut path, &rings(w - r), bottom, feeds.finish);
            }
        }
        path.line(e0, top, CycleFeed::Rapid);
    }
    let here = [path.cur[0], path.cur[1]];
    path.line(here, safe, CycleFeed::Rapid);
    Ok(())
}
