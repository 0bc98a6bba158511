//! Recesses: the G22 recess element of a FINISHED PART contour and the recessing cycles
//! G866/G870 (one recess element) and G860 (a contour area cut by plunges).
//!
//! **G22-Geo** puts a rectangular recess into the axis-parallel line programmed just
//! before it. On a lateral surface (the line runs along Z) `Z` is where the recess starts,
//! `I` the diameter of its floor (or `Ii` its depth, a signed diameter value) and `K` the Z
//! where it ends (or `Ki` its signed width). On a face (the line runs along X) `X` is the
//! start diameter, `I` the end diameter (`Ii` the signed width, a diameter value), `K` the Z
//! of the floor (`Ki` the signed depth). The line is split there: along the line to the
//! first edge, in to the floor, along the floor, out to the line, on to the line's end. The
//! recess elements carry the G22 block's number, the pieces of the line keep theirs.
//! Outside radii/chamfers B and inside radii R are not supported.
//!
//! Tools have no cutting width in klar's tool data, so the recessing cycles take it as `P`
//! (mm). The tool's reference point is the corner at the upper end of its width: for a
//! lateral recess the corner towards +Z (the tool covers Z from z − P to z), for a face
//! recess the corner towards +X.
//!
//! **G866 / G870** (`NS`, `I`, `E`, `P`, `F`) cut the G22 recess of block NS by plunges:
//! the first at the edge that lies at the upper end of the width, the last at the other
//! edge, the ones between spaced equally and no more than 0.8 × P apart (the cuts
//! overlap). Each plunge runs at the feed from the safety distance [`SAFETY`] above the
//! surface to the floor, dwells E seconds when E is given, and rapids back out. With the
//! allowance I (mm, on walls and floor alike) the plunges stay I away from them and a
//! finishing pass follows: down the upper wall, along the floor, up the other wall. The
//! tool moves paraxially: first along the width to the recess, then down; at the end out
//! and back to where it stood.
//!
//! **G860** (`NS`, `NE`, `P`, `I`, `K`, `Q`, `E`, `F`) cuts the contour area from block NS
//! to NE (a recess with sloped or round walls, too) radially: the area spans the Z range of
//! those elements and reaches up to where the tool stands. Plunges as for G866, each down
//! to the highest point of the contour (shifted by the allowances I — a diameter value —
//! and K) under the tool's width. Q0 (default) roughs and finishes, Q1 only roughs, Q2 only
//! finishes; the finishing pass runs along the same envelope at the feed E (default: the
//! active feed) from the upper edge to the lower and out.
//!
//! G860 works radially or axially (the manual's "axially/radially from NS to NE"): klar
//! takes a section that spans more along X than along Z from its first point to its last
//! as a recess in the front face and cuts it axially: the same plunges along −Z, the tool's
//! width along X with its reference at the +X corner (it covers x − P … x), the area
//! reaching up to the Z where the tool stands; at the end out along Z first, then along X
//! back to the start (radially: X first, then Z).

use std::collections::VecDeque;

use super::contour::Seg;
use super::lathe::{Group, Lathe, err_at, num};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Feed, Op, OpKind, Pose, SourceLoc};
use crate::tnc::exec::ExecError;

/// Clearance above the surface for the plunges, mm.
pub const SAFETY: f64 = 1.0;

/// Most plunges of one cycle.
pub const MAX_PLUNGES: f64 = 10_000.0;

/// A rectangular recess in the turning plane; coordinates index 0 = Z, 1 = X radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Recess {
    /// The coordinate the plunges run along: 1 (X) on a lateral surface, 0 (Z) on a face.
    pub plunge: usize,
    /// The surface level (plunge coordinate).
    pub top: f64,
    /// The floor level (plunge coordinate).
    pub floor: f64,
    /// The recess's extent along the width coordinate, low and high.
    pub span: [f64; 2],
}

