//! Point patterns: cycles 220 and 221, and the points of PATTERN DEF.
//!
//! 220 POLAR PATTERN and 221 CARTESIAN PATTERN are DEF-active: they run the last defined
//! machining cycle at each of their positions. The pattern's set-up clearance Q200, surface
//! coordinate Q203 and 2nd set-up clearance Q204 replace those of the machining cycle. The
//! tool first goes at FMAX to the 2nd set-up clearance, then in the working plane to the
//! first position, then down to the set-up clearance, and the machining cycle runs. Between
//! positions the tool travels at FMAX at the set-up clearance (Q301 = 0) or at the 2nd
//! set-up clearance (Q301 = 1): with Q301 = 0 the machining cycle retracts only to the
//! set-up clearance, except at the last position, where its own retraction to the 2nd
//! set-up clearance applies.
//!
//! Old-format machining cycles (1, 2, …) have no surface parameter and start where the
//! tool is: at each position the tool is put at their set-up clearance (sub-block 1) above
//! the pattern's surface Q203.
//!
//! The clearance heights assume the usual working direction (tool approaching from +t);
//! a machining cycle with a positive depth inside a pattern is not specially handled.

use super::drill::common::{EPS, LEN_MAX, Params, Path};
use super::{CycleContext, CycleError, CycleFeed, Move, P3, ParamKey, ParamSource};

/// Upper bound on the moves one pattern call may generate: a guard against parameter
/// combinations (99999 × 99999 positions, each with thousands of pecks) that would exhaust
/// memory, not a manual limit.
const MAX_PATTERN_MOVES: usize = 2_000_000;

/// The error for a pattern that grows past [`MAX_PATTERN_MOVES`].
fn too_many(cycle: u32) -> CycleError {
    CycleError::Geometry {
        cycle,
        msg: format!("the pattern generates more than {MAX_PATTERN_MOVES} moves"),
    }
}

/// True when `number` is a pattern cycle.
pub(super) fn knows(number: u32) -> bool {
    matches!(number, 220 | 221)
}

/// The machining cycle's parameters with some of them replaced.
struct Override<'a> {
    inner: &'a dyn ParamSource,
    q200: Option<f64>,
    q203: Option<f64>,
    q204: Option<f64>,
}

impl ParamSource for Override<'_> {
    fn get(&self, key: ParamKey) -> Option<f64> {
        let replaced = match key {
            ParamKey::Q(200) => self.q200,
            ParamKey::Q(203) => self.q203,
            ParamKey::Q(204) => self.q204,
            _ => None,
        };
        replaced.or_else(|| self.inner.get(key))
    }
}

/// Whether `machining` is a cycle a pattern can call (one that [`super::generate`] knows).
fn check_machining(machining: u32) -> Result<(), CycleError> {
    if super::drill::knows(machining) || super::pocket::knows(machining) {
        Ok(())
    } else {
        Err(CycleError::Unknown(machining))
    }
}

/// The set-up clearance of an old-format machining cycle (sub-block 1, by magnitude).
fn old_clearance(mp: &dyn ParamSource, machining: u32) -> Result<f64, CycleError> {
    let p = Params::new(machining, mp);
    Ok(p.req_key(
        ParamKey::Old { line: 1, index: 0 },
        "set-up clearance",
        -LEN_MAX,
        LEN_MAX,
        "-99999.9999..=99999.9999",
    )?
    .abs())
}

/// Where the last move of `moves` ends, if any moves the tool.
fn end_of(moves: &[Move]) -> Option<P3> {
    moves.iter().rev().find_map(|m| match *m {
        Move::Line { to, .. } | Move::Arc { to, .. } => Some(to),
        _ => None,
    })
}

/// How the tool travels between pattern positions.
#[derive(Clone, Copy)]
enum Travel {
    /// Straight line.
    Line,
    /// Arc about `centre` in the direction `ccw` (220 with Q365 = 1).
    Arc { centre: [f64; 2], ccw: bool },
}

/// The heights and the travel of one pattern run.
struct Run<'a> {
    pattern: u32,
    machining: u32,
    mp: &'a dyn ParamSource,
    q200: f64,
    q203: f64,
    q204: f64,
    /// Q301 = 1: travel at the 2nd set-up clearance.
    high_travel: bool,
    travel: Travel,
}

