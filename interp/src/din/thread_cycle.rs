//! The thread cycle G31: a whole thread in passes, each pass a geared G33-style pass.
//!
//! What the MANUALplus 4110 / MANUALplus 620 / CNC PILOT 4290 DIN manuals say, in our words,
//! and what klar makes of it:
//!
//! - **By coordinates** (`X`/`Xi` and `Z`/`Zi`): the thread runs from where the tool stands
//!   (its Z) to the end point; `X` is the thread's diameter at the end. `R` is the difference
//!   in radii for a taper: the thread starts at the radius X/2 − R. The pass starts at the
//!   tool's Z, so a run-in `B` lies within it (as with G33, the programmer stands the tool B
//!   in front of the thread); a run-out `P` lies before the end point. The pitch is measured
//!   along Z.
//! - **On a contour** (`NS`, optionally `NE`): every straight FINISHED PART element from
//!   block NS to NE is a thread of its own (a succession of threads). The element is the
//!   thread proper; the pass is extended by `B` before it and by `P` after it. `J` says
//!   the reference direction: 0 longitudinal (pitch along Z, infeed in X), 1 transverse
//!   (pitch along X, infeed in Z); without J the element decides (closer to Z:
//!   longitudinal).
//! - `F` pitch, `U` thread depth (a radius): U > 0 infeed towards + (an internal thread on
//!   a longitudinal thread), U < 0 towards − (external). `I` is the largest infeed, `IC`
//!   the number of cuts instead (with V0 and V1).
//! - `V` the type of infeed, with n cuts and d_k the depth after cut k:
//!   - V0 constant cross-section: the chip of a V-shaped thread grows with the square of
//!     the depth, so d_k = I·√k (the last cut ends at U; n = ⌈(U/I)²⌉). Without I or IC,
//!     I = F/3. With IC: d_k = U·√(k/IC).
//!   - V1 constant infeed: n = ⌈U/I⌉ (or IC) equal infeeds U/n.
//!   - V2 with distribution of the remaining cut: infeeds of I, where the remainder of U/I
//!     makes the first infeed smaller; the last infeed is cut in four: ½, ¼, ⅛, ⅛ of it.
//!   - V3 without the distribution: as V2 with the last infeed whole.
//! - `H` the offset that smooths the flanks: every pass moves along the thread axis by
//!   d·tan A (`A` the infeed angle, default 30°, |A| < 60°): H0 none, H1 from the left
//!   (towards −Z, or −X on a transverse thread), H2 from the right, H3 alternately, left
//!   first.
//! - `Q` air cuts: passes repeated at the full depth (and the last offset).
//! - `C` starting angle; `D` number of starts: start j (0-based) has the angle
//!   C + j·360°/D. At every depth klar cuts all starts in turn.
//! - Sequence of a pass, from the cycle's start point S (where the tool stood, outside the
//!   thread): rapid along the thread axis to the pass's start, rapid infeed to its depth,
//!   the geared pass, rapid retraction to S's depth, and so on; at the end the tool
//!   returns to S at rapid.
//!
//! Not supported: V4 to V6 (the 620's compatibility infeeds and the remaining-cut depth
//! R with V4), a variable pitch E ≠ 0, arcs as thread elements, the chamfer identifier O
//! and auxiliary contours ID.

use std::collections::VecDeque;

use super::contour::Seg;
use super::lathe::{Group, Lathe, num};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Feed, Op, OpKind, Pose, SourceLoc, ThreadLead};
use crate::tnc::exec::ExecError;

/// The words a G31 block takes.
pub(crate) const G31_WORDS: [&str; 21] = [
    "X", "Xi", "Z", "Zi", "NS", "NE", "J", "F", "U", "I", "IC", "R", "B", "P", "A", "V", "H", "Q",
    "C", "D", "E",
];

/// Most passes one G31 may make.
pub const MAX_PASSES: usize = 10_000;

/// The infeed types V0 to V3.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Infeed {
    /// V0: every cut takes the same chip cross-section.
    ConstantSection,
    /// V1: equal infeeds.
    ConstantDepth,
    /// V2: first infeed reduced by the remainder, last infeed split ½ ¼ ⅛ ⅛.
    Distributed,
    /// V3: first infeed reduced by the remainder.
    Remainder,
}

