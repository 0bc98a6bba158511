//! Tests of 202 BORING and 204 BACK BORING against sequences written from the manual's
//! description, with the positions and feeds worked out by hand.

use super::testutil::{Defs, assert_no_rapid_into_material, ctx_at, qs, with, without};
use crate::cycles::{CycleContext, CycleError, CycleFeed, Move, generate};
use crate::op::SpindleDir::{self, Ccw, Cw, Off};

use CycleFeed::{Rapid, Rate};

fn run(n: u32, d: &Defs, ctx: &CycleContext) -> Result<Vec<Move>, CycleError> {
    let mut out = Vec::new();
    generate(n, d, ctx, &mut out)?;
    Ok(out)
}

fn line(a: f64, b: f64, t: f64, feed: CycleFeed) -> Move {
    Move::Line {
        to: [a, b, t],
        feed,
    }
}

fn turning(ctx: CycleContext, spindle: SpindleDir) -> CycleContext {
    CycleContext { spindle, ..ctx }
}

fn d202() -> Defs {
    qs(&[
        (200, 2.0),
        (201, -15.0),
        (206, 120.0),
        (211, 0.5),
        (208, 300.0),
        (203, 0.0),
        (204, 30.0),
        (214, 1.0),
        (336, 0.0),
    ])
}

#[test]
fn boring_202_orients_disengages_retracts_and_restores_the_spindle() {
    let ctx = ctx_at([10.0, 20.0, 50.0]);
    let m = run(202, &d202(), &ctx).unwrap();
    // Q206 = 120 mm/min = 2 mm/s, Q208 = 300 mm/min = 5 mm/s; Q214 = 1: 0.2 mm towards -X
    let expected = vec![
        line(10.0, 20.0, 2.0, Rapid),
        line(10.0, 20.0, -15.0, Rate(2.0)),
        Move::Dwell(0.5),
        Move::Spindle(Off),
        line(9.8, 20.0, -15.0, Rate(5.0)),
        line(9.8, 20.0, 2.0, Rate(5.0)),
        line(10.0, 20.0, 2.0, Rapid),
        Move::Spindle(Cw),
        line(10.0, 20.0, 30.0, Rapid),
    ];
    assert_eq!(m, expected);
    assert_no_rapid_into_material(&m, ctx.pos, -1.0, |_, _| 2.0, |_, _| 2.0);
}

#[test]
fn boring_202_each_disengaging_direction_moves_its_axis_by_its_sign() {
    let ctx = ctx_at([10.0, 20.0, 50.0]);
    // 1: -reference axis, 2: -minor axis, 3: +reference axis, 4: +minor axis
    let want = [
        (1.0, [9.8, 20.0]),
        (2.0, [10.0, 19.8]),
        (3.0, [10.2, 20.0]),
        (4.0, [10.0, 20.2]),
    ];
    for (q214, [a, b]) in want {
        let m = run(202, &with(&d202(), 214, q214), &ctx).unwrap();
        let Move::Line { to, feed } = m[4] else {
            panic!("Q214={q214}: {m:?}");
        };
        assert!(
            (to[0] - a).abs() < 1e-12 && (to[1] - b).abs() < 1e-12,
            "Q214={q214}: {to:?}"
        );
        assert_eq!((to[2], feed), (-15.0, Rate(5.0)), "Q214={q214}");
        // out of the hole on the offset axis, then back to the centre at the clearance
        assert_eq!(m[5], line(a, b, 2.0, Rate(5.0)));
        assert_eq!(m[6], line(10.0, 20.0, 2.0, Rapid));
    }
    // 0: no sideways move; the tool leaves on the axis of the hole
    let m = run(202, &with(&d202(), 214, 0.0), &ctx).unwrap();
    assert_eq!(
        m[3..],
        [
            Move::Spindle(Off),
            line(10.0, 20.0, 2.0, Rate(5.0)),
            Move::Spindle(Cw),
            line(10.0, 20.0, 30.0, Rapid),
        ]
    );
}