impl Run<'_> {
    fn go(
        &self,
        points: &[[f64; 2]],
        ctx: &CycleContext,
        out: &mut Vec<Move>,
    ) -> Result<(), CycleError> {
        check_machining(self.machining)?;
        let safe = self.q203 + self.q200;
        let high = self.q203 + self.q200.max(self.q204);
        let travel = if self.high_travel { high } else { safe };
        let entry = if super::drill::is_old_format(self.machining) {
            self.q203 + old_clearance(self.mp, self.machining)?
        } else {
            safe
        };
        let mut pos = ctx.pos;
        let first = out.len();
        for (i, pt) in points.iter().enumerate() {
            let mut path = Path::new(out, pos);
            if i == 0 {
                path.rapid_axis(high);
                path.plane(pt[0], pt[1], CycleFeed::Rapid);
            } else {
                path.rapid_axis(travel);
                let to = [pt[0], pt[1], travel];
                let moved = (to[0] - path.pos[0]).abs() + (to[1] - path.pos[1]).abs() > EPS;
                match self.travel {
                    Travel::Arc { centre, ccw } if moved => {
                        path.arc(centre, to, ccw, CycleFeed::Rapid)
                    }
                    _ => path.line(to, CycleFeed::Rapid),
                }
            }
            path.rapid_axis(entry);
            pos = path.pos;
            let last = i + 1 == points.len();
            let mp = Override {
                inner: self.mp,
                q200: Some(self.q200),
                q203: Some(self.q203),
                q204: Some(if !self.high_travel && !last {
                    0.0
                } else {
                    self.q204
                }),
            };
            let call = CycleContext { pos, ..*ctx };
            let mark = out.len();
            super::generate(self.machining, &mp, &call, out)?;
            pos = end_of(out.get(mark..).unwrap_or(&[])).unwrap_or(pos);
            if out.len() - first > MAX_PATTERN_MOVES {
                return Err(too_many(self.pattern));
            }
        }
        Ok(())
    }
}

/// Reads Q200, Q203, Q204 and Q301 of a pattern.
fn heights(p: &Params<'_>) -> Result<(f64, f64, f64, bool), CycleError> {
    const LEN: &str = "0..=99999.9999";
    let q200 = p.req(200, "set-up clearance", 0.0, LEN_MAX, LEN)?;
    let q203 = p.req(
        203,
        "workpiece surface coordinate",
        -LEN_MAX,
        LEN_MAX,
        "-99999.9999..=99999.9999",
    )?;
    let q204 = p.req(204, "2nd set-up clearance", 0.0, LEN_MAX, LEN)?;
    let q301 = p.opt_int(
        301,
        0,
        0,
        1,
        "0 (set-up clearance) or 1 (2nd set-up clearance)",
    )?;
    Ok((q200, q203, q204, q301 == 1))
}

/// Positions of a polar pattern, the centre of its pitch circle and the stepping angle
/// (degrees, + counter-clockwise).
type Polar = (Vec<[f64; 2]>, [f64; 2], f64);

/// The positions of cycle 220 POLAR PATTERN and the centre of its pitch circle.
///
/// Positions lie on the circle of diameter Q244 about (Q216, Q217), the first at the start
/// angle Q245 (from the reference axis), Q241 of them. A stepping angle Q247 ≠ 0 spaces
/// them (its sign gives the direction, − clockwise) and the stop angle Q246 is ignored;
/// with Q247 = 0 the step comes from the start and stop angles: (Q246 − Q245)/(Q241 − 1),
/// so the last position lies on the stop angle. When stop − start is a full turn (±360°)
/// the step is that turn divided by Q241 instead, so the last position does not fall on
/// the first. Equal start and stop angles with Q247 = 0 and more than one position are an
/// error (the manual forbids them).
pub(super) fn polar_points(p: &Params<'_>) -> Result<Polar, CycleError> {
    const ANY: &str = "-99999.9999..=99999.9999";
    const ANGLE: &str = "-360..=360";
    let ca = p.req(216, "center 1st axis", -LEN_MAX, LEN_MAX, ANY)?;
    let cb = p.req(217, "center 2nd axis", -LEN_MAX, LEN_MAX, ANY)?;
    let diameter = p.req(244, "pitch circle diameter", 0.0, LEN_MAX, "0..=99999.9999")?;
    let start = p.req(245, "starting angle", -360.0, 360.0, ANGLE)?;
    let stop = p.opt(246, start, -360.0, 360.0, ANGLE)?;
    let step = p.opt(247, 0.0, -360.0, 360.0, ANGLE)?;
    let n = p.req_int(241, "number of repetitions", 1, 99_999, "1..=99999")?;
    let step = if step != 0.0 || n == 1 {
        step
    } else {
        let span = stop - start;
        if span == 0.0 {
            return Err(p.geometry(
                "the starting angle Q245 equals the stopping angle Q246 and Q247 is 0: the positions cannot be spread",
            ));
        }
        if (span.abs() - 360.0).abs() < 1e-9 {
            span / n as f64
        } else {
            span / (n - 1) as f64
        }
    };
    let r = diameter / 2.0;
    let points = (0..n)
        .map(|i| {
            let a = (start + step * i as f64).to_radians();
            [ca + r * a.cos(), cb + r * a.sin()]
        })
        .collect();
    Ok((points, [ca, cb], step))
}