/// The cumulative depths (≥ 0, the last equal to `depth`) of the cuts of a thread `depth`
/// deep with the largest infeed `max` or `cuts` cuts.
pub fn infeed_depths(
    kind: Infeed,
    depth: f64,
    max: Option<f64>,
    cuts: Option<u32>,
) -> Result<Vec<f64>, ProgramError> {
    let too_many = |n: f64| {
        ProgramError::OutOfRange(format!("G31 would cut {n} passes: more than {MAX_PASSES}"))
    };
    if !(depth.is_finite() && depth > 0.0) {
        return Err(ProgramError::OutOfRange(format!(
            "G31 thread depth U{depth} must not be 0"
        )));
    }
    if let Some(c) = cuts {
        if c == 0 || c as usize > MAX_PASSES {
            return Err(too_many(f64::from(c)));
        }
        let n = f64::from(c);
        return match kind {
            Infeed::ConstantSection => {
                Ok((1..=c).map(|k| depth * (f64::from(k) / n).sqrt()).collect())
            }
            Infeed::ConstantDepth => Ok((1..=c).map(|k| depth * f64::from(k) / n).collect()),
            _ => Err(ProgramError::OutOfRange(
                "G31 IC (number of cuts) goes with V0 or V1 only".into(),
            )),
        };
    }
    let i = max.ok_or(ProgramError::Missing(
        "G31 needs the largest infeed I or the number of cuts IC",
    ))?;
    if !(i.is_finite() && i > 0.0) {
        return Err(ProgramError::OutOfRange(format!(
            "G31 infeed I{i} must be positive"
        )));
    }
    let ratio = depth / i;
    let n = match kind {
        Infeed::ConstantSection => (ratio * ratio - 1e-9).ceil().max(1.0),
        _ => (ratio - 1e-9).ceil().max(1.0),
    };
    if n > MAX_PASSES as f64 {
        return Err(too_many(n));
    }
    let n = n as u32;
    Ok(match kind {
        Infeed::ConstantSection => (1..=n)
            .map(|k| (i * f64::from(k).sqrt()).min(depth))
            .collect(),
        Infeed::ConstantDepth => (1..=n)
            .map(|k| depth * f64::from(k) / f64::from(n))
            .collect(),
        Infeed::Distributed | Infeed::Remainder => {
            let first = depth - f64::from(n - 1) * i;
            let mut steps = vec![first];
            steps.extend((1..n).map(|_| i));
            if kind == Infeed::Distributed
                && let Some(last) = steps.pop()
            {
                steps.extend([last / 2.0, last / 4.0, last / 8.0, last / 8.0]);
            }
            let mut sum = 0.0;
            let mut out: Vec<f64> = steps
                .iter()
                .map(|s| {
                    sum += s;
                    sum
                })
                .collect();
            if let Some(l) = out.last_mut() {
                *l = depth;
            }
            out
        }
    })
}

/// The flank offset type H.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Offset {
    /// H0: straight infeed.
    None,
    /// H1: towards − along the thread axis.
    Left,
    /// H2: towards + along the thread axis.
    Right,
    /// H3: alternately, left first.
    Alternate,
}

impl Offset {
    /// The offset along the thread axis of pass `k` (0-based) at depth `d`, infeed angle
    /// `angle` degrees.
    pub fn of(self, k: usize, d: f64, angle: f64) -> f64 {
        let size = d * angle.to_radians().tan();
        match self {
            Offset::None => 0.0,
            Offset::Left => -size,
            Offset::Right => size,
            Offset::Alternate if k.is_multiple_of(2) => -size,
            Offset::Alternate => size,
        }
    }
}

/// What a G31 block says, read and checked.
struct Params {
    pitch: f64,
    depth: f64,
    depths: Vec<f64>,
    offset: Offset,
    angle: f64,
    air: u32,
    start_angle: f64,
    starts: u32,
    run_in: Option<f64>,
    run_out: Option<f64>,
    taper: f64,
    direction: Option<bool>,
}

/// A whole number word in `lo..=hi`.
fn whole_in(g: &Group<'_>, addr: &str, lo: f64, hi: f64) -> Result<Option<u32>, ExecError> {
    match g.get(addr) {
        None => Ok(None),
        Some(w) => {
            let v = num(w)?;
            if v.fract() == 0.0 && (lo..=hi).contains(&v) {
                Ok(Some(v as u32))
            } else {
                Err((
                    Some(w.pos as u32),
                    ProgramError::OutOfRange(format!(
                        "G31 {addr}{v}: expected a whole number from {lo} to {hi}"
                    )),
                ))
            }
        }
    }
}

