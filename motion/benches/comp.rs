//! Cost per contour element of the radius-compensation stage: a long program of lines and
//! arcs with outside and inside corners, pushed through and drained.

use klar_interp::{AxisLetter, CompSide, Feed, Op, OpKind, Plane, Pose, SourceLoc};
use klar_motion::comp::Compensator;

fn main() {
    divan::main();
}

fn loc(line: u32) -> SourceLoc {
    SourceLoc {
        file: 0,
        line,
        col: 1,
        block: None,
    }
}

/// A zigzag of `n` elements: lines alternating with half-circle bumps, so every join is a
/// real corner (inside or outside depending on the side).
fn program(n: u32) -> Vec<Op> {
    let mut ops = vec![
        Op {
            kind: OpKind::ToolChange {
                tool: 1,
                name: None,
                axis: AxisLetter::Z,
                length: 50.0,
                radius: 1.0,
            },
            loc: loc(1),
        },
        Op {
            kind: OpKind::RadiusComp {
                side: CompSide::Left,
            },
            loc: loc(2),
        },
    ];
    let mut pos = Pose::xyz(0.0, -10.0, 0.0);
    let feed = Feed::Rate(20.0);
    for i in 0..n {
        let x = pos[AxisLetter::X];
        let line = 10 + i;
        if i % 2 == 0 {
            let to = Pose::xyz(x + 10.0, if i % 4 == 0 { 0.0 } else { 3.0 }, 0.0);
            ops.push(Op {
                kind: OpKind::Line {
                    from: pos,
                    to,
                    feed,
                },
                loc: loc(line),
            });
            pos = to;
        } else {
            let y = pos[AxisLetter::Y];
            let to = Pose::xyz(x + 8.0, y, 0.0);
            ops.push(Op {
                kind: OpKind::Arc {
                    from: pos,
                    to,
                    center: [x + 4.0, y],
                    plane: Plane::XY,
                    sweep: -180.0,
                    feed,
                },
                loc: loc(line),
            });
            pos = to;
        }
    }
    ops
}

/// Elements per run; divan reports the time per run, divide by this for the cost per element.
const ELEMENTS: u32 = 10_000;

#[divan::bench]
fn compensate_10k_elements(bencher: divan::Bencher) {
    let ops = program(ELEMENTS);
    bencher
        .counter(divan::counter::ItemsCount::new(ELEMENTS as usize))
        .bench_local(|| {
            let mut c = Compensator::new(Pose::xyz(0.0, -10.0, 0.0));
            let mut n = 0usize;
            for op in ops.iter().cloned() {
                if c.push(op).is_err() {
                    break;
                }
                while c.pop().is_some() {
                    n += 1;
                }
            }
            let _ = c.finish();
            while c.pop().is_some() {
                n += 1;
            }
            n
        });
}
