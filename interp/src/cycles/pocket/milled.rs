//! Pockets and slots milled from the inside out: cycles 251, 252 and 253.
//!
//! The three cycles share one sequence; they differ in the outline (a rounded rectangle,
//! a circle, a slot with round ends — all [`RoundedRect`]s) and in where it lies.
//!
//! 1. From the call position the tool goes at rapid traverse up to the 2nd set-up
//!    clearance Q204 above the surface Q203 when it is lower, over the pocket centre, and
//!    down to the set-up clearance Q200.
//! 2. Roughing (Q215 = 0 or 1): for each infeed of at most Q202 (full infeeds first, the
//!    remainder last) down to the depth Q201 less the floor allowance Q369, the tool
//!    plunges at the centre with feed Q206 — straight down (Q366 = 0), on a helix of one
//!    turn (Q366 = 1), or on one ramp forth and back along the pocket's first axis
//!    (Q366 = 2) — and then clears the level in closed rings from the inside out at feed
//!    Q207. The outer ring keeps the side allowance Q368 from the wall; the rings follow
//!    the outline offset inwards, their spacing is at most Q370 × tool diameter. The tool
//!    runs counter-clockwise for climb milling (Q351 = +1 with M3) and clockwise for
//!    up-cut milling. After the outer ring it returns to the centre.
//! 3. Finishing (Q215 = 0 or 2, when an allowance is left or Q215 = 2): the walls are
//!    finished at the infeeds of Q338 (all at once when 0) at feed Q385: the tool goes to
//!    the depth at the centre, approaches the wall on a tangential half circle, runs once
//!    round the finished outline offset by the tool radius, and leaves on a half circle
//!    back towards the centre. When a floor allowance Q369 is given the floor is then
//!    cleared at the depth Q201 in rings from the inside out at feed Q385.
//! 4. The tool retracts at rapid traverse to the set-up clearance and then to the 2nd
//!    set-up clearance.
//!
//! Approximations: the helix radius is the tool radius, or less when the pocket has no
//! room for it (then straight down when there is no room at all); one helix turn or one
//! ramp forth and back per infeed (the tool's plunge angle is not known here).
//!
//! Depth 0 means the cycle does nothing; a positive depth is refused.

use super::super::{CycleContext, CycleError, CycleFeed, Move};
use super::geom::{EPS, Frame, Path, RoundedRect, check_size, steps_down};
use super::params::{Params, pocket_ccw};

/// How the tool enters the material for roughing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Plunge {
    /// Straight down.
    Vertical,
    /// On a helix.
    Helical,
    /// On a ramp forth and back.
    Reciprocating,
}

/// Everything the inside-out sequence needs, in the pocket's frame.
#[derive(Debug, Clone, Copy)]
pub(super) struct Pocket {
    /// Cycle number, for errors.
    pub cycle: u32,
    /// Finished outline.
    pub shape: RoundedRect,
    /// Where the outline lies.
    pub frame: Frame,
    /// Q215: 0 rough + finish, 1 rough, 2 finish.
    pub op: u32,
    /// Surface Q203.
    pub surface: f64,
    /// Depth Q201 (negative).
    pub depth: f64,
    /// Infeed Q202.
    pub infeed: f64,
    /// Finishing infeed Q338.
    pub finish_infeed: f64,
    /// Set-up clearance Q200.
    pub clear: f64,
    /// 2nd set-up clearance Q204.
    pub clear2: f64,
    /// Side allowance Q368.
    pub side: f64,
    /// Floor allowance Q369.
    pub floor: f64,
    /// Largest distance between rings.
    pub stepover: f64,
    /// Counter-clockwise rings.
    pub ccw: bool,
    /// Plunging.
    pub plunge: Plunge,
    /// Q206.
    pub f_plunge: CycleFeed,
    /// Q207.
    pub f_mill: CycleFeed,
    /// Q385.
    pub f_finish: CycleFeed,
}

