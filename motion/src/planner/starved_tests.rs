//! A planner whose input stops arriving (its source fell behind) brakes for the end of the
//! committed path within the limits, rests there, and goes on when input comes again.

use super::Step;
use super::test_machine::planner;
use klar_interp::{Feed, Op, OpKind, Pose, SourceLoc};

/// Twenty 10 mm lines along X at the machine's top speed.
fn lines() -> Vec<Op> {
    (0..20)
        .map(|i| Op {
            kind: OpKind::Line {
                from: Pose::xyz(10.0 * f64::from(i), 0.0, 0.0),
                to: Pose::xyz(10.0 * f64::from(i + 1), 0.0, 0.0),
                feed: Feed::Rate(100.0),
            },
            loc: SourceLoc::default(),
        })
        .collect()
}

#[test]
fn a_starved_planner_brakes_within_its_limits_rests_and_goes_on() {
    let mut p = planner();
    let mut ops = lines().into_iter();
    let mut pushed_to = 0.0;
    let mut x = Vec::new();
    // 0.3 s fed as the planner asks, then nothing for 2.5 s (its look-ahead holds less).
    let mut starved_from = None;
    for cycle in 0..2800 {
        let starving = cycle >= 300;
        if !starving {
            while p.needs_input() {
                let op = ops.next().expect("more lines than 0.3 s needs");
                if let OpKind::Line { to, .. } = &op.kind {
                    pushed_to = to.0[0];
                }
                p.push(op).expect("op accepted");
            }
        }
        let step = if starving {
            starved_from.get_or_insert(x.len());
            p.next_step_starved()
        } else {
            p.next_step()
        };
        match step {
            Some(Step::Sample(s)) => x.push(s.pose.0[0]),
            other => panic!("a sample every cycle, got {other:?}"),
        }
    }
    let from = starved_from.expect("starved");
    let dt = 0.001;
    // Moving at full speed when the input stopped.
    let v0 = (x[from - 1] - x[from - 2]) / dt;
    assert!(v0 > 99.0, "{v0} mm/s before the starvation");
    // Braked within the acceleration limit (finite differences, independent of the planner).
    for w in x[from - 2..].windows(3) {
        let a = (w[2] - 2.0 * w[1] + w[0]) / (dt * dt);
        assert!(a.abs() <= 1000.0 * 1.001, "acceleration {a} mm/s²");
    }
    // At rest, short of the end of what was pushed, without going back.
    let rest = x[x.len() - 1];
    assert!(
        x[x.len() - 100..].iter().all(|&v| v == rest),
        "at rest: {:?}, pushed to {pushed_to}, starved from {}",
        &x[x.len() - 5..],
        x[from]
    );
    assert!(x.windows(2).all(|w| w[1] >= w[0]), "never backwards");
    assert!(
        rest <= pushed_to + 1e-9 && rest > x[from],
        "{rest} of {pushed_to}"
    );
    // Input again: the path goes on to the last line's end.
    let mut last = rest;
    loop {
        while p.needs_input() {
            match ops.next() {
                Some(op) => p.push(op).expect("op accepted"),
                None => p.finish(),
            }
        }
        match p.next_step() {
            Some(Step::Sample(s)) => last = s.pose.0[0],
            Some(Step::Event(_)) => {}
            None => break,
        }
    }
    assert!((last - 200.0).abs() < 1e-9, "ends at {last}");
}
