//! The last stage of op output: turning ops from the tilted working plane into the untilted
//! workpiece system (see [`super::plane`]).
//!
//! Points (X Y Z of every pose) are multiplied by the plane's rotation; the other axes pass
//! unchanged. An arc of a tilted plane no longer lies in XY, ZX or YZ, so it becomes a chain
//! of lines whose chords stay within [`ARC_CHORD_TOLERANCE`] of the arc (helices and other
//! axes move in proportion to the angle, as the arc op defines). A spline stays a spline:
//! its polynomial is linear in its coefficients, so the X, Y, Z coefficient vectors of each
//! power of t are turned like points and the turned polynomial is exactly the turned curve.
//!
//! Two ways to use it:
//! - By default the interpreter applies it itself as ops leave its queue
//!   ([`Machine::tilt_output`]), so its users see workpiece coordinates only. Radius
//!   compensation (RL/RR, APPR/DEP) is then refused in a tilted plane, since it would run
//!   after the tilt, in the wrong plane.
//! - With working-plane ops on (`Interpreter::set_working_plane_ops`) the interpreter leaves
//!   the ops in the tilted system and marks each change of the plane with
//!   [`OpKind::WorkingPlane`] where it takes effect in the stream. The radius compensation of
//!   motion then compensates in the tilted system and turns its output with [`tilt_kind`]
//!   (through [`OpKind::in_workpiece`]).

use std::collections::VecDeque;

use super::exec::{ExecError, Machine, here};
use super::op_points::map_points;
use super::plane_math::{self as pm, M3};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, CompSide, Op, OpKind, Pose};

/// Largest distance (mm) between a tilted arc and the lines that replace it.
pub const ARC_CHORD_TOLERANCE: f64 = 0.001;

/// Most lines one arc becomes.
const MAX_ARC_LINES: f64 = 100_000.0;

/// `p` with X Y Z turned by `r` (the other axes unchanged).
pub(super) fn turn(r: &M3, p: &Pose) -> Pose {
    let v = pm::apply(r, [p[AxisLetter::X], p[AxisLetter::Y], p[AxisLetter::Z]]);
    let mut out = *p;
    out[AxisLetter::X] = v[0];
    out[AxisLetter::Y] = v[1];
    out[AxisLetter::Z] = v[2];
    out
}

/// The ops `kind` becomes under the rotation `r` (one, or the lines of an arc). APPR and DEP
/// have their points turned but keep their plane: they are meant to be resolved (by the
/// radius compensation) before the tilt.
pub(crate) fn tilt_kind(r: &M3, kind: &OpKind) -> Vec<OpKind> {
    if let Some(mapped) = map_points(kind, |p| turn(r, p), |v| pm::apply(r, v)) {
        return vec![mapped];
    }
    match kind {
        OpKind::Arc {
            from,
            to,
            center,
            plane,
            sweep,
            feed,
        } => arc_points(from, to, *center, *plane, *sweep)
            .windows(2)
            .filter_map(|w| match w {
                [a, b] => Some(OpKind::Line {
                    from: turn(r, a),
                    to: turn(r, b),
                    feed: *feed,
                }),
                _ => None,
            })
            .collect(),
        OpKind::RigidTap {
            from,
            to,
            pitch,
            hand,
            strokes,
            retract_factor,
        } => vec![OpKind::RigidTap {
            from: turn(r, from),
            to: turn(r, to),
            pitch: *pitch,
            hand: *hand,
            strokes: strokes.clone(),
            retract_factor: *retract_factor,
        }],
        other => vec![other.clone()],
    }
}

/// Points along an arc op, start and end included, chords within the tolerance.
fn arc_points(
    from: &Pose,
    to: &Pose,
    center: [f64; 2],
    plane: crate::op::Plane,
    sweep: f64,
) -> Vec<Pose> {
    let (a, b, _) = plane.axes();
    let (da, db) = (from[a] - center[0], from[b] - center[1]);
    let radius = da.hypot(db);
    let start = db.atan2(da);
    let sweep_rad = sweep.to_radians();
    // A chord of angle φ lies at most r·(1 − cos(φ/2)) from its arc.
    let steps = if radius > ARC_CHORD_TOLERANCE {
        let phi = 2.0 * (1.0 - ARC_CHORD_TOLERANCE / radius).acos();
        (sweep_rad.abs() / phi).ceil().clamp(1.0, MAX_ARC_LINES)
    } else {
        1.0
    };
    let n = steps as usize;
    let mut pts = Vec::with_capacity(n + 1);
    pts.push(*from);
    for k in 1..n {
        let f = k as f64 / steps;
        let mut p = *from;
        for (i, v) in p.0.iter_mut().enumerate() {
            *v += (to.0[i] - from.0[i]) * f;
        }
        let ang = start + sweep_rad * f;
        p[a] = center[0] + radius * ang.cos();
        p[b] = center[1] + radius * ang.sin();
        pts.push(p);
    }
    pts.push(*to);
    pts
}