/// The parameters common to 251, 252 and 253, read from `p`; `stepover_max` is the upper
/// limit of Q370 for the cycle.
fn common(
    p: &Params,
    ctx: &CycleContext,
    shape: RoundedRect,
    frame: Frame,
    plunge_choices: [Plunge; 3],
    stepover_max: f64,
) -> Result<Option<Pocket>, CycleError> {
    let op = p.choice(215, p.q_or(215, 0.0), 2, "0, 1 or 2")?;
    let h = p.heights()?;
    let side = p.check(368, p.q_or(368, 0.0), 0.0, f64::MAX, "0 or more")?;
    let floor = p.check(369, p.q_or(369, 0.0), 0.0, f64::MAX, "0 or more")?;
    let overlap = p.check(
        370,
        p.q_or(370, 1.0),
        0.1,
        stepover_max,
        "0.1 to the cycle's maximum",
    )?;
    let q351 = p.q_or(351, 1.0);
    let plunge_idx = p.choice(366, p.q_or(366, 1.0), 2, "0, 1 or 2")?;
    let plunge = match plunge_idx {
        0 => plunge_choices[0],
        1 => plunge_choices[1],
        _ => plunge_choices[2],
    };
    let feeds = p.feeds(ctx)?;
    if h.depth == 0.0 {
        return Ok(None);
    }
    let r = p.tool_radius(ctx)?;
    if shape.half_min() < r - EPS {
        return Err(p.geometry(format!(
            "the tool (diameter {}) is larger than the pocket (width {})",
            2.0 * r,
            2.0 * shape.half_min()
        )));
    }
    if op != 2 && shape.half_min() < r + side - EPS {
        return Err(p.geometry("the side allowance Q368 leaves no room for the tool"));
    }
    if -h.depth < floor - EPS && op != 2 {
        return Err(p.geometry("the floor allowance Q369 is larger than the depth"));
    }
    Ok(Some(Pocket {
        cycle: p.cycle,
        shape,
        frame,
        op,
        surface: h.surface,
        depth: h.depth,
        infeed: h.infeed,
        finish_infeed: h.finish_infeed,
        clear: h.clear,
        clear2: h.clear2,
        side,
        floor,
        stepover: overlap * 2.0 * r,
        ccw: pocket_ccw(q351, ctx.spindle),
        plunge,
        f_plunge: feeds.plunge,
        f_mill: feeds.mill,
        f_finish: feeds.finish,
    }))
}

/// Offset of the pocket centre from the tool position for Q367 (251, 256): 0 centre,
/// 1 the tool is at the lower left corner, 2 lower right, 3 upper right, 4 upper left
/// (corners of the unrotated outline, in the outline's own frame).
pub(super) fn corner_offset(q367: u32, ha: f64, hb: f64) -> [f64; 2] {
    match q367 {
        1 => [ha, hb],
        2 => [-ha, hb],
        3 => [-ha, -hb],
        4 => [ha, -hb],
        _ => [0.0, 0.0],
    }
}

/// The pocket frame for a centre given relative to the tool position in a frame turned
/// by `deg`.
fn placed(ctx: &CycleContext, deg: f64, local_offset: [f64; 2]) -> Frame {
    Frame::new(placed_centre(ctx, deg, local_offset), deg)
}

/// The centre that lies `local_offset` from the tool position in a frame turned by `deg`.
fn placed_centre(ctx: &CycleContext, deg: f64, local_offset: [f64; 2]) -> [f64; 2] {
    Frame::new([ctx.pos[0], ctx.pos[1]], deg).map(local_offset)
}

/// The side lengths Q218 and Q219 of a rectangle (251, 256), each greater than 0.
pub(super) fn rect_sides(p: &Params) -> Result<(f64, f64), CycleError> {
    let l1 = p.q(218, "first side length")?;
    let l2 = p.q(219, "second side length")?;
    p.check(218, l1, EPS, f64::MAX, "greater than 0")?;
    p.check(219, l2, EPS, f64::MAX, "greater than 0")?;
    Ok((l1, l2))
}

/// The outline of sides `l1` × `l2` with corner radius Q220 (251, 256), its turn Q224 in
/// degrees, and its centre placed by Q367 (see [`corner_offset`]) from the tool position.
pub(super) fn rect_outline(
    p: &Params,
    ctx: &CycleContext,
    l1: f64,
    l2: f64,
) -> Result<(RoundedRect, f64, [f64; 2]), CycleError> {
    let rc = p.check(
        220,
        p.q_or(220, 0.0),
        0.0,
        l1.min(l2) / 2.0,
        "0 to half the shorter side",
    )?;
    let rot = p.check(224, p.q_or(224, 0.0), -360.0, 360.0, "-360 to 360")?;
    let pos = p.choice(367, p.q_or(367, 0.0), 4, "0 to 4")?;
    let shape = RoundedRect {
        ha: l1 / 2.0,
        hb: l2 / 2.0,
        rc,
    };
    let centre = placed_centre(ctx, rot, corner_offset(pos, shape.ha, shape.hb));
    Ok((shape, rot, centre))
}

