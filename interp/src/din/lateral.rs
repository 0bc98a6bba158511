//! Hole patterns on the lateral surface (G744 linear, G746 circular) and the drilling
//! cycles G71, G74 and G36 run radially at their positions.
//!
//! A lateral position is (z, c): the Z coordinate and the spindle angle C in degrees. The
//! drill works along X: from the start diameter `XS` (default: where the tool stands) to
//! the end diameter `XE`, with the cycles' own motion (see `cycles::plunge`). At each
//! position: rapid in C (the shortest way from where C stands) and Z at the clearance X
//! (the radius where the tool stood when the pattern began), the drilling motion, rapid
//! back out to the clearance X. With `XE` in the pattern block the pattern drills by
//! itself (G71); without it the G71, G74 or G36 of the next block runs at every position,
//! taking XS/XE from the pattern where it leaves them out.
//!
//! G744 (this version's reading of the manual's parameter list; the row rules mirror the
//! face pattern G743): first position `Z`, `C` (default 0°); Q positions (default 1) in a
//! row whose Z advances as `K` (Z of the last position, the span divided into Q − 1 steps)
//! or `Ki` (distance) says and whose angle advances as `W` (angle of the last position) or
//! `Wi` (angle step) says.
//!
//! G746: centre `Z`, `C` on the unrolled lateral surface of the reference diameter `X`
//! (default: `XS`); pattern diameter `K`; positions from `A`, `W`/`Wi`, `Q`, `V` exactly as
//! for G745. On the unrolled surface the angles are measured from the +Z direction towards
//! increasing C; a point (z, s) with s the arc length on the reference circle is the
//! position (z, c = s / (X/2) in degrees).

use std::collections::VecDeque;

use super::cycles::{self, CycleCall, pattern_count};
use super::lathe::{Group, Lathe, err_at, num};
use super::pattern::{CircleLayout, LinearStep, PatternEnd, linear_positions};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Feed, Op, SourceLoc};
use crate::tnc::exec::ExecError;

/// A lateral pattern waiting for its cycle (or drilling by itself with XE).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LateralPattern {
    /// Positions (z, c in degrees).
    pub points: Vec<[f64; 2]>,
    /// XS: start diameter of the drilling.
    pub xs: Option<f64>,
    /// XE: end diameter of the drilling.
    pub xe: Option<f64>,
    /// The block number of the pattern (for diagnostics).
    pub block: Option<u64>,
}

fn step(g: &Group<'_>, abs: &str, inc: &str) -> Result<Option<LinearStep>, ExecError> {
    match (g.get(abs), g.get(inc)) {
        (Some(_), Some(w)) => Err(err_at(
            w,
            ProgramError::Unexpected(format!("{abs} and {inc} in one pattern: give one")),
        )),
        (Some(w), None) => Ok(Some(LinearStep::To(num(w)?))),
        (None, Some(w)) => Ok(Some(LinearStep::By(num(w)?))),
        (None, None) => Ok(None),
    }
}

fn need_z(g: &Group<'_>, what: &'static str) -> Result<f64, ExecError> {
    g.value("Z")?
        .ok_or((g.g_word.map(|w| w.pos as u32), ProgramError::Missing(what)))
}

/// Reads a G744 group.
pub(crate) fn g744(g: &Group<'_>, block: Option<u64>) -> Result<LateralPattern, ExecError> {
    let start = [
        need_z(g, "G744 needs the Z of the first position")?,
        g.value("C")?.unwrap_or(0.0),
    ];
    let count = pattern_count(g)?;
    let steps = [step(g, "K", "Ki")?, step(g, "W", "Wi")?];
    Ok(LateralPattern {
        points: linear_positions(start, steps, count),
        xs: g.value("XS")?,
        xe: g.value("XE")?,
        block,
    })
}