/// Reads a G22 group on the reference line from `a` to `b` (Z, X radius): the recess and
/// the points that replace the line (a, entry, floor corner, floor corner, exit, b).
pub(crate) fn g22(
    g: &Group<'_>,
    a: [f64; 2],
    b: [f64; 2],
) -> Result<(Recess, [[f64; 2]; 6]), ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    if let Some(w) = ["B", "R"].iter().find_map(|k| g.get(k))
        && num(w)? != 0.0
    {
        return Err(err_at(
            w,
            ProgramError::NotSupported("G22 outside radii/chamfers B and inside radii R".into()),
        ));
    }
    let lateral = (a[1] - b[1]).abs() < 1e-9 && (a[0] - b[0]).abs() > 1e-9;
    let face = (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() > 1e-9;
    if !lateral && !face {
        return Err((
            here,
            ProgramError::Geometry(
                "G22 needs an axis-parallel straight element just before it".into(),
            ),
        ));
    }
    let pick = |abs: &str, inc: &str| -> Result<Option<(f64, bool)>, ExecError> {
        match (g.get(abs), g.get(inc)) {
            (Some(_), Some(w)) => Err(err_at(
                w,
                ProgramError::Unexpected(format!("{abs} and {inc} in one G22: give one")),
            )),
            (Some(w), None) => Ok(Some((num(w)?, false))),
            (None, Some(w)) => Ok(Some((num(w)?, true))),
            (None, None) => Ok(None),
        }
    };
    let need =
        |v: Option<(f64, bool)>, what: &'static str| v.ok_or((here, ProgramError::Missing(what)));
    let (plunge, start, floor, end) = if lateral {
        let z = g.value("Z")?.ok_or((
            here,
            ProgramError::Missing("G22 on a lateral surface needs its start Z"),
        ))?;
        let top = a[1];
        let (i, inc) = need(
            pick("I", "Ii")?,
            "G22 needs the floor diameter I (or the depth Ii)",
        )?;
        let floor = if inc { top + i / 2.0 } else { i / 2.0 };
        let (k, kinc) = need(pick("K", "Ki")?, "G22 needs the end K (or the width Ki)")?;
        (1, z, floor, if kinc { z + k } else { k })
    } else {
        let x = g.value("X")?.ok_or((
            here,
            ProgramError::Missing("G22 on a face needs its start diameter X"),
        ))? / 2.0;
        let top = a[0];
        let (k, kinc) = need(pick("K", "Ki")?, "G22 needs the floor K (or the depth Ki)")?;
        let floor = if kinc { top + k } else { k };
        let (i, inc) = need(
            pick("I", "Ii")?,
            "G22 needs the end diameter I (or the width Ii)",
        )?;
        (0, x, floor, if inc { x + i / 2.0 } else { i / 2.0 })
    };
    let w = 1 - plunge;
    let top = a[plunge];
    let (lo, hi) = (a[w].min(b[w]), a[w].max(b[w]));
    let inside = |v: f64| v >= lo - 1e-9 && v <= hi + 1e-9;
    if !(inside(start) && inside(end)) || (start - end).abs() < 1e-9 {
        return Err((
            here,
            ProgramError::Geometry(format!(
                "G22: the recess from {start:.3} to {end:.3} must lie on its reference element ({lo:.3} to {hi:.3}) and have a width"
            )),
        ));
    }
    if (floor - top).abs() < 1e-9 || (plunge == 1 && floor < -1e-9) {
        return Err((
            here,
            ProgramError::Geometry(
                "G22: the recess needs a depth (and a floor at X0 or above)".into(),
            ),
        ));
    }
    // the edge the line reaches first, then the other
    let (first, second) = if (start - a[w]).abs() <= (end - a[w]).abs() {
        (start, end)
    } else {
        (end, start)
    };
    let at = |wv: f64, pv: f64| {
        let mut p = [0.0; 2];
        p[w] = wv;
        p[plunge] = pv;
        p
    };
    let recess = Recess {
        plunge,
        top,
        floor,
        span: [start.min(end), start.max(end)],
    };
    Ok((
        recess,
        [
            a,
            at(first, top),
            at(first, floor),
            at(second, floor),
            at(second, top),
            b,
        ],
    ))
}

/// The parameters of G866/G870.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Plunges {
    /// P: cutting width of the tool.
    pub width: f64,
    /// I: allowance on walls and floor.
    pub allowance: f64,
    /// E: dwell at the floor, seconds.
    pub dwell: Option<f64>,
    /// The cutting feed.
    pub feed: Feed,
}

/// Reads the cutting width P (required, positive).
fn width(g: &Group<'_>) -> Result<f64, ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    let p = g.value("P")?.ok_or((
        here,
        ProgramError::Missing("the recessing cycle needs the tool's cutting width P"),
    ))?;
    if !(p > 0.0 && p.is_finite()) {
        return Err((
            here,
            ProgramError::OutOfRange(format!("cutting width P{p} must be positive")),
        ));
    }
    Ok(p)
}

