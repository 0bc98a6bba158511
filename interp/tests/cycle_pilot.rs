//! SL cycle 21 PILOT DRILLING: a hole wherever cycle 22 with the rough-out tool Q13 plunges,
//! down to the rough-out floor in infeeds of at most Q10, each hole clear of the contour by the
//! rough-out tool's radius plus the side allowance.

use klar_interp::{Feed, Interpreter, Op, OpKind, Pose};

fn ops_of(text: &str) -> Vec<Op> {
    Interpreter::from_source("pilot.h", text, Pose::ZERO)
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|d| panic!("{d}"))
}

/// The program: a 70 × 60 pocket (LBL 1, clockwise with RR: the tool inside), depth 7 with a
/// floor allowance of 1, rough-out tool 1 (R 4), side allowance 0.5; `call` is the cycle run.
fn program(call: &str) -> String {
    format!(
        "0 BEGIN PGM PILOT MM
1 TOOL DEF 1 L+60 R+4
2 TOOL DEF 2 L+70 R+2
3 TOOL CALL {tool} Z S3000 F500
4 L Z+50 R0 FMAX M3
5 CYCL DEF 14.0 CONTOUR
6 CYCL DEF 14.1 CONTOUR LABEL1
7 CYCL DEF 20 CONTOUR DATA ~
  Q1=-7 ;DEPTH ~
  Q2=+1 ;OVERLAP ~
  Q3=+0.5 ;SIDE ~
  Q4=+1 ;FLOOR ~
  Q5=+0 ;SURFACE ~
  Q6=+2 ;SET-UP CLEARANCE ~
  Q7=+50 ;CLEARANCE HEIGHT ~
  Q8=+0 ;ROUNDING ~
  Q9=+1 ;DIRECTION
8 {call}
9 CYCL CALL
10 L Z+50 R0 FMAX M30
11 LBL 1
12 L X+10 Y+10 RR
13 L X+10 Y+70
14 L X+80 Y+70
15 L X+80 Y+10
16 L X+10 Y+10
17 LBL 0
18 END PGM PILOT MM
",
        tool = if call.contains("CYCL DEF 21") { 2 } else { 1 },
    )
}

/// (X, Y) of the feed moves straight down that start at the set-up clearance (Z+2), and the
/// depths every straight-down feed move reaches, per point.
fn plunges(ops: &[Op]) -> (Vec<[f64; 2]>, Vec<Vec<f64>>) {
    let mut points: Vec<[f64; 2]> = Vec::new();
    let mut depths: Vec<Vec<f64>> = Vec::new();
    for op in ops {
        if let OpKind::Line {
            from,
            to,
            feed: Feed::Rate(_),
        } = &op.kind
        {
            let (f, t) = (from.0, to.0);
            let vertical = (f[0] - t[0]).abs() < 1e-9 && (f[1] - t[1]).abs() < 1e-9;
            if vertical && t[2] < f[2] {
                if (f[2] - 2.0).abs() < 1e-9 {
                    points.push([t[0], t[1]]);
                    depths.push(Vec::new());
                }
                if let Some(d) = depths.last_mut() {
                    d.push(t[2]);
                }
            }
        }
    }
    (points, depths)
}

#[test]
fn pilot_holes_are_where_the_rough_out_plunges() {
    let pilot = ops_of(&program(
        "CYCL DEF 21 PILOT DRILLING ~\n  Q10=-2.5 ;PLUNGING DEPTH ~\n  Q11=+100 ;FEED ~\n  Q13=+1 ;ROUGH-OUT TOOL",
    ));
    let rough = ops_of(&program(
        "CYCL DEF 22 ROUGH-OUT ~\n  Q10=-2.5 ;PLUNGING DEPTH ~\n  Q11=+100 ;FEED PLUNGING ~\n  Q12=+400 ;FEED MILLING",
    ));
    let (holes, depths) = plunges(&pilot);
    let (mut plunge_points, _) = plunges(&rough);
    assert!(!holes.is_empty());
    // every hole is one of the rough-out's plunge points, and every plunge point has a hole
    plunge_points.dedup_by(|a, b| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-6);
    for p in &plunge_points {
        assert!(
            holes
                .iter()
                .any(|h| (h[0] - p[0]).hypot(h[1] - p[1]) < 1e-6),
            "no pilot hole at the plunge point {p:?} (holes {holes:?})"
        );
    }
    for h in &holes {
        assert!(
            plunge_points
                .iter()
                .any(|p| (h[0] - p[0]).hypot(h[1] - p[1]) < 1e-6),
            "hole {h:?} where the rough-out never plunges"
        );
        // clear of the pocket walls by the rough-out radius 4 plus the allowance 0.5
        let wall = (h[0] - 10.0)
            .min(80.0 - h[0])
            .min(h[1] - 10.0)
            .min(70.0 - h[1]);
        assert!(wall >= 4.5 - 1e-6, "hole {h:?} {wall} mm from the wall");
    }
    // infeeds of at most 2.5 down to the rough-out floor −7 + 1 = −6: −2.5, −5, −6
    for d in &depths {
        assert_eq!(d.len(), 3, "{d:?}");
        for (got, want) in d.iter().zip([-2.5, -5.0, -6.0]) {
            assert!((got - want).abs() < 1e-9, "{d:?}");
        }
    }
}

#[test]
fn pilot_drilling_needs_the_rough_out_tool_in_the_table() {
    let text = program(
        "CYCL DEF 21 PILOT DRILLING ~\n  Q10=-2.5 ;PLUNGING DEPTH ~\n  Q11=+100 ;FEED ~\n  Q13=+7 ;ROUGH-OUT TOOL",
    );
    let err = Interpreter::from_source("pilot.h", &text, Pose::ZERO)
        .find_map(Result::err)
        .expect("an error");
    assert!(err.message.contains("rough-out tool Q13"), "{err}");
    // reported at the CYCL CALL (block 9)
    assert_eq!((err.line, err.block), (22, Some(9)), "{err}");
}
