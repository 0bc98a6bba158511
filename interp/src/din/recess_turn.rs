//! Recess turning G869 on a section of the FINISHED PART contour.
//!
//! From the CNC PILOT / MANUALplus DIN manual, in our words: G869 clears the contour area
//! NS…NE with a recessing tool by alternating plunges and turning passes, so that the tool
//! lifts and re-enters as little as possible. `NS` alone (or the block of a G22 recess)
//! names one element (or the recess); `P` is the largest infeed, `I` (a diameter value) and
//! `K` the oversizes in X and Z, `X` (diameter) and `Z` cutting limits, `Q` the sequence
//! (0 rough and finish, 1 rough only, 2 finish only), `U` the turning direction (0 both
//! ways, 1 always from NS towards NE), `O` the recessing feed and `E` the finishing feed
//! (both default: the active feed), `NS` = `NE` the one element against its programmed
//! direction (so the first plunge is at its other end), `H` the retraction at the end (0: back to the start
//! point, radially X first, then Z, axially Z first; 1: in front of the finished contour;
//! 2: at the safety clearance). The control tells radial from axial by the tool.
//!
//! klar's cuts (radial on an outside or inside contour, axial on a front or rear face):
//!
//! - Outside or inside: a tool that starts at or above the section's highest point cuts it
//!   from outside; one that starts at or below its lowest point (in the bore) cuts it from
//!   inside, the same cycle mirrored in X: levels go outwards, the safety distance and the
//!   retraction lie towards the axis. Between the two the cycle refuses to start. Below,
//!   "up" means away from the material, towards where the tool stands (and axially X and
//!   Z read exchanged).
//! - Axial: klar's tools carry no orientation, so, as with G860, a section that spans more
//!   along X than along Z from its first point to its last (a recess in a face) is cut
//!   the same way with Z and X exchanged: plunges along Z, turning passes along X, the
//!   tool's width along X with its reference corner at the +X end, I/K still the X/Z
//!   oversizes, the Z limit bounds the depth and the X limit the passes, and the
//!   retraction at the end runs first along Z, then along X. A tool standing behind the
//!   section (below its lowest Z) cuts a rear face, plunging along +Z.
//! - The manual's G869 has no word for the cutting width: its `P` is the largest infeed
//!   (unlike G860/G866/G870, whose `P` is the cutting width) and `B` the offset width; the
//!   control takes the width from the tool table. Tools carry no cutting width in klar's
//!   tool data, so G869 takes it as `SB` (mm), the name of the cutting width in that tool
//!   table; `P` stays the infeed as in the manual. The tool's reference point is the
//!   corner at the +Z end of its width: standing at z it covers z − SB … z.
//! - With the oversizes the tool keeps K away from the contour along Z and I/2 along X: at
//!   a reference position z the lowest radius it may reach is the highest contour point
//!   under z − SB − K … z + K, raised by I/2 (points exactly on the window's edges do not
//!   count, so a tool flush with a vertical wall may go down along it).
//! - The area reaches from the highest point T of the section down to the lowest radius B
//!   the tool reaches anywhere (not below the X limit). It is cut in n = ⌈(T − B)/P⌉ levels
//!   of equal depth d = (T − B)/n, so no infeed exceeds P. Level k lies at T − k·d.
//! - On each level the tool may stand wherever the contour lets it reach that level: one
//!   stretch of Z per level (contours whose level splits into several valleys are not
//!   supported). At each level the tool plunges at the recessing feed by d (the first
//!   plunge from the safety distance above T) and then turns at the feed along the whole
//!   stretch. With U0 the next plunge starts where the turning pass ended (moving along the
//!   level just cut when the next stretch is shorter), so the passes go back and forth;
//!   with U1 the tool lifts to the safety distance above T after each pass, returns to the
//!   start side and comes down at rapid to the safety distance above the level just cut.
//!   The first plunge is at the end of the area where the section begins (NS).
//! - `B` (offset width, U0 only): from the second plunge on, each pass back to the NS end
//!   that turns into a plunge stops short of it, by j·B the j-th time, never more than
//!   0.8·SB; one cut at the NS end takes away what these passes left (see
//!   `recess_offset`).
//! - Finishing (Q0, Q2) follows the contour itself (without oversizes): from the safety
//!   distance above T down to the lowest reachable point at the NS end, along the contour
//!   under the tool's width to the NE end and up again, at the finishing feed.
//! - At the end (H0) the tool moves out in X to where it started, then along Z to the start
//!   point. It must start outside the area (at or above T). With H2 it stays where the last
//!   cut left it at the safety distance (the manual: retract to the safety clearance and
//!   stop).
//!
//! Not supported: the turning depth compensation R (the manual names its purpose, the tool
//! tip yielding while it turns, but not along which finishing moves it acts), approach and
//! departure angles A/W (no reference direction given), H1 ("in front of the finished
//! contour", no place given), auxiliary contours ID.