fn params(g: &Group<'_>) -> Result<Params, ExecError> {
    let gpos = g.g_word.map(|w| w.pos as u32);
    let at = |addr: &str| g.get(addr).map(|w| w.pos as u32).or(gpos);
    let bad = |addr: &str, what: String| (at(addr), ProgramError::OutOfRange(what));
    let pitch = g
        .value("F")?
        .ok_or((gpos, ProgramError::Missing("G31 needs the thread pitch F")))?;
    if !(pitch.is_finite() && pitch > 0.0) {
        return Err(bad("F", format!("G31 pitch F{pitch} must be positive")));
    }
    let u = g
        .value("U")?
        .ok_or((gpos, ProgramError::Missing("G31 needs the thread depth U")))?;
    if !(u.is_finite() && u != 0.0) {
        return Err(bad("U", format!("G31 thread depth U{u} must not be 0")));
    }
    let kind = match whole_in(g, "V", 0.0, 6.0)? {
        None | Some(0) => Infeed::ConstantSection,
        Some(1) => Infeed::ConstantDepth,
        Some(2) => Infeed::Distributed,
        Some(3) => Infeed::Remainder,
        Some(v) => {
            return Err((
                at("V"),
                ProgramError::NotSupported(format!("G31 infeed type V{v}")),
            ));
        }
    };
    let cuts = whole_in(g, "IC", 1.0, MAX_PASSES as f64)?;
    let mut max = g.value("I")?;
    if max.is_none() && cuts.is_none() && kind == Infeed::ConstantSection {
        max = Some(pitch / 3.0);
    }
    let depths = infeed_depths(kind, u.abs(), max, cuts).map_err(|e| (at("I"), e))?;
    let offset = match whole_in(g, "H", 0.0, 3.0)? {
        None | Some(0) => Offset::None,
        Some(1) => Offset::Left,
        Some(2) => Offset::Right,
        _ => Offset::Alternate,
    };
    let angle = g.value("A")?.unwrap_or(30.0);
    if !(angle.is_finite() && angle.abs() < 60.0) {
        return Err(bad(
            "A",
            format!("G31 infeed angle A{angle}: expected −60° < A < 60°"),
        ));
    }
    let length = |addr: &str| -> Result<Option<f64>, ExecError> {
        match g.value(addr)? {
            Some(v) if !(v.is_finite() && v >= 0.0) => {
                Err(bad(addr, format!("G31 {addr}{v} must be a length ≥ 0")))
            }
            v => Ok(v),
        }
    };
    if let Some(e) = g.value("E")?
        && e != 0.0
    {
        return Err((
            at("E"),
            ProgramError::NotSupported("G31 with a variable pitch E".into()),
        ));
    }
    let start_angle = g.value("C")?.unwrap_or(0.0);
    if !start_angle.is_finite() {
        return Err(bad("C", "G31 starting angle C".into()));
    }
    let taper = g.value("R")?.unwrap_or(0.0);
    if !taper.is_finite() {
        return Err(bad("R", "G31 difference in radii R".into()));
    }
    let passes = (depths.len() + whole_in(g, "Q", 0.0, 1000.0)?.unwrap_or(0) as usize)
        * whole_in(g, "D", 1.0, 360.0)?.unwrap_or(1) as usize;
    if passes > MAX_PASSES {
        return Err((
            gpos,
            ProgramError::OutOfRange(format!(
                "G31 would cut {passes} passes: more than {MAX_PASSES}"
            )),
        ));
    }
    Ok(Params {
        pitch,
        depth: u,
        depths,
        offset,
        angle,
        air: whole_in(g, "Q", 0.0, 1000.0)?.unwrap_or(0),
        start_angle,
        starts: whole_in(g, "D", 1.0, 360.0)?.unwrap_or(1),
        run_in: length("B")?,
        run_out: length("P")?,
        taper,
        direction: whole_in(g, "J", 0.0, 1.0)?.map(|j| j == 0),
    })
}

