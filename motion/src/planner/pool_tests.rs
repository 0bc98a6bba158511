//! A planner whose blend slots are all held stops exactly at the corners that find none,
//! counts them, and still runs the whole program; with its slots free the same corners are
//! blended.

use super::test_machine::planner;
use super::{Planner, Step};
use crate::blend::BlendPool;
use klar_interp::{Feed, Op, OpKind, Pose, SourceLoc};

/// X and Y of a 10 mm line at 15° to X.
const RISE: [f64; 2] = [9.659_258_262_890_683, 2.588_190_451_025_207_4];

/// The corners of a staircase of 10 mm lines in XY, each turning by 15° (gentle enough
/// to be blended at once): along X, up at 15°, along X, up at 15°.
const CORNERS: [[f64; 2]; 3] = [
    [10.0, 0.0],
    [10.0 + RISE[0], RISE[1]],
    [20.0 + RISE[0], RISE[1]],
];

/// Where the staircase ends.
const END: [f64; 2] = [20.0 + 2.0 * RISE[0], 2.0 * RISE[1]];

/// Distance of the last sample from the staircase's end.
fn off_end(samples: &[[f64; 2]]) -> f64 {
    samples
        .last()
        .map_or(f64::INFINITY, |p| (p[0] - END[0]).hypot(p[1] - END[1]))
}

/// The staircase's lines at 50 mm/s, from the origin to [`END`].
fn lines() -> Vec<Op> {
    let points = [[0.0, 0.0], CORNERS[0], CORNERS[1], CORNERS[2], END];
    points
        .windows(2)
        .map(|w| Op {
            kind: OpKind::Line {
                from: Pose::xyz(w[0][0], w[0][1], 0.0),
                to: Pose::xyz(w[1][0], w[1][1], 0.0),
                feed: Feed::Rate(50.0),
            },
            loc: SourceLoc::default(),
        })
        .collect()
}

/// The XY positions of every sample of the whole program.
fn run(p: &mut Planner) -> Vec<[f64; 2]> {
    for op in lines() {
        p.push(op).expect("a line is accepted");
    }
    p.finish();
    let mut out = Vec::new();
    while let Some(step) = p.next_step() {
        if let Step::Sample(s) = step {
            out.push([s.pose.0[0], s.pose.0[1]]);
        }
        assert!(out.len() < 100_000, "the program ends");
    }
    out
}

/// The smallest distance of the samples from `c`.
fn nearest(samples: &[[f64; 2]], c: [f64; 2]) -> f64 {
    samples
        .iter()
        .map(|p| (p[0] - c[0]).hypot(p[1] - c[1]))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn corners_that_find_no_free_slot_stop_exactly_and_are_counted() {
    // Every corner blended: the path passes each corner at a distance (the blend cuts it,
    // within the 0.01 mm tolerance).
    let mut free = planner();
    let path = run(&mut free);
    assert_eq!((free.blends_made(), free.blends_refused()), (3, 0));
    for c in CORNERS {
        let d = nearest(&path, c);
        assert!(d > 1e-4 && d < 0.01, "corner {c:?} passed at {d} mm");
    }
    assert!(off_end(&path) < 1e-9);
    // One slot: the whole staircase is committed before the machine moves (its look-ahead
    // reaches past the staircase's 40 mm), so the first corner's blend still holds the slot when the other
    // two are committed: those two stop exactly, on the corner itself.
    let mut short = planner();
    short.blends = BlendPool::new(1);
    let path = run(&mut short);
    assert_eq!((short.blends_made(), short.blends_refused()), (1, 2));
    assert!(nearest(&path, CORNERS[0]) > 1e-4);
    for c in &CORNERS[1..] {
        assert!(nearest(&path, *c) < 1e-9, "corner {c:?} not stopped at");
    }
    assert!(off_end(&path) < 1e-9);
}

#[test]
fn a_slot_is_reused_once_the_pieces_of_its_blend_are_passed() {
    // Two slots for three corners, the lines fed one at a time as a reader that falls
    // behind would: the path rests just after each corner's blend (its last committed
    // piece, which holds that blend's slot), the next line commits the next corner into the
    // other slot, and passing the first blend frees its slot for the third corner.
    let mut p = planner();
    p.blends = BlendPool::new(2);
    let mut ops = lines().into_iter();
    for op in ops.by_ref().take(2) {
        p.push(op).expect("a line is accepted");
    }
    let mut samples: Vec<[f64; 2]> = Vec::new();
    let mut finished = false;
    loop {
        let n = samples.len();
        let resting = n < 2 || samples[n - 1] == samples[n - 2];
        if resting && !finished {
            match ops.next() {
                Some(op) => p.push(op).expect("a line is accepted"),
                None => {
                    p.finish();
                    finished = true;
                }
            }
        }
        let step = if finished {
            p.next_step()
        } else {
            p.next_step_starved()
        };
        match step {
            Some(Step::Sample(s)) => samples.push([s.pose.0[0], s.pose.0[1]]),
            Some(Step::Event(_)) => {}
            None => break,
        }
        assert!(samples.len() < 100_000, "the program ends");
    }
    assert_eq!((p.blends_made(), p.blends_refused()), (3, 0));
    for c in CORNERS {
        let d = nearest(&samples, c);
        assert!(d > 1e-4 && d < 0.01, "corner {c:?} passed at {d} mm");
    }
    assert!(off_end(&samples) < 1e-9);
}
