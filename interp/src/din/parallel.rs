//! Contour-parallel roughing G830 on the FINISHED PART contour.
//!
//! From the MANUALplus 620 DIN manual, in our words: G830 removes the material between the
//! blank and the contour section NS…NE in cuts that run parallel to the contour. `NE`
//! left out: the element NS alone. `P` is the largest infeed, `I` (a diameter value) and
//! `K` the allowances in X and Z, `X` (diameter) and `Z` cutting limits, `A`/`W` the
//! approach and departure angles (default: approach parallel to Z, departure
//! perpendicular to it), `Q` the retraction at the end (0: back to the start point, X
//! first, then Z), `B` the side the tool works on (0 automatic, 1 left of the contour as
//! G41, 2 right as G42).
//!
//! klar's cuts:
//!
//! - The contour keeps the allowances as G810 does: shifted by I/2 in X and K in Z.
//! - The material lies on the tool's side of the contour (B; automatic: right of a contour
//!   programmed towards −Z, left of one programmed towards +Z — the outside of a shaft).
//!   Cut k runs on the contour offset by o_k = T − k·T/n towards the material, where T is
//!   the largest distance from the blank's front face and outer surface (where they lie on
//!   the material side) to the contour and
//!   n = ⌈T/P⌉: equal steps no deeper than P, the last cut on the contour itself.
//! - An offset contour is built from the elements moved along their normals by o; two
//!   neighbours meet where their lines cross (a sharp corner around outer corners),
//!   elements that vanish inside a narrow valley drop out. The first and the last element
//!   are extended beyond the contour's ends. Arcs are followed as chords of at most 1.4°.
//! - Each offset contour is clipped to the blank (G20 bar; without one the box up to where
//!   the tool stands), the Z limit and the X limit and the axis; what lies inside is cut
//!   at the feed, in the direction the contour was programmed.
//! - Approach: from the clearance point (the start point, or the blank's corner when the
//!   tool stands farther in) at rapid to the cut's radius, then at the feed along Z to the
//!   cut (so A0). Departure: at rapid straight out in X to the clearance radius (W90), and
//!   back along Z to the clearance point. At the end: X, then Z to the start point (Q0).
//!
//! Not supported: internal contours (the tool standing inside the contour), cuts that would
//! begin inside the material (valleys whose offset contour does not reach the blank's
//! surface), A/W other than their defaults, Q1/Q2, the chamfer identifier V, auxiliary
//! contours ID.

use std::collections::VecDeque;

use super::contour::Seg;
use super::lathe::{Group, Lathe, num};
use super::roughing::{Bar, MAX_CUTS};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Feed, Op, Pose, SourceLoc};
use crate::tnc::exec::ExecError;

/// The words a G830 block takes.
pub(crate) const G830_WORDS: [&str; 13] = [
    "NS", "NE", "P", "I", "K", "X", "Z", "A", "W", "Q", "V", "B", "F",
];

/// How far the first and last elements are extended past the contour's ends, mm.
const EXTEND: f64 = 10_000.0;

/// The parameters of one G830.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Parallel {
    /// P: largest infeed.
    pub depth: f64,
    /// Allowances (z, x radius).
    pub allowance: [f64; 2],
    /// Z limit: no cut goes below it.
    pub z_limit: Option<f64>,
    /// X limit (radius): no cut goes below it.
    pub x_limit: Option<f64>,
    /// B: 0 automatic, 1 left, 2 right.
    pub side: u8,
    /// The cutting feed.
    pub feed: Feed,
}

