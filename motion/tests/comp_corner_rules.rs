//! M97 (small contour steps) and M98 (open contour corners) on the compensated path,
//! interpreted from Klartext and checked against tool-centre points worked out by hand from
//! the rules: M97 extends the offset lines at an outside corner to their intersection, M98
//! runs both offsets to their full ends at an inside corner and joins them straight.

use klar_interp::{CornerRule, Interpreter, Op, OpKind, Pose};
use klar_motion::comp::{CompError, Compensator};

fn ops_of(text: &str) -> Vec<Op> {
    Interpreter::from_source("test.h", text, Pose::ZERO)
        .collect::<Result<Vec<_>, _>>()
        .expect("program runs")
}

fn compensate(ops: &[Op]) -> Result<Vec<Op>, CompError> {
    let mut c = Compensator::new(Pose::ZERO);
    let mut out = Vec::new();
    for op in ops {
        c.push(op.clone())?;
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

/// End points (X, Y) of the motion ops at depth Z-5, in order.
fn path_at_depth(out: &[Op]) -> Vec<[f64; 2]> {
    out.iter()
        .filter_map(|op| match &op.kind {
            OpKind::Line { to, .. } | OpKind::Arc { to, .. } if (to.0[2] + 5.0).abs() < 1e-9 => {
                Some([to.0[0], to.0[1]])
            }
            _ => None,
        })
        .collect()
}

fn assert_points(got: &[[f64; 2]], want: &[[f64; 2]]) {
    assert_eq!(got.len(), want.len(), "got {got:?}\nwant {want:?}");
    for (g, w) in got.iter().zip(want) {
        assert!(
            (g[0] - w[0]).abs() < 1e-9 && (g[1] - w[1]).abs() < 1e-9,
            "got {got:?}\nwant {want:?}"
        );
    }
}

/// Distance from `p` to the segment a–b.
fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
    ((p[0] - a[0] - t * dx).powi(2) + (p[1] - a[1] - t * dy).powi(2)).sqrt()
}

/// Contour steps of 5 mm and 2 mm, smaller than the tool radius 8 (tool Ø16), cut with RL.
fn steps(m97: &str) -> String {
    format!(
        "0 BEGIN PGM STEPS MM
1 TOOL CALL 1 Z S3000 DR+8
2 L X-20 Y+50 Z+10 R0 FMAX
3 L Z-5 F300
4 L X+0 Y+30 RL F600
5 L X+10 {m97}
6 L Y+25
7 L X+50 {m97}
8 L Y+23
9 L X+100
10 L X+110 Y+50 R0
11 END PGM STEPS MM
"
    )
}

#[test]
fn m97_reaches_the_compensation_as_a_corner_rule_before_its_block_motion() {
    let ops = ops_of(&steps("M97"));
    let i = ops
        .iter()
        .position(|o| {
            matches!(
                o.kind,
                OpKind::CornerRule {
                    rule: CornerRule::Intersect
                }
            )
        })
        .expect("a corner rule op");
    assert_eq!(ops[i].loc.line, 6);
    assert!(matches!(ops[i + 1].kind, OpKind::Line { .. }));
    assert_eq!(ops[i + 1].loc.line, 6);
}

#[test]
fn small_steps_without_m97_are_refused_and_with_m97_pass_on_the_intersections() {
    // Without M97: the transition arc around (10, 30) ends at (18, 30), but the next inside
    // corner lies at y = 25 + 8 = 33 — the element would run backwards.
    let err = compensate(&ops_of(&steps(""))).expect_err("contour violation");
    assert!(
        matches!(
            err,
            CompError::RunsBackwards { .. } | CompError::Gouge { .. }
        ),
        "{err}"
    );

    let out = compensate(&ops_of(&steps("M97"))).expect("M97 passes the steps");
    // Offsets (tool on the left): y = 38, x = 18, y = 33, x = 58, y = 31. Outside corners
    // with M97 at the intersections of the extended offsets, inside corners as always.
    let want = [
        [-20.0, 50.0], // the plunge
        [0.0, 38.0],   // lead-in: perpendicular to the first element
        [18.0, 38.0],  // M97 at (10, 30): y = 38 meets x = 18
        [18.0, 33.0],  // inside corner at (10, 25)
        [58.0, 33.0],  // M97 at (50, 25): y = 33 meets x = 58
        [58.0, 31.0],  // inside corner at (50, 23)
        [100.0, 31.0],
        [110.0, 50.0], // R0: leaves from the last element's normal
    ];
    let got = path_at_depth(&out);
    assert_points(&got, &want);
    let got = &got[1..got.len() - 1];
    // No point of the tool path comes closer than the tool radius to the contour.
    let contour = [
        [0.0, 30.0],
        [10.0, 30.0],
        [10.0, 25.0],
        [50.0, 25.0],
        [50.0, 23.0],
        [100.0, 23.0],
    ];
    for w in got.windows(2) {
        for k in 0..=100 {
            let s = k as f64 / 100.0;
            let p = [
                w[0][0] + s * (w[1][0] - w[0][0]),
                w[0][1] + s * (w[1][1] - w[0][1]),
            ];
            let d = contour
                .windows(2)
                .map(|c| seg_dist(p, c[0], c[1]))
                .fold(f64::INFINITY, f64::min);
            assert!(d >= 8.0 - 1e-9, "{p:?} is {d} mm from the contour");
        }
    }
}

/// An inside corner at (0, 20) between a move down X0 and a move along +X, tool radius 5, RL.
fn open_corner(m98: &str) -> String {
    format!(
        "0 BEGIN PGM OPEN MM
1 TOOL CALL 1 Z S3000 DR+5
2 L X-30 Y+60 Z+10 R0 FMAX
3 L Z-5 F300
4 L X+0 Y+50 RL F600
5 L Y+20 {m98}
6 L X+40
7 L X+50 Y+0 R0
8 END PGM OPEN MM
"
    )
}

#[test]
fn m98_runs_both_offsets_to_their_full_ends_at_an_inside_corner() {
    // Standard: the offsets x = 5 and y = 25 are cut at their intersection (5, 25).
    let plain = path_at_depth(&compensate(&ops_of(&open_corner(""))).expect("valid"));
    assert_points(
        &plain,
        &[
            [-30.0, 60.0],
            [5.0, 50.0],
            [5.0, 25.0],
            [40.0, 25.0],
            [50.0, 0.0],
        ],
    );
    // M98: to the full end (5, 20) on the normal at the corner, straight to the full start
    // (0, 25) of the next offset, then on along it.
    let open = path_at_depth(&compensate(&ops_of(&open_corner("M98"))).expect("valid"));
    assert_points(
        &open,
        &[
            [-30.0, 60.0],
            [5.0, 50.0],
            [5.0, 20.0],
            [0.0, 25.0],
            [40.0, 25.0],
            [50.0, 0.0],
        ],
    );
}

#[test]
fn m98_at_an_outside_corner_and_m97_at_an_inside_corner_change_nothing() {
    let path = |text: String| path_at_depth(&compensate(&ops_of(&text)).expect("valid"));
    // With RL the corner at (0, 20) is an inside corner: M97 leaves it alone.
    assert_points(&path(open_corner("M97")), &path(open_corner("")));
    // With RR it is an outside corner: M98 leaves the transition arc alone.
    let rr = |s: String| s.replace(" RL ", " RR ");
    assert_points(&path(rr(open_corner("M98"))), &path(rr(open_corner(""))));
}
