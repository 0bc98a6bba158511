//! Random contours of lines and arcs: the stage either refuses them as a contour violation,
//! or every point of its tool path lies at the tool radius from the contour (never farther,
//! never closer than the 1 µm gouge tolerance).

mod comp_support;

use comp_support::*;
use klar_interp::{CompSide, Op, Pose};
use klar_motion::comp::CompError;
use proptest::prelude::*;

/// One random contour element: turn of the heading before it (degrees), then a line of
/// `len` or an arc of radius `len` through `sweep` degrees.
#[derive(Debug, Clone, Copy)]
struct Step {
    turn: f64,
    len: f64,
    sweep: Option<f64>,
}

fn step() -> impl Strategy<Value = Step> {
    let turn = prop_oneof![2 => Just(0.0), 5 => -150.0..150.0f64];
    let sweep = prop_oneof![
        1 => Just(None),
        1 => (20.0..200.0f64, any::<bool>()).prop_map(|(s, neg)| Some(if neg { -s } else { s })),
    ];
    (turn, 3.0..30.0f64, sweep).prop_map(|(turn, len, sweep)| Step { turn, len, sweep })
}

/// The contour ops (blocks 10, 11, …) after a lead-in from (0, −15) to the origin.
fn contour(steps: &[Step], side: CompSide, tool: f64) -> Vec<Op> {
    let mut ops = vec![
        tool_op(1, tool),
        comp_op(2, side),
        line_op(3, p(0.0, -15.0), p(0.0, 0.0)),
    ];
    let (mut x, mut y, mut heading) = (0.0f64, 0.0f64, 0.0f64);
    for (i, s) in steps.iter().enumerate() {
        heading += s.turn.to_radians();
        let line = 10 + i as u32;
        let from = p(x, y);
        match s.sweep {
            None => {
                x += s.len * heading.cos();
                y += s.len * heading.sin();
                ops.push(line_op(line, from, p(x, y)));
            }
            Some(sw) => {
                // Centre on the left of travel for counter-clockwise arcs, right for clockwise.
                let side = sw.signum();
                let c = [
                    x - side * s.len * heading.sin(),
                    y + side * s.len * heading.cos(),
                ];
                let to = arc_end(from, c, sw);
                ops.push(arc_op(line, from, to, c, sw));
                x = to.0[0];
                y = to.0[1];
                heading += sw.to_radians();
            }
        }
    }
    ops
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn accepted_contours_keep_the_tool_radius_everywhere(
        steps in proptest::collection::vec(step(), 1..6),
        left in any::<bool>(),
        tool in 0.5..5.0f64,
    ) {
        let side = if left { CompSide::Left } else { CompSide::Right };
        let ops = contour(&steps, side, tool);
        let programmed = pieces(&ops[3..]);
        let start = p(0.0, -15.0);
        match run(start, ops) {
            Ok(out) => {
                assert_continuous(start, &out);
                assert_arcs_consistent(&out);
                // Every point is at most the tool radius from the contour (it lies on the
                // offset of its own block), and none comes closer than the stage's gouge
                // tolerance of 1 µm.
                let (lo, hi) = offset_range(&out, &programmed, tool, |l| l >= 10);
                prop_assert!(hi < 1e-6, "point {} mm beyond the offset in {:#?}", hi, out);
                prop_assert!(lo > -1e-3, "gouge of {} mm in {:#?}", -lo, out);
            }
            Err(e) => {
                let violation = matches!(
                    e,
                    CompError::ArcTooSmall { .. }
                        | CompError::NoIntersection { .. }
                        | CompError::RunsBackwards { .. }
                        | CompError::Gouge { .. }
                );
                prop_assert!(violation, "unexpected refusal: {}", e);
            }
        }
    }
}

#[test]
fn a_smooth_random_like_contour_is_accepted() {
    // Guards the property test against refusing everything: a gentle wave is accepted.
    let steps = [
        Step {
            turn: 0.0,
            len: 20.0,
            sweep: None,
        },
        Step {
            turn: 0.0,
            len: 10.0,
            sweep: Some(90.0),
        },
        Step {
            turn: -30.0,
            len: 15.0,
            sweep: None,
        },
        Step {
            turn: 0.0,
            len: 12.0,
            sweep: Some(-60.0),
        },
    ];
    for side in [CompSide::Left, CompSide::Right] {
        let ops = contour(&steps, side, 2.0);
        let programmed = pieces(&ops[3..]);
        let out = run(p(0.0, -15.0), ops).expect("accepted");
        let worst = worst_offset_error(&out, &programmed, 2.0, |l| l >= 10);
        assert!(worst < 1e-6);
    }
    let _ = Pose::ZERO;
}
