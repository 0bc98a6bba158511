//! APPR/DEP on the compensated path, checked against closed-form points and the tangency
//! conditions the manual states (the arc meets the line and the contour without a kink).

mod comp_support;

use comp_support::*;
use klar_interp::{ApproachShape, AxisLetter, CompSide, Feed, Op, OpKind, Plane, Pose};
use klar_motion::comp::CompError;

fn appr(line: u32, from: Pose, to: Pose, shape: ApproachShape, side: CompSide) -> Op {
    Op {
        kind: OpKind::Approach {
            from,
            to,
            shape,
            side,
            feed_to_aux: Feed::Rapid,
            feed: F,
            plane: Plane::XY,
            with_tool_axis: from[AxisLetter::Z] != to[AxisLetter::Z],
        },
        loc: at(line),
    }
}

fn dep(line: u32, from: Pose, to: Option<Pose>, shape: ApproachShape) -> Op {
    Op {
        kind: OpKind::Depart {
            from,
            to,
            shape,
            feed: F,
            plane: Plane::XY,
        },
        loc: at(line),
    }
}

/// APPR from (0,-20) to PA (10,0), then the contour (10,0) → (30,0) → (30,10), with `r`.
fn approach_case(shape: ApproachShape, side: CompSide, r: f64) -> Vec<Op> {
    let ps = p(0.0, -20.0);
    let ops = vec![
        tool_op(1, r),
        appr(2, ps, p(10.0, 0.0), shape, side),
        line_op(3, p(10.0, 0.0), p(30.0, 0.0)),
        line_op(4, p(30.0, 0.0), p(30.0, 10.0)),
    ];
    let out = run(ps, ops).expect("valid approach");
    assert_continuous(ps, &out);
    assert_arcs_consistent(&out);
    out
}

fn of_block(out: &[Op], line: u32) -> Vec<Op> {
    out.iter()
        .filter(|o| o.loc.line == line && o.kind.is_motion())
        .cloned()
        .collect()
}

#[test]
fn appr_lt_starts_len_before_pa_on_the_tangent() {
    let out = approach_case(ApproachShape::LineTangent { len: 5.0 }, CompSide::Left, 2.0);
    let a = of_block(&out, 2);
    assert_eq!(a.len(), 2);
    assert!(close(end_xy(&a[0]), [5.0, 2.0], 1e-12));
    assert!(matches!(
        a[0].kind,
        OpKind::Line {
            feed: Feed::Rapid,
            ..
        }
    ));
    assert!(close(end_xy(&a[1]), [10.0, 2.0], 1e-12));
    assert!(matches!(a[1].kind, OpKind::Line { feed, .. } if feed == F));
}

#[test]
fn appr_ln_starts_len_plus_tool_radius_out_on_the_normal() {
    let out = approach_case(ApproachShape::LineNormal { len: 5.0 }, CompSide::Left, 2.0);
    let a = of_block(&out, 2);
    assert!(close(end_xy(&a[0]), [10.0, 7.0], 1e-12));
    assert!(close(end_xy(&a[1]), [10.0, 2.0], 1e-12));
    let out = approach_case(ApproachShape::LineNormal { len: 5.0 }, CompSide::Right, 2.0);
    let a = of_block(&out, 2);
    assert!(close(end_xy(&a[0]), [10.0, -7.0], 1e-12));
    assert!(close(end_xy(&a[1]), [10.0, -2.0], 1e-12));
}