/// Reads the words of G830 (NS/NE are read by the caller).
pub(crate) fn params(lathe: &mut Lathe, g: &Group<'_>) -> Result<Parallel, ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    let at = |a: &str| g.get(a).map(|w| w.pos as u32).or(here);
    if let Some(f) = g.get("F") {
        lathe.set_feed(num(f)?, f)?;
    }
    let feed = lathe.need_feed().map_err(|(_, e)| (here, e))?;
    let depth = g.value("P")?.ok_or((
        here,
        ProgramError::Missing("G830 needs the largest infeed P"),
    ))?;
    if !(depth.is_finite() && depth > 0.0) {
        return Err((
            at("P"),
            ProgramError::OutOfRange(format!("G830 infeed P{depth} must be positive")),
        ));
    }
    for (addr, default) in [("A", [0.0, 180.0]), ("W", [90.0, 270.0])] {
        if let Some(v) = g.value(addr)?
            && !default.contains(&v)
        {
            return Err((
                at(addr),
                ProgramError::NotSupported(format!("G830 {addr}{v} (only its default)")),
            ));
        }
    }
    for addr in ["Q", "V"] {
        if let Some(v) = g.value(addr)?
            && v != 0.0
        {
            return Err((
                at(addr),
                ProgramError::NotSupported(format!("G830 {addr}{v}")),
            ));
        }
    }
    let side = match g.value("B")? {
        None => 0,
        Some(b) if b == 0.0 || b == 1.0 || b == 2.0 => b as u8,
        Some(b) => {
            return Err((
                at("B"),
                ProgramError::OutOfRange(format!("G830 B{b}: expected 0, 1 or 2")),
            ));
        }
    };
    let allowance = [
        g.value("K")?.unwrap_or(0.0),
        g.value("I")?.unwrap_or(0.0) / 2.0,
    ];
    if !allowance.iter().all(|a| a.is_finite()) {
        return Err((here, ProgramError::OutOfRange("G830 allowance I/K".into())));
    }
    Ok(Parallel {
        depth,
        allowance,
        z_limit: g.value("Z")?,
        x_limit: g.value("X")?.map(|d| d / 2.0),
        side,
        feed,
    })
}

