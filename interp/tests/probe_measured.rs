//! Measured probing: the interpreter waits at each probing move and takes the touch point
//! the machine answers with (its drives' latched positions), never a probe model's. The
//! answers here come from a bore placed where no model puts it; the cycle's results must be
//! that bore's, worked out in closed form.

mod common;

use klar_interp::{
    Blank, Interpreter, Op, OpKind, Pose, Probe, ProbeAnswer, ProbeData, ProbeRequest,
};

/// A model that always answers a touch 1 mm into the move: what measured probing must not
/// use.
#[derive(Debug)]
struct WrongModel;

impl Probe for WrongModel {
    fn touch(
        &mut self,
        from: [f64; 3],
        to: [f64; 3],
        _radius: f64,
        _blank: Option<&Blank>,
    ) -> Option<[f64; 3]> {
        let d: Vec<f64> = (0..3).map(|i| to[i] - from[i]).collect();
        let len = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        Some([0, 1, 2].map(|i| from[i] + d[i] / len))
    }
}

/// The true bore: centre (machine X, Y) and diameter.
const CENTRE: [f64; 2] = [-24.5, -9.75];
const DIAMETER: f64 = 24.6;
/// The probe's ball radius (klar's default probe data).
const BALL: f64 = 2.0;
/// How far the axes run past the trigger before they stand.
const OVERRUN: f64 = 0.3;

/// Where the ball centre triggers moving from `from` toward `to` inside the bore: at
/// distance (D/2 − ball) from the centre, the root of |from + t·u − c|² = ρ² with t > 0.
fn bore_answer(r: &ProbeRequest) -> ProbeAnswer {
    let d = [r.to[0] - r.from[0], r.to[1] - r.from[1]];
    let len = d[0].hypot(d[1]);
    let u = [d[0] / len, d[1] / len];
    let w = [r.from[0] - CENTRE[0], r.from[1] - CENTRE[1]];
    let rho = DIAMETER / 2.0 - BALL;
    let b = u[0] * w[0] + u[1] * w[1];
    let c = w[0] * w[0] + w[1] * w[1] - rho * rho;
    let t = -b + (b * b - c).sqrt();
    assert!(
        t > 0.0 && t <= len,
        "the bore lies within the probing distance"
    );
    let at = |s: f64| [r.from[0] + u[0] * s, r.from[1] + u[1] * s, r.from[2]];
    ProbeAnswer {
        trigger: Some(at(t)),
        stop: at(t + OVERRUN),
    }
}

/// Cycle 412 of `programs/probing_412.h` without its touch on the tool axis, in a program
/// of its own: the cycle's block on line 3, a move over the new datum after it.
fn program() -> String {
    let text = common::lathe::program_file("probing_412.h");
    let mut block = String::new();
    for line in text.lines().skip_while(|l| !l.starts_with("TCH PROBE 412")) {
        block += line;
        block += "\n";
        if !line.ends_with('~') {
            break;
        }
    }
    for (from, to) in [
        ("Q381=+1 ;", "Q381=+0 ;"),
        ("Q382=+30 ;", "Q382=+0 ;"),
        ("Q383=+25 ;", "Q383=+0 ;"),
    ] {
        assert!(block.contains(from), "{from} in {block}");
        block = block.replacen(from, to, 1);
    }
    format!("BEGIN PGM M MM\nL X-25 Y-10 Z+20 R0 FMAX\n{block}L X+0 Y+0 Z+50 FMAX\nEND PGM M MM\n")
}

fn start() -> Pose {
    let mut p = Pose::default();
    p[klar_interp::AxisLetter::Z] = 100.0;
    p
}

fn xyz(p: &Pose) -> [f64; 3] {
    use klar_interp::AxisLetter::{X, Y, Z};
    [p[X], p[Y], p[Z]]
}

/// What a run with measured probing gave.
struct Outcome {
    /// The ops handed out.
    ops: Vec<Op>,
    /// Each probing move asked for, with the number of ops handed out before it.
    asked: Vec<(ProbeRequest, usize)>,
    /// The interpreter (for its Q parameters).
    interp: Interpreter,
    /// The diagnostic that ended the program, if any.
    error: Option<String>,
}

/// Runs `text` with measured probing, answering each probing move with `answer`.
fn run(text: &str, mut answer: impl FnMut(&ProbeRequest) -> ProbeAnswer) -> Outcome {
    let mut interp = Interpreter::from_source("m.h", text, start())
        .with_probe(ProbeData::default(), Box::new(WrongModel))
        .with_measured_probing(ProbeData::default());
    let (mut ops, mut asked) = (Vec::new(), Vec::new());
    let mut error = None;
    loop {
        match interp.next() {
            Some(Ok(op)) => ops.push(op),
            Some(Err(d)) => {
                error = Some(d.to_string());
                break;
            }
            None => match interp.probe_request() {
                Some(r) => {
                    asked.push((r, ops.len()));
                    let a = answer(&r);
                    interp.answer_probe(a);
                }
                None => break,
            },
        }
        assert!(asked.len() < 100, "the cycle keeps asking");
    }
    Outcome {
        ops,
        asked,
        interp,
        error,
    }
}

