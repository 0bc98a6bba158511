//! Shared helpers of the radius-compensation tests: building ops, running the stage, and an
//! independent geometry (dense sampling, point-to-contour distance) to check its output.

#![allow(dead_code)]

use klar_interp::{AxisLetter, CompSide, Feed, Op, OpKind, Plane, Pose, SourceLoc, SplineAxis};
use klar_motion::comp::{CompError, Compensator};
use std::f64::consts::TAU;

/// A source location on `line`.
pub fn at(line: u32) -> SourceLoc {
    SourceLoc {
        file: 0,
        line,
        col: 1,
        block: Some(u64::from(line)),
    }
}

/// Feed used by the tests (mm/s).
pub const F: Feed = Feed::Rate(10.0);

pub fn p(x: f64, y: f64) -> Pose {
    Pose::xyz(x, y, 0.0)
}

pub fn line_op(line: u32, from: Pose, to: Pose) -> Op {
    Op {
        kind: OpKind::Line { from, to, feed: F },
        loc: at(line),
    }
}

pub fn arc_op(line: u32, from: Pose, to: Pose, c: [f64; 2], sweep: f64) -> Op {
    Op {
        kind: OpKind::Arc {
            from,
            to,
            center: c,
            plane: Plane::XY,
            sweep,
            feed: F,
        },
        loc: at(line),
    }
}

pub fn comp_op(line: u32, side: CompSide) -> Op {
    Op {
        kind: OpKind::RadiusComp { side },
        loc: at(line),
    }
}

pub fn tool_op(line: u32, radius: f64) -> Op {
    Op {
        kind: OpKind::ToolChange {
            tool: 1,
            name: None,
            axis: AxisLetter::Z,
            length: 50.0,
            radius,
        },
        loc: at(line),
    }
}

pub fn spline_op(line: u32, from: Pose, to: Pose) -> Op {
    Op {
        kind: OpKind::Spline {
            from,
            to,
            axes: vec![SplineAxis {
                axis: AxisLetter::X,
                k: [0.0, 0.0, from[AxisLetter::X] - to[AxisLetter::X]],
            }],
            feed: F,
        },
        loc: at(line),
    }
}

/// End point of an arc about `c` starting at `from` after `sweep` degrees (same Z).
pub fn arc_end(from: Pose, c: [f64; 2], sweep: f64) -> Pose {
    let (dx, dy) = (from[AxisLetter::X] - c[0], from[AxisLetter::Y] - c[1]);
    let (s, co) = sweep.to_radians().sin_cos();
    let mut to = from;
    to[AxisLetter::X] = c[0] + co * dx - s * dy;
    to[AxisLetter::Y] = c[1] + s * dx + co * dy;
    to
}

/// Pushes all ops, finishes, and collects everything popped.
pub fn run(start: Pose, ops: Vec<Op>) -> Result<Vec<Op>, CompError> {
    let mut c = Compensator::new(start);
    let mut out = Vec::new();
    for op in ops {
        c.push(op)?;
        while let Some(o) = c.pop() {
            out.push(o);
        }
    }
    c.finish()?;
    while let Some(o) = c.pop() {
        out.push(o);
    }
    Ok(out)
}

/// A programmed contour made of its motion ops, built from closed-form pieces.
#[derive(Clone, Debug)]
pub enum Piece {
    /// Segment between two points.
    Seg([f64; 2], [f64; 2]),
    /// Arc: centre, radius, start angle (rad), signed sweep (rad).
    Arc([f64; 2], f64, f64, f64),
}

/// The in-plane pieces of programmed line/arc ops.
pub fn pieces(ops: &[Op]) -> Vec<Piece> {
    ops.iter()
        .filter_map(|op| match &op.kind {
            OpKind::Line { from, to, .. } => Some(Piece::Seg(
                [from[AxisLetter::X], from[AxisLetter::Y]],
                [to[AxisLetter::X], to[AxisLetter::Y]],
            )),
            OpKind::Arc {
                from,
                center,
                sweep,
                ..
            } => {
                let dx = from[AxisLetter::X] - center[0];
                let dy = from[AxisLetter::Y] - center[1];
                Some(Piece::Arc(
                    *center,
                    dx.hypot(dy),
                    dy.atan2(dx),
                    sweep.to_radians(),
                ))
            }
            _ => None,
        })
        .collect()
}