/// Reads the words of G866/G870 (NS is read by the caller).
pub(crate) fn plunge_params(lathe: &mut Lathe, g: &Group<'_>) -> Result<Plunges, ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    if let Some(f) = g.get("F") {
        lathe.set_feed(num(f)?, f)?;
    }
    let feed = lathe.need_feed().map_err(|(_, e)| (here, e))?;
    let allowance = g.value("I")?.unwrap_or(0.0);
    if !(allowance >= 0.0 && allowance.is_finite()) {
        return Err((
            here,
            ProgramError::OutOfRange(format!("allowance I{allowance} must not be negative")),
        ));
    }
    let dwell = g.value("E")?;
    if let Some(e) = dwell
        && !(e >= 0.0 && e.is_finite())
    {
        return Err((here, ProgramError::OutOfRange(format!("dwell E{e}"))));
    }
    Ok(Plunges {
        width: width(g)?,
        allowance,
        dwell,
        feed,
    })
}

/// The plunge positions (tool reference, width coordinate) that cover `lo..hi` with a
/// tool `p` wide: from `hi` down to `lo + p`, equally spaced, no more than 0.8·p apart.
pub(crate) fn positions(lo: f64, hi: f64, p: f64) -> Result<Vec<f64>, ProgramError> {
    let span = hi - lo;
    if span < p - 1e-9 {
        return Err(ProgramError::Geometry(format!(
            "the recess is {span:.3} mm wide: narrower than the cutting width P{p}"
        )));
    }
    let travel = (span - p).max(0.0);
    let gaps = (travel / (0.8 * p) - 1e-9).ceil().max(0.0);
    if gaps + 1.0 > MAX_PLUNGES {
        return Err(ProgramError::OutOfRange(format!(
            "{} plunges of P{p}: more than {MAX_PLUNGES}",
            gaps + 1.0
        )));
    }
    if gaps == 0.0 {
        return Ok(vec![hi]);
    }
    let step = travel / gaps;
    Ok((0..=(gaps as u32))
        .map(|i| hi - step * f64::from(i))
        .collect())
}

/// A pose with the turning-plane point `q` (Z, X radius), other axes from `base`.
fn pose(q: [f64; 2], base: Pose) -> Pose {
    let mut b = base;
    b[AxisLetter::Z] = q[0];
    b[AxisLetter::X] = q[1];
    b
}

/// Runs G866/G870 on `r` from where the tool stands.
pub(crate) fn cut_recess(
    lathe: &mut Lathe,
    r: &Recess,
    p: &Plunges,
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) -> Result<(), ProgramError> {
    let (k, w) = (r.plunge, 1 - r.plunge);
    let start = [lathe.pos[AxisLetter::Z], lathe.pos[AxisLetter::X]];
    // +1 when the surface lies above the floor (outside recess, front face)
    let up = if r.top > r.floor { 1.0 } else { -1.0 };
    let clear = r.top + up * SAFETY;
    if (start[k] - clear) * up < -1e-9 {
        return Err(ProgramError::Geometry(
            "the recessing cycle starts below the surface: stand outside the part".into(),
        ));
    }
    let i = p.allowance;
    let floor = r.floor + up * i;
    if (r.top - floor) * up <= 1e-9 {
        return Err(ProgramError::Geometry(format!(
            "the allowance I{i} fills the recess"
        )));
    }
    let at = |wv: f64, pv: f64| {
        let mut q = [0.0; 2];
        q[w] = wv;
        q[k] = pv;
        q
    };
    let places = positions(r.span[0] + i, r.span[1] - i, p.width)?;
    let dwell = |out: &mut VecDeque<Op>| {
        if let Some(s) = p.dwell {
            out.push_back(Op {
                kind: OpKind::Dwell { seconds: s },
                loc,
            });
        }
    };
    // along the width to the first position, then in to the clearance
    lathe.line(
        pose(at(places[0], start[k]), lathe.pos),
        Feed::Rapid,
        loc,
        out,
    );
    for c in &places {
        lathe.line(pose(at(*c, clear), lathe.pos), Feed::Rapid, loc, out);
        lathe.line(pose(at(*c, floor), lathe.pos), p.feed, loc, out);
        dwell(out);
        lathe.line(pose(at(*c, clear), lathe.pos), Feed::Rapid, loc, out);
    }
    if i > 0.0 {
        let (hi, lo) = (r.span[1], r.span[0] + p.width);
        lathe.line(pose(at(hi, clear), lathe.pos), Feed::Rapid, loc, out);
        lathe.line(pose(at(hi, r.floor), lathe.pos), p.feed, loc, out);
        lathe.line(pose(at(lo, r.floor), lathe.pos), p.feed, loc, out);
        lathe.line(pose(at(lo, clear), lathe.pos), p.feed, loc, out);
    }
    lathe.line(
        pose(at(lathe_w(lathe, w), start[k]), lathe.pos),
        Feed::Rapid,
        loc,
        out,
    );
    lathe.line(pose(start, lathe.pos), Feed::Rapid, loc, out);
    Ok(())
}

