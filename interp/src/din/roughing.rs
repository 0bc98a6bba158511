//! Roughing along the FINISHED PART contour: G810 (longitudinal) and G820 (transverse), and
//! the bar blank G20 they clip to.
//!
//! `G20 X… Z… K…` in the BLANK section is a bar of diameter X and length Z whose front face
//! lies K in front of Z0 (it spans Z from K back to K − Z). Without a blank the material is
//! taken to reach out to where the tool stands when the cycle starts.
//!
//! `G810 NS… NE… P… I… K… Z… F…` removes the material between the blank and the contour
//! (blocks NS to NE, default all) in cuts parallel to Z: the cut radii go from the blank's
//! radius down to the contour's smallest radius in equal steps no deeper than P (a radius
//! value). Each cut starts at the cycle's start Z, runs towards the chuck until it meets the
//! contour (its first crossing seen from the front; past the end of the contour: its last
//! Z), and lifts off at 45° by the safety distance [`SAFETY`] before the rapid back. The
//! contour keeps the allowances I (in X, a diameter value) and K (in Z) — the contour
//! shifted by I/2 outwards and by K towards the front, which is the allowance on cylinders
//! and on faces. Z limits the cuts in Z (the cut does not go beyond it). Afterwards the tool
//! returns to the start point.
//!
//! `G820` is the same with cuts parallel to X (facing): Z levels from the blank's front
//! down to the contour's last Z, each cut running inwards from the start radius until it
//! meets the contour (no crossing: to the axis); X limits the cuts in X (a diameter).
//!
//! Not supported: recesses that a straight cut would enter behind the first crossing (the
//! cut stops at the first one), the plunge and retraction variants of the manual's E, H,
//! A, W parameters.

use std::collections::VecDeque;

use super::contour::Seg;
use super::lathe::{Group, Lathe, num};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Feed, Op, Pose, SourceLoc};
use crate::tnc::exec::ExecError;

/// Lift-off and clearance distance of the roughing cuts, mm.
pub const SAFETY: f64 = 1.0;

/// Most cuts of one cycle.
pub const MAX_CUTS: f64 = 10_000.0;

/// A bar blank (G20).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Bar {
    /// Radius.
    pub radius: f64,
    /// Z of the front face.
    pub front: f64,
    /// Z of the back end.
    pub back: f64,
}

/// Reads `G20 X… Z… K…`.
pub(crate) fn bar(g: &Group<'_>) -> Result<Bar, ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    let d = g
        .value("X")?
        .ok_or((here, ProgramError::Missing("G20 needs the bar diameter X")))?;
    let len = g
        .value("Z")?
        .ok_or((here, ProgramError::Missing("G20 needs the bar length Z")))?;
    if !(d > 0.0 && len > 0.0) {
        return Err((
            here,
            ProgramError::OutOfRange("G20: diameter X and length Z must be positive".into()),
        ));
    }
    let front = g.value("K")?.unwrap_or(0.0);
    Ok(Bar {
        radius: d / 2.0,
        front,
        back: front - len,
    })
}

/// The parameters of one roughing cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rough {
    /// G820: cuts parallel to X.
    pub transverse: bool,
    /// P: largest depth of cut.
    pub depth: f64,
    /// Allowances (z, x radius).
    pub allowance: [f64; 2],
    /// Cutting limit: Z for G810, X radius for G820.
    pub limit: Option<f64>,
    /// The cutting feed.
    pub feed: Feed,
}

/// Reads the words of G810/G820 (NS/NE are read by the caller).
pub(crate) fn params(lathe: &mut Lathe, g: &Group<'_>, code: u32) -> Result<Rough, ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    if let Some(f) = g.get("F") {
        lathe.set_feed(num(f)?, f)?;
    }
    let feed = lathe.need_feed().map_err(|(_, e)| (here, e))?;
    let depth = g.value("P")?.ok_or((
        here,
        ProgramError::Missing("roughing needs the depth of cut P"),
    ))?;
    if depth.is_nan() || depth <= 0.0 {
        return Err((
            here,
            ProgramError::OutOfRange(format!("depth of cut P{depth} must be positive")),
        ));
    }
    let transverse = code == 820;
    let limit = if transverse {
        g.value("X")?.map(|d| d / 2.0)
    } else {
        g.value("Z")?
    };
    Ok(Rough {
        transverse,
        depth,
        allowance: [
            g.value("K")?.unwrap_or(0.0),
            g.value("I")?.unwrap_or(0.0) / 2.0,
        ],
        limit,
        feed,
    })
}