impl Machine {
    /// Tilts the queued ops not yet tilted (after mapping them with the cycle transforms),
    /// so that they keep the plane that was active when they were programmed.
    pub(super) fn premap_queue(&mut self, out: &mut VecDeque<Op>) {
        let tilt_here = !self.tilt.identity && !self.tilt.deferred;
        if !tilt_here && self.cyc.identity {
            self.cyc.pre_mapped = out.len();
            self.tilt.pre = out.len();
            return;
        }
        let mut mapped = VecDeque::with_capacity(out.len());
        for (i, op) in out.drain(..).enumerate() {
            let kind = if i >= self.cyc.pre_mapped && !self.cyc.identity {
                self.cyc.xf.map_op(&op.kind).unwrap_or(op.kind)
            } else {
                op.kind
            };
            if i >= self.tilt.pre && tilt_here {
                for k in tilt_kind(&self.tilt.r, &kind) {
                    mapped.push_back(Op {
                        kind: k,
                        loc: op.loc,
                    });
                }
            } else {
                mapped.push_back(Op { kind, loc: op.loc });
            }
        }
        *out = mapped;
        self.cyc.pre_mapped = out.len();
        self.tilt.pre = out.len();
    }

    /// Output hook: turns an op leaving the queue into the workpiece system. An arc's first
    /// line is returned, the rest wait in [`Machine::tilt_pending`]. With working-plane ops
    /// on, ops leave in the tilted system unchanged.
    pub fn tilt_output(&mut self, op: Op) -> Op {
        if self.tilt.pre > 0 {
            self.tilt.pre -= 1;
            return op;
        }
        if self.tilt.identity || self.tilt.deferred {
            return op;
        }
        let mut lines = tilt_kind(&self.tilt.r, &op.kind).into_iter();
        let Some(first) = lines.next() else {
            return op;
        };
        for k in lines {
            self.tilt.pending.push_back(Op {
                kind: k,
                loc: op.loc,
            });
        }
        Op {
            kind: first,
            loc: op.loc,
        }
    }

    /// The next line of a tilted arc, handed out before anything else.
    pub fn tilt_pending(&mut self) -> Option<Op> {
        self.tilt.pending.pop_front()
    }

    /// Leaves the ops in the tilted system and marks each change of the working plane with
    /// [`OpKind::WorkingPlane`] (`on`), or turns them into the workpiece system here (the
    /// default). Meant to be set before the program runs.
    pub fn set_working_plane_ops(&mut self, on: bool) {
        self.tilt.deferred = on;
    }

    /// Refuses the ops from `mark` on that cannot be tilted here (while a plane is tilted and
    /// the tilt is applied by the interpreter): radius compensation and APPR/DEP, which must
    /// run in the tilted plane, before the tilt.
    pub(super) fn check_tilt(&self, out: &VecDeque<Op>, mark: usize) -> Result<(), ExecError> {
        if self.tilt.identity || self.tilt.deferred {
            return Ok(());
        }
        for op in out.iter().skip(mark.max(self.tilt.pre)) {
            let what = match &op.kind {
                OpKind::Approach { .. } => "APPR",
                OpKind::Depart { .. } => "DEP",
                OpKind::RadiusComp { side } if *side != CompSide::Off => {
                    "radius compensation RL/RR"
                }
                _ => continue,
            };
            return Err(here(ProgramError::NotSupported(format!(
                "{what} in a tilted working plane (here the plane is turned before the \
                 radius compensation)"
            ))));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::op::{Feed, Plane};

    #[test]
    fn tilted_quarter_circle_stays_on_the_turned_circle() {
        // Quarter circle r = 10 about the origin in XY, turned by SPA 90 (Rx(90): y → z).
        let r = pm::spatial(90.0, 0.0, 0.0);
        let arc = OpKind::Arc {
            from: Pose::xyz(10.0, 0.0, 0.0),
            to: Pose::xyz(0.0, 10.0, 0.0),
            center: [0.0, 0.0],
            plane: Plane::XY,
            sweep: 90.0,
            feed: Feed::Rate(10.0),
        };
        let lines = tilt_kind(&r, &arc);
        // φ = 2·acos(1 − 0.001/10) ≈ 0.02828 rad: ⌈(π/2)/φ⌉ = 56 chords.
        assert_eq!(lines.len(), 56);
        for l in &lines {
            let OpKind::Line { from, to, .. } = l else {
                panic!("not a line: {l:?}")
            };
            for p in [from, to] {
                // On the circle x² + z² = 100 in the plane y = 0.
                assert!(p[AxisLetter::Y].abs() < 1e-12);
                assert!((p[AxisLetter::X].hypot(p[AxisLetter::Z]) - 10.0).abs() < 1e-9);
            }
        }
        let OpKind::Line { to, .. } = lines[55] else {
            panic!()
        };
        assert!((to[AxisLetter::Z] - 10.0).abs() < 1e-12);
    }
}