/// The tool's current width coordinate.
fn lathe_w(lathe: &Lathe, w: usize) -> f64 {
    if w == 0 {
        lathe.pos[AxisLetter::Z]
    } else {
        lathe.pos[AxisLetter::X]
    }
}

/// The parameters of G860.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Area {
    /// P: cutting width.
    pub width: f64,
    /// Allowances (z, x radius).
    pub allowance: [f64; 2],
    /// Q: 0 rough and finish, 1 rough, 2 finish.
    pub variant: u8,
    /// Roughing feed.
    pub feed: Feed,
    /// Finishing feed (E).
    pub finish: Feed,
}

/// Reads the words of G860 (NS/NE are read by the caller).
pub(crate) fn area_params(lathe: &mut Lathe, g: &Group<'_>) -> Result<Area, ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    if let Some(f) = g.get("F") {
        lathe.set_feed(num(f)?, f)?;
    }
    let feed = lathe.need_feed().map_err(|(_, e)| (here, e))?;
    let variant = match g.get("Q") {
        None => 0,
        Some(q) => {
            let v = num(q)?;
            if !(v == 0.0 || v == 1.0 || v == 2.0) {
                return Err(err_at(
                    q,
                    ProgramError::OutOfRange(format!("G860 Q{v}: expected 0, 1 or 2")),
                ));
            }
            v as u8
        }
    };
    let finish = match g.get("E") {
        None => feed,
        Some(e) => {
            let v = num(e)?;
            let mut tmp = Lathe::new(lathe.pos);
            tmp.feed_unit = lathe.feed_unit;
            tmp.driven_speed = lathe.driven_speed;
            tmp.set_feed(v, e)?;
            tmp.need_feed().map_err(|(_, m)| (here, m))?
        }
    };
    Ok(Area {
        width: width(g)?,
        allowance: [
            g.value("K")?.unwrap_or(0.0),
            g.value("I")?.unwrap_or(0.0) / 2.0,
        ],
        variant,
        feed,
        finish,
    })
}

/// The highest radius of the contour `segs` over Z from `lo` to `hi` (None: no element
/// there).
pub(crate) fn envelope(segs: &[Seg], lo: f64, hi: f64) -> Option<f64> {
    let mut best: Option<f64> = None;
    let mut take = |v: f64| best = Some(best.map_or(v, |b: f64| b.max(v)));
    for s in segs {
        for q in s.samples() {
            if q[0] >= lo - 1e-9 && q[0] <= hi + 1e-9 {
                take(q[1]);
            }
        }
        for z in [lo, hi] {
            for x in s.crossings(0, z) {
                take(x);
            }
        }
    }
    best
}

/// The element with Z and X exchanged (a mirror: arcs turn the other way).
fn swapped(s: &Seg) -> Seg {
    let m = |p: [f64; 2]| [p[1], p[0]];
    match *s {
        Seg::Line { a, b } => Seg::Line { a: m(a), b: m(b) },
        Seg::Arc {
            a,
            b,
            centre,
            sweep,
        } => Seg::Arc {
            a: m(a),
            b: m(b),
            centre: m(centre),
            sweep: -sweep,
        },
    }
}

