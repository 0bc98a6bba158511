//! Contour blocks against closed-form geometry written from the manual's definitions: CHF,
//! RND, CTP, polar coordinates in all planes, CC variants, the helix table, SPL and the
//! APPR/DEP ops.

mod common;
use common::*;
use klar_interp::{
    ApproachShape, AxisLetter, CompSide, Diagnostic, Feed, Interpreter, Op, OpKind, Plane, Pose,
    SplineAxis,
};

/// Where the machine stands before each test program: off the origin, so that a first
/// `L X+0 Y+0` moves.
const START: Pose = Pose::xyz(-1.0, -1.0, 0.0);

fn run(text: &str) -> Vec<Op> {
    run_from(text, START)
}

fn run_until_error(text: &str) -> (Vec<Op>, Diagnostic) {
    let mut ops = Vec::new();
    for r in Interpreter::from_source("t.h", text, START) {
        match r {
            Ok(op) => ops.push(op),
            Err(d) => return (ops, d),
        }
    }
    panic!("expected a diagnostic, got {} ops", ops.len());
}

fn line_pts(k: &OpKind) -> (Pose, Pose) {
    match k {
        OpKind::Line { from, to, .. } => (*from, *to),
        other => panic!("not a line: {other:?}"),
    }
}

fn xy(p: Pose) -> [f64; 2] {
    [p[AxisLetter::X], p[AxisLetter::Y]]
}

fn close2(a: [f64; 2], b: [f64; 2]) {
    close(a[0], b[0]);
    close(a[1], b[1]);
}

#[test]
fn chamfer_cuts_equal_lengths_off_both_lines() {
    let m = motions(&run(&program(
        "L X+0 Y+0 F100\nL X+10 Y+0\nCHF 2\nL X+10 Y+10",
    )));
    assert_eq!(m.len(), 4);
    let (_, a_end) = line_pts(&m[1]);
    let (c0, c1) = line_pts(&m[2]);
    let (b0, b1) = line_pts(&m[3]);
    close2(xy(a_end), [8.0, 0.0]);
    close2(xy(c0), [8.0, 0.0]);
    close2(xy(c1), [10.0, 2.0]);
    close2(xy(b0), [10.0, 2.0]);
    close2(xy(b1), [10.0, 10.0]);
}

