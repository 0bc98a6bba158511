//! FK free contour programming against geometry computed here by hand: tangent points of
//! lines and circles, circles through three points, distances from a line, relative data,
//! closed contours, FSELECT and the FK errors.

mod common;
use common::*;
use klar_interp::{AxisLetter, OpKind, Pose};

/// Tolerance of the FK solver results, mm.
const TOL: f64 = 1e-6;

#[track_caller]
fn near(a: f64, b: f64) {
    assert!((a - b).abs() < TOL, "{a} != {b}");
}

#[track_caller]
fn near2(a: [f64; 2], b: [f64; 2]) {
    near(a[0], b[0]);
    near(a[1], b[1]);
}

fn xy(p: Pose) -> [f64; 2] {
    [p[AxisLetter::X], p[AxisLetter::Y]]
}

/// Start, end, and for an arc its centre and sweep.
type Element = ([f64; 2], [f64; 2], Option<([f64; 2], f64)>);

/// Start, end, and for arcs centre and sweep, of the motions after the first (the L that
/// places the tool at the section start).
fn path(text: &str) -> Vec<Element> {
    motions(&run_from(text, Pose::xyz(-1.0, -1.0, 0.0)))
        .into_iter()
        .skip(1)
        .map(|k| match k {
            OpKind::Line { from, to, .. } => (xy(from), xy(to), None),
            OpKind::Arc {
                from,
                to,
                center,
                sweep,
                ..
            } => (xy(from), xy(to), Some((center, sweep))),
            other => panic!("unexpected motion {other:?}"),
        })
        .collect()
}

fn head(body: &str) -> String {
    program(&format!(
        "1 TOOL CALL 1 Z S1000\n2 L X+0 Y+0 Z+0 R0 F200\n{body}"
    ))
}

#[test]
fn line_tangent_arc_tangent_line() {
    // FL along +X, then a DR+ arc about (30,10) with R10 tangent to it: the tangent point is
    // the foot of the perpendicular from the centre, (30,0). FLT to (40,30): of the two
    // tangents from (40,30) to the circle, the one travelled counter-clockwise touches at
    // (40,10), where the direction of travel is +Y.
    let p = path(&head(
        "3 FL AN+0\n4 FCT DR+ R10 CCX+30 CCY+10\n5 FLT X+40 Y+30\n6 L X+40 Y+50",
    ));
    assert_eq!(p.len(), 4);
    near2(p[0].0, [0.0, 0.0]);
    near2(p[0].1, [30.0, 0.0]);
    let (c, sweep) = p[1].2.expect("arc");
    near2(p[1].0, [30.0, 0.0]);
    near2(p[1].1, [40.0, 10.0]);
    near2(c, [30.0, 10.0]);
    near(sweep, 90.0);
    near2(p[2].0, [40.0, 10.0]);
    near2(p[2].1, [40.0, 30.0]);
    // tangency at both ends of the arc: radius vector ⟂ the neighbouring lines
    let r0 = [p[1].0[0] - c[0], p[1].0[1] - c[1]];
    let d0 = [p[0].1[0] - p[0].0[0], p[0].1[1] - p[0].0[1]];
    near(r0[0] * d0[0] + r0[1] * d0[1], 0.0);
    let r1 = [p[1].1[0] - c[0], p[1].1[1] - c[1]];
    let d1 = [p[2].1[0] - p[2].0[0], p[2].1[1] - p[2].0[1]];
    near(r1[0] * d1[0] + r1[1] * d1[1], 0.0);
}

#[test]
fn flt_after_arc_is_tangent() {
    // C arc about (10,0) from (0,0) DR- to (10,10); its end direction (cw) is +X, so
    // FLT LEN 15 ends at (25,10).
    let p = path(&head(
        "3 CC X+10 Y+0\n4 C X+10 Y+10 DR-\n5 FLT LEN 15\n6 L X+25 Y+30",
    ));
    near2(p[1].0, [10.0, 10.0]);
    near2(p[1].1, [25.0, 10.0]);
}

#[test]
fn arc_through_auxiliary_point() {
    // circle through (0,0), (20,0) and (10,5): the centre (10,k) is equally far from (0,0)
    // and (10,5): 100 + k² = (5 - k)² → k = -7.5, radius 12.5
    let p = path(&head("3 FC DR- X+20 Y+0 P1X+10 P1Y+5\n4 L X+20 Y+20"));
    let (c, sweep) = p[0].2.expect("arc");
    near2(c, [10.0, -7.5]);
    near2(p[0].1, [20.0, 0.0]);
    let r = (10.0f64 * 10.0 + 7.5 * 7.5).sqrt();
    near(((10.0 - c[0]).powi(2) + (5.0 - c[1]).powi(2)).sqrt(), r);
    let a0 = (7.5f64).atan2(-10.0).to_degrees();
    let a1 = (7.5f64).atan2(10.0).to_degrees();
    near(sweep, a1 - a0);
}

