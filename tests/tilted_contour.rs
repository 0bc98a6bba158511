//! Radius compensation and APPR/DEP in a tilted working plane: the tool-centre path is built
//! in the tilted plane and then turned into the workpiece system. Checked against offset
//! contours worked out by hand in the plane's own coordinates and turned by the plane's
//! rotation (PLANE SPATIAL SPA+30: a rotation of 30° about X).

mod common;

use klar::config::MachineConfig;
use klar_interp::{AxisLetter, Interpreter, Op, OpKind, Pose};

const AC: [AxisLetter; 5] = [
    AxisLetter::X,
    AxisLetter::Y,
    AxisLetter::Z,
    AxisLetter::A,
    AxisLetter::C,
];

/// Rx(−30°) applied to `v`: back into the tilted system.
fn rx30_back(v: [f64; 3]) -> [f64; 3] {
    let (s, c) = 30f64.to_radians().sin_cos();
    [v[0], c * v[1] + s * v[2], -s * v[1] + c * v[2]]
}

fn xyz(p: &Pose) -> [f64; 3] {
    [p[AxisLetter::X], p[AxisLetter::Y], p[AxisLetter::Z]]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The compensated tool-centre ops of a program body on an A/C machine, as `klar run` makes
/// them: working-plane ops on, through the compensator.
fn tool_centre(body: &str) -> Vec<Op> {
    let text = format!("BEGIN PGM T MM\n{body}\nEND PGM T MM\n");
    let interp = Interpreter::from_source("t.h", &text, Pose::ZERO).with_rotary_axes(&AC);
    common::compensated(interp, Pose::ZERO)
}

/// End points of the motion ops, in order.
fn ends(ops: &[Op]) -> Vec<[f64; 3]> {
    ops.iter()
        .filter_map(|op| match &op.kind {
            OpKind::Line { to, .. } | OpKind::Arc { to, .. } => Some(xyz(to)),
            _ => None,
        })
        .collect()
}

/// A piece of an expected path in the tilted system: a segment, or an arc of the XY plane
/// (centre, radius) at a height.
#[derive(Clone, Copy, Debug)]
enum Piece {
    Line([f64; 3], [f64; 3]),
    Circle([f64; 2], f64, f64),
}

fn dist_to(p: [f64; 3], piece: Piece) -> f64 {
    match piece {
        Piece::Line(a, b) => {
            let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let ap = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
            let len2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
            let t = if len2 == 0.0 {
                0.0
            } else {
                ((ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / len2).clamp(0.0, 1.0)
            };
            dist(p, [a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]])
        }
        Piece::Circle(c, r, z) => ((p[0] - c[0]).hypot(p[1] - c[1]) - r).abs() + (p[2] - z).abs(),
    }
}

/// Every point of `got` (workpiece system) turned back into the tilted system lies on one of
/// `path`, and the corner points `corners` are reached in order.
fn follows(got: &[[f64; 3]], path: &[Piece], corners: &[[f64; 3]]) {
    for (i, p) in got.iter().enumerate() {
        let q = rx30_back(*p);
        let d = path
            .iter()
            .map(|piece| dist_to(q, *piece))
            .fold(f64::INFINITY, f64::min);
        assert!(d < 1e-9, "point {i} {q:?} is {d} mm off the expected path");
    }
    let mut next = corners.iter().peekable();
    for p in got {
        if let Some(c) = next.peek()
            && dist(*p, common::mill5::rx(30.0, **c)) < 1e-9
        {
            next.next();
        }
    }
    assert!(
        next.peek().is_none(),
        "corner {:?} not reached in order",
        next.peek()
    );
}

/// The contour of the first tests: a 40 × 20 rectangle counter-clockwise from (20, 0), left
/// compensation with a tool of radius 5 (the tool inside), in PLANE SPATIAL SPA+30.
const RECT_RL: &str = "TOOL CALL 1 Z S3000 DR+5
PLANE SPATIAL SPA+30 SPB+0 SPC+0 STAY
L X+20 Y+10 Z+5 R0 FMAX
L Z-2 F300
L X+20 Y+0 RL F500
L X+40
L Y+20
L X+0
L Y+0
L X+20
L Y+10 R0
L Z+5 FMAX";

#[test]
fn a_rectangle_with_rl_is_offset_inside_the_tilted_plane() {
    let ops = tool_centre(RECT_RL);
    let got = ends(&ops);
    // By hand, in the tilted system: the tool arrives on the normal of the first element
    // (20, 5), runs the inside offset rectangle (5, 5)–(35, 15) with its corners at the
    // intersections, leaves on the last element's normal and goes to (20, 10) with R0.
    let expect = common::mill5::RECT_RL_CENTRE;
    assert_eq!(got.len(), expect.len(), "{got:?}");
    // The tilted plane at depth −2: n · p = −2 with n = Rx(30)·(0, 0, 1) = (0, −½, √3/2).
    let n = common::mill5::rx(30.0, [0.0, 0.0, 1.0]);
    for (g, e) in got.iter().zip(expect) {
        assert!(
            dist(*g, common::mill5::rx(30.0, e)) < 1e-9,
            "{g:?} vs {:?}",
            common::mill5::rx(30.0, e)
        );
        if e[2] == -2.0 {
            let height = g[0] * n[0] + g[1] * n[1] + g[2] * n[2];
            assert!((height + 2.0).abs() < 1e-9, "{g:?} off the plane");
        }
    }
    // On the contour the tool centre keeps the tool radius from the rectangle's turned image:
    // every point from the arrival on the contour to the leaving lies 5 mm in from the
    // nearest edge of the 40 × 20 rectangle (measured back in the tilted system).
    for g in &got[2..8] {
        let q = rx30_back(*g);
        let to_edges = [q[0], 40.0 - q[0], q[1], 20.0 - q[1]];
        let nearest = to_edges.iter().copied().fold(f64::INFINITY, f64::min);
        assert!((nearest - 5.0).abs() < 1e-9);
    }
    // Everything leaves in workpiece coordinates: no working-plane op reaches the planner.
    assert!(
        !ops.iter()
            .any(|op| matches!(op.kind, OpKind::WorkingPlane { .. }))
    );
}

/// APPR LCT / DEP LCT on a three-sided contour, left compensation, tool radius 5, R 10.
const LCT: &str = "TOOL CALL 1 Z S3000 DR+5
PLANE SPATIAL SPA+30 SPB+0 SPC+0 STAY
L X-10 Y+40 Z+5 R0 FMAX
L Z-2 F300
APPR LCT X+0 Y+0 R10 RL F500
L X+40
L Y+20
L X+0
DEP LCT X-10 Y-20 R10 F500
L Z+5 FMAX";

#[test]
fn appr_and_dep_lct_are_built_in_the_tilted_plane() {
    let got = ends(&tool_centre(LCT));
    // By hand, in the tilted system. APPR: the tool-centre point of PA is (0, 5) with the
    // contour heading +X; the arc of radius 10 turning counter-clockwise into it has its
    // centre at (0, 15); the line from PS (−10, 40) touches it at its leftmost point
    // PH (−10, 15). DEP: PE's tool-centre point is (0, 15) heading −X; the counter-clockwise
    // arc leaving it has its centre at (0, 5) and reaches the tangent of the line to
    // PN (−10, −20) at (−10, 5).
    let path = [
        Piece::Line([-10.0, 40.0, 5.0], [-10.0, 40.0, -2.0]),
        Piece::Line([-10.0, 40.0, -2.0], [-10.0, 15.0, -2.0]),
        Piece::Circle([0.0, 15.0], 10.0, -2.0),
        Piece::Line([0.0, 5.0, -2.0], [35.0, 5.0, -2.0]),
        Piece::Line([35.0, 5.0, -2.0], [35.0, 15.0, -2.0]),
        Piece::Line([35.0, 15.0, -2.0], [0.0, 15.0, -2.0]),
        Piece::Circle([0.0, 5.0], 10.0, -2.0),
        Piece::Line([-10.0, 5.0, -2.0], [-10.0, -20.0, -2.0]),
        Piece::Line([-10.0, -20.0, -2.0], [-10.0, -20.0, 5.0]),
    ];
    let corners = [
        [-10.0, 40.0, -2.0],
        [-10.0, 15.0, -2.0],
        [0.0, 5.0, -2.0],
        [35.0, 5.0, -2.0],
        [35.0, 15.0, -2.0],
        [0.0, 15.0, -2.0],
        [-10.0, 5.0, -2.0],
        [-10.0, -20.0, -2.0],
        [-10.0, -20.0, 5.0],
    ];
    // The arcs are quarter circles of radius 10: as lines within 1 µm they give
    // ⌈(π/2) / (2·acos(1 − 0.001/10))⌉ = 56 chords each.
    let chord_points = got.len() - (corners.len() + 1);
    assert_eq!(chord_points, 2 * 55, "{} points", got.len());
    follows(&got[1..], &path, &corners);
}

/// The pieces of an untilted compensated stream (lines and XY arcs).
fn pieces(ops: &[Op]) -> Vec<Piece> {
    ops.iter()
        .filter_map(|op| match &op.kind {
            OpKind::Line { from, to, .. } => Some(Piece::Line(xyz(from), xyz(to))),
            OpKind::Arc {
                from, center, to, ..
            } => {
                let r = (from[AxisLetter::X] - center[0]).hypot(from[AxisLetter::Y] - center[1]);
                assert_eq!(from[AxisLetter::Z], to[AxisLetter::Z]);
                Some(Piece::Circle(*center, r, to[AxisLetter::Z]))
            }
            _ => None,
        })
        .collect()
}

#[test]
fn the_tilted_path_is_the_untilted_path_turned() {
    for body in [RECT_RL, LCT] {
        let untilted_body = body.replace("PLANE SPATIAL SPA+30 SPB+0 SPC+0 STAY\n", "");
        let flat = tool_centre(&untilted_body);
        let tilted = ends(&tool_centre(body));
        // The untilted run: its end points are the corners, its elements the path.
        let corners = ends(&flat);
        assert!(corners.len() >= 9);
        follows(&tilted[1..], &pieces(&flat), &corners[1..]);
        let (a, b) = (tilted[tilted.len() - 1], corners[corners.len() - 1]);
        assert!(dist(a, common::mill5::rx(30.0, b)) < 1e-9);
    }
}

#[test]
fn a_plane_change_while_compensating_is_refused() {
    let text = "BEGIN PGM T MM\nTOOL CALL 1 Z S3000 DR+5\nL X+0 Y+0 Z-2 R0 F300\n\
                L X+10 RL\nPLANE SPATIAL SPA+30 SPB+0 SPC+0 STAY\nL Y+10\nEND PGM T MM\n";
    let mut interp = Interpreter::from_source("t.h", text, Pose::ZERO).with_rotary_axes(&AC);
    interp.set_working_plane_ops(true);
    let err = interp
        .find_map(|r| r.err())
        .expect("the PLANE block is refused");
    assert_eq!(err.line, 5, "{err}");
    assert!(err.message.contains("radius compensation"), "{err}");
}

#[test]
fn without_working_plane_ops_rl_in_a_tilted_plane_is_refused_as_before() {
    let text = format!("BEGIN PGM T MM\n{RECT_RL}\nEND PGM T MM\n");
    let interp = Interpreter::from_source("t.h", &text, Pose::ZERO).with_rotary_axes(&AC);
    let err = interp
        .into_iter()
        .find_map(|r| r.err())
        .expect("RL is refused");
    assert!(err.message.contains("tilted working plane"), "{err}");
}

/// The ops of a program file on an A/C machine: as the interpreter turns them itself
/// (working-plane ops off), and through working-plane ops and the tilt stage.
fn both_ways(name: &str) -> (Vec<Op>, Vec<Op>) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("programs")
        .join(name);
    let open = || {
        Interpreter::open(&path, Pose::xyz(0.0, 0.0, 150.0))
            .unwrap_or_else(|d| panic!("{d}"))
            .with_rotary_axes(&AC)
    };
    let own: Vec<Op> = open()
        .collect::<Result<_, _>>()
        .unwrap_or_else(|d| panic!("{d}"));
    let mut interp = open();
    interp.set_working_plane_ops(true);
    let mut stage = klar_motion::tilt::TiltStage::new();
    let mut staged = std::collections::VecDeque::new();
    let mut saw_plane = false;
    for op in interp {
        let op = op.unwrap_or_else(|d| panic!("{d}"));
        saw_plane |= matches!(op.kind, OpKind::WorkingPlane { .. });
        stage.push(op, &mut staged);
    }
    // Only a program with a PLANE has working-plane ops.
    assert_eq!(saw_plane, name.starts_with("plane"), "{name}");
    (own, staged.into())
}