/// The contour as points (z, x radius): lines by their ends, arcs by chords.
fn points(segs: &[Seg], shift: [f64; 2]) -> Vec<[f64; 2]> {
    let mut pts: Vec<[f64; 2]> = Vec::new();
    for s in segs {
        let s = s.shifted(shift);
        let more = match s {
            Seg::Line { a, b } => vec![a, b],
            Seg::Arc { .. } => s.samples(),
        };
        for p in more {
            if pts
                .last()
                .is_none_or(|q| (q[0] - p[0]).hypot(q[1] - p[1]) > 1e-9)
            {
                pts.push(p);
            }
        }
    }
    pts
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// Where the lines through `p1`→`q1` and `p2`→`q2` cross (None: parallel).
fn cross_point(p1: [f64; 2], q1: [f64; 2], p2: [f64; 2], q2: [f64; 2]) -> Option<[f64; 2]> {
    let d1 = sub(q1, p1);
    let d2 = sub(q2, p2);
    let den = d1[0] * d2[1] - d1[1] * d2[0];
    if den.abs() < 1e-12 * (dot(d1, d1) * dot(d2, d2)).sqrt().max(1e-300) {
        return None;
    }
    let w = sub(p2, p1);
    let t = (w[0] * d2[1] - w[1] * d2[0]) / den;
    Some([p1[0] + t * d1[0], p1[1] + t * d1[1]])
}

/// The polyline `pts` (first and last elements extended) offset by `o` to the side `s`
/// (+1 right of the direction of travel, −1 left).
pub(crate) fn offset(pts: &[[f64; 2]], o: f64, s: f64) -> Vec<[f64; 2]> {
    // elements as (start, end, unit direction), moved along their normals
    let mut els: Vec<([f64; 2], [f64; 2], [f64; 2])> = pts
        .windows(2)
        .filter_map(|w| {
            let d = sub(w[1], w[0]);
            let len = dot(d, d).sqrt();
            (len > 1e-12).then(|| {
                let u = [d[0] / len, d[1] / len];
                // right normal of (dz, dx) is (dx, −dz)
                let n = [s * u[1], -s * u[0]];
                let m = |p: [f64; 2]| [p[0] + o * n[0], p[1] + o * n[1]];
                (m(w[0]), m(w[1]), u)
            })
        })
        .collect();
    if let Some(f) = els.first_mut() {
        f.0 = [f.0[0] - EXTEND * f.2[0], f.0[1] - EXTEND * f.2[1]];
    }
    if let Some(l) = els.last_mut() {
        l.1 = [l.1[0] + EXTEND * l.2[0], l.1[1] + EXTEND * l.2[1]];
    }
    loop {
        let n = els.len();
        let mut ends: Vec<([f64; 2], [f64; 2])> = els.iter().map(|e| (e.0, e.1)).collect();
        for i in 0..n.saturating_sub(1) {
            let c = cross_point(els[i].0, els[i].1, els[i + 1].0, els[i + 1].1).unwrap_or(els[i].1);
            ends[i].1 = c;
            ends[i + 1].0 = c;
        }
        // an element whose trimmed ends run against its direction vanished in a valley
        let gone = (0..n).find(|&i| n > 1 && dot(sub(ends[i].1, ends[i].0), els[i].2) < -1e-9);
        match gone {
            Some(i) => {
                els.remove(i);
            }
            None => {
                let mut out: Vec<[f64; 2]> = ends.iter().map(|e| e.0).collect();
                if let Some(l) = ends.last() {
                    out.push(l.1);
                }
                return out;
            }
        }
    }
}

/// The parts of the polyline inside the box `lo`..`hi` (z, x), each a polyline.
pub(crate) fn clip(path: &[[f64; 2]], lo: [f64; 2], hi: [f64; 2]) -> Vec<Vec<[f64; 2]>> {
    let mut pieces: Vec<Vec<[f64; 2]>> = Vec::new();
    let mut cur: Vec<[f64; 2]> = Vec::new();
    for w in path.windows(2) {
        let (p, d) = (w[0], sub(w[1], w[0]));
        // Liang–Barsky
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        let mut inside = true;
        for k in 0..2 {
            for (q, r) in [(-d[k], p[k] - lo[k]), (d[k], hi[k] - p[k])] {
                if q.abs() < 1e-15 {
                    if r < -1e-9 {
                        inside = false;
                    }
                } else {
                    let t = r / q;
                    if q < 0.0 {
                        t0 = t0.max(t);
                    } else {
                        t1 = t1.min(t);
                    }
                }
            }
        }
        if !inside || t0 > t1 - 1e-12 {
            if cur.len() > 1 {
                pieces.push(std::mem::take(&mut cur));
            }
            cur.clear();
            continue;
        }
        let a = [p[0] + t0 * d[0], p[1] + t0 * d[1]];
        let b = [p[0] + t1 * d[0], p[1] + t1 * d[1]];
        let joined = cur
            .last()
            .is_some_and(|q| (q[0] - a[0]).abs() < 1e-9 && (q[1] - a[1]).abs() < 1e-9);
        if !joined {
            if cur.len() > 1 {
                pieces.push(std::mem::take(&mut cur));
            }
            cur = vec![a];
        }
        cur.push(b);
    }
    if cur.len() > 1 {
        pieces.push(cur);
    }
    pieces
}

/// Distance from `q` to the polyline, negative when `q` lies on the other side than `s`
/// (+1 right of the direction of travel, −1 left) of its nearest element.
fn distance(path: &[[f64; 2]], q: [f64; 2], s: f64) -> f64 {
    let mut best = (f64::INFINITY, 1.0);
    for w in path.windows(2) {
        let d = sub(w[1], w[0]);
        let l2 = dot(d, d);
        let t = if l2 > 0.0 {
            (dot(sub(q, w[0]), d) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let c = [w[0][0] + t * d[0], w[0][1] + t * d[1]];
        let dist = (q[0] - c[0]).hypot(q[1] - c[1]);
        if dist < best.0 - 1e-12 {
            let n = [s * d[1], -s * d[0]];
            best = (dist, if dot(sub(q, c), n) < -1e-9 { -1.0 } else { 1.0 });
        }
    }
    best.0 * best.1
}

/// Runs G830 over `segs` from where the tool stands.
pub(crate) fn rough(
    lathe: &mut Lathe,
    segs: &[Seg],
    blank: Option<Bar>,
    p: &Parallel,
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) -> Result<(), ProgramError> {
    let pts = points(segs, p.allowance);
    if pts.len() < 2 {
        return Err(ProgramError::Missing(
            "G830 needs a FINISHED PART contour (with elements from NS to NE)",
        ));
    }
    let start = [lathe.pos[AxisLetter::Z], lathe.pos[AxisLetter::X]];
    let (outer, front, back) = match blank {
        Some(b) => (b.radius, b.front, b.back),
        None => (start[1], start[0], f64::NEG_INFINITY),
    };
    if start[1] < outer - 1e-9 && start[0] < front - 1e-9 {
        return Err(ProgramError::Geometry(
            "G830 starts inside the blank: stand in front of it or above it".into(),
        ));
    }
    let top = pts.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max);
    if start[1] < top - 1e-9 && start[0] < front - 1e-9 {
        return Err(ProgramError::NotSupported(
            "G830 on an internal contour (the tool stands inside it)".into(),
        ));
    }
    let (first, last) = (pts[0], pts[pts.len() - 1]);
    let side = match p.side {
        1 => -1.0,
        2 => 1.0,
        _ if last[0] <= first[0] => 1.0,
        _ => -1.0,
    };
    let lo = [
        p.z_limit.unwrap_or(f64::NEG_INFINITY).max(back),
        p.x_limit.unwrap_or(0.0).max(0.0),
    ];
    let hi = [front, outer];
    // the farthest the blank's surface lies from the (extended) contour
    let reach = offset(&pts, 0.0, side);
    let z_lo = if lo[0].is_finite() {
        lo[0]
    } else {
        pts.iter().map(|q| q[0]).fold(f64::INFINITY, f64::min)
    };
    let total = (0..=400)
        .flat_map(|i| {
            let t = f64::from(i) / 400.0;
            [
                [front, lo[1] + t * (outer - lo[1])],
                [front + t * (z_lo - front), outer],
            ]
        })
        .filter(|q| q[0] <= hi[0] + 1e-9 && q[1] <= hi[1] + 1e-9)
        .map(|q| distance(&reach, q, side))
        .fold(0.0, f64::max);
    let n = (total / p.depth - 1e-9).ceil().max(1.0);
    if n > MAX_CUTS {
        return Err(ProgramError::OutOfRange(format!(
            "G830: {n} cuts of P{}: more than {MAX_CUTS}",
            p.depth
        )));
    }
    let step = total / n;
    let clear = [start[0].max(front), start[1].max(outer)];
    let mut cuts = Vec::new();
    for k in 1..=(n as u32) {
        let o = (total - step * f64::from(k)).max(0.0);
        for piece in clip(&offset(&pts, o, side), lo, hi) {
            let a = piece[0];
            let on_surface = a[0] >= hi[0] - 1e-6 || a[1] >= hi[1] - 1e-6 || a[1] <= lo[1] + 1e-6;
            if !on_surface {
                return Err(ProgramError::NotSupported(format!(
                    "G830: a cut at {o:.3} mm from the contour would begin inside the \
                     material (Z{:.3} X{:.3})",
                    a[0],
                    a[1] * 2.0
                )));
            }
            cuts.push(piece);
        }
    }
    let pose = |q: [f64; 2], base: Pose| {
        let mut b = base;
        b[AxisLetter::Z] = q[0];
        b[AxisLetter::X] = q[1];
        b
    };
    for piece in cuts {
        let a = piece[0];
        lathe.line(pose([clear[0], a[1]], lathe.pos), Feed::Rapid, loc, out);
        for q in &piece {
            lathe.line(pose(*q, lathe.pos), p.feed, loc, out);
        }
        let end = lathe.pos[AxisLetter::Z];
        lathe.line(pose([end, clear[1]], lathe.pos), Feed::Rapid, loc, out);
        lathe.line(pose(clear, lathe.pos), Feed::Rapid, loc, out);
    }
    lathe.line(pose([clear[0], start[1]], lathe.pos), Feed::Rapid, loc, out);
    lathe.line(pose(start, lathe.pos), Feed::Rapid, loc, out);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_of_a_step_meets_at_the_corners() {
        // a step down the face, along Z, up a shoulder, along Z again (towards −Z)
        let pts = [
            [0.0, 0.0],
            [0.0, 10.0],
            [-20.0, 10.0],
            [-20.0, 15.0],
            [-40.0, 15.0],
        ];
        let o = offset(&pts, 2.0, 1.0);
        assert_eq!(o.len(), 5);
        assert_eq!(o[1], [2.0, 12.0]);
        assert_eq!(o[2], [-18.0, 12.0]);
        assert_eq!(o[3], [-18.0, 17.0]);
        // a shoulder narrower than the offset vanishes: 1 mm wide step, offset 2
        let pts = [
            [0.0, 10.0],
            [-10.0, 10.0],
            [-10.0, 12.0],
            [-11.0, 12.0],
            [-11.0, 10.0],
            [-30.0, 10.0],
        ];
        let o = offset(&pts, 2.0, -1.0);
        assert!(o.iter().all(|q| q[1] >= 7.999), "{o:?}");
    }
}