/// A line from (0,0) to X=20 with (10,0) 5 mm from it: 10·|y| / √(400 + y²) = 5 gives
/// y = ±20/√3.
const PD: &str = "3 FL X+20 PDX+10 PDY+0 D5";

#[test]
fn fselect_picks_each_solution() {
    let y = 20.0 / 3f64.sqrt();
    for (n, want) in [(1, -y), (2, y)] {
        let p = path(&head(&format!("{PD}\n4 FSELECT {n}\n5 L X+0 Y+0")));
        near2(p[0].1, [20.0, want]);
        // the distance of (10,0) from the solved line
        let e = p[0].1;
        let d = (e[0] * 0.0 - e[1] * 10.0).abs() / (e[0] * e[0] + e[1] * e[1]).sqrt();
        near(d, 5.0);
    }
}

#[test]
fn two_solutions_without_fselect() {
    let (_, d) = run_until_error(&head(&format!("{PD}\n4 L X+0 Y+0")));
    assert!(
        d.message.contains("2 solutions for blocks 3") && d.message.contains("FSELECT"),
        "{}",
        d.message
    );
    assert_eq!((d.line, d.col, d.block), (5, 1, Some(4)));
}

#[test]
fn relative_data() {
    // block 5: end 5 mm in X beyond block 3's end, Y as block 3's end: (15,0);
    // block 6: direction of block 3 (+X) turned 90°, 5 long: (15,5)
    let p = path(&head(
        "3 FL X+10 Y+0\n4 FL X+10 Y+10\n5 FL IX+5 IY+0 RX 3 RY 3\n6 FL AN+90 RAN 3 LEN 5\n7 L X+0",
    ));
    near2(p[2].1, [15.0, 0.0]);
    near2(p[3].1, [15.0, 5.0]);
}

#[test]
fn polar_fk_data() {
    // pole at the start (0,0); end at PR 10 PA 90: (0,10). The arc's centre is at PR 10
    // PA 45 (5√2, 5√2) and its end at PR 10 PA 0: (10,0), as far from the centre as the
    // start. Seen from the centre the start lies at 157.5°, the end at 292.5°: DR+ sweeps 135°.
    let p = path(&head(
        "3 FPOL X+0 Y+0\n4 FL PR+10 PA+90\n5 FC DR+ CCPR+10 CCPA+45 PR+10 PA+0\n6 L X+0 Y+0",
    ));
    near2(p[0].1, [0.0, 10.0]);
    near2(p[1].1, [10.0, 0.0]);
    let (c, sweep) = p[1].2.expect("arc");
    let h = 50f64.sqrt();
    near2(c, [h, h]);
    near(sweep, 135.0);
}

#[test]
fn closed_contour() {
    // CLSD- ends where the CLSD+ element started; its direction is free
    let p = path(&head(
        "3 FL X+10 Y+0 CLSD+\n4 FL X+10 Y+10\n5 FL X+0 Y+10\n6 FL CLSD-\n7 L Z+10",
    ));
    assert_eq!(p.len(), 5, "four FK lines and the Z move");
    near2(p[3].0, [0.0, 10.0]);
    near2(p[3].1, [0.0, 0.0]);
}