/// The positions of cycle 221 CARTESIAN PATTERN in machining order.
///
/// Q242 positions per line spaced Q237 along the reference axis, Q243 lines spaced Q238
/// along the minor axis, starting at (Q225, Q226); the whole pattern is rotated by Q224
/// about the starting point. The first line runs in the direction of Q237, the second back
/// (the tool goes to the last point of the second line first), and so on alternately.
pub(super) fn cartesian_points(p: &Params<'_>) -> Result<Vec<[f64; 2]>, CycleError> {
    const ANY: &str = "-99999.9999..=99999.9999";
    let sa = p.req(225, "starting point 1st axis", -LEN_MAX, LEN_MAX, ANY)?;
    let sb = p.req(226, "starting point 2nd axis", -LEN_MAX, LEN_MAX, ANY)?;
    let da = p.req(237, "spacing in 1st axis", -LEN_MAX, LEN_MAX, ANY)?;
    let db = p.req(238, "spacing in 2nd axis", -LEN_MAX, LEN_MAX, ANY)?;
    let cols = p.req_int(242, "number of columns", 1, 99_999, "1..=99999")?;
    let lines = p.req_int(243, "number of lines", 1, 99_999, "1..=99999")?;
    let rot = p.opt(224, 0.0, -360.0, 360.0, "-360..=360")?.to_radians();
    if cols.saturating_mul(lines) > MAX_PATTERN_MOVES as i64 {
        return Err(too_many(p.cycle));
    }
    let (s, c) = rot.sin_cos();
    let mut points = Vec::new();
    for j in 0..lines {
        for k in 0..cols {
            let i = if j % 2 == 0 { k } else { cols - 1 - k };
            let u = i as f64 * da;
            let v = j as f64 * db;
            points.push([sa + u * c - v * s, sb + u * s + v * c]);
        }
    }
    Ok(points)
}

/// See [`super::generate_pattern`].
pub(super) fn generate(
    pattern: u32,
    pp: &dyn ParamSource,
    machining: u32,
    mp: &dyn ParamSource,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let p = Params::new(pattern, pp);
    let (points, travel) = match pattern {
        220 => {
            let (points, centre, step) = polar_points(&p)?;
            let arcs =
                p.opt_int(365, 0, 0, 1, "0 (straight line) or 1 (on the pitch circle)")? == 1;
            let travel = if arcs {
                Travel::Arc {
                    centre,
                    ccw: step > 0.0,
                }
            } else {
                Travel::Line
            };
            (points, travel)
        }
        221 => (cartesian_points(&p)?, Travel::Line),
        _ => return Err(CycleError::Unknown(pattern)),
    };
    let (q200, q203, q204, high_travel) = heights(&p)?;
    Run {
        pattern,
        machining,
        mp,
        q200,
        q203,
        q204,
        high_travel,
        travel,
    }
    .go(&points, ctx, out)
}

/// See [`super::generate_at_points`].
///
/// The tool-axis coordinate of each point is the workpiece surface there (it replaces the
/// machining cycle's Q203). Between points the tool retracts at FMAX to the clearance
/// height: the larger of the tool-axis position at the call and the 2nd set-up clearance
/// (here: the highest 2nd set-up clearance over all points, so that one height serves the
/// whole pattern), then moves in the plane at FMAX and lets the machining cycle go down.
pub(super) fn at_points(
    points: &[P3],
    machining: u32,
    mp: &dyn ParamSource,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    check_machining(machining)?;
    let p = Params::new(machining, mp);
    let old = super::drill::is_old_format(machining);
    let (clear, second) = if old {
        (old_clearance(mp, machining)?, 0.0)
    } else {
        (
            p.req(200, "set-up clearance", 0.0, LEN_MAX, "0..=99999.9999")?,
            p.opt(204, 0.0, 0.0, LEN_MAX, "0..=99999.9999")?,
        )
    };
    let height = points
        .iter()
        .map(|q| q[2] + clear.max(second))
        .fold(ctx.pos[2], f64::max);
    let mut pos = ctx.pos;
    let first = out.len();
    for q in points {
        let mut path = Path::new(out, pos);
        path.rapid_axis(height);
        path.plane(q[0], q[1], CycleFeed::Rapid);
        if old {
            path.rapid_axis(q[2] + clear);
        }
        pos = path.pos;
        let mp = Override {
            inner: mp,
            q200: None,
            q203: if old { None } else { Some(q[2]) },
            q204: None,
        };
        let call = CycleContext { pos, ..*ctx };
        let mark = out.len();
        super::generate(machining, &mp, &call, out)?;
        pos = end_of(out.get(mark..).unwrap_or(&[])).unwrap_or(pos);
        if out.len() - first > MAX_PATTERN_MOVES {
            return Err(too_many(machining));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