fn poses(kind: &OpKind) -> Vec<Pose> {
    match kind {
        OpKind::Line { from, to, .. } | OpKind::Arc { from, to, .. } => vec![*from, *to],
        _ => Vec::new(),
    }
}

#[test]
fn the_tilt_stage_gives_the_ops_the_interpreter_gave_itself() {
    for name in ["plane_spatial.h", "m128_swivel.h"] {
        let (own, staged) = both_ways(name);
        assert_eq!(own.len(), staged.len(), "{name}");
        for (a, b) in own.iter().zip(&staged) {
            assert_eq!(
                std::mem::discriminant(&a.kind),
                std::mem::discriminant(&b.kind),
                "{name}: {a:?} vs {b:?}"
            );
            assert_eq!(a.loc, b.loc);
            for (p, q) in poses(&a.kind).iter().zip(poses(&b.kind)) {
                for (u, v) in p.0.iter().zip(q.0) {
                    assert!((u - v).abs() < 1e-9, "{name}: {a:?} vs {b:?}");
                }
            }
        }
    }
}

#[test]
fn a_spline_in_a_tilted_plane_is_the_turned_polynomial() {
    // In the tilted system P(t) = (t³ + 2t, 2t², 0), t from 1 (start (3, 2, 0)) to 0.
    let ops = tool_centre(
        "TOOL CALL 1 Z S3000
PLANE SPATIAL SPA+30 SPB+0 SPC+0 STAY
L X+3 Y+2 Z+0 R0 F500
SPL X+0 Y+0 K3X+1 K2X+0 K1X+2 K3Y+0 K2Y+2 K1Y+0 F500",
    );
    let splines: Vec<&OpKind> = ops
        .iter()
        .map(|op| &op.kind)
        .filter(|k| matches!(k, OpKind::Spline { .. }))
        .collect();
    let [OpKind::Spline { to, axes, .. }] = splines.as_slice() else {
        panic!("not one spline: {ops:?}")
    };
    for t in [0.0, 0.3, 0.7, 1.0] {
        let want = common::mill5::rx(30.0, [t * t * t + 2.0 * t, 2.0 * t * t, 0.0]);
        for (i, letter) in [AxisLetter::X, AxisLetter::Y, AxisLetter::Z]
            .into_iter()
            .enumerate()
        {
            let k = axes
                .iter()
                .find(|a| a.axis == letter)
                .map_or([0.0; 3], |a| a.k);
            let got = k[0] * t.powi(3) + k[1] * t * t + k[2] * t + to[letter];
            assert!(
                (got - want[i]).abs() < 1e-9,
                "t {t} {letter}: {got} vs {}",
                want[i]
            );
        }
    }
}