use std::collections::VecDeque;

use super::contour::Seg;
use super::grooving::SAFETY;
use super::lathe::{Group, Lathe, err_at, num};
use super::recess_offset::{Offsets, Step, clean_up};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Feed, Op, SourceLoc};
use crate::tnc::exec::ExecError;

/// The words a G869 block takes.
pub(crate) const G869_WORDS: [&str; 18] = [
    "NS", "NE", "P", "SB", "I", "K", "X", "Z", "Q", "U", "O", "E", "F", "R", "B", "A", "W", "H",
];

/// Most levels of one cycle.
pub const MAX_LEVELS: f64 = 2_000.0;

/// How far inside the tool's window a contour point must lie to count, mm: keeps a wall
/// that lies exactly on the window's edge out of it.
const EDGE: f64 = 1e-10;

/// How many places per level are checked for the stretch the tool may stand on.
const PROBES: u32 = 400;

/// The parameters of one G869.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RecessTurn {
    /// SB: cutting width of the tool.
    pub width: f64,
    /// P: largest infeed.
    pub infeed: f64,
    /// Oversizes (z, x radius).
    pub allowance: [f64; 2],
    /// X limit (radius): no cut goes below it.
    pub x_limit: Option<f64>,
    /// Z limit: the tool stays at or above it.
    pub z_limit: Option<f64>,
    /// Q: 0 rough and finish, 1 rough, 2 finish.
    pub variant: u8,
    /// U1: every turning pass runs from the NS end to the NE end.
    pub one_way: bool,
    /// The turning feed.
    pub feed: Feed,
    /// O: the recessing (plunge) feed.
    pub plunge: Feed,
    /// E: the finishing feed.
    pub finish: Feed,
    /// H2: the cycle ends at the safety distance where its last cut ended.
    pub stop_at_safety: bool,
    /// B: the offset width of the passes that turn into a plunge at the NS end (0: none).
    pub offset: f64,
}

/// A feed word other than F (O, E) in the active feed unit, or `default`.
fn other_feed(lathe: &Lathe, g: &Group<'_>, addr: &str, default: Feed) -> Result<Feed, ExecError> {
    match g.get(addr) {
        None => Ok(default),
        Some(w) => {
            let mut tmp = Lathe::new(lathe.pos);
            tmp.feed_unit = lathe.feed_unit;
            tmp.driven_speed = lathe.driven_speed;
            tmp.set_feed(num(w)?, w)?;
            tmp.need_feed().map_err(|(_, m)| (Some(w.pos as u32), m))
        }
    }
}

/// A positive, finite length word that the cycle needs.
fn positive(g: &Group<'_>, addr: &str, what: &'static str) -> Result<f64, ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    let w = g.get(addr).ok_or((here, ProgramError::Missing(what)))?;
    let v = num(w)?;
    if !(v > 0.0 && v.is_finite()) {
        return Err(err_at(
            w,
            ProgramError::OutOfRange(format!("G869 {addr}{v} must be positive")),
        ));
    }
    Ok(v)
}