#[test]
fn cycle_412_takes_the_measured_touch_points_not_the_model() {
    let Outcome {
        ops,
        asked,
        interp,
        error,
    } = run(&program(), bore_answer);
    assert_eq!(error, None);
    assert_eq!(asked.len(), 4, "four touch points, one wait each");
    // least squares through four points on one circle: that circle exactly
    assert!(
        (interp.q(151) - CENTRE[0]).abs() < 1e-9,
        "Q151 {}",
        interp.q(151)
    );
    assert!(
        (interp.q(152) - CENTRE[1]).abs() < 1e-9,
        "Q152 {}",
        interp.q(152)
    );
    assert!(
        (interp.q(153) - DIAMETER).abs() < 1e-9,
        "Q153 {}",
        interp.q(153)
    );
    for (r, at) in &asked {
        // the machine runs the probing move: the ops before it end where it starts, and the
        // first op after it leaves from where the axes came to rest, back to the start
        let before = ops[..*at].iter().rev().find_map(|o| match &o.kind {
            OpKind::Line { to, .. } | OpKind::Arc { to, .. } => Some(xyz(to)),
            _ => None,
        });
        let before = before.expect("a move before the probing move");
        assert!((0..3).all(|i| (before[i] - r.from[i]).abs() < 1e-9));
        let a = bore_answer(r);
        let after = ops[*at..].iter().find_map(|o| match &o.kind {
            OpKind::Line { from, to, .. } => Some((xyz(from), xyz(to))),
            _ => None,
        });
        let (from, to) = after.expect("the return move");
        assert!((0..3).all(|i| (from[i] - a.stop[i]).abs() < 1e-9));
        assert!((0..3).all(|i| (to[i] - r.from[i]).abs() < 1e-9));
        // the whole probing distance at the probing feed
        let len = (0..3).map(|i| (r.to[i] - r.from[i]).powi(2)).sum::<f64>();
        assert!((len.sqrt() - ProbeData::default().distance).abs() < 1e-9);
        assert_eq!(r.feed, ProbeData::default().feed);
    }
    // the program goes on after the cycle in the preset it set (no table: its op stream
    // is in the new program coordinates): the last move starts where the cycle left the
    // probe, seen from the measured centre
    let lines: Vec<_> = ops
        .iter()
        .filter_map(|o| match &o.kind {
            OpKind::Line { from, to, .. } => Some((xyz(from), xyz(to))),
            _ => None,
        })
        .collect();
    let [.., (_, left), (from, to)] = lines[..] else {
        panic!("moves before and after the cycle");
    };
    let shifted = [left[0] - CENTRE[0], left[1] - CENTRE[1], left[2]];
    assert!(
        (0..3).all(|i| (from[i] - shifted[i]).abs() < 1e-9),
        "{from:?} against {shifted:?}"
    );
    assert_eq!(to, [0.0, 0.0, 50.0]);
}

#[test]
fn a_probing_move_without_a_trigger_ends_in_touch_point_inaccessible() {
    let mut n = 0;
    let Outcome {
        ops, asked, error, ..
    } = run(&program(), |r| {
        n += 1;
        if n == 2 {
            // nothing found: the axes ran the whole probing distance and stand at its end
            ProbeAnswer {
                trigger: None,
                stop: r.to,
            }
        } else {
            bore_answer(r)
        }
    });
    assert_eq!(asked.len(), 2);
    let e = error.expect("an error");
    assert!(
        e.contains("m.h:3:") && e.contains("touch point inaccessible"),
        "{e}"
    );
    // no move after the unanswered touch: the program stops where the axes stand
    assert_eq!(ops.len(), asked[1].1);
}

#[test]
fn a_tnc_iso_probing_cycle_is_refused_before_it_moves_on_a_measuring_machine() {
    let iso = "%M G71 *
N10 G00 G40 G90 X-25 Y-10 Z+40 *
N20 G412 PRESET INSIDE CIRCLE
    Q321=-25   ;CENTER IN 1ST AXIS
    Q322=-10   ;CENTER IN 2ND AXIS
    Q262=+24   ;NOMINAL DIAMETER
    Q325=+0    ;STARTING ANGLE
    Q247=+90   ;STEPPING ANGLE
    Q261=-10   ;MEASURING HEIGHT
    Q320=+5    ;SET-UP CLEARANCE
    Q260=+20   ;CLEARANCE HEIGHT
    Q301=+0    ;MOVE TO CLEARANCE
    Q305=+0    ;NUMBER IN TABLE
    Q331=+0    ;DATUM
    Q332=+0    ;DATUM
    Q303=+1    ;MEAS. VALUE TRANSFER
    Q381=+0    ;PROBE IN TS AXIS
    Q423=+4    ;NO. OF PROBE POINTS
    Q365=+1    ;TYPE OF TRAVERSE *
N30 G00 X+0 Y+0 Z+50 *
N99999 %M G71 *
";
    let interp =
        Interpreter::from_source("m.i", iso, start()).with_measured_probing(ProbeData::default());
    let mut moves = Vec::new();
    let mut error = None;
    for item in interp {
        match item {
            Ok(op) => {
                if let OpKind::Line { to, .. } = op.kind {
                    moves.push(xyz(&to));
                }
            }
            Err(d) => {
                error = Some(d.to_string());
                break;
            }
        }
    }
    let e = error.expect("refused");
    assert!(e.contains("m.i:3:") && e.contains("G412"), "{e}");
    // only the move of the block before
    assert_eq!(moves, vec![[-25.0, -10.0, 40.0]]);
}