/// The workpiece point under machine X Y Z `m` with the table of the built-in 5-axis mill at
/// A `a`, C 0 (tilt line at z = −100): the tilt undone.
fn tip_at_a(m: [f64; 3], a: f64) -> [f64; 3] {
    let (s, c) = a.to_radians().sin_cos();
    let z = m[2] + 100.0;
    [m[0], c * m[1] - s * z, s * m[1] + c * z - 100.0]
}

#[test]
fn plane_contour_runs_the_offset_outline_on_the_inclined_face() {
    let machine = MachineConfig::builtin_mill5();
    let (result, trace) = common::run(&common::program("plane_contour.h"), &machine);
    result.unwrap_or_else(|f| panic!("{}", f.error));
    common::assert_within_limits(&trace, &machine);
    let col = |l: &str| trace.column(l).expect("axis column");
    let (x, y, z, a, c) = (col("X"), col("Y"), col("Z"), col("A"), col("C"));
    let tol = machine.tolerance * 1.01;
    let mut on_outline = 0;
    for i in 0..x.len() {
        if (a[i] - 30.0).abs() > 1e-9 || c[i].abs() > 1e-9 {
            continue;
        }
        let t = rx30_back(tip_at_a([x[i], y[i], z[i]], 30.0));
        if (t[2] + 3.0).abs() > 1e-6 {
            continue;
        }
        // The boss is the 40 × 30 rectangle with R5 corners: the points within 5 mm of the
        // rectangle (±15, ±10). The tool centre (RR, radius 4) stays 9 mm or more from that
        // rectangle, and runs on 9 mm along the outline.
        let dx = (t[0].abs() - 15.0).max(0.0);
        let dy = (t[1].abs() - 10.0).max(0.0);
        let d = dx.hypot(dy);
        assert!(d >= 9.0 - tol, "the tool cuts into the boss at {t:?}");
        if (d - 9.0).abs() <= tol {
            on_outline += 1;
        }
    }
    assert!(on_outline > 500, "{on_outline} rows on the outline");
}
