//! 202 and 204 run from the example program and from its ISO twin: the ops the interpreter
//! emits, and where a bad parameter is reported.

use crate::op::{Feed, OpKind, SpindleDir};
use crate::{Interpreter, Pose};

fn ops(name: &str, text: &str) -> Vec<OpKind> {
    Interpreter::from_source(name, text, Pose::ZERO)
        .map(|r| r.unwrap_or_else(|d| panic!("{d}")).kind)
        .collect()
}

fn example() -> String {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../programs/cycle_boring.h");
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// One op in short: a line end point with its feed (mm/min, 0 for rapid), a dwell, or a
/// spindle direction.
#[derive(Debug, PartialEq)]
enum Step {
    L([f64; 3], f64),
    Dwell(f64),
    S(SpindleDir),
}

fn steps(ops: &[OpKind]) -> Vec<Step> {
    ops.iter()
        .filter_map(|o| match o {
            OpKind::Line { to, feed, .. } => {
                let f = match feed {
                    Feed::Rate(v) => (v * 60.0 * 1e9).round() / 1e9,
                    _ => 0.0,
                };
                let p = to.0;
                let r = |v: f64| (v * 1e9).round() / 1e9;
                Some(Step::L([r(p[0]), r(p[1]), r(p[2])], f))
            }
            OpKind::Dwell { seconds } => Some(Step::Dwell(*seconds)),
            OpKind::Spindle { dir, .. } => Some(Step::S(*dir)),
            _ => None,
        })
        .collect()
}

#[test]
fn example_bores_through_then_counterbores_the_underside() {
    let s = steps(&ops("cycle_boring.h", &example()));
    use SpindleDir::{Cw, Off};
    use Step::{Dwell, L, S};
    // 202 at X25 Y25: set-up clearance 2, depth -22 at 100 mm/min, dwell 0.5, oriented
    // stop, 0.2 towards -X at Q208 = 250 mm/min, out at 250, centre, M3, to Z+50
    let hole = [
        L([25.0, 25.0, 2.0], 0.0),
        L([25.0, 25.0, -22.0], 100.0),
        Dwell(0.5),
        S(Off),
        L([24.8, 25.0, -22.0], 250.0),
        L([24.8, 25.0, 2.0], 250.0),
        L([25.0, 25.0, 2.0], 0.0),
        S(Cw),
        L([25.0, 25.0, 50.0], 0.0),
    ];
    let at = s.iter().position(|x| *x == hole[0]).expect("first hole");
    assert_eq!(s[at..at + hole.len()], hole);
    // 204 at the same hole: bar offset 3.5 towards -X at the clearance, through at 750 until
    // the edge (15 above the tip) is 2 below the underside Z-20 (tip -37), centre, M3,
    // counterbore 5 deep at 200 (edge -15, tip -30), dwell, stop, offset, out, centre, M3
    let back = [
        L([25.0, 25.0, 2.0], 0.0),
        S(Off),
        L([21.5, 25.0, 2.0], 0.0),
        L([21.5, 25.0, -37.0], 750.0),
        L([25.0, 25.0, -37.0], 750.0),
        S(Cw),
        L([25.0, 25.0, -30.0], 200.0),
        Dwell(0.5),
        S(Off),
        L([21.5, 25.0, -30.0], 750.0),
        L([21.5, 25.0, 2.0], 750.0),
        L([25.0, 25.0, 2.0], 0.0),
        S(Cw),
        L([25.0, 25.0, 50.0], 0.0),
    ];
    let at = s.iter().position(|x| *x == back[2]).expect("back boring") - 2;
    assert_eq!(s[at..at + back.len()], back);
}

const ISO_TWIN: &str = "%CYCLE_BORING G71 *
N10 G30 G17 X+0 Y+0 Z-20 *
N20 G31 G90 X+100 Y+100 Z+0 *
N30 G99 T1 L+80 R+6 *
N40 G99 T2 L+90 R+4 *
N50 T1 G17 S800 F100 *
N60 G00 G40 Z+50 M03 *
N70 G202 BORING
    Q200=+2 Q201=-22 Q206=+100 Q211=+0.5 Q208=+250
    Q203=+0 Q204=+50 Q214=+1 Q336=+0 *
N80 G00 G40 X+25 Y+25 M99 *
N90 G00 G40 X+75 Y+25 M99 *
N100 T2 G17 S600 F80 *
N110 G00 G40 Z+50 M03 *
N120 G204 BACK BORING
    Q200=+2 Q249=+5 Q250=+20 Q251=+3.5 Q252=+15 Q253=+750
    Q254=+200 Q255=+0.5 Q203=+0 Q204=+50 Q214=+1 Q336=+0 *
N130 G00 G40 X+25 Y+25 M99 *
N140 G00 G40 Z+100 M05 *
N99999999 %CYCLE_BORING G71 *
";

#[test]
fn iso_g202_g204_match_the_klartext_example() {
    let k = steps(&ops("cycle_boring.h", &example()));
    let i = steps(&ops("cycle_boring.i", ISO_TWIN));
    assert!(k.len() > 40, "{k:?}");
    assert_eq!(k, i);
}

/// The first error of `text` as `(line, col, message)`, and the ops before it.
fn first_error(name: &str, text: &str) -> ((usize, usize, String), Vec<OpKind>) {
    let mut before = Vec::new();
    for r in Interpreter::from_source(name, text, Pose::ZERO) {
        match r {
            Ok(op) => before.push(op.kind),
            Err(d) => {
                let shown = d.to_string();
                let rest = shown
                    .strip_prefix(&format!("{name}:"))
                    .unwrap_or_else(|| panic!("{shown}"));
                let mut parts = rest.splitn(3, ':');
                let mut num = || parts.next().and_then(|v| v.parse::<usize>().ok());
                let (line, col) = (num(), num());
                let msg = parts.next().unwrap_or("").trim().to_string();
                return ((line.expect("line"), col.expect("col"), msg), before);
            }
        }
    }
    panic!("no error in {name}");
}

/// 1-based number of the first line of `text` that starts with `start`.
fn line_of(text: &str, start: &str) -> usize {
    text.lines()
        .position(|l| l.starts_with(start))
        .map(|i| i + 1)
        .unwrap_or_else(|| panic!("no line {start}"))
}

#[test]
fn range_errors_are_reported_at_the_call_without_motion() {
    let good = example();
    // Q214 = 0 is no way through the hole for the back boring bar
    let cut = good.rfind("Q214=+1").expect("Q214 of 204");
    let bad = format!("{}Q214=+0{}", &good[..cut], &good[cut + 7..]);
    let ((line, col, msg), before) = first_error("bad.h", &bad);
    assert_eq!(line, line_of(&bad, "13 L X+25 Y+25"));
    assert!(col >= 1);
    assert!(msg.contains("cycle 204: Q214 = 0 is out of range"), "{msg}");
    // nothing of the calling block ran: the last move is the end of the second 202 hole
    let last = before.iter().rev().find_map(|o| match o {
        OpKind::Line { to, .. } => Some(to.0),
        _ => None,
    });
    let last = last.expect("moves before the error");
    assert_eq!([last[0], last[1], last[2]], [75.0, 25.0, 50.0]);
    assert!(
        !before
            .iter()
            .rev()
            .take_while(|o| !matches!(o, OpKind::ToolChange { .. }))
            .any(|o| matches!(
                o,
                OpKind::Spindle {
                    dir: SpindleDir::Off,
                    ..
                }
            ))
    );
    // Q214 = 5 on 202: reported at the first call
    let bad = good.replacen("Q214=+1", "Q214=+5", 1);
    let ((line, _, msg), before) = first_error("bad.h", &bad);
    assert_eq!(line, line_of(&bad, "8  L X+25 Y+25"));
    assert!(msg.contains("cycle 202: Q214 = 5 is out of range"), "{msg}");
    assert!(!before.iter().any(|o| matches!(o, OpKind::Dwell { .. })));
    // a counterbore depth of 0 in the ISO twin
    let bad = ISO_TWIN.replace("Q249=+5", "Q249=+0");
    let ((line, _, msg), _) = first_error("bad.i", &bad);
    assert_eq!(line, line_of(&bad, "N130"));
    assert!(msg.contains("cycle 204: Q249 = 0 is out of range"), "{msg}");
}
