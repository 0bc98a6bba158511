//! Thread cutting on the lathe: G33, the single thread pass.
//!
//! The rules this follows, from the CNC PILOT 640 / MANUALplus 620 DIN manual:
//!
//! - G33 cuts one thread pass from where the tool stands to the end point `X` (diameter)
//!   `Z`; incremental `Xi`/`Zi` count from the start. The direction is free: along Z
//!   (longitudinal), along X (face thread) or both (taper).
//! - `F` is the pitch, mm per spindle revolution. `H` says which travel it measures:
//!   0 the Z travel (the default; threads up to 45° from Z), 1 the X travel (face threads
//!   and steeper tapers), 3 the travel along the path.
//! - `B` is the run-in: the slide accelerates over this length, which lies before the
//!   thread proper (the programmer positions the tool that much in front of it). `P` is the
//!   run-out: the slide brakes over this length before the end point. Without them klar uses
//!   the shortest lengths the axes' acceleration allows at the spindle speed of the run.
//! - `C` is the starting angle: the spindle stands at this angle when the run-in ends.
//!   Passes with the same `C` cut the same groove; a multi-start thread gives each start its
//!   own angle (360° / starts apart).
//! - `E` (variable pitch) has no effect on the control; klar accepts only `E0`. `I`/`K`
//!   (retraction on a cycle stop) are accepted and not needed: a hold in a pass finishes the
//!   pass.
//!
//! The pass becomes one [`OpKind::SpindleSync`]: the servo loop gears the axes to the
//! measured spindle angle. For the simulated spindle's load, the chip cross-section of a
//! pass is its pitch times its infeed below the previous pass of the same thread (same
//! pitch, same end Z); the first pass of a thread, whose depth below the blank the program
//! does not say, counts as no load.

use std::collections::VecDeque;

use super::lathe::{Group, Lathe, num};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Op, OpKind, Pose, SourceLoc, ThreadLead};
use crate::tnc::exec::ExecError;

/// The words a G33 block takes.
pub(crate) const G33_WORDS: [&str; 12] =
    ["X", "Xi", "Z", "Zi", "F", "B", "P", "C", "H", "E", "I", "K"];

/// What the lathe remembers between thread passes.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub(crate) struct ThreadState {
    /// The last pass: its pitch and end point.
    last: Option<(f64, Pose)>,
}

/// A length word that must be a finite number ≥ 0, if given.
fn length(g: &Group<'_>, addr: &str) -> Result<Option<f64>, ExecError> {
    match g.get(addr) {
        None => Ok(None),
        Some(w) => {
            let v = num(w)?;
            if v.is_finite() && v >= 0.0 {
                Ok(Some(v))
            } else {
                Err((
                    Some(w.pos as u32),
                    ProgramError::OutOfRange(format!("G33 {addr}{v} must be a length ≥ 0")),
                ))
            }
        }
    }
}

/// G33: one thread pass from the present position to the block's end point.
pub(crate) fn g33(
    l: &mut Lathe,
    state: &mut ThreadState,
    g: &Group<'_>,
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) -> Result<(), ExecError> {
    let gpos = g.g_word.map(|w| w.pos as u32);
    let at = |addr: &str| g.get(addr).map(|w| w.pos as u32).or(gpos);
    let pitch = g
        .value("F")?
        .ok_or((gpos, ProgramError::Missing("G33 needs the thread pitch F")))?;
    if !(pitch.is_finite() && pitch > 0.0) {
        return Err((
            at("F"),
            ProgramError::OutOfRange(format!("G33 pitch F{pitch} must be positive")),
        ));
    }
    let lead = match g.value("H")? {
        None | Some(0.0) => ThreadLead::Z,
        Some(1.0) => ThreadLead::X,
        Some(3.0) => ThreadLead::Path,
        Some(h) => {
            return Err((
                at("H"),
                ProgramError::OutOfRange(format!(
                    "G33 H{h}: expected 0 (pitch along Z), 1 (along X) or 3 (along the path)"
                )),
            ));
        }
    };
    if let Some(e) = g.value("E")?
        && e != 0.0
    {
        return Err((
            at("E"),
            ProgramError::NotSupported("G33 with a variable pitch E".into()),
        ));
    }
    let start_angle = g.value("C")?.unwrap_or(0.0);
    if !start_angle.is_finite() {
        return Err((
            at("C"),
            ProgramError::OutOfRange("G33 starting angle C".into()),
        ));
    }
    let run_in = length(g, "B")?;
    let run_out = length(g, "P")?;
    let from = l.pos;
    // C is the starting angle here, not the C axis: only X/Xi and Z/Zi make the end point.
    let mut to = from;
    for (abs, inc, axis, scale) in [
        ("X", "Xi", AxisLetter::X, 0.5),
        ("Z", "Zi", AxisLetter::Z, 1.0),
    ] {
        match (g.get(abs), g.get(inc)) {
            (Some(a), Some(_)) => {
                return Err((
                    Some(a.pos as u32),
                    ProgramError::Unexpected(format!("{abs} and {inc} in one block")),
                ));
            }
            (Some(a), None) => to[axis] = num(a)? * scale,
            (None, Some(i)) => to[axis] += num(i)? * scale,
            (None, None) => {}
        }
    }
    let (dx, dz) = (
        to[AxisLetter::X] - from[AxisLetter::X],
        to[AxisLetter::Z] - from[AxisLetter::Z],
    );
    let moved: f64 = (0..9)
        .map(|i| (to.0[i] - from.0[i]).powi(2))
        .sum::<f64>()
        .sqrt();
    if moved < 1e-6 {
        return Err((
            gpos,
            ProgramError::Geometry("G33 needs an end point away from the start".into()),
        ));
    }
    let measured = match lead {
        ThreadLead::Z => dz.abs(),
        ThreadLead::X => dx.abs(),
        ThreadLead::Path => moved,
    };
    if measured < 1e-6 {
        let axis = if lead == ThreadLead::X { "X" } else { "Z" };
        return Err((
            gpos,
            ProgramError::Geometry(format!(
                "G33 measures the pitch along {axis}, but the pass does not move {axis} \
                 (H1 measures it along X, H3 along the path)"
            )),
        ));
    }
    if let (Some(b), Some(p)) = (run_in, run_out)
        && b + p > moved + 1e-9
    {
        return Err((
            gpos,
            ProgramError::Geometry(format!(
                "G33 run-in B{b} and run-out P{p} are longer than the pass ({moved:.4} mm)"
            )),
        ));
    }
    let section = match state.last {
        Some((p, last)) if p == pitch && (last[AxisLetter::Z] - to[AxisLetter::Z]).abs() < 1e-6 => {
            pitch * (last[AxisLetter::X] - to[AxisLetter::X]).abs()
        }
        _ => 0.0,
    };
    state.last = Some((pitch, to));
    out.push_back(Op {
        kind: OpKind::SpindleSync {
            from,
            to,
            pitch,
            lead,
            start_angle,
            run_in,
            run_out,
            section,
        },
        loc,
    });
    l.pos = to;
    Ok(())
}
