//! Bad input to the compensation stage: each case is refused with a diagnostic naming the
//! block, releases no motion for it, and nothing panics on arbitrary ops.

mod comp_support;

use comp_support::*;
use klar_interp::{ApproachShape, CompSide, Feed, Op, OpKind, Plane, Pose};
use klar_motion::comp::{CompError, Compensator};
use proptest::prelude::*;

fn refuse(start: Pose, ops: Vec<Op>) -> CompError {
    run(start, ops).expect_err("must be refused")
}

#[test]
fn rl_to_rr_without_r0_is_refused() {
    let e = refuse(
        p(0.0, -5.0),
        vec![
            tool_op(1, 1.0),
            comp_op(2, CompSide::Left),
            line_op(3, p(0.0, -5.0), p(0.0, 0.0)),
            line_op(4, p(0.0, 0.0), p(10.0, 0.0)),
            comp_op(5, CompSide::Right),
        ],
    );
    assert!(
        matches!(e, CompError::SideSwitch { loc } if loc.line == 5),
        "{e}"
    );
    assert!(e.to_string().contains("line 5"));
}

#[test]
fn rl_rr_through_r0_is_accepted() {
    let out = run(
        p(0.0, -5.0),
        vec![
            tool_op(1, 1.0),
            comp_op(2, CompSide::Left),
            line_op(3, p(0.0, -5.0), p(0.0, 0.0)),
            line_op(4, p(0.0, 0.0), p(10.0, 0.0)),
            comp_op(5, CompSide::Off),
            line_op(6, p(10.0, 0.0), p(10.0, -5.0)),
            comp_op(7, CompSide::Right),
            line_op(8, p(10.0, -5.0), p(10.0, 0.0)),
            line_op(9, p(10.0, 0.0), p(20.0, 0.0)),
        ],
    )
    .unwrap();
    let last = motions(&out).last().copied().cloned().unwrap();
    assert!(close(end_xy(&last), [20.0, -1.0], 1e-12));
}

#[test]
fn compensation_waits_for_the_first_move_in_the_plane() {
    // RL on a tool-axis move: the plunge runs as programmed, compensation starts with the
    // next straight line in the plane.
    let out = run(
        p(0.0, -5.0),
        vec![
            tool_op(1, 1.0),
            comp_op(2, CompSide::Left),
            line_op(3, p(0.0, -5.0), Pose::xyz(0.0, -5.0, -5.0)),
            line_op(4, Pose::xyz(0.0, -5.0, -5.0), Pose::xyz(0.0, 0.0, -5.0)),
            line_op(5, Pose::xyz(0.0, 0.0, -5.0), Pose::xyz(10.0, 0.0, -5.0)),
        ],
    )
    .unwrap();
    let m = motions(&out);
    assert_eq!(m.len(), 3);
    assert!(close(end_xy(m[0]), [0.0, -5.0], 1e-12));
    assert!(close(end_xy(m[1]), [0.0, 1.0], 1e-12));
    assert!(close(end_xy(m[2]), [10.0, 1.0], 1e-12));
}

#[test]
fn compensation_starting_on_an_arc_is_refused() {
    let e = refuse(
        p(10.0, 0.0),
        vec![
            tool_op(1, 1.0),
            comp_op(2, CompSide::Left),
            arc_op(3, p(10.0, 0.0), p(-10.0, 0.0), [0.0, 0.0], 180.0),
        ],
    );
    assert!(
        matches!(e, CompError::StartOnArc { loc } if loc.line == 3),
        "{e}"
    );
}

#[test]
fn dep_without_compensation_is_refused() {
    let e = refuse(
        p(0.0, 0.0),
        vec![Op {
            kind: OpKind::Depart {
                from: p(0.0, 0.0),
                to: None,
                shape: ApproachShape::LineTangent { len: 2.0 },
                feed: F,
                plane: Plane::XY,
            },
            loc: at(4),
        }],
    );
    assert!(
        matches!(e, CompError::DepartWithoutContour { loc } if loc.line == 4),
        "{e}"
    );
}

#[test]
fn spline_and_tool_change_while_compensating_are_refused() {
    let base = vec![
        tool_op(1, 1.0),
        comp_op(2, CompSide::Left),
        line_op(3, p(0.0, -5.0), p(0.0, 0.0)),
    ];
    let mut ops = base.clone();
    ops.push(spline_op(4, p(0.0, 0.0), p(5.0, 0.0)));
    let e = refuse(p(0.0, -5.0), ops);
    assert!(
        matches!(e, CompError::SplineCompensated { loc } if loc.line == 4),
        "{e}"
    );
    let mut ops = base;
    ops.push(tool_op(4, 2.0));
    let e = refuse(p(0.0, -5.0), ops);
    assert!(matches!(e, CompError::ToolChangeWhileCompensating { loc } if loc.line == 4));
}