/// Reads the words of G869 (NS/NE are read by the caller).
pub(crate) fn params(lathe: &mut Lathe, g: &Group<'_>) -> Result<RecessTurn, ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    if let Some(w) = g.get("R")
        && num(w)? != 0.0
    {
        return Err(err_at(
            w,
            ProgramError::NotSupported(
                "G869 R other than 0 (the turning depth compensation for finishing: the \
                 manual does not say along which moves of the finishing pass it acts)"
                    .into(),
            ),
        ));
    }
    let stop_at_safety = match g.get("H") {
        None => false,
        Some(w) => {
            let v = num(w)?;
            if v == 1.0 {
                return Err(err_at(
                    w,
                    ProgramError::NotSupported(
                        "G869 H1 (positioning in front of the finished contour)".into(),
                    ),
                ));
            }
            if v != 0.0 && v != 2.0 {
                return Err(err_at(
                    w,
                    ProgramError::OutOfRange(format!("G869 H{v}: expected 0, 1 or 2")),
                ));
            }
            v == 2.0
        }
    };
    for addr in ["A", "W"] {
        if let Some(w) = g.get(addr) {
            return Err(err_at(
                w,
                ProgramError::NotSupported(format!(
                    "G869 {addr}: approach and departure run opposite to the plunge"
                )),
            ));
        }
    }
    if let Some(f) = g.get("F") {
        lathe.set_feed(num(f)?, f)?;
    }
    let feed = lathe.need_feed().map_err(|(_, e)| (here, e))?;
    let choice = |addr: &str, top: f64| -> Result<u8, ExecError> {
        match g.get(addr) {
            None => Ok(0),
            Some(w) => {
                let v = num(w)?;
                if v.fract() != 0.0 || !(0.0..=top).contains(&v) {
                    return Err(err_at(
                        w,
                        ProgramError::OutOfRange(format!("G869 {addr}{v}: expected 0 to {top}")),
                    ));
                }
                Ok(v as u8)
            }
        }
    };
    let variant = choice("Q", 2.0)?;
    let one_way = choice("U", 1.0)? == 1;
    let offset = match g.get("B") {
        None => 0.0,
        Some(w) => {
            let v = num(w)?;
            if !(v.is_finite() && v >= 0.0) {
                return Err(err_at(
                    w,
                    ProgramError::OutOfRange(format!(
                        "G869 offset width B{v} must not be negative"
                    )),
                ));
            }
            if v > 0.0 && one_way {
                return Err(err_at(
                    w,
                    ProgramError::NotSupported(
                        "G869 B with U1: one-way passes never turn into a plunge, where the \
                         offset acts"
                            .into(),
                    ),
                ));
            }
            v
        }
    };
    let allowance = [
        g.value("K")?.unwrap_or(0.0),
        g.value("I")?.unwrap_or(0.0) / 2.0,
    ];
    if !allowance.iter().all(|a| a.is_finite() && *a >= 0.0) {
        return Err((
            here,
            ProgramError::OutOfRange("G869 oversizes I/K must not be negative".into()),
        ));
    }
    Ok(RecessTurn {
        width: positive(g, "SB", "G869 needs the tool's cutting width SB")?,
        infeed: positive(g, "P", "G869 needs the largest infeed P")?,
        allowance,
        x_limit: g.value("X")?.map(|x| x / 2.0),
        z_limit: g.value("Z")?,
        variant,
        one_way,
        feed,
        plunge: other_feed(lathe, g, "O", feed)?,
        finish: other_feed(lathe, g, "E", feed)?,
        stop_at_safety,
        offset,
    })
}

/// Where the straight or round element crosses Z = `z` strictly between its ends (ends
/// count as points of their own).
fn crossings(s: &Seg, z: f64) -> Vec<f64> {
    match *s {
        Seg::Line { a, b } => {
            if (z - a[0]) * (z - b[0]) < 0.0 {
                vec![a[1] + (z - a[0]) / (b[0] - a[0]) * (b[1] - a[1])]
            } else {
                Vec::new()
            }
        }
        Seg::Arc { .. } => s.crossings(0, z),
    }
}

/// The highest contour point strictly inside Z `lo`…`hi` (None: no element there).
fn highest(segs: &[Seg], lo: f64, hi: f64) -> Option<f64> {
    let (lo, hi) = (lo + EDGE, hi - EDGE);
    let mut best: Option<f64> = None;
    let mut take = |v: f64| best = Some(best.map_or(v, |b: f64| b.max(v)));
    for s in segs {
        for q in s.samples() {
            if q[0] > lo && q[0] < hi {
                take(q[1]);
            }
        }
        for z in [lo, hi] {
            for x in crossings(s, z) {
                take(x);
            }
        }
    }
    best
}