/// Cycle 251 RECTANGULAR POCKET: sides Q218 × Q219, corner radius Q220, turned by Q224
/// about the pocket centre, placed by Q367 (see [`corner_offset`]).
pub(super) fn rect_pocket(
    p: &Params,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let (l1, l2) = rect_sides(p)?;
    let (shape, rot, centre) = rect_outline(p, ctx, l1, l2)?;
    let frame = Frame::new(centre, rot);
    let plunges = [Plunge::Vertical, Plunge::Helical, Plunge::Reciprocating];
    match common(p, ctx, shape, frame, plunges, 1.414)? {
        Some(pk) => run(&pk, ctx, out),
        None => Ok(()),
    }
}

/// Cycle 252 CIRCULAR POCKET: diameter Q223 about the tool position.
pub(super) fn circ_pocket(
    p: &Params,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let d = p.q(223, "circle diameter")?;
    p.check(223, d, EPS, f64::MAX, "greater than 0")?;
    let shape = RoundedRect {
        ha: d / 2.0,
        hb: d / 2.0,
        rc: d / 2.0,
    };
    let frame = placed(ctx, 0.0, [0.0, 0.0]);
    let plunges = [Plunge::Vertical, Plunge::Helical, Plunge::Reciprocating];
    match common(p, ctx, shape, frame, plunges, 1.9999)? {
        Some(pk) => run(&pk, ctx, out),
        None => Ok(()),
    }
}

/// Cycle 253 SLOT MILLING: length Q218 and width Q219 with round ends, turned by Q374,
/// placed by Q367 along the slot: 0 centre, 1 the tool is at the left end, 2 at the
/// centre of the left end circle, 3 at the centre of the right end circle, 4 at the right
/// end. Q366 = 0 plunges straight down, 1 and 2 on a ramp along the slot.
pub(super) fn slot(p: &Params, ctx: &CycleContext, out: &mut Vec<Move>) -> Result<(), CycleError> {
    let len = p.q(218, "slot length")?;
    let width = p.q(219, "slot width")?;
    p.check(219, width, EPS, f64::MAX, "greater than 0")?;
    if len < width - EPS {
        return Err(p.geometry(format!(
            "the slot length {len} is smaller than its width {width}"
        )));
    }
    let rot = p.check(374, p.q_or(374, 0.0), -360.0, 360.0, "-360 to 360")?;
    let pos = p.choice(367, p.q_or(367, 0.0), 4, "0 to 4")?;
    let (ha, hb) = (len / 2.0, width / 2.0);
    let along = match pos {
        1 => ha,
        2 => ha - hb,
        3 => -(ha - hb),
        4 => -ha,
        _ => 0.0,
    };
    let shape = RoundedRect { ha, hb, rc: hb };
    let frame = placed(ctx, rot, [along, 0.0]);
    let plunges = [
        Plunge::Vertical,
        Plunge::Reciprocating,
        Plunge::Reciprocating,
    ];
    match common(p, ctx, shape, frame, plunges, 1.9999)? {
        Some(pk) => run(&pk, ctx, out),
        None => Ok(()),
    }
}

/// Rings clearing `outer` from the inside out, at most `step` apart, innermost first.
pub(super) fn rings_inside_out(outer: RoundedRect, step: f64) -> Vec<RoundedRect> {
    let hmin = outer.half_min();
    let n = if step > EPS {
        (hmin / step - 1e-9).ceil().clamp(0.0, 1_000_000.0)
    } else {
        0.0
    };
    // n is a small whole number.
    let count = n as usize;
    (0..=count)
        .map(|i| {
            let inset = if count == 0 {
                0.0
            } else {
                hmin * (count - i) as f64 / n
            };
            outer.offset(-inset)
        })
        .collect()
}