fn seg_dist(q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (vx, vy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = vx * vx + vy * vy;
    let t = if len2 == 0.0 {
        0.0
    } else {
        (((q[0] - a[0]) * vx + (q[1] - a[1]) * vy) / len2).clamp(0.0, 1.0)
    };
    (q[0] - a[0] - t * vx).hypot(q[1] - a[1] - t * vy)
}

/// Distance from a point to one piece.
pub fn piece_dist(q: [f64; 2], pc: &Piece) -> f64 {
    match *pc {
        Piece::Seg(a, b) => seg_dist(q, a, b),
        Piece::Arc(c, r, phi0, sweep) => {
            let ang = (q[1] - c[1]).atan2(q[0] - c[0]);
            let along = ((ang - phi0) * sweep.signum()).rem_euclid(TAU);
            let inside = sweep.abs() >= TAU || along <= sweep.abs();
            if inside {
                ((q[0] - c[0]).hypot(q[1] - c[1]) - r).abs()
            } else {
                let e0 = [c[0] + r * phi0.cos(), c[1] + r * phi0.sin()];
                let pe = phi0 + sweep;
                let e1 = [c[0] + r * pe.cos(), c[1] + r * pe.sin()];
                (q[0] - e0[0])
                    .hypot(q[1] - e0[1])
                    .min((q[0] - e1[0]).hypot(q[1] - e1[1]))
            }
        }
    }
}

/// Distance from a point to the whole contour.
pub fn contour_dist(q: [f64; 2], contour: &[Piece]) -> f64 {
    contour
        .iter()
        .map(|pc| piece_dist(q, pc))
        .fold(f64::INFINITY, f64::min)
}

/// Dense samples (x, y, full pose) along a compensated line/arc op, ends included.
pub fn sample(op: &Op, n: usize) -> Vec<Pose> {
    match &op.kind {
        OpKind::Line { from, to, .. } => (0..=n)
            .map(|i| {
                let u = i as f64 / n as f64;
                let mut p = *from;
                for k in 0..9 {
                    p.0[k] = from.0[k] + (to.0[k] - from.0[k]) * u;
                }
                p
            })
            .collect(),
        OpKind::Arc {
            from,
            to,
            center,
            sweep,
            ..
        } => {
            let dx = from[AxisLetter::X] - center[0];
            let dy = from[AxisLetter::Y] - center[1];
            let r = dx.hypot(dy);
            let a0 = dy.atan2(dx);
            (0..=n)
                .map(|i| {
                    let u = i as f64 / n as f64;
                    let a = a0 + sweep.to_radians() * u;
                    let mut p = *from;
                    for k in 0..9 {
                        p.0[k] = from.0[k] + (to.0[k] - from.0[k]) * u;
                    }
                    p[AxisLetter::X] = center[0] + r * a.cos();
                    p[AxisLetter::Y] = center[1] + r * a.sin();
                    p
                })
                .collect()
        }
        _ => Vec::new(),
    }
}

/// The largest deviation of |distance to contour − r| over dense samples of the motion ops
/// whose source line satisfies `keep`.
pub fn worst_offset_error(
    out: &[Op],
    contour: &[Piece],
    r: f64,
    keep: impl Fn(u32) -> bool,
) -> f64 {
    let mut worst: f64 = 0.0;
    for op in out.iter().filter(|o| keep(o.loc.line)) {
        for q in sample(op, 200) {
            let d = contour_dist([q[AxisLetter::X], q[AxisLetter::Y]], contour);
            worst = worst.max((d - r).abs());
        }
    }
    worst
}

/// The range (lowest, highest) of distance-to-contour − r over dense samples of the motion
/// ops whose source line satisfies `keep`.
pub fn offset_range(
    out: &[Op],
    contour: &[Piece],
    r: f64,
    keep: impl Fn(u32) -> bool,
) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for op in out.iter().filter(|o| keep(o.loc.line)) {
        for q in sample(op, 200) {
            let d = contour_dist([q[AxisLetter::X], q[AxisLetter::Y]], contour) - r;
            lo = lo.min(d);
            hi = hi.max(d);
        }
    }
    (lo, hi)
}

/// Checks the output is one continuous path: each motion op starts exactly where the
/// previous one ended, from `start`.
pub fn assert_continuous(start: Pose, out: &[Op]) {
    let mut pos = start;
    for op in out {
        match &op.kind {
            OpKind::Line { from, to, .. }
            | OpKind::Arc { from, to, .. }
            | OpKind::Spline { from, to, .. } => {
                assert_eq!(*from, pos, "op {op:?} does not start at the tool position");
                pos = *to;
            }
            OpKind::Approach { .. } | OpKind::Depart { .. } => {
                panic!("unresolved APPR/DEP in the output: {op:?}")
            }
            _ => {}
        }
    }
}

/// Checks that every arc op ends on its circle at its sweep (as the planner requires).
pub fn assert_arcs_consistent(out: &[Op]) {
    for op in out {
        if let OpKind::Arc {
            from,
            to,
            center,
            sweep,
            ..
        } = &op.kind
        {
            let e = arc_end(*from, *center, *sweep);
            let dev =
                (e[AxisLetter::X] - to[AxisLetter::X]).hypot(e[AxisLetter::Y] - to[AxisLetter::Y]);
            assert!(dev < 1e-9, "arc {op:?} ends {dev} mm off its circle");
        }
    }
}

/// The motion ops (lines and arcs) of an output.
pub fn motions(out: &[Op]) -> Vec<&Op> {
    out.iter().filter(|o| o.kind.is_motion()).collect()
}

/// In-plane end point of a motion op.
pub fn end_xy(op: &Op) -> [f64; 2] {
    match &op.kind {
        OpKind::Line { to, .. } | OpKind::Arc { to, .. } => [to[AxisLetter::X], to[AxisLetter::Y]],
        _ => [f64::NAN, f64::NAN],
    }
}

/// In-plane start point of a motion op.
pub fn start_xy(op: &Op) -> [f64; 2] {
    match &op.kind {
        OpKind::Line { from, .. } | OpKind::Arc { from, .. } => {
            [from[AxisLetter::X], from[AxisLetter::Y]]
        }
        _ => [f64::NAN, f64::NAN],
    }
}

pub fn close(a: [f64; 2], b: [f64; 2], tol: f64) -> bool {
    (a[0] - b[0]).hypot(a[1] - b[1]) <= tol
}