#[test]
fn appr_ct_turns_as_the_manual_table_says() {
    // (side, sign of R, expected rotation +1 = counter-clockwise)
    for (side, rs, turn) in [
        (CompSide::Left, 1.0, 1.0),
        (CompSide::Left, -1.0, -1.0),
        (CompSide::Right, 1.0, -1.0),
        (CompSide::Right, -1.0, 1.0),
    ] {
        let tool = 2.0;
        let shape = ApproachShape::CircleTangent {
            cca: 90.0,
            radius: 4.0 * rs,
        };
        let out = approach_case(shape, side, tool);
        let a = of_block(&out, 2);
        assert_eq!(a.len(), 2);
        let OpKind::Arc { center, sweep, .. } = &a[1].kind else {
            panic!("{:?}", a[1]);
        };
        let sgn = if side == CompSide::Left { 1.0 } else { -1.0 };
        let pa = [10.0, sgn * tool];
        // Ends in PA' tangent to +X: centre straight above or below PA' at 4 mm, on the
        // left of travel for a counter-clockwise arc.
        assert!(
            (sweep - turn * 90.0).abs() < 1e-9,
            "{side:?} R{rs}: {sweep}"
        );
        assert!(close(*center, [10.0, pa[1] + turn * 4.0], 1e-12));
        assert!(close(end_xy(&a[1]), pa, 1e-12));
        // PH: a quarter turn back from PA' about the centre.
        assert!(close(end_xy(&a[0]), [6.0, pa[1] + turn * 4.0], 1e-12));
    }
}

#[test]
fn appr_lct_of_the_manual_example_is_tangent_to_line_and_contour() {
    // 7 L X+40 Y+10 R0 FMAX / 8 APPR LCT X+10 Y+20 Z-10 R10 RR F100 / 9 L X+20 Y+35
    let tool = 5.0;
    let ps = p(40.0, 10.0);
    let pa = Pose::xyz(10.0, 20.0, -10.0);
    let first_end = Pose::xyz(20.0, 35.0, -10.0);
    let ops = vec![
        tool_op(1, tool),
        appr(
            8,
            ps,
            pa,
            ApproachShape::LineCircleTangent { radius: 10.0 },
            CompSide::Right,
        ),
        line_op(9, pa, first_end),
    ];
    let out = run(ps, ops).unwrap();
    assert_continuous(ps, &out);
    assert_arcs_consistent(&out);
    let a = of_block(&out, 8);
    assert_eq!(a.len(), 2);
    let (
        OpKind::Line { to: ph, .. },
        OpKind::Arc {
            center, sweep, to, ..
        },
    ) = (&a[0].kind, &a[1].kind)
    else {
        panic!("{a:?}");
    };
    // All axes reach PH together: Z is at depth there; the arc stays in the plane.
    assert_eq!(ph[AxisLetter::Z], -10.0);
    assert_eq!(to[AxisLetter::Z], -10.0);
    let t = {
        let (dx, dy) = (10.0, 15.0);
        let n = f64::hypot(dx, dy);
        [dx / n, dy / n]
    };
    // PA' is the contour point moved right of travel by the tool radius.
    let pa_c = [10.0 + tool * t[1], 20.0 - tool * t[0]];
    assert!(close(end_xy(&a[1]), pa_c, 1e-9));
    let c = *center;
    let phx = [ph[AxisLetter::X], ph[AxisLetter::Y]];
    let rad = |q: [f64; 2]| (q[0] - c[0]).hypot(q[1] - c[1]);
    assert!((rad(phx) - 10.0).abs() < 1e-9);
    assert!((rad(pa_c) - 10.0).abs() < 1e-9);
    // RR turns clockwise; tangent to the contour at PA': radius ⟂ t.
    assert!(*sweep < 0.0);
    let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
    assert!(dot([pa_c[0] - c[0], pa_c[1] - c[1]], t).abs() < 1e-9);
    // Clockwise travel at PA' heads along t.
    let u = [(pa_c[0] - c[0]) / 10.0, (pa_c[1] - c[1]) / 10.0];
    let cw_dir = [u[1], -u[0]];
    assert!(close(cw_dir, t, 1e-9));
    // Tangent to the line PS → PH at PH, travelling on in the same direction.
    let l = [phx[0] - 40.0, phx[1] - 10.0];
    let v = [(phx[0] - c[0]) / 10.0, (phx[1] - c[1]) / 10.0];
    assert!(dot(l, v).abs() < 1e-9);
    assert!(dot(l, [v[1], -v[0]]) > 0.0);
}