#[test]
fn boring_202_retraction_feed_and_spindle_of_the_call() {
    let ctx = ctx_at([0.0, 0.0, 50.0]);
    // Q208 absent or 0: retract (and disengage) at the plunging feed; FMAX: rapid
    for d in [without(&d202(), 208), with(&d202(), 208, 0.0)] {
        let m = run(202, &d, &ctx).unwrap();
        assert_eq!(m[4], line(-0.2, 0.0, -15.0, Rate(2.0)));
        assert_eq!(m[5], line(-0.2, 0.0, 2.0, Rate(2.0)));
    }
    let m = run(202, &with(&d202(), 208, f64::INFINITY), &ctx).unwrap();
    assert_eq!(m[5], line(-0.2, 0.0, 2.0, Rapid));
    // M4 at the call comes back as M4; a stopped spindle gets no spindle moves at all
    let m = run(202, &d202(), &turning(ctx, Ccw)).unwrap();
    assert_eq!((m[3], m[7]), (Move::Spindle(Off), Move::Spindle(Ccw)));
    let m = run(202, &d202(), &turning(ctx, Off)).unwrap();
    assert!(!m.iter().any(|m| matches!(m, Move::Spindle(_))), "{m:?}");
    assert_eq!(m.len(), 7);
    // depth 0: nothing
    assert_eq!(run(202, &with(&d202(), 201, 0.0), &ctx).unwrap(), vec![]);
}

fn d204() -> Defs {
    qs(&[
        (200, 2.0),
        (249, 5.0),
        (250, 20.0),
        (251, 3.5),
        (252, 15.0),
        (253, 750.0),
        (254, 200.0),
        (255, 0.5),
        (203, 0.0),
        (204, 50.0),
        (214, 1.0),
        (336, 0.0),
    ])
}

#[test]
fn back_boring_204_sequence_from_the_manual() {
    let ctx = ctx_at([0.0, 0.0, 60.0]);
    let m = run(204, &d204(), &ctx).unwrap();
    // surface 0, far face 20 below at -20. Through the hole until the edge (15 above the
    // tool tip) is the set-up clearance 2 below the far face: edge -22, tip -37.
    // Counterbore 5 deep from the far face: edge -15, tip -30.
    // Q253 = 750 mm/min = 12.5 mm/s, Q254 = 200 mm/min.
    let pre = Rate(12.5);
    let expected = vec![
        line(0.0, 0.0, 2.0, Rapid),
        Move::Spindle(Off),
        line(-3.5, 0.0, 2.0, Rapid),
        line(-3.5, 0.0, -37.0, pre),
        line(0.0, 0.0, -37.0, pre),
        Move::Spindle(Cw),
        line(0.0, 0.0, -30.0, Rate(200.0 / 60.0)),
        Move::Dwell(0.5),
        Move::Spindle(Off),
        line(-3.5, 0.0, -30.0, pre),
        line(-3.5, 0.0, 2.0, pre),
        line(0.0, 0.0, 2.0, Rapid),
        Move::Spindle(Cw),
        line(0.0, 0.0, 50.0, Rapid),
    ];
    assert_eq!(m, expected);
    assert_no_rapid_into_material(&m, ctx.pos, -1.0, |_, _| 2.0, |_, _| 2.0);
}

