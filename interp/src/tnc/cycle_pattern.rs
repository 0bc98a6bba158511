//! `PATTERN DEF`: the points of its elements, for `CYCL CALL PAT`.
//!
//! Elements (all coordinates absolute, in the working plane `X`/`Y` = its first and second
//! axis, `Z` = the workpiece surface at the point):
//! - `POS (X Y Z)`: one point;
//! - `ROW (X Y D NUM ROT Z)`: NUM points from (X, Y), D apart, in the direction ROT;
//! - `PAT (X Y DX DY NUMX NUMY ROT ROTX ROTY Z)`: a grid of NUMX × NUMY points, DX and DY
//!   apart, the whole grid turned by ROT, its rows by ROTX more and its columns by ROTY more
//!   (a sheared grid); points are listed row by row;
//! - `FRAME (…)`: as PAT, only the points on the grid's outline;
//! - `CIRC (X Y D START NUM Z)`: NUM points evenly on a full circle of diameter D about
//!   (X, Y), the first at angle START;
//! - `PITCHCIRC (X Y D START STEP NUM Z)`: NUM points from angle START, STEP degrees apart.

use super::cycle_words::{PatternItem, PatternKind};
use super::exec::{ExecError, Flow, Machine, at};
use super::stmt::Parsed;
use crate::cycles::P3;
use crate::diag::ProgramError;

/// Most points one PATTERN DEF grid may have (a guard against runaway counts).
pub const MAX_PATTERN_POINTS: usize = 100_000;

impl Machine {
    /// `PATTERN DEF`: computes the points of its elements.
    pub(super) fn pattern_def(&mut self, parsed: &Parsed) -> Result<Flow, ExecError> {
        let mut pts = Vec::new();
        for item in &parsed.cycle.pattern {
            self.pattern_points(item, &mut pts)?;
        }
        self.cyc.pattern = pts;
        Ok(Flow::Continue)
    }

    fn pattern_points(&self, it: &PatternItem, pts: &mut Vec<P3>) -> Result<(), ExecError> {
        let get = |w: &[u8]| it.get(w).map(|v| self.params.value(v));
        let len = |w: &[u8]| get(w).map(|v| v * self.unit);
        let x = len(b"X").unwrap_or(0.0);
        let y = len(b"Y").unwrap_or(0.0);
        let z = len(b"Z").unwrap_or(0.0);
        let count = |w: &'static str| -> Result<usize, ExecError> {
            let v = get(w.as_bytes()).unwrap_or(1.0);
            if !(v >= 1.0 && v.fract() == 0.0 && v <= 10_000.0) {
                return Err(at(
                    it.pos,
                    ProgramError::OutOfRange(format!(
                        "{w}{v} must be a whole number from 1 to 10000"
                    )),
                ));
            }
            Ok(v as usize)
        };
        let dir = |deg: f64| {
            let (s, c) = deg.to_radians().sin_cos();
            [c, s]
        };
        match it.kind {
            PatternKind::Pos => pts.push([x, y, z]),
            PatternKind::Row => {
                let d = len(b"D").unwrap_or(0.0);
                let u = dir(get(b"ROT").unwrap_or(0.0));
                for i in 0..count("NUM")? {
                    let s = d * i as f64;
                    pts.push([x + s * u[0], y + s * u[1], z]);
                }
            }
            PatternKind::Pat | PatternKind::Frame => {
                let (dx, dy) = (len(b"DX").unwrap_or(0.0), len(b"DY").unwrap_or(0.0));
                let rot = get(b"ROT").unwrap_or(0.0);
                let ux = dir(rot + get(b"ROTX").unwrap_or(0.0));
                let vy = dir(rot + 90.0 + get(b"ROTY").unwrap_or(0.0));
                let (nx, ny) = (count("NUMX")?, count("NUMY")?);
                if nx * ny > MAX_PATTERN_POINTS {
                    return Err(at(
                        it.pos,
                        ProgramError::OutOfRange(format!(
                            "a pattern of {nx} x {ny} points is larger than {MAX_PATTERN_POINTS}"
                        )),
                    ));
                }
                for j in 0..ny {
                    for i in 0..nx {
                        let edge = i == 0 || j == 0 || i + 1 == nx || j + 1 == ny;
                        if it.kind == PatternKind::Frame && !edge {
                            continue;
                        }
                        let (s, t) = (dx * i as f64, dy * j as f64);
                        pts.push([x + s * ux[0] + t * vy[0], y + s * ux[1] + t * vy[1], z]);
                    }
                }
            }
            PatternKind::Circ | PatternKind::PitchCirc => {
                let r = len(b"D").unwrap_or(0.0) / 2.0;
                let start = get(b"START").unwrap_or(0.0);
                let num = count("NUM")?;
                let step = if it.kind == PatternKind::Circ {
                    360.0 / num as f64
                } else {
                    get(b"STEP").unwrap_or(0.0)
                };
                for k in 0..num {
                    let u = dir(start + step * k as f64);
                    pts.push([x + r * u[0], y + r * u[1], z]);
                }
            }
        }
        Ok(())
    }
}