/// Appends the sequence described in the module documentation.
pub(super) fn run(pk: &Pocket, ctx: &CycleContext, out: &mut Vec<Move>) -> Result<(), CycleError> {
    let r = ctx.tool_radius;
    let mut path = Path::new(out, pk.frame, ctx.pos);
    let top = pk.surface + pk.clear;
    let safe = pk.surface + pk.clear2;
    let bottom = pk.surface + pk.depth;
    let o = [0.0, 0.0];
    if ctx.pos[2] < safe {
        path.line_abs([ctx.pos[0], ctx.pos[1], safe], CycleFeed::Rapid);
    }
    let high = ctx.pos[2].max(safe);
    path.line(o, high, CycleFeed::Rapid);
    path.line(o, top, CycleFeed::Rapid);

    let rough_outer = pk.shape.offset(-(r + pk.side));
    if pk.op != 2 {
        let rings = rings_inside_out(rough_outer, pk.stepover);
        let levels = steps_down(pk.surface, bottom + pk.floor, pk.infeed);
        check_size(pk.cycle, 10.0 * (levels.len() * (rings.len() + 1)) as f64)?;
        let mut t = top;
        for z in levels {
            plunge(&mut path, pk, rough_outer, r, t, z);
            for ring in &rings {
                path.ring(*ring, pk.ccw, z, pk.f_mill);
            }
            path.line(o, z, pk.f_mill);
            t = z;
        }
    }
    if pk.op != 1 {
        let fin = pk.shape.offset(-r);
        if pk.side > 0.0 || pk.op == 2 {
            let levels = steps_down(pk.surface, bottom, pk.finish_infeed);
            check_size(pk.cycle, 12.0 * levels.len() as f64)?;
            for z in levels {
                path.line(o, z, pk.f_plunge);
                finish_ring(&mut path, fin, pk.ccw, z, pk.f_finish);
                path.line(o, z, pk.f_finish);
            }
        }
        if pk.floor > 0.0 {
            path.line(o, bottom, pk.f_plunge);
            for ring in rings_inside_out(fin, pk.stepover) {
                path.ring(ring, pk.ccw, bottom, pk.f_finish);
            }
            path.line(o, bottom, pk.f_finish);
        }
    }
    path.line(o, top, CycleFeed::Rapid);
    path.line(o, safe, CycleFeed::Rapid);
    Ok(())
}

/// One finishing ring round `fin` at `z`, entered and left on half circles tangent to the
/// outline at its start `(ha, 0)`; the tool starts and ends on the first axis.
pub(super) fn finish_ring(path: &mut Path, fin: RoundedRect, ccw: bool, z: f64, feed: CycleFeed) {
    // A half circle of radius rho about (ha - rho, 0) stays inside the outline when it
    // keeps off the corners (rho <= hb - rc) or, for round ends (rc = hb), when it is
    // smaller than the end circle it touches.
    let straight = fin.hb - fin.rc;
    let limit = if straight > 1e-6 { straight } else { fin.rc };
    let rho = (fin.half_min() / 2.0).min(limit);
    if rho > 1e-3 {
        let c = [fin.ha - rho, 0.0];
        path.line([fin.ha - 2.0 * rho, 0.0], z, feed);
        path.arc(c, [fin.ha, 0.0], z, ccw, 0, feed);
        path.segs(&fin.ring(ccw), z, feed);
        path.arc(c, [fin.ha - 2.0 * rho, 0.0], z, ccw, 0, feed);
    } else {
        path.ring(fin, ccw, z, feed);
    }
}

/// Plunge at the centre from height `from` to `z` as the pocket asks, keeping inside
/// `room` (the region the tool centre may use).
fn plunge(path: &mut Path, pk: &Pocket, room: RoundedRect, r: f64, from: f64, z: f64) {
    let o = [0.0, 0.0];
    match pk.plunge {
        Plunge::Helical if room.half_min().min(r) > 1e-3 => {
            let rh = room.half_min().min(r);
            path.line([rh, 0.0], from, pk.f_plunge);
            path.arc(o, [rh, 0.0], z, pk.ccw, 0, pk.f_plunge);
            path.line(o, z, pk.f_plunge);
        }
        Plunge::Reciprocating if room.ha.min(2.0 * r.max(1.0)) > 1e-3 => {
            let l = room.ha.min(2.0 * r.max(1.0));
            let dz = z - from;
            path.line([l, 0.0], from + dz / 4.0, pk.f_plunge);
            path.line([-l, 0.0], from + 3.0 * dz / 4.0, pk.f_plunge);
            path.line(o, z, pk.f_plunge);
        }
        _ => path.line(o, z, pk.f_plunge),
    }
}