#[test]
fn incremental_end_and_feed() {
    let ops = run_from(
        &head("3 FL IX+10 IY+5 F600\n4 L X+0 Y+0"),
        Pose::xyz(-1.0, -1.0, 0.0),
    );
    let m = motions(&ops);
    match &m[1] {
        OpKind::Line { to, feed, .. } => {
            near2(xy(*to), [10.0, 5.0]);
            assert_eq!(*feed, klar_interp::Feed::Rate(10.0));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn under_determined() {
    let (_, d) = run_until_error(&head("3 FL AN+0\n4 L X+0 Y+10"));
    assert!(
        d.message.contains("blocks 3 are under-determined"),
        "{}",
        d.message
    );
    assert_eq!((d.line, d.col, d.block), (5, 1, Some(4)));
}

#[test]
fn contradictory() {
    // from (0,0) to (10,0) cannot be 20 long
    let (_, d) = run_until_error(&head("3 FL X+10 Y+0 LEN 20\n4 L X+0"));
    assert!(d.message.contains("block 3 contradict"), "{}", d.message);
    assert_eq!((d.line, d.col, d.block), (4, 1, Some(3)));
}

#[test]
fn unknown_block_reference() {
    let (_, d) = run_until_error(&head("3 FL IX+5 RX 99\n4 L X+0"));
    assert!(d.message.contains("block 99"), "{}", d.message);
    assert_eq!(d.line, 4);
}

/// Outer tangent from circle `a` (radius `ra`) to circle `b` (radius `rb`) for clockwise
/// travel (both centres right of the line): with D = b − a at angle φ, the right normal n
/// satisfies n·D = rb − ra, so the direction angle is θ = φ + asin((rb − ra)/|D|).
/// Returns the tangent points on `a` and on `b`.
fn cw_tangent(a: [f64; 2], ra: f64, b: [f64; 2], rb: f64) -> ([f64; 2], [f64; 2]) {
    let d = [b[0] - a[0], b[1] - a[1]];
    let l = (d[0] * d[0] + d[1] * d[1]).sqrt();
    let theta = d[1].atan2(d[0]) + ((rb - ra) / l).asin();
    let n = [theta.sin(), -theta.cos()];
    (
        [a[0] - ra * n[0], a[1] - ra * n[1]],
        [b[0] - rb * n[0], b[1] - rb * n[1]],
    )
}

#[test]
fn closed_contour_around_three_circles() {
    // a closed contour round three circles joined by tangent lines, all clockwise
    let text = program(
        "1 TOOL CALL 1 Z S1000\n2 L X+2 Y+30 Z+0 R0 F250\n\
         3 FC DR- R18 CLSD+ CCX+20 CCY+30\n4 FLT\n5 FCT DR- R15 CCX+50 CCY+75\n\
         6 FLT\n7 FCT DR- R15 CCX+75 CCY+20\n8 FLT\n9 FCT DR- R18 CLSD- CCX+20 CCY+30\n\
         10 L Z+50 FMAX",
    );
    let m: Vec<_> = motions(&run_from(&text, Pose::xyz(0.0, 0.0, 0.0)))
        .into_iter()
        .skip(1)
        .collect();
    assert_eq!(m.len(), 8, "seven FK elements and the retract");
    let (a, b, c) = ([20.0, 30.0], [50.0, 75.0], [75.0, 20.0]);
    let (t1a, t1b) = cw_tangent(a, 18.0, b, 15.0);
    let (t2a, t2b) = cw_tangent(b, 15.0, c, 15.0);
    let (t3a, t3b) = cw_tangent(c, 15.0, a, 18.0);
    let want = [
        ([2.0, 30.0], t1a, Some(a)),
        (t1a, t1b, None),
        (t1b, t2a, Some(b)),
        (t2a, t2b, None),
        (t2b, t3a, Some(c)),
        (t3a, t3b, None),
        (t3b, [2.0, 30.0], Some(a)),
    ];
    for (k, (s, e, centre)) in want.iter().enumerate() {
        match (&m[k], centre) {
            (OpKind::Line { from, to, .. }, None) => {
                near2(xy(*from), *s);
                near2(xy(*to), *e);
            }
            (
                OpKind::Arc {
                    from,
                    to,
                    center,
                    sweep,
                    ..
                },
                Some(cc),
            ) => {
                near2(xy(*from), *s);
                near2(xy(*to), *e);
                near2(*center, *cc);
                assert!(*sweep < 0.0, "DR- arcs run clockwise");
            }
            (other, _) => panic!("element {k}: {other:?}"),
        }
    }
}

fn program_file(name: &str) -> Vec<OpKind> {
    let path = format!("{}/../programs/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).expect("program file");
    motions(&run_from(&text, Pose::xyz(0.0, 0.0, 100.0)))
}

#[test]
fn example_programs() {
    // fk_contour.h: the closed contour comes back to its start X+2 Y+30
    let m = program_file("fk_contour.h");
    let arcs = m.iter().filter(|k| matches!(k, OpKind::Arc { .. })).count();
    assert_eq!(arcs, 4);
    let last_fk = m
        .iter()
        .rev()
        .find(|k| matches!(k, OpKind::Arc { .. }))
        .expect("arc");
    if let OpKind::Arc { to, .. } = last_fk {
        near2(xy(*to), [2.0, 30.0]);
    }
    // fk_select.h: FSELECT 2 takes the line to Y = +20/√3; the arc about (30, 11.547)
    // through that point meets X+30 at Y = 11.547 ± r, and FSELECT 1 takes the lower one
    let m = program_file("fk_select.h");
    let y = 20.0 / 3f64.sqrt();
    let fk: Vec<_> = m
        .iter()
        .filter_map(|k| match k {
            OpKind::Line { to, .. } if to[AxisLetter::Z] == -2.0 => Some(xy(*to)),
            OpKind::Arc { to, .. } => Some(xy(*to)),
            _ => None,
        })
        .collect();
    near2(fk[1], [20.0, y]);
    let r = ((30.0f64 - 20.0).powi(2) + (11.547 - y).powi(2)).sqrt();
    near2(fk[2], [30.0, 11.547 - r]);
}

#[test]
fn working_plane_of_the_tool_axis() {
    // tool axis Y: plane ZX, first axis Z. Centre X+10 Z+0 from X+0 Z+0 to X+20 Z+0: in
    // (Z, X) the start is at -90° from the centre, the end at +90°, DR+ sweeps +180°.
    let text = program(
        "1 TOOL CALL 1 Y S1000\n2 L X+0 Y+0 Z+0 R0 F200\n3 FC DR+ CCX+10 CCZ+0 X+20 Z+0\n\
         4 L Y+10",
    );
    let m = motions(&run_from(&text, Pose::xyz(-1.0, 0.0, 0.0)));
    match &m[1] {
        OpKind::Arc {
            to,
            center,
            plane,
            sweep,
            ..
        } => {
            assert_eq!(*plane, klar_interp::Plane::ZX);
            near2(*center, [0.0, 10.0]);
            near(to[AxisLetter::X], 20.0);
            near(to[AxisLetter::Z], 0.0);
            near(*sweep, 180.0);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn compensation_and_rounding_after_fk() {
    // RL in an FK block switches compensation before its motion; RND after a solved FK
    // element rounds its corner with the next L: lines (0,0)→(10,0)→(10,10), R2 fillet
    // ends 2 mm before and after the corner.
    let ops = run_from(
        &head("3 FL X+10 Y+0 RL\n4 RND R2\n5 L X+10 Y+10\n6 L X+0 R0"),
        Pose::xyz(-1.0, -1.0, 0.0),
    );
    let comp = ops
        .iter()
        .position(|o| {
            matches!(
                o.kind,
                OpKind::RadiusComp {
                    side: klar_interp::CompSide::Left
                }
            )
        })
        .expect("RL");
    let m = motions(&ops[comp..]);
    match (&m[0], &m[1]) {
        (OpKind::Line { to, .. }, OpKind::Arc { to: e, center, .. }) => {
            near2(xy(*to), [8.0, 0.0]);
            near2(xy(*e), [10.0, 2.0]);
            near2(*center, [8.0, 2.0]);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn arc_end_angle_chord_and_full_circle() {
    // CCA: end at 90° about the centre (10,0), radius 10 from the start (0,0): (10,10);
    // counter-clockwise from 180° to 90° is 270°
    let p = path(&head("3 FC DR+ CCX+10 CCY+0 CCA+90\n4 L X+0 Y+0"));
    near2(p[0].1, [10.0, 10.0]);
    near(p[0].2.expect("arc").1, 270.0);
    // chord LEN 10√2 from (0,0) on that circle: (10,-10) or (10,10); FSELECT 2 takes the
    // second in order of X, then Y
    let p = path(&head(
        "3 FC DR+ CCX+10 CCY+0 LEN 14.142135623730951\n4 FSELECT 2\n5 L X+0 Y+0",
    ));
    near2(p[0].1, [10.0, 10.0]);
    // end point = start point with both coordinates programmed: a full circle
    let p = path(&head("3 FC DR- CCX+10 CCY+0 X+0 Y+0\n4 L X+0 Y+10"));
    near2(p[0].1, [0.0, 0.0]);
    near(p[0].2.expect("arc").1, -360.0);
}

#[test]
fn word_errors_point_at_the_word() {
    // CCX belongs to arcs: column of the word in the FL block
    let (_, d) = run_until_error(&head("3 FL X+5 CCX+5\n4 L X+0"));
    assert_eq!((d.line, d.col), (4, 10), "{}", d.message);
    // an arc needs its direction
    let (_, d) = run_until_error(&head("3 FC R+5 CCX+0 CCY+5\n4 L X+0"));
    assert!(d.message.contains("DR+ or DR-"), "{}", d.message);
    assert_eq!(d.line, 4);
    // polar data without FPOL
    let (_, d) = run_until_error(&head("3 FL PR+5 PA+0\n4 L X+0"));
    assert!(d.message.contains("FPOL"), "{}", d.message);
    assert_eq!((d.line, d.col), (4, 6));
    // FSELECT beyond the number of solutions
    let (_, d) = run_until_error(&head(&format!("{PD}\n4 FSELECT 3\n5 L X+0")));
    assert!(d.message.contains("FSELECT 3"), "{}", d.message);
    assert_eq!((d.line, d.col), (5, 11));
    // M30 inside the contour
    let (_, d) = run_until_error(&head("3 FL X+5 Y+0 M30\n4 L X+0"));
    assert_eq!((d.line, d.col), (4, 14), "{}", d.message);
}