#[test]
fn negative_effective_radius_and_non_finite_values_are_refused() {
    let e = refuse(
        p(0.0, 0.0),
        vec![tool_op(1, -0.5), comp_op(2, CompSide::Left)],
    );
    assert!(
        matches!(e, CompError::NegativeRadius { loc, .. } if loc.line == 2),
        "{e}"
    );
    let e = refuse(p(0.0, 0.0), vec![tool_op(1, f64::NAN)]);
    assert!(matches!(e, CompError::NonFinite { .. }), "{e}");
    let e = refuse(
        p(0.0, -5.0),
        vec![
            tool_op(1, 1.0),
            comp_op(2, CompSide::Left),
            line_op(3, p(0.0, -5.0), p(0.0, 0.0)),
            line_op(4, p(0.0, 0.0), p(f64::INFINITY, 0.0)),
        ],
    );
    assert!(
        matches!(e, CompError::NonFinite { loc, .. } if loc.line == 4),
        "{e}"
    );
}

#[test]
fn arc_right_after_r0_must_not_start_off_the_tool() {
    let e = refuse(
        p(0.0, -5.0),
        vec![
            tool_op(1, 1.0),
            comp_op(2, CompSide::Left),
            line_op(3, p(0.0, -5.0), p(0.0, 0.0)),
            line_op(4, p(0.0, 0.0), p(10.0, 0.0)),
            comp_op(5, CompSide::Off),
            arc_op(6, p(10.0, 0.0), p(-10.0, 0.0), [0.0, 0.0], 180.0),
        ],
    );
    assert!(
        matches!(e, CompError::CurveAfterCompensation { loc } if loc.line == 6),
        "{e}"
    );
}

#[test]
fn gap_between_compensated_blocks_is_refused() {
    let e = refuse(
        p(0.0, -5.0),
        vec![
            tool_op(1, 1.0),
            comp_op(2, CompSide::Left),
            line_op(3, p(0.0, -5.0), p(0.0, 0.0)),
            line_op(4, p(0.0, 0.0), p(10.0, 0.0)),
            line_op(5, p(11.0, 0.0), p(20.0, 0.0)),
        ],
    );
    assert!(matches!(e, CompError::Discontinuity { loc, gap } if loc.line == 5 && gap == 1.0));
}

#[test]
fn after_an_error_nothing_more_is_released() {
    let mut c = Compensator::new(p(0.0, -5.0));
    c.push(tool_op(1, 1.0)).unwrap();
    c.push(comp_op(2, CompSide::Left)).unwrap();
    c.push(line_op(3, p(0.0, -5.0), p(0.0, 0.0))).unwrap();
    assert!(c.push(comp_op(4, CompSide::Right)).is_err());
    assert!(c.pop().is_none());
    assert!(matches!(
        c.push(line_op(5, p(0.0, 0.0), p(1.0, 0.0))),
        Err(CompError::Stopped { .. })
    ));
    assert!(!c.needs_input());
}

fn any_pose() -> impl Strategy<Value = Pose> {
    let v = prop_oneof![
        8 => -50.0..50.0f64,
        1 => Just(f64::NAN),
        1 => Just(0.0),
    ];
    (v.clone(), v.clone(), v).prop_map(|(x, y, z)| Pose::xyz(x, y, z))
}