/// Whether G860 works axially on `segs`: the section spans more along X than along Z
/// from its first point to its last (a recess in a face).
pub(crate) fn is_axial(segs: &[Seg]) -> bool {
    let ends = |s: &Seg| match *s {
        Seg::Line { a, b } | Seg::Arc { a, b, .. } => (a, b),
    };
    match (segs.first(), segs.last()) {
        (Some(f), Some(l)) => {
            let (a, b) = (ends(f).0, ends(l).1);
            (b[1] - a[1]).abs() > (b[0] - a[0]).abs() + 1e-9
        }
        _ => false,
    }
}

/// Runs G860 over the contour elements `segs` from where the tool stands.
///
/// The cycle is worked out in a frame (u, v) where u runs along the tool's width and the
/// tool plunges towards −v: (Z, X radius) radially, (X radius, Z) axially.
pub(crate) fn cut_area(
    lathe: &mut Lathe,
    segs: &[Seg],
    a: &Area,
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) -> Result<(), ProgramError> {
    if segs.is_empty() {
        return Err(ProgramError::Missing(
            "G860 needs a FINISHED PART contour (with elements from NS to NE)",
        ));
    }
    let axial = is_axial(segs);
    // (u, v) ↔ (z, x)
    let to_zx = |q: [f64; 2]| if axial { [q[1], q[0]] } else { q };
    let segs: Vec<Seg> = segs
        .iter()
        .map(|s| {
            let s = s.shifted(a.allowance);
            if axial { swapped(&s) } else { s }
        })
        .collect();
    let at = |q: [f64; 2], base: Pose| pose(to_zx(q), base);
    let pts: Vec<[f64; 2]> = segs.iter().flat_map(Seg::samples).collect();
    let lo = pts.iter().map(|q| q[0]).fold(f64::INFINITY, f64::min);
    let hi = pts.iter().map(|q| q[0]).fold(f64::NEG_INFINITY, f64::max);
    let top = pts.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max);
    let start = to_zx([lathe.pos[AxisLetter::Z], lathe.pos[AxisLetter::X]]);
    if start[1] < top - 1e-9 {
        return Err(ProgramError::Geometry(if axial {
            format!(
                "G860 starts at Z{:.3}, behind the face recess's top Z{:.3}: stand in front of it",
                start[1], top
            )
        } else {
            format!(
                "G860 starts at X{:.3}, below the area's top X{:.3}: stand above it",
                start[1] * 2.0,
                top * 2.0
            )
        }));
    }
    let clear = start[1];
    let places = positions(lo, hi, a.width)?;
    let depth = |c: f64| envelope(&segs, c - a.width, c).unwrap_or(top);
    lathe.line(at([places[0], clear], lathe.pos), Feed::Rapid, loc, out);
    if a.variant != 2 {
        for c in &places {
            lathe.line(at([*c, clear], lathe.pos), Feed::Rapid, loc, out);
            lathe.line(at([*c, depth(*c)], lathe.pos), a.feed, loc, out);
            lathe.line(at([*c, clear], lathe.pos), Feed::Rapid, loc, out);
        }
    }
    if a.variant != 1 {
        // the envelope changes slope only where an element's corner meets an edge of the
        // tool: walk through those places
        let mut stops: Vec<f64> = pts
            .iter()
            .flat_map(|q| [q[0], q[0] + a.width])
            .chain([hi, lo + a.width])
            .filter(|z| *z >= lo + a.width - 1e-9 && *z <= hi + 1e-9)
            .collect();
        stops.sort_by(|x, y| y.total_cmp(x));
        stops.dedup_by(|x, y| (*x - *y).abs() < 1e-9);
        lathe.line(at([hi, clear], lathe.pos), Feed::Rapid, loc, out);
        let mut u = hi;
        for z in stops {
            lathe.line(at([z, depth(z)], lathe.pos), a.finish, loc, out);
            u = z;
        }
        lathe.line(at([u, clear], lathe.pos), a.finish, loc, out);
    }
    // out along the plunge axis first (it is at the clearance already), then across
    lathe.line(at(start, lathe.pos), Feed::Rapid, loc, out);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plunge_positions_cover_the_recess() {
        // 10 wide, P4: travel 6, at most 3.2 apart -> 2 gaps of 3
        assert_eq!(
            positions(-30.0, -20.0, 4.0).unwrap(),
            vec![-20.0, -23.0, -26.0]
        );
        assert_eq!(positions(-24.0, -20.0, 4.0).unwrap(), vec![-20.0]);
        assert!(positions(-23.0, -20.0, 4.0).is_err());
    }
}