impl Seg {
    /// The element moved by `d` (z, x radius).
    pub(crate) fn shifted(self, d: [f64; 2]) -> Seg {
        let m = |p: [f64; 2]| [p[0] + d[0], p[1] + d[1]];
        match self {
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
                sweep,
            },
        }
    }

    /// Points along the element (ends included) for its extent.
    pub(crate) fn samples(&self) -> Vec<[f64; 2]> {
        match *self {
            Seg::Line { a, b } => vec![a, b],
            Seg::Arc {
                a, centre, sweep, ..
            } => {
                let r = (a[0] - centre[0]).hypot(a[1] - centre[1]);
                let a0 = (a[1] - centre[1]).atan2(a[0] - centre[0]);
                (0..=64)
                    .map(|k| {
                        let t = a0 + sweep.to_radians() * f64::from(k) / 64.0;
                        [centre[0] + r * t.cos(), centre[1] + r * t.sin()]
                    })
                    .collect()
            }
        }
    }

    /// Where the element crosses the line "coordinate `k` = `v`": the other coordinate.
    pub(crate) fn crossings(&self, k: usize, v: f64) -> Vec<f64> {
        let o = 1 - k;
        match *self {
            Seg::Line { a, b } => {
                let d = b[k] - a[k];
                if d.abs() < 1e-12 {
                    return Vec::new();
                }
                let t = (v - a[k]) / d;
                if (-1e-9..=1.0 + 1e-9).contains(&t) {
                    vec![a[o] + t * (b[o] - a[o])]
                } else {
                    Vec::new()
                }
            }
            Seg::Arc {
                a, centre, sweep, ..
            } => {
                let r = (a[0] - centre[0]).hypot(a[1] - centre[1]);
                let d = v - centre[k];
                if d.abs() > r + 1e-12 {
                    return Vec::new();
                }
                let h = (r * r - d * d).max(0.0).sqrt();
                let a0 = (a[1] - centre[1]).atan2(a[0] - centre[0]).to_degrees();
                [centre[o] - h, centre[o] + h]
                    .into_iter()
                    .filter(|w| {
                        let mut p = [0.0; 2];
                        p[k] = v;
                        p[o] = *w;
                        let ang = (p[1] - centre[1]).atan2(p[0] - centre[0]).to_degrees();
                        // how far along the sweep's direction the point lies
                        let along = if sweep >= 0.0 {
                            (ang - a0).rem_euclid(360.0)
                        } else {
                            (a0 - ang).rem_euclid(360.0)
                        };
                        along <= sweep.abs() + 1e-9 || along >= 360.0 - 1e-9
                    })
                    .collect()
            }
        }
    }
}

/// Runs G810/G820 over `segs` from where the tool stands.
pub(crate) fn rough(
    lathe: &mut Lathe,
    segs: &[Seg],
    blank: Option<Bar>,
    p: &Rough,
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) -> Result<(), ProgramError> {
    if segs.is_empty() {
        return Err(ProgramError::Missing(
            "roughing needs a FINISHED PART contour (with elements from NS to NE)",
        ));
    }
    let segs: Vec<Seg> = segs.iter().map(|s| s.shifted(p.allowance)).collect();
    let start = [lathe.pos[AxisLetter::Z], lathe.pos[AxisLetter::X]];
    let (outer, front) = match blank {
        Some(b) => (b.radius, b.front),
        None => (start[1], start[0]),
    };
    if start[1] < outer - 1e-9 && start[0] < front - 1e-9 {
        return Err(ProgramError::Geometry(
            "the roughing cycle starts inside the blank: stand in front of it or above it".into(),
        ));
    }
    let pts: Vec<[f64; 2]> = segs.iter().flat_map(Seg::samples).collect();
    let min = |k: usize| pts.iter().map(|q| q[k]).fold(f64::INFINITY, f64::min);
    let (z_last, r_least) = (min(0), min(1).max(0.0));
    // k: the coordinate that steps from cut to cut; the cut runs along the other one
    let (k, from, to, cut_start) = if p.transverse {
        (0, front, z_last, start[1])
    } else {
        (1, outer, r_least, start[0])
    };
    let total = from - to;
    if total <= 1e-9 {
        return Ok(());
    }
    let n = (total / p.depth - 1e-9).ceil().max(1.0);
    if n > MAX_CUTS {
        return Err(ProgramError::OutOfRange(format!(
            "{n} cuts of P{}: more than {MAX_CUTS}",
            p.depth
        )));
    }
    let step = total / n;
    let o = 1 - k;
    let pose = |q: [f64; 2], base: Pose| {
        let mut b = base;
        b[AxisLetter::Z] = q[0];
        b[AxisLetter::X] = q[1];
        b
    };
    for i in 1..=(n as u32) {
        let level = from - step * f64::from(i);
        // where the cut meets the contour: the crossing nearest to its start
        let ends: Vec<f64> = segs
            .iter()
            .flat_map(|s| s.crossings(k, level))
            .filter(|w| *w <= cut_start + 1e-9)
            .collect();
        let mut end = ends.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if end == f64::NEG_INFINITY {
            end = if p.transverse { 0.0 } else { z_last };
        }
        if !p.transverse
            && let Some(b) = blank
        {
            end = end.max(b.back);
        }
        if let Some(l) = p.limit {
            end = end.max(l);
        }
        if end >= cut_start - 1e-9 {
            continue;
        }
        let mut a = [0.0; 2];
        a[k] = level;
        a[o] = cut_start;
        let mut b = a;
        b[o] = end;
        let mut lift = b;
        lift[k] = level + SAFETY;
        lift[o] = (end + SAFETY).min(cut_start);
        let mut back = lift;
        back[o] = cut_start;
        lathe.line(pose(a, lathe.pos), Feed::Rapid, loc, out);
        lathe.line(pose(b, lathe.pos), p.feed, loc, out);
        lathe.line(pose(lift, lathe.pos), Feed::Rapid, loc, out);
        lathe.line(pose(back, lathe.pos), Feed::Rapid, loc, out);
    }
    lathe.line(pose(start, lathe.pos), Feed::Rapid, loc, out);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_crossings_respect_the_sweep() {
        // quarter circle about (0, 0) radius 10 from (10, 0) to (0, 10), counter-clockwise
        let s = Seg::Arc {
            a: [10.0, 0.0],
            b: [0.0, 10.0],
            centre: [0.0, 0.0],
            sweep: 90.0,
        };
        // x = 6: z = ±8, only +8 lies on the quarter
        assert_eq!(s.crossings(1, 6.0), vec![8.0]);
        // z = -5 misses it
        assert!(s.crossings(0, -5.0).is_empty());
        let l = Seg::Line {
            a: [0.0, 10.0],
            b: [-20.0, 20.0],
        };
        assert_eq!(l.crossings(1, 15.0), vec![-10.0]);
        assert!(l.crossings(1, 25.0).is_empty());
    }
}
