//! `M140 MB MAX`: how far the tool can back out along the tool axis before a machine axis
//! reaches its travel limit.
//!
//! The TNC retracts along the active tool axis until the first linear machine axis stands at
//! its software limit, in a tilted working plane too (the tool axis is then the tilted one).
//! klar's machine axes carry the tool tip (the tool length is part of the tool, not of the
//! axis position), so the retract ends where the tip's axis reaches the end of its travel,
//! whatever the tool length; the travel limits come from the machine file
//! (`Interpreter::with_travel`).
//!
//! The computation runs in three frames: program coordinates (`Machine::pos`), workpiece
//! coordinates (after the datum shift, preset, mirror, rotation and scaling, then the tilted
//! working plane) and machine coordinates. Between workpiece and machine stands the
//! table-table geometry while the tool-tip transformation (TCPM, or a tilted plane) is on,
//! and the identity otherwise. Every map is affine, so a unit step along the program's tool
//! axis moves the machine by a fixed vector `dm`, and the retract distance is the smallest
//! `s ≥ 0` at which `m0 + s·dm` meets a face of the travel box.

use super::exec::Machine;
use super::plane_math::{self as pm, Tilt, V3};
use crate::op::AxisLetter;

/// Linear machine axes X, Y, Z with their travel `[min, max]` (mm), when the machine file
/// gives them.
pub(crate) type Travel = [Option<[f64; 2]>; 3];

/// Directions shorter than this (per mm of retract) do not move an axis towards a limit.
const STILL: f64 = 1e-12;

impl Machine {
    /// The distance (mm, program coordinates) from the present position up the tool axis to
    /// the first travel limit a linear machine axis meets; `None` when no axis that the
    /// retract moves has a known travel.
    pub(super) fn retract_distance(&self) -> Option<f64> {
        let axis = self.tool_axis;
        let mut e = [0.0; 3];
        let i = axis.index();
        *e.get_mut(i)? = 1.0;
        let w0 = self.workpiece_pos();
        let p0: V3 = [w0[AxisLetter::X], w0[AxisLetter::Y], w0[AxisLetter::Z]];
        let dw = pm::apply(&self.tilt.r, self.cyc.xf.linear(e));
        let p1: V3 = [p0[0] + dw[0], p0[1] + dw[1], p0[2] + dw[2]];
        let (m0, m1) = match self.tilt.geometry {
            Some(g) if self.tilt.kin_on => {
                let t = match g.tilt {
                    Tilt::A => w0[AxisLetter::A],
                    Tilt::B => w0[AxisLetter::B],
                };
                let c = w0[AxisLetter::C];
                (g.tip_to_machine(p0, t, c), g.tip_to_machine(p1, t, c))
            }
            _ => (p0, p1),
        };
        let mut best: Option<f64> = None;
        for k in 0..3 {
            let Some([lo, hi]) = self.travel[k] else {
                continue;
            };
            let d = m1[k] - m0[k];
            let s = if d > STILL {
                (hi - m0[k]) / d
            } else if d < -STILL {
                (lo - m0[k]) / d
            } else {
                continue;
            };
            best = Some(best.map_or(s, |b| b.min(s)));
        }
        best.map(|s| s.max(0.0))
    }
}

#[cfg(test)]
mod tests {
    use crate::Interpreter;
    use crate::op::{AxisLetter, OpKind, Pose};

    fn ends(text: &str, travel: &[(AxisLetter, [f64; 2])]) -> Vec<Pose> {
        let mut interp = Interpreter::from_source("t.h", text, Pose::ZERO);
        for (a, t) in travel {
            interp = interp.with_travel(*a, *t);
        }
        interp
            .filter_map(|r| match r.ok()?.kind {
                OpKind::Line { to, .. } => Some(to),
                _ => None,
            })
            .collect()
    }

    const XYZ: [(AxisLetter, [f64; 2]); 3] = [
        (AxisLetter::X, [-300.0, 300.0]),
        (AxisLetter::Y, [-300.0, 300.0]),
        (AxisLetter::Z, [-200.0, 200.0]),
    ];

    #[test]
    fn mb_max_ends_at_the_travel_limit_of_the_tool_axis() {
        let p = "BEGIN PGM T MM\nL X+10 Y+5 Z-20 F500\nL M140 MB MAX\nEND PGM T MM\n";
        let e = ends(p, &XYZ);
        let last = e.last().copied().unwrap_or(Pose::ZERO);
        assert_eq!(
            (
                last[AxisLetter::X],
                last[AxisLetter::Y],
                last[AxisLetter::Z]
            ),
            (10.0, 5.0, 200.0)
        );
    }

    #[test]
    fn a_datum_shift_moves_the_program_target_not_the_machine_one() {
        // shifted by Z+50: program Z 150 is machine Z 200
        let p = "BEGIN PGM T MM\nCYCL DEF 7.0 DATUM SHIFT\nCYCL DEF 7.1 Z+50\n\
                 L Z-20 F500\nL M140 MB MAX\nL IX+1 F500\nEND PGM T MM\n";
        let e = ends(p, &XYZ);
        let z: Vec<f64> = e.iter().map(|p| p[AxisLetter::Z]).collect();
        // ops carry machine (mapped) coordinates
        assert_eq!(z.last().copied(), Some(200.0), "{z:?}");
    }

    #[test]
    fn tool_axis_x_retracts_along_x() {
        let p = "BEGIN PGM T MM\nTOOL CALL 0 X\nL X+10 Y+5 Z-20 F500\nL M140 MB MAX\n\
                 END PGM T MM\n";
        let e = ends(p, &XYZ);
        let last = e.last().copied().unwrap_or(Pose::ZERO);
        assert_eq!(last[AxisLetter::X], 300.0);
        assert_eq!(last[AxisLetter::Z], -20.0);
    }
}