/// One thread: its line (z, x radius) and how the passes run on it.
struct Thread {
    /// Start and end of the thread line (the pass at depth 0, before extension).
    a: [f64; 2],
    b: [f64; 2],
    /// Length added before `a` and after `b` along the line.
    before: f64,
    after: f64,
    /// True: pitch along Z, infeed in X.
    longitudinal: bool,
}

/// G31: the whole thread cycle from where the tool stands. `segs` are the contour
/// elements NS..NE when the block names them.
pub(crate) fn g31(
    l: &mut Lathe,
    g: &Group<'_>,
    segs: Option<Vec<Seg>>,
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) -> Result<(), ExecError> {
    let gpos = g.g_word.map(|w| w.pos as u32);
    let p = params(g)?;
    let start = [l.pos[AxisLetter::Z], l.pos[AxisLetter::X]];
    let coords = ["X", "Xi", "Z", "Zi"].iter().find_map(|a| g.get(a));
    let threads = match (segs, coords) {
        (Some(_), Some(w)) => {
            return Err((
                Some(w.pos as u32),
                ProgramError::OutOfRange(
                    "G31 takes its thread either by coordinates or from the contour NS…NE".into(),
                ),
            ));
        }
        (Some(segs), None) => {
            if segs.is_empty() {
                return Err((
                    gpos,
                    ProgramError::Missing("G31 NS: no contour elements to thread"),
                ));
            }
            let mut ts = Vec::new();
            for s in segs {
                let Seg::Line { a, b } = s else {
                    return Err((
                        gpos,
                        ProgramError::NotSupported("G31 on an arc element".into()),
                    ));
                };
                let longitudinal = p
                    .direction
                    .unwrap_or((b[0] - a[0]).abs() >= (b[1] - a[1]).abs());
                ts.push(Thread {
                    a,
                    b,
                    before: p.run_in.unwrap_or(0.0),
                    after: p.run_out.unwrap_or(0.0),
                    longitudinal,
                });
            }
            ts
        }
        (None, _) => {
            let end_r = match (g.get("X"), g.get("Xi")) {
                (Some(x), None) => num(x)? / 2.0,
                (None, Some(xi)) => start[1] + num(xi)? / 2.0,
                _ => {
                    return Err((
                        gpos,
                        ProgramError::Missing(
                            "G31 needs the thread's end point X (or Xi) and Z (or Zi), or NS",
                        ),
                    ));
                }
            };
            let end_z = match (g.get("Z"), g.get("Zi")) {
                (Some(z), None) => num(z)?,
                (None, Some(zi)) => start[0] + num(zi)?,
                _ => {
                    return Err((
                        gpos,
                        ProgramError::Missing(
                            "G31 needs the thread's end point Z (or Zi) as well as X",
                        ),
                    ));
                }
            };
            if (end_z - start[0]).abs() < 1e-6 {
                return Err((
                    gpos,
                    ProgramError::Geometry(
                        "G31 by coordinates threads along Z: the end Z must differ from \
                         the tool's Z"
                            .into(),
                    ),
                ));
            }
            if p.direction == Some(false) {
                return Err((
                    g.get("J").map(|w| w.pos as u32),
                    ProgramError::NotSupported(
                        "G31 J1 (transverse) by coordinates: give the thread as a contour".into(),
                    ),
                ));
            }
            vec![Thread {
                a: [start[0], end_r - p.taper],
                b: [end_z, end_r],
                before: 0.0,
                after: 0.0,
                longitudinal: true,
            }]
        }
    };
    // check every thread first: nothing moves if one of them is wrong
    for t in &threads {
        check(t, &p, start).map_err(|e| (gpos, e))?;
    }
    for t in &threads {
        cut(l, t, &p, start, loc, out);
    }
    let mut home = l.pos;
    home[AxisLetter::Z] = start[0];
    home[AxisLetter::X] = start[1];
    l.line(home, Feed::Rapid, loc, out);
    Ok(())
}

/// Index of the depth coordinate in (z, x) and the infeed direction (±1).
fn axes(t: &Thread, p: &Params) -> (usize, f64) {
    (if t.longitudinal { 1 } else { 0 }, p.depth.signum())
}