/// A contour (0,-10) → (30,0)... ending with the line (10,0) → (30,0) under `side`, then DEP.
fn depart_case(shape: ApproachShape, to: Option<Pose>, side: CompSide, r: f64) -> Vec<Op> {
    let start = p(10.0, -10.0);
    let ops = vec![
        tool_op(1, r),
        comp_op(2, side),
        line_op(3, start, p(10.0, 0.0)),
        line_op(4, p(10.0, 0.0), p(30.0, 0.0)),
        dep(5, p(30.0, 0.0), to, shape),
        line_op(6, p(0.0, 0.0), p(0.0, 50.0)),
    ];
    let out = run(start, ops).expect("valid departure");
    assert_continuous(start, &out);
    assert_arcs_consistent(&out);
    out
}

#[test]
fn dep_lt_of_the_manual_example_continues_the_tangent() {
    // 23 L Y+20 RR F100 / 24 DEP LT LEN12.5
    let tool = 3.0;
    let start = p(30.0, 0.0);
    let ops = vec![
        tool_op(1, tool),
        comp_op(22, CompSide::Right),
        line_op(23, start, p(30.0, 20.0)),
        dep(
            24,
            p(30.0, 20.0),
            None,
            ApproachShape::LineTangent { len: 12.5 },
        ),
    ];
    let out = run(start, ops).unwrap();
    let d = of_block(&out, 24);
    assert_eq!(d.len(), 1);
    assert!(close(start_xy(&d[0]), [33.0, 20.0], 1e-12));
    assert!(close(end_xy(&d[0]), [33.0, 32.5], 1e-12));
}

#[test]
fn dep_ln_leaves_len_out_on_the_normal() {
    let out = depart_case(
        ApproachShape::LineNormal { len: 5.0 },
        None,
        CompSide::Left,
        2.0,
    );
    let d = of_block(&out, 5);
    assert!(close(start_xy(&d[0]), [30.0, 2.0], 1e-12));
    assert!(close(end_xy(&d[0]), [30.0, 7.0], 1e-12));
    // The next block starts where the departure ended, without compensation.
    let next = of_block(&out, 6);
    assert!(close(start_xy(&next[0]), [30.0, 7.0], 1e-12));
    assert!(close(end_xy(&next[0]), [0.0, 50.0], 1e-12));
}

#[test]
fn dep_ct_turns_away_through_cca() {
    let out = depart_case(
        ApproachShape::CircleTangent {
            cca: 90.0,
            radius: 4.0,
        },
        None,
        CompSide::Left,
        2.0,
    );
    let d = of_block(&out, 5);
    let OpKind::Arc { center, sweep, .. } = &d[0].kind else {
        panic!("{d:?}")
    };
    assert!(close(*center, [30.0, 6.0], 1e-12));
    assert!((sweep - 90.0).abs() < 1e-9);
    assert!(close(end_xy(&d[0]), [34.0, 6.0], 1e-12));
}

#[test]
fn dep_lct_arc_then_tangent_line_to_the_programmed_end_point() {
    let pn = Pose::xyz(50.0, 20.0, 5.0);
    let out = depart_case(
        ApproachShape::LineCircleTangent { radius: 4.0 },
        Some(pn),
        CompSide::Left,
        2.0,
    );
    let d = of_block(&out, 5);
    assert_eq!(d.len(), 2);
    let OpKind::Arc {
        center, sweep, to, ..
    } = &d[0].kind
    else {
        panic!("{d:?}")
    };
    assert!(close(*center, [30.0, 6.0], 1e-12));
    assert!(*sweep > 0.0);
    assert_eq!(to[AxisLetter::Z], 0.0);
    let ph = [to[AxisLetter::X], to[AxisLetter::Y]];
    let v = [ph[0] - 30.0, ph[1] - 6.0];
    assert!((v[0].hypot(v[1]) - 4.0).abs() < 1e-9);
    let l = [50.0 - ph[0], 20.0 - ph[1]];
    assert!((l[0] * v[0] + l[1] * v[1]).abs() < 1e-9, "line not tangent");
    // Counter-clockwise travel at PH heads towards PN.
    assert!(l[0] * -v[1] + l[1] * v[0] > 0.0);
    let OpKind::Line { to: end, .. } = &d[1].kind else {
        panic!()
    };
    assert_eq!(*end, pn);
}