/// The area G869 works on, for one contour section and set of parameters.
struct Area<'a> {
    segs: &'a [Seg],
    width: f64,
    allowance: [f64; 2],
    /// The highest point of the section (radius).
    top: f64,
    /// The range of tool reference positions, low and high.
    range: [f64; 2],
    /// Places where the reach changes its course: corners and corners shifted by the
    /// window, inside the range, ascending.
    stops: Vec<f64>,
    /// How the cycle's plane lies in the turning plane (for messages).
    frame: Frame,
}

impl Area<'_> {
    /// The lowest radius the tool may reach standing at `z`, with the oversizes `a`.
    fn reach_with(&self, z: f64, a: [f64; 2]) -> f64 {
        highest(self.segs, z - self.width - a[0], z + a[0]).map_or(self.top, |x| x + a[1])
    }

    /// The reach with the roughing oversizes.
    fn reach(&self, z: f64) -> f64 {
        self.reach_with(z, self.allowance)
    }

    /// The places probed for a level: the range's ends, the stops and a grid.
    fn probes(&self) -> Vec<f64> {
        let [lo, hi] = self.range;
        let mut p: Vec<f64> = (0..=PROBES)
            .map(|i| lo + (hi - lo) * f64::from(i) / f64::from(PROBES))
            .chain(self.stops.iter().copied())
            .collect();
        p.sort_by(f64::total_cmp);
        p.dedup_by(|x, y| (*x - *y).abs() < 1e-9);
        p
    }

    /// The stretch of reference positions from which the tool reaches down to `x`, given
    /// the probes `p` with their reaches `r`.
    fn stretch(&self, p: &[f64], r: &[f64], x: f64) -> Result<[f64; 2], ProgramError> {
        let ok: Vec<bool> = r.iter().map(|v| *v <= x + 1e-9).collect();
        let first = ok.iter().position(|o| *o);
        let last = ok.iter().rposition(|o| *o);
        let (Some(i), Some(j)) = (first, last) else {
            return Err(ProgramError::Geometry(format!(
                "G869: no place reaches {}",
                self.frame.depth(x)
            )));
        };
        if ok.get(i..=j).is_some_and(|s| s.iter().any(|o| !*o)) {
            return Err(ProgramError::NotSupported(format!(
                "G869 on a contour whose level {} splits into several valleys",
                self.frame.depth(x)
            )));
        }
        let edge = |inside: f64, outside: Option<f64>| match outside {
            None => inside,
            Some(out) => self.snap(self.boundary(inside, out, x)),
        };
        let lo = edge(p[i], i.checked_sub(1).map(|k| p[k]));
        let hi = edge(p[j], p.get(j + 1).copied());
        Ok([lo, hi])
    }

    /// Bisects between a place `inside` that reaches `x` and one `outside` that does not.
    fn boundary(&self, mut inside: f64, mut outside: f64, x: f64) -> f64 {
        for _ in 0..60 {
            let mid = 0.5 * (inside + outside);
            if self.reach(mid) <= x + 1e-9 {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        inside
    }

    /// `z` moved onto a stop lying within 1e-7 of it.
    fn snap(&self, z: f64) -> f64 {
        self.stops
            .iter()
            .copied()
            .find(|s| (s - z).abs() < 1e-7)
            .unwrap_or(z)
    }
}

/// How the cycle's own plane (u along the contour, v the depth the tool plunges against)
/// lies in the turning plane (z, x radius): radial cuts have u = z, axial cuts u = x; an
/// inside (or rear face) cut mirrors v, so that the tool always comes from high v.
#[derive(Debug, Clone, Copy)]
struct Frame {
    /// u is the radius, v is Z.
    axial: bool,
    /// −1: the tool comes from the low side of the depth axis (a bore or a rear face).
    sign: f64,
}

impl Frame {
    /// The cycle's (u, v) of a turning-plane point (z, x radius).
    fn inward(&self, q: [f64; 2]) -> [f64; 2] {
        let [u, v] = if self.axial { [q[1], q[0]] } else { q };
        [u, v * self.sign]
    }

    /// The turning-plane point (z, x radius) of the cycle's (u, v).
    fn outward(&self, q: [f64; 2]) -> [f64; 2] {
        let q = [q[0], q[1] * self.sign];
        if self.axial { [q[1], q[0]] } else { q }
    }

    /// The element in the cycle's plane; every mirror turns arcs the other way.
    fn seg(&self, s: &Seg) -> Seg {
        let flips = u8::from(self.axial) + u8::from(self.sign < 0.0);
        let turn = if flips == 1 { -1.0 } else { 1.0 };
        match *s {
            Seg::Line { a, b } => Seg::Line {
                a: self.inward(a),
                b: self.inward(b),
            },
            Seg::Arc {
                a,
                b,
                centre,
                sweep,
            } => Seg::Arc {
                a: self.inward(a),
                b: self.inward(b),
                centre: self.inward(centre),
                sweep: sweep * turn,
            },
        }
    }

    /// A depth `v` as the program writes it (X as a diameter, or Z).
    fn depth(&self, v: f64) -> String {
        if self.axial {
            format!("Z{:.3}", v * self.sign)
        } else {
            format!("X{:.3}", v * self.sign * 2.0)
        }
    }

    /// Where the tool stands, in the cycle's plane.
    fn here(&self, lathe: &Lathe) -> [f64; 2] {
        self.inward([lathe.pos[AxisLetter::Z], lathe.pos[AxisLetter::X]])
    }
}

/// The section run the other way: last element first, each from its end to its start.
pub(crate) fn reversed(segs: &[Seg]) -> Vec<Seg> {
    segs.iter()
        .rev()
        .map(|s| match *s {
            Seg::Line { a, b } => Seg::Line { a: b, b: a },
            Seg::Arc {
                a,
                b,
                centre,
                sweep,
            } => Seg::Arc {
                a: b,
                b: a,
                centre,
                sweep: -sweep,
            },
        })
        .collect()
}

/// Runs G869 over the contour elements `segs` (in their programmed order) from where the
/// tool stands.
pub(crate) fn run(
    lathe: &mut Lathe,
    segs: &[Seg],
    c: &RecessTurn,
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) -> Result<(), ProgramError> {
    if segs.is_empty() {
        return Err(ProgramError::Missing(
            "G869 needs a FINISHED PART contour (with elements from NS to NE)",
        ));
    }
    let axial = super::grooving::is_axial(segs);
    // outside (tool above the section's top) or inside (below its bottom)
    let plain = Frame { axial, sign: 1.0 };
    let vs: Vec<f64> = segs
        .iter()
        .map(|s| plain.seg(s))
        .flat_map(|s| s.samples())
        .map(|q| q[1])
        .collect();
    let top = vs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let bottom = vs.iter().copied().fold(f64::INFINITY, f64::min);
    let stand = plain.here(lathe)[1];
    let sign = if stand >= top - 1e-9 {
        1.0
    } else if stand <= bottom + 1e-9 {
        -1.0
    } else {
        return Err(ProgramError::Geometry(format!(
            "G869 starts at {}, below the area's top {} and above its bottom {}: stand outside it",
            plain.depth(stand),
            plain.depth(top),
            plain.depth(bottom)
        )));
    };
    let frame = Frame { axial, sign };
    let segs: Vec<Seg> = segs.iter().map(|s| frame.seg(s)).collect();
    // oversizes along u and v; the limits: the depth one on v, the other on u
    let (allowance, v_limit, u_limit) = if axial {
        (
            [c.allowance[1], c.allowance[0]],
            c.z_limit.map(|z| z * sign),
            c.x_limit,
        )
    } else {
        (c.allowance, c.x_limit.map(|x| x * sign), c.z_limit)
    };
    cut(
        lathe,
        &segs,
        c,
        frame,
        [allowance, [0.0, 0.0]],
        (v_limit, u_limit),
        loc,
        out,
    )
}

/// The cycle in its own plane: `segs` are in (u, v), `a[0]` the oversizes along u and v,
/// `lim` the depth limit (v) and the limit along u.
#[allow(clippy::too_many_arguments)]
fn cut(
    lathe: &mut Lathe,
    segs: &[Seg],
    c: &RecessTurn,
    frame: Frame,
    a: [[f64; 2]; 2],
    lim: (Option<f64>, Option<f64>),
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) -> Result<(), ProgramError> {
    let (Some(first), Some(last)) = (segs.first(), segs.last()) else {
        return Err(ProgramError::Missing(
            "G869 needs a FINISHED PART contour (with elements from NS to NE)",
        ));
    };
    let allowance = a[0];
    let (x_limit, z_limit) = lim;
    let ends = |s: &Seg| match *s {
        Seg::Line { a, b } | Seg::Arc { a, b, .. } => (a, b),
    };
    // the direction the section runs along u: the first plunge at its NS end
    let towards_minus = ends(first).0[0] >= ends(last).1[0];
    let pts: Vec<[f64; 2]> = segs.iter().flat_map(Seg::samples).collect();
    let zmin = pts.iter().map(|q| q[0]).fold(f64::INFINITY, f64::min);
    let zmax = pts.iter().map(|q| q[0]).fold(f64::NEG_INFINITY, f64::max);
    let top = pts.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max);
    let lo_edge = z_limit.map_or(zmin, |z| z.max(zmin));
    let range = [lo_edge + c.width + allowance[0], zmax - allowance[0]];
    if range[1] < range[0] - 1e-9 {
        return Err(ProgramError::Geometry(format!(
            "G869: the section ({:.3} mm across) is narrower than SB{} with the oversize",
            zmax - lo_edge,
            c.width
        )));
    }
    let corner_shifts = [0.0, c.width, allowance[0] + c.width, -allowance[0]];
    let mut stops: Vec<f64> = pts
        .iter()
        .flat_map(|q| corner_shifts.map(|s| q[0] + s))
        .chain(range)
        .filter(|z| *z >= range[0] - 1e-9 && *z <= range[1] + 1e-9)
        .collect();
    stops.sort_by(f64::total_cmp);
    stops.dedup_by(|x, y| (*x - *y).abs() < 1e-9);
    let area = Area {
        segs,
        width: c.width,
        allowance,
        top,
        range,
        stops,
        frame,
    };
    let start = frame.here(lathe);
    let clear = start[1];
    let above = (top + SAFETY).min(clear);
    // the NS end and the NE end of a stretch
    let ns_end = |s: [f64; 2]| if towards_minus { s[1] } else { s[0] };
    let ne_end = |s: [f64; 2]| if towards_minus { s[0] } else { s[1] };
    let go = |lathe: &mut Lathe, z: f64, x: f64, feed: Feed, out: &mut VecDeque<Op>| {
        go(lathe, frame, z, x, feed, loc, out)
    };

    if c.variant != 2 {
        let probes = area.probes();
        let reach: Vec<f64> = probes.iter().map(|z| area.reach(*z)).collect();
        let bottom = reach
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
            .max(x_limit.unwrap_or(f64::NEG_INFINITY));
        let depth = top - bottom;
        if depth <= 1e-9 {
            return Err(ProgramError::Geometry(
                "G869: nothing to cut between the section's top and its floor with the oversizes"
                    .into(),
            ));
        }
        let n = (depth / c.infeed - 1e-9).ceil().max(1.0);
        if n > MAX_LEVELS {
            return Err(ProgramError::OutOfRange(format!(
                "G869: {n} levels of P{}: more than {MAX_LEVELS}",
                c.infeed
            )));
        }
        let step = depth / n;
        let levels: Vec<f64> = (1..=(n as u32))
            .map(|k| {
                if k == n as u32 {
                    bottom
                } else {
                    top - step * f64::from(k)
                }
            })
            .collect();
        let stretches = levels
            .iter()
            .map(|x| area.stretch(&probes, &reach, *x))
            .collect::<Result<Vec<_>, _>>()?;
        let z0 = ns_end(stretches[0]);
        go(lathe, z0, clear, Feed::Rapid, out);
        let mut prev = top;
        let mut offsets = Offsets::new(c.offset, c.width);
        // from the NS end into the stretch
        let inward = if towards_minus { -1.0 } else { 1.0 };
        let mut left = vec![false; levels.len()];
        for (k, (x, s)) in levels.iter().zip(&stretches).enumerate() {
            let mut z = frame.here(lathe)[0];
            if k == 0 || c.one_way {
                if k > 0 {
                    go(lathe, z, above, Feed::Rapid, out);
                    z = ns_end(*s);
                }
                go(lathe, z, above, Feed::Rapid, out);
                let down = (prev + SAFETY).min(above);
                go(lathe, z, down, Feed::Rapid, out);
            } else {
                let inside = z.clamp(s[0], s[1]);
                if (inside - z).abs() > 1e-12 {
                    go(lathe, inside, prev, c.feed, out);
                    z = inside;
                }
            }
            go(lathe, z, *x, c.plunge, out);
            // back and forth: even levels towards the NE end, odd ones back to the NS end,
            // where a pass that turns into a plunge stops short by the offset B
            let back = !c.one_way && k % 2 == 1;
            let to = if !back {
                ne_end(*s)
            } else if offsets.active() && k + 1 < levels.len() {
                let short = ns_end(*s) + inward * offsets.next();
                // never beyond where the pass began
                if (short - z) * inward >= 0.0 {
                    z
                } else {
                    short
                }
            } else {
                ns_end(*s)
            };
            if (to - z).abs() > 1e-12 {
                go(lathe, to, *x, c.feed, out);
            }
            left[k] =
                offsets.active() && (z - ns_end(*s)).abs() > 1e-9 && (to - ns_end(*s)).abs() > 1e-9;
            prev = *x;
        }
        let z = frame.here(lathe)[0];
        go(lathe, z, above, Feed::Rapid, out);
        let ns: Vec<f64> = stretches.iter().map(|s| ns_end(*s)).collect();
        for (step, [u, v]) in clean_up(&levels, &ns, &left, above) {
            let feed = match step {
                Step::Rapid => Feed::Rapid,
                Step::Plunge => c.plunge,
                Step::Turn => c.feed,
            };
            go(lathe, u, v, feed, out);
        }
    }

    if c.variant != 1 {
        let floor = |z: f64| {
            area.reach_with(z, [0.0, 0.0])
                .max(x_limit.unwrap_or(f64::NEG_INFINITY))
        };
        // the places where the finishing path changes its course, in its direction
        let span = [lo_edge + c.width, zmax];
        let mut path: Vec<f64> = pts
            .iter()
            .flat_map(|q| [q[0], q[0] + c.width])
            .chain(span)
            .filter(|z| *z >= span[0] - 1e-9 && *z <= span[1] + 1e-9)
            .collect();
        path.sort_by(f64::total_cmp);
        path.dedup_by(|x, y| (*x - *y).abs() < 1e-9);
        let dir = if towards_minus {
            path.reverse();
            -1.0
        } else {
            1.0
        };
        let z0 = path.first().copied().unwrap_or(span[1]);
        let x_now = frame.here(lathe)[1];
        go(lathe, z0, x_now, Feed::Rapid, out);
        go(lathe, z0, above, Feed::Rapid, out);
        let last = path.len().saturating_sub(1);
        for (i, z) in path.into_iter().enumerate() {
            // a step of the contour on either side of this place: along it here
            let at = floor(z);
            let before = floor(z - dir * 1e-7);
            if i > 0 && (before - at).abs() > 1e-6 {
                go(lathe, z, before, c.finish, out);
            }
            go(lathe, z, at, c.finish, out);
            let after = floor(z + dir * 1e-7);
            if i < last && (after - at).abs() > 1e-6 {
                go(lathe, z, after, c.finish, out);
            }
        }
        let z = frame.here(lathe)[0];
        go(lathe, z, above, c.finish, out);
    }
    if c.stop_at_safety {
        return Ok(());
    }
    let z = frame.here(lathe)[0];
    go(lathe, z, clear, Feed::Rapid, out);
    go(lathe, start[0], clear, Feed::Rapid, out);
    Ok(())
}

/// Moves to the cycle's point (u, v) unless the tool stands there already.
fn go(
    lathe: &mut Lathe,
    frame: Frame,
    u: f64,
    v: f64,
    feed: Feed,
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) {
    let [z, x] = frame.outward([u, v]);
    let mut to = lathe.pos;
    to[AxisLetter::Z] = z;
    to[AxisLetter::X] = x;
    if to != lathe.pos {
        lathe.line(to, feed, loc, out);
    }
}