#[test]
fn rounding_arc_is_tangent_to_both_lines() {
    // a 60° deflection: from +X to the direction 60°
    let (c, s) = (60f64.to_radians().cos(), 60f64.to_radians().sin());
    let text = program(&format!(
        "L X+0 Y+0 F100\nL X+10 Y+0\nRND R3 F50\nL X+{:.12} Y+{:.12}",
        10.0 + 10.0 * c,
        10.0 * s
    ));
    let m = motions(&run(&text));
    assert_eq!(m.len(), 4);
    let (t1, t2, centre, plane, sweep) = arc(&m[2]);
    assert_eq!(plane, Plane::XY);
    close(sweep, 60.0);
    // tangent length R·tan(deflection/2) from the corner along both lines
    let d = 3.0 * 30f64.to_radians().tan();
    close2(xy(t1), [10.0 - d, 0.0]);
    close2(xy(t2), [10.0 + d * c, d * s]);
    // centre at distance R from both lines, radius vectors perpendicular to the lines
    close(centre[1], 3.0);
    let r2 = [t2[AxisLetter::X] - centre[0], t2[AxisLetter::Y] - centre[1]];
    close((r2[0] * r2[0] + r2[1] * r2[1]).sqrt(), 3.0);
    close(r2[0] * c + r2[1] * s, 0.0);
    // the lines end and start at the tangent points; the RND feed acts on the arc only
    close2(xy(line_pts(&m[1]).1), xy(t1));
    close2(xy(line_pts(&m[3]).0), xy(t2));
    match (&m[2], &m[3]) {
        (OpKind::Arc { feed: f1, .. }, OpKind::Line { feed: f2, .. }) => {
            assert_eq!(*f1, Feed::Rate(50.0 / 60.0));
            assert_eq!(*f2, Feed::Rate(100.0 / 60.0));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn rounding_errors() {
    let (_, d) = run_until_error(&program("L X+0 Y+0 F100\nL X+2 Y+0\nRND R5\nL X+2 Y+2"));
    assert!(d.message.contains("does not fit"), "{}", d.message);
    let (_, d) = run_until_error(&program("RND R5\nL X+2 Y+2 F100"));
    assert!(
        d.message.contains("must follow a contour element"),
        "{}",
        d.message
    );
    let (_, d) = run_until_error(&program("L X+5 F100\nRND R1\nM8"));
    assert!(d.message.contains("must be followed"), "{}", d.message);
}

#[test]
fn ctp_arc_is_tangent_and_ends_at_the_polar_point() {
    let m = motions(&run(&program(
        "L X+0 Y+0 F100\nL X+10 Y+0\nCC X+10 Y+0\nCTP PR+10 PA+90",
    )));
    let (s, e, centre, _, sweep) = arc(&m[2]);
    close2(xy(s), [10.0, 0.0]);
    close2(xy(e), [10.0, 10.0]);
    // tangent to +X at the start: the centre lies on the normal through the start point
    close(centre[0], 10.0);
    let rs = (s[AxisLetter::Y] - centre[1]).abs();
    let re =
        ((e[AxisLetter::X] - centre[0]).powi(2) + (e[AxisLetter::Y] - centre[1]).powi(2)).sqrt();
    close(rs, re);
    close(sweep, 180.0);
}

#[test]
fn polar_lines_in_all_planes_and_cc_variants() {
    let m = motions(&run(&program("CC X+5 Y+5\nL X+0 Y+0 F100\nLP PR+10 PA+30")));
    let (_, e) = line_pts(&m[1]);
    close2(xy(e), [5.0 + 10.0 * 30f64.to_radians().cos(), 10.0]);
    // tool axis Y: the plane is Z/X, angles from +Z towards +X
    let m = motions(&run(&program(
        "TOOL CALL 1 Y\nCC Z+0 X+0\nL X+1 Z+0 F100\nLP PR+2 PA+90",
    )));
    let (_, e) = line_pts(&m[1]);
    close(e[AxisLetter::X], 2.0);
    close(e[AxisLetter::Z], 0.0);
    // CC with Y and Z picks the Y/Z plane for CP
    let m = motions(&run(&program(
        "L X+0 Y+3 Z+0 F100\nCC Y+0 Z+0\nCP PA+90 DR+",
    )));
    let (_, e, _, plane, sweep) = arc(&m[1]);
    assert_eq!(plane, Plane::YZ);
    close(sweep, 90.0);
    close(e[AxisLetter::Z], 3.0);
    // CC alone: the last position is the pole; CC incremental: relative to it
    let m = motions(&run(&program(
        "L X+3 Y+4 F100\nCC\nL X+10 Y+0\nLP PR+1 PA+0\nCC IX+2 IY+0\nLP PR+1 PA+90",
    )));
    close2(xy(line_pts(&m[2]).1), [4.0, 4.0]);
    close2(xy(line_pts(&m[3]).1), [6.0, 5.0]);
    // rotary axes in L blocks
    let m = motions(&run(&program("L X+1 A+30 C-45 F100")));
    let (_, e) = line_pts(&m[0]);
    close(e[AxisLetter::A], 30.0);
    close(e[AxisLetter::C], -45.0);
}

/// One row of the helix table: thread, direction of work along Z, hand, DR, compensation.
struct HelixRow {
    internal: bool,
    up: bool,
    right_hand: bool,
    ccw: bool,
    comp: &'static str,
}

#[test]
fn helix_table_gives_the_right_thread() {
    // the table of the TNC manual (internal/external × Z+/Z− × right/left hand)
    let rows = [
        HelixRow {
            internal: true,
            up: true,
            right_hand: true,
            ccw: true,
            comp: "RL",
        },
        HelixRow {
            internal: true,
            up: true,
            right_hand: false,
            ccw: false,
            comp: "RR",
        },
        HelixRow {
            internal: true,
            up: false,
            right_hand: true,
            ccw: false,
            comp: "RR",
        },
        HelixRow {
            internal: true,
            up: false,
            right_hand: false,
            ccw: true,
            comp: "RL",
        },
        HelixRow {
            internal: false,
            up: true,
            right_hand: true,
            ccw: true,
            comp: "RR",
        },
        HelixRow {
            internal: false,
            up: true,
            right_hand: false,
            ccw: false,
            comp: "RL",
        },
        HelixRow {
            internal: false,
            up: false,
            right_hand: true,
            ccw: false,
            comp: "RL",
        },
        HelixRow {
            internal: false,
            up: false,
            right_hand: false,
            ccw: true,
            comp: "RR",
        },
    ];
    for r in rows {
        let (dr, ipa) = if r.ccw { ("+", 1080.0) } else { ("-", -1080.0) };
        let iz = if r.up { "+4.5" } else { "-4.5" };
        let text = program(&format!(
            "CC X+0 Y+0\nL X+20 Y+0 Z-5 {} F200\nCP IPA{ipa:+} IZ{iz} DR{dr}",
            r.comp
        ));
        let ops = run(&text);
        let m = motions(&ops);
        let (s, e, centre, plane, sweep) = arc(&m[1]);
        assert_eq!(plane, Plane::XY);
        close(sweep, ipa);
        // three turns end where they started in the plane, 4.5 mm along Z
        close2(xy(e), xy(s));
        close(
            e[AxisLetter::Z] - s[AxisLetter::Z],
            if r.up { 4.5 } else { -4.5 },
        );
        // handedness: a counter-clockwise turn while rising along +Z is a right-hand helix
        let right = (sweep > 0.0) == (e[AxisLetter::Z] > s[AxisLetter::Z]);
        assert_eq!(right, r.right_hand, "row {}", text);
        // side: looking along the travel, left of a counter-clockwise circle is its inside
        let side = ops
            .iter()
            .find_map(|o| match o.kind {
                OpKind::RadiusComp { side } => Some(side),
                _ => None,
            })
            .unwrap();
        let tool_inside = (side == CompSide::Left) == (sweep > 0.0);
        assert_eq!(tool_inside, r.internal, "row {}", text);
        assert_eq!(centre, [0.0, 0.0]);
    }
    // IPA limits and the sign rule
    let (_, d) = run_until_error(&program("CC X+0 Y+0\nL X+1 F100\nCP IPA+100000 IZ+1 DR+"));
    assert!(d.message.contains("99999.9999"), "{}", d.message);
    let (_, d) = run_until_error(&program("CC X+0 Y+0\nL X+1 F100\nCP IPA-360 IZ+1 DR+"));
    assert!(d.message.contains("different signs"), "{}", d.message);
    let ok = run(&program(
        "CC X+0 Y+0\nL X+1 F100\nCP IPA-99999.9999 IZ-1 DR-",
    ));
    close(arc(&motions(&ok)[1]).4, -99_999.999_9);
}

/// The seed's spline block 8 after the L block 7 that ends at its start point.
const SEED_SPLINE: &str = "L X+28.338 Y+19.385 Z-0.5 FMAX\n\
SPL X24.875 Y15.924 Z-0.5 ~\n\
K3X-4.688E-002 K2X2.459E-002 K1X3.486E+000 ~\n\
K3Y-4.563E-002 K2Y2.155E-002 K1Y3.486E+000 ~\n\
K3Z0.000E+000 K2Z0.000E+000 K1Z0.000E+000 F10000";

fn eval(axes: &[SplineAxis], to: Pose, t: f64) -> Pose {
    let mut p = to;
    for a in axes {
        p[a.axis] = a.k[0] * t * t * t + a.k[1] * t * t + a.k[2] * t + to[a.axis];
    }
    p
}

#[test]
fn spline_of_the_seed_starts_at_the_previous_end() {
    let ops = run(&program(SEED_SPLINE));
    let m = motions(&ops);
    let OpKind::Spline {
        from,
        to,
        axes,
        feed,
    } = &m[1]
    else {
        panic!("{:?}", m[1]);
    };
    assert_eq!(axes.len(), 3);
    assert_eq!(*feed, Feed::Rate(10000.0 / 60.0));
    // t = 1 is the start: within 1 µm of the L block's end point
    let start = eval(axes, *to, 1.0);
    for a in [AxisLetter::X, AxisLetter::Y, AxisLetter::Z] {
        assert!(
            (start[a] - from[a]).abs() <= 1e-3,
            "{a}: {} vs {}",
            start[a],
            from[a]
        );
    }
    close(from[AxisLetter::X], 28.338);
    // t = 0 is the end point written in the block
    assert_eq!(eval(axes, *to, 0.0), *to);
    // exponents: K1X 3.486E+000 = 3.486, K3X -4.688E-002 = -0.04688
    let x = axes.iter().find(|a| a.axis == AxisLetter::X).unwrap();
    close(x.k[0], -0.04688);
    close(x.k[2], 3.486);
    // direction of travel: at the start −(3K3 + 2K2 + K1), at the end −K1; both point
    // towards −X and −Y at about 45° (the seed's tangent-continuous pair of blocks)
    let y = axes.iter().find(|a| a.axis == AxisLetter::Y).unwrap();
    let start_dir = [
        -(3.0 * x.k[0] + 2.0 * x.k[1] + x.k[2]),
        -(3.0 * y.k[0] + 2.0 * y.k[1] + y.k[2]),
    ];
    let end_dir = [-x.k[2], -y.k[2]];
    let deg = |v: [f64; 2]| v[1].atan2(v[0]).to_degrees();
    assert!((deg(start_dir) + 135.0).abs() < 0.5, "{}", deg(start_dir));
    assert!((deg(end_dir) + 135.0).abs() < 1e-9);
}

#[test]
fn spline_exponent_forms_and_errors() {
    // `E2` after a space, `E-002` attached: start = end + K3 + K2 + K1
    let ops = run(&program(
        "L X+1 Y+0.03 F100\nSPL X+0 Y+0 K3X+0.01 E2 K2X-0.5 K1X+0.5 K3Y+1E-002 K2Y+1 E-002 K1Y+1E-2",
    ));
    let OpKind::Spline { axes, .. } = &motions(&ops)[1] else {
        panic!()
    };
    close(axes[0].k[0], 1.0);
    close(axes[1].k[1], 0.01);
    // start 2 µm away from the previous end point
    let (_, d) = run_until_error(&program(
        "L X+1.002 Y+0 F100\nSPL X+0 Y+0 K3X+0 K2X+0 K1X+1 K3Y+0 K2Y+0 K1Y+0",
    ));
    assert!(
        d.message.contains("away from the previous end point"),
        "{}",
        d.message
    );
    // a missing coefficient, an axis without its triple, a triple without its axis, 1 axis
    for bad in [
        "SPL X+0 Y+0 K3X+0 K2X+0 K3Y+0 K2Y+0 K1Y+0",
        "SPL X+0 Y+0 K3X+0 K2X+0 K1X+1",
        "SPL X+0 K3X+0 K2X+0 K1X+1 K3Y+0 K2Y+0 K1Y+0",
        "SPL X+0 K3X+0 K2X+0 K1X+1",
    ] {
        let (_, d) = run_until_error(&program(&format!("L X+1 F100\n{bad}")));
        assert_eq!(d.line, 3, "{bad}: {d}");
    }
    // coefficients out of order is a syntax error
    let (_, d) = run_until_error(&program("SPL X+0 Y+0 K2X+0 K3X+0 K1X+1 K3Y+0 K2Y+0 K1Y+0"));
    assert!(d.message.contains("in that order"), "{}", d.message);
}

#[test]
fn appr_lct_of_the_seed() {
    let ops = run(&program(
        "L X+40 Y+10 R0 FMAX M3\nAPPR LCT X+10 Y+20 Z-10 R10 RR F100\nL X+20 Y+35",
    ));
    let m = motions(&ops);
    let OpKind::Approach {
        from,
        to,
        shape,
        side,
        feed_to_aux,
        feed,
        plane,
        with_tool_axis,
    } = &m[1]
    else {
        panic!("{:?}", m[1]);
    };
    assert_eq!(*from, Pose::xyz(40.0, 10.0, 0.0));
    assert_eq!(*to, Pose::xyz(10.0, 20.0, -10.0));
    assert_eq!(*shape, ApproachShape::LineCircleTangent { radius: 10.0 });
    assert_eq!(*side, CompSide::Right);
    // LCT: the APPR block's feed all the way from PS to PA
    assert_eq!(*feed_to_aux, Feed::Rate(100.0 / 60.0));
    assert_eq!(*feed, Feed::Rate(100.0 / 60.0));
    assert_eq!(*plane, Plane::XY);
    assert!(*with_tool_axis);
    // the next line starts at PA
    assert_eq!(line_pts(&m[2]).0, *to);
}

#[test]
fn appr_feeds_and_dep_lt_of_the_seed() {
    // LT after FMAX: to PH in rapid, then the block's feed
    let ops = run(&program(
        "L X+0 Y+0 FMAX\nAPPR LT X+10 Y+0 LEN 15 RL F300\nL Y+20 RR F100\nDEP LT LEN12.5 F100\nL Z+100 FMAX",
    ));
    let m = motions(&ops);
    match &m[1] {
        OpKind::Approach {
            shape,
            feed_to_aux,
            feed,
            with_tool_axis,
            ..
        } => {
            assert_eq!(*shape, ApproachShape::LineTangent { len: 15.0 });
            assert_eq!(*feed_to_aux, Feed::Rapid);
            assert_eq!(*feed, Feed::Rate(5.0));
            assert!(!with_tool_axis);
        }
        other => panic!("{other:?}"),
    }
    match &m[3] {
        OpKind::Depart {
            from,
            to,
            shape,
            feed,
            ..
        } => {
            assert_eq!(*from, Pose::xyz(10.0, 20.0, 0.0));
            assert_eq!(*to, None);
            assert_eq!(*shape, ApproachShape::LineTangent { len: 12.5 });
            assert_eq!(*feed, Feed::Rate(100.0 / 60.0));
        }
        other => panic!("{other:?}"),
    }
    // after DEP LT the position is LEN further along the last element (+Y)
    close(line_pts(&m[4]).0[AxisLetter::Y], 32.5);
    // polar APPR PLCT, DEP LN / CT with CCA
    let ops = run(&program(
        "CC X+0 Y+0\nL X+30 Y+0 F100\nAPPR PLCT PR+10 PA+90 R5 RL\nL X-10\nDEP CT CCA 90 R+5",
    ));
    let m = motions(&ops);
    match &m[1] {
        OpKind::Approach { to, .. } => {
            close(to[AxisLetter::X], 0.0);
            close(to[AxisLetter::Y], 10.0);
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        m[3],
        OpKind::Depart {
            shape: ApproachShape::CircleTangent { cca, radius },
            ..
        } if cca == 90.0 && radius == 5.0
    ));
}

#[test]
fn appr_dep_bad_input() {
    let (ops, d) = run_until_error(&program("L X+0 Y+0 F100\nAPPR LT X+10 Y+0 LEN5"));
    assert!(d.message.contains("RL or RR"), "{}", d.message);
    assert_eq!(motions(&ops).len(), 1);
    let (_, d) = run_until_error(&program("L X+0 Y+0 F100\nDEP LT LEN5"));
    assert!(
        d.message.contains("without active radius compensation"),
        "{}",
        d.message
    );
    let (_, d) = run_until_error(&program("L X+0 Y+0 F100\nAPPR CT X+1 Y+1 CCA400 R5 RL"));
    assert!(d.message.contains("CCA"), "{}", d.message);
    let (_, d) = run_until_error(&program("L X+0 Y+0 F100\nAPPR LCT X+1 Y+1 RL"));
    assert!(d.message.contains("radius"), "{}", d.message);
    let (_, d) = run_until_error(&program("L X+0 Y+0 RL F100\nAPPR LT X+1 Y+1 LEN5 RL"));
    assert!(d.message.contains("already on"), "{}", d.message);
}

#[test]
fn cr_chord_longer_than_diameter_is_refused() {
    let (ops, d) = run_until_error(&program("L X+0 Y+0 F100\nCR X+30 Y+0 R+10 DR+"));
    assert_eq!(motions(&ops).len(), 1);
    assert!(d.message.contains("longer than 2R"), "{}", d.message);
}