#[test]
fn appr_then_dep_contour_keeps_the_offset_everywhere_between() {
    let tool = 2.5;
    let ps = p(-20.0, -20.0);
    let ops = vec![
        tool_op(1, tool),
        appr(
            2,
            ps,
            p(0.0, 0.0),
            ApproachShape::LineCircleTangent { radius: 6.0 },
            CompSide::Right,
        ),
        line_op(3, p(0.0, 0.0), p(40.0, 0.0)),
        arc_op(4, p(40.0, 0.0), p(40.0, 20.0), [40.0, 10.0], 180.0),
        line_op(5, p(40.0, 20.0), p(0.0, 20.0)),
        dep(
            6,
            p(0.0, 20.0),
            None,
            ApproachShape::LineTangent { len: 5.0 },
        ),
        comp_op(7, CompSide::Off),
    ];
    let contour = pieces(&ops[2..5]);
    let out = run(ps, ops).unwrap();
    assert_continuous(ps, &out);
    let worst = worst_offset_error(&out, &contour, tool, |l| (3..=5).contains(&l));
    assert!(worst < 1e-6, "{worst}");
}

#[test]
fn lct_start_inside_its_circle_is_refused() {
    let ps = p(10.0, 3.0);
    let ops = vec![
        tool_op(1, 1.0),
        appr(
            2,
            ps,
            p(10.0, 0.0),
            ApproachShape::LineCircleTangent { radius: 5.0 },
            CompSide::Left,
        ),
        line_op(3, p(10.0, 0.0), p(30.0, 0.0)),
    ];
    match run(ps, ops) {
        Err(CompError::LctInsideCircle { loc, radius }) => {
            assert_eq!(loc.line, 2);
            assert_eq!(radius, 5.0);
        }
        r => panic!("{r:?}"),
    }
}

#[test]
fn appr_parameters_out_of_range_are_refused() {
    for shape in [
        ApproachShape::LineTangent { len: 0.0 },
        ApproachShape::LineNormal { len: -1.0 },
        ApproachShape::CircleTangent {
            cca: 0.0,
            radius: 3.0,
        },
        ApproachShape::CircleTangent {
            cca: 400.0,
            radius: 3.0,
        },
        ApproachShape::CircleTangent {
            cca: 90.0,
            radius: 0.0,
        },
        ApproachShape::LineCircleTangent { radius: -2.0 },
        ApproachShape::LineTangent { len: f64::NAN },
    ] {
        let ps = p(0.0, -20.0);
        let ops = vec![
            tool_op(1, 1.0),
            appr(2, ps, p(10.0, 0.0), shape, CompSide::Left),
            line_op(3, p(10.0, 0.0), p(30.0, 0.0)),
        ];
        let e = run(ps, ops).unwrap_err();
        assert!(
            matches!(
                e,
                CompError::BadApproach { .. } | CompError::NonFinite { .. }
            ),
            "{shape:?}: {e}"
        );
        assert!(e.to_string().contains("line 2"), "{e}");
    }
}

#[test]
fn appr_without_a_contour_element_is_reported_at_finish() {
    let ps = p(0.0, -20.0);
    let ops = vec![
        tool_op(1, 1.0),
        appr(
            2,
            ps,
            p(10.0, 0.0),
            ApproachShape::LineTangent { len: 3.0 },
            CompSide::Left,
        ),
    ];
    match run(ps, ops) {
        Err(CompError::ApproachWithoutContour { loc }) => assert_eq!(loc.line, 2),
        r => panic!("{r:?}"),
    }
}