#[test]
fn back_boring_204_directions_mirroring_and_a_stopped_spindle() {
    let ctx = ctx_at([0.0, 0.0, 60.0]);
    let want = [
        (1.0, [-3.5, 0.0]),
        (2.0, [0.0, -3.5]),
        (3.0, [3.5, 0.0]),
        (4.0, [0.0, 3.5]),
    ];
    for (q214, [a, b]) in want {
        let m = run(204, &with(&d204(), 214, q214), &ctx).unwrap();
        assert_eq!(m[2], line(a, b, 2.0, Rapid), "Q214={q214}");
        assert_eq!(m[9], line(a, b, -30.0, Rate(12.5)), "Q214={q214}");
    }
    // Q249 < 0 cuts towards -t: everything mirrored about the surface Q203 = 10
    let d = with(&with(&d204(), 249, -5.0), 203, 10.0);
    let m = run(204, &d, &ctx_at([0.0, 0.0, -60.0])).unwrap();
    let ts: Vec<f64> = m
        .iter()
        .filter_map(|m| match m {
            Move::Line { to, .. } => Some(to[2]),
            _ => None,
        })
        .collect();
    // safe 10 - 2 = 8; far face 30; through: 30 + 2 + 15 = 47; counterbore 30 - 5 + 15 = 40;
    // end at 10 - 50 = -40
    assert_eq!(ts, vec![8.0, 8.0, 47.0, 47.0, 40.0, 40.0, 8.0, 8.0, -40.0]);
    // a stopped spindle at the call: M3 for the counterbore, stopped again at the end
    let m = run(204, &d204(), &turning(ctx_at([0.0, 0.0, 60.0]), Off)).unwrap();
    let spindle: Vec<Move> = m
        .iter()
        .copied()
        .filter(|m| matches!(m, Move::Spindle(_)))
        .collect();
    assert_eq!(spindle, vec![Move::Spindle(Cw), Move::Spindle(Off)]);
    // FMAX for pre-positioning
    let m = run(204, &with(&d204(), 253, f64::INFINITY), &ctx).unwrap();
    assert_eq!(m[3], line(-3.5, 0.0, -37.0, Rapid));
}

#[test]
fn boring_range_errors_name_the_parameter_and_leave_output_alone() {
    let ctx = ctx_at([0.0, 0.0, 60.0]);
    let cases: Vec<(u32, Defs, &str)> = vec![
        (202, with(&d202(), 214, 5.0), "Q214"),
        (202, with(&d202(), 214, -1.0), "Q214"),
        (202, with(&d202(), 214, 1.5), "Q214"),
        (202, with(&d202(), 336, 361.0), "Q336"),
        (202, with(&d202(), 208, -1.0), "Q208"),
        (202, with(&d202(), 206, 0.0), "Q206"),
        (204, with(&d204(), 214, 0.0), "Q214"),
        (204, with(&d204(), 214, 5.0), "Q214"),
        (204, with(&d204(), 249, 0.0), "Q249"),
        (204, with(&d204(), 250, 0.0), "Q250"),
        (204, with(&d204(), 251, 0.0), "Q251"),
        (204, with(&d204(), 252, -1.0), "Q252"),
        (204, with(&d204(), 253, 0.0), "Q253"),
        (204, with(&d204(), 254, 0.0), "Q254"),
        (204, with(&d204(), 255, -0.5), "Q255"),
        (204, with(&d204(), 336, -1.0), "Q336"),
        (204, with(&d204(), 200, -2.0), "Q200"),
    ];
    for (n, d, param) in cases {
        let mut out = vec![Move::Dwell(9.0)];
        match generate(n, &d, &ctx, &mut out) {
            Err(CycleError::OutOfRange {
                cycle, param: p, ..
            }) => {
                assert_eq!((cycle, p.as_str()), (n, param));
            }
            other => panic!("{n} {param}: {other:?}"),
        }
        assert_eq!(out, vec![Move::Dwell(9.0)]);
    }
    let e = run(204, &with(&d204(), 214, 0.0), &ctx).unwrap_err();
    assert_eq!(
        e.to_string(),
        "cycle 204: Q214 = 0 is out of range (1 (-ref. axis), 2 (-minor axis), 3 (+ref. axis), 4 (+minor axis))"
    );
    // a counterbore as deep as the material is not a counterbore
    let r = run(204, &with(&d204(), 249, -20.0), &ctx);
    assert!(
        matches!(r, Err(CycleError::Geometry { cycle: 204, .. })),
        "{r:?}"
    );
    for (n, d, q) in [
        (202, without(&d202(), 214), "Q214"),
        (204, without(&d204(), 253), "Q253"),
    ] {
        let r = run(n, &d, &ctx);
        assert!(
            matches!(r, Err(CycleError::Missing { cycle, ref param, .. }) if cycle == n && param == q),
            "{r:?}"
        );
    }
}