fn check(t: &Thread, p: &Params, start: [f64; 2]) -> Result<(), ProgramError> {
    let (k, s) = axes(t, p);
    let along = 1 - k;
    let len = (t.b[along] - t.a[along]).abs();
    if len < 1e-6 {
        return Err(ProgramError::Geometry(format!(
            "G31: the thread does not move along {} (J chooses the direction)",
            if t.longitudinal { "Z" } else { "X" }
        )));
    }
    let line_len = (t.b[0] - t.a[0]).hypot(t.b[1] - t.a[1]);
    if let (Some(b), Some(pp)) = (p.run_in, p.run_out)
        && t.before == 0.0
        && b + pp > line_len + 1e-9
    {
        return Err(ProgramError::Geometry(format!(
            "G31 run-in B{b} and run-out P{pp} are longer than the thread ({line_len:.4} mm)"
        )));
    }
    // the cycle's start point must lie outside the thread, on the side the infeed comes from
    let outside = if s < 0.0 {
        start[k] >= t.a[k].max(t.b[k]) - 1e-9
    } else {
        start[k] <= t.a[k].min(t.b[k]) + 1e-9
    };
    if !outside {
        return Err(ProgramError::Geometry(format!(
            "G31 starts inside the thread: with U{} stand the tool {} the thread {} first",
            p.depth,
            if s < 0.0 { "above" } else { "below" },
            if k == 1 { "diameter" } else { "face" }
        )));
    }
    Ok(())
}

/// Emits the passes of one thread and leaves the tool at the start point's depth.
fn cut(
    l: &mut Lathe,
    t: &Thread,
    p: &Params,
    start: [f64; 2],
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) {
    let (k, s) = axes(t, p);
    let along = 1 - k;
    let len = (t.b[0] - t.a[0]).hypot(t.b[1] - t.a[1]);
    let u = [(t.b[0] - t.a[0]) / len, (t.b[1] - t.a[1]) / len];
    let a = [t.a[0] - u[0] * t.before, t.a[1] - u[1] * t.before];
    let b = [t.b[0] + u[0] * t.after, t.b[1] + u[1] * t.after];
    let pose = |q: [f64; 2], base: Pose| {
        let mut r = base;
        r[AxisLetter::Z] = q[0];
        r[AxisLetter::X] = q[1];
        r
    };
    let last = p.depths.last().copied().unwrap_or(0.0);
    let mut list: Vec<f64> = p.depths.clone();
    list.extend((0..p.air).map(|_| last));
    let mut previous = 0.0;
    for (i, &d) in list.iter().enumerate() {
        let shift = p.offset.of(i.min(p.depths.len() - 1), d, p.angle);
        let section = p.pitch * (d - previous);
        previous = d;
        let mut from = a;
        let mut to = b;
        from[k] += s * d;
        to[k] += s * d;
        from[along] += shift;
        to[along] += shift;
        for j in 0..p.starts {
            // along the thread axis at the start point's depth, then in
            let mut over = from;
            over[k] = start[k];
            l.line(pose(over, l.pos), Feed::Rapid, loc, out);
            l.line(pose(from, l.pos), Feed::Rapid, loc, out);
            let (fp, tp) = (l.pos, pose(to, l.pos));
            out.push_back(Op {
                kind: OpKind::SpindleSync {
                    from: fp,
                    to: tp,
                    pitch: p.pitch,
                    lead: if t.longitudinal {
                        ThreadLead::Z
                    } else {
                        ThreadLead::X
                    },
                    start_angle: p.start_angle + f64::from(j) * 360.0 / f64::from(p.starts),
                    run_in: p.run_in,
                    run_out: p.run_out,
                    section,
                },
                loc,
            });
            l.pos = tp;
            let mut back = to;
            back[k] = start[k];
            l.line(pose(back, l.pos), Feed::Rapid, loc, out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distributed_infeed_splits_the_last_cut() {
        // U 1.0, I 0.3: ceil(3.33) = 4 cuts, first 1.0 − 3·0.3 = 0.1, then 0.3, 0.3, and the
        // last 0.3 split into 0.15, 0.075, 0.0375, 0.0375
        let d = infeed_depths(Infeed::Distributed, 1.0, Some(0.3), None).unwrap();
        let want = [0.1, 0.4, 0.7, 0.85, 0.925, 0.9625, 1.0];
        assert_eq!(d.len(), want.len());
        for (a, b) in d.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{d:?}");
        }
    }
}