/// Reads a G746 group.
pub(crate) fn g746(g: &Group<'_>, block: Option<u64>) -> Result<LateralPattern, ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    let z0 = need_z(g, "G746 needs the Z of the pattern centre")?;
    let c0 = g.value("C")?.unwrap_or(0.0);
    let xs = g.value("XS")?;
    let reference = g.value("X")?.or(xs).ok_or((
        here,
        ProgramError::Missing("G746 needs the reference diameter X (or XS)"),
    ))?;
    if reference.is_nan() || reference <= 0.0 {
        return Err((
            here,
            ProgramError::OutOfRange(format!("reference diameter X{reference} must be positive")),
        ));
    }
    let k = g.get("K").ok_or((
        here,
        ProgramError::Missing("G746 needs the pattern diameter K"),
    ))?;
    let radius = num(k)? / 2.0;
    let end = match (g.get("W"), g.get("Wi")) {
        (Some(_), Some(wi)) => {
            return Err(err_at(
                wi,
                ProgramError::Unexpected("W and Wi in one pattern: give one of them".into()),
            ));
        }
        (Some(w), None) => PatternEnd::EndAngle(num(w)?),
        (None, Some(wi)) => PatternEnd::Increment(num(wi)?),
        (None, None) => PatternEnd::None,
    };
    let direction = match g.value("V")? {
        None => 0,
        Some(v) if v == 0.0 || v == 1.0 || v == 2.0 => v as u8,
        Some(v) => {
            return Err((
                g.get("V").map(|w| w.pos as u32),
                ProgramError::OutOfRange(format!("pattern direction V{v}: expected 0, 1 or 2")),
            ));
        }
    };
    let layout = CircleLayout {
        start: g.value("A")?.unwrap_or(0.0),
        end,
        count: pattern_count(g)?,
        direction,
    };
    let angles = layout.angles().map_err(|e| (here, e))?;
    let r_ref = reference / 2.0;
    let s0 = c0.to_radians() * r_ref;
    let points = angles
        .iter()
        .map(|a| {
            let (sa, ca) = a.to_radians().sin_cos();
            let s = s0 + radius * sa;
            [z0 + radius * ca, (s / r_ref).to_degrees()]
        })
        .collect();
    Ok(LateralPattern {
        points,
        xs,
        xe: g.value("XE")?,
        block,
    })
}

/// Reads a radial drilling cycle (G71, G74, G36) for a lateral pattern: XE (or X) and XS
/// as diameters, taken from the pattern where the cycle leaves them out; the call holds
/// them as radii.
pub(crate) fn lateral_call(
    lathe: &mut Lathe,
    g: &Group<'_>,
    code: u32,
    pattern: &LateralPattern,
) -> Result<CycleCall, ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    if code == 791 {
        return Err((
            here,
            ProgramError::Unexpected(
                "G791 mills a slot on the face: it cannot follow a lateral pattern".into(),
            ),
        ));
    }
    let xe = g.value("XE")?.or(g.value("X")?).or(pattern.xe).ok_or((
        here,
        ProgramError::Missing("drilling on the lateral surface needs its end diameter XE"),
    ))?;
    let xs = g.value("XS")?.or(pattern.xs);
    let (cycle, feed) = cycles::cycle_of(lathe, g, code)?;
    Ok(CycleCall {
        cycle,
        zs: xs.map(|d| d / 2.0),
        ze: xe / 2.0,
        feed,
    })
}

/// Runs a radial cycle at lateral position `p` (z, c), from the clearance radius.
pub(crate) fn run_lateral(
    lathe: &mut Lathe,
    call: &CycleCall,
    p: [f64; 2],
    clearance: f64,
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) {
    let mut at = lathe.pos;
    at[AxisLetter::X] = clearance;
    at[AxisLetter::Y] = 0.0;
    at[AxisLetter::Z] = p[0];
    let c0 = lathe.pos[AxisLetter::C];
    let mut d = (p[1] - c0).rem_euclid(360.0);
    if d > 180.0 {
        d -= 360.0;
    }
    at[AxisLetter::C] = c0 + d;
    lathe.line(at, Feed::Rapid, loc, out);
    let start = call.zs.unwrap_or(clearance);
    cycles::plunge(lathe, call, AxisLetter::X, start, call.ze, loc, out);
    let mut back = lathe.pos;
    back[AxisLetter::X] = clearance;
    lathe.line(back, Feed::Rapid, loc, out);
}