fn any_op() -> impl Strategy<Value = Op> {
    let side = prop_oneof![
        Just(CompSide::Off),
        Just(CompSide::Left),
        Just(CompSide::Right)
    ];
    let shape = prop_oneof![
        (-5.0..20.0f64).prop_map(|len| ApproachShape::LineTangent { len }),
        (-5.0..20.0f64).prop_map(|len| ApproachShape::LineNormal { len }),
        (-10.0..400.0f64, -10.0..10.0f64)
            .prop_map(|(cca, radius)| ApproachShape::CircleTangent { cca, radius }),
        (-10.0..20.0f64).prop_map(|radius| ApproachShape::LineCircleTangent { radius }),
    ];
    prop_oneof![
        (any_pose(), any_pose()).prop_map(|(a, b)| line_op(1, a, b)),
        (any_pose(), -50.0..50.0f64, -50.0..50.0f64, -720.0..720.0f64)
            .prop_map(|(a, cx, cy, s)| arc_op(2, a, arc_end(a, [cx, cy], s), [cx, cy], s)),
        side.clone().prop_map(|s| comp_op(3, s)),
        (-2.0..10.0f64).prop_map(|r| tool_op(4, r)),
        (any_pose(), any_pose(), shape.clone(), side).prop_map(|(a, b, sh, s)| Op {
            kind: OpKind::Approach {
                from: a,
                to: b,
                shape: sh,
                side: s,
                feed_to_aux: Feed::Rapid,
                feed: F,
                plane: Plane::XY,
                with_tool_axis: false,
            },
            loc: at(5),
        }),
        (any_pose(), proptest::option::of(any_pose()), shape).prop_map(|(a, b, sh)| Op {
            kind: OpKind::Depart {
                from: a,
                to: b,
                shape: sh,
                feed: F,
                plane: Plane::XY,
            },
            loc: at(6),
        }),
        Just(Op {
            kind: OpKind::Coolant { on: true },
            loc: at(7)
        }),
    ]
}

proptest! {
    /// Arbitrary op sequences never panic, and whatever is released is one continuous path
    /// of lines and arcs (no APPR/DEP left unresolved).
    #[test]
    fn arbitrary_ops_never_panic(ops in proptest::collection::vec(any_op(), 0..40)) {
        let start = p(0.0, 0.0);
        let mut c = Compensator::new(start);
        let mut out = Vec::new();
        for op in ops {
            if c.push(op).is_err() {
                break;
            }
            while let Some(o) = c.pop() {
                out.push(o);
            }
        }
        let _ = c.finish();
        while let Some(o) = c.pop() {
            out.push(o);
        }
        for o in &out {
            let unresolved = matches!(o.kind, OpKind::Approach { .. } | OpKind::Depart { .. });
            prop_assert!(!unresolved, "unresolved op {:?}", o);
        }
    }

    /// Convex polygons (vertices on a circle) compensated on the outside: every sample of the
    /// tool path around the polygon lies at exactly the tool radius from it.
    #[test]
    fn convex_polygon_outside_keeps_the_tool_radius(
        mut angles in proptest::collection::vec(0.0..std::f64::consts::TAU, 3..9),
        size in 5.0..60.0f64,
        tool in 0.1..8.0f64,
    ) {
        angles.sort_by(f64::total_cmp);
        angles.dedup_by(|a, b| (*a - *b).abs() < 0.05);
        prop_assume!(angles.len() >= 3);
        prop_assume!(std::f64::consts::TAU - (angles[angles.len() - 1] - angles[0]) > 0.05);
        let v: Vec<Pose> = angles.iter().map(|a| p(size * a.cos(), size * a.sin())).collect();
        // Start in the middle of the first edge, go round, come back to it.
        let mid = |a: Pose, b: Pose| p((a.0[0] + b.0[0]) / 2.0, (a.0[1] + b.0[1]) / 2.0);
        let m = mid(v[0], v[1]);
        let start = p(0.0, 0.0);
        let mut ops = vec![tool_op(1, tool), comp_op(2, CompSide::Right), line_op(3, start, m)];
        let mut prev = m;
        let mut line = 10;
        for q in v.iter().skip(1).chain(v.iter().take(1)) {
            ops.push(line_op(line, prev, *q));
            prev = *q;
            line += 1;
        }
        ops.push(line_op(line, prev, m));
        let contour = pieces(&ops[3..]);
        let out = run(start, ops).unwrap();
        assert_continuous(start, &out);
        assert_arcs_consistent(&out);
        let worst = worst_offset_error(&out, &contour, tool, |l| l >= 10);
        prop_assert!(worst < 1e-6, "offset error {}", worst);
    }
}

#[test]
fn curves_without_compensation_pass_through_from_the_tool_position() {
    let out = run(
        p(10.0, 0.0),
        vec![
            arc_op(1, p(10.0, 0.0), p(-10.0, 0.0), [0.0, 0.0], 180.0),
            spline_op(2, p(-10.0, 0.0), p(-5.0, 0.0)),
        ],
    )
    .unwrap();
    assert_continuous(p(10.0, 0.0), &out);
    assert_eq!(motions(&out).len(), 2);
    let e = refuse(
        p(10.0, 0.0),
        vec![arc_op(
            1,
            p(10.0, f64::NAN),
            p(-10.0, 0.0),
            [0.0, 0.0],
            180.0,
        )],
    );
    assert!(
        matches!(e, CompError::CurveAfterCompensation { loc } if loc.line == 1),
        "{e}"
    );
}
