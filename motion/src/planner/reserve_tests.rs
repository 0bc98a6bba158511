//! A look-ahead that would hold more pieces or stops than the planner reserved stops taking
//! ops short of the reserve (back-pressure) and still runs the whole program to its end.

use super::test_machine::planner;
use super::{PIECE_MARGIN, RESERVED_PIECES, Step};
use klar_interp::{Feed, Op, OpKind, Pose, SourceLoc};

/// A zigzag of `n` chords along X, 0.02 mm forward and `across` mm across each, at
/// 100 mm/s: with 0.02 mm, corners of 90°, so every chord leaves pieces (and stops) of
/// its own (gentler ones are fitted over many chords).
fn chords(n: usize, across: f64) -> Vec<Op> {
    let at = |k: usize| Pose::xyz(0.02 * k as f64, across * (k % 2) as f64, 0.0);
    let mut ops = vec![Op {
        kind: OpKind::Line {
            from: Pose::ZERO,
            to: at(0),
            feed: Feed::Rate(100.0),
        },
        loc: SourceLoc::default(),
    }];
    ops.extend((1..=n).map(|k| Op {
        kind: OpKind::Line {
            from: at(k - 1),
            to: at(k),
            feed: Feed::Rate(100.0),
        },
        loc: SourceLoc::default(),
    }));
    ops
}

/// Runs the zigzag through the planner; returns the most pieces and markers it held, and
/// the periods in which it had ops left but did not ask for them before the look-ahead
/// distance was filled.
fn run(n: usize, across: f64) -> (usize, usize, u64) {
    let ops = chords(n, across);
    let end = match ops.last().map(|o| &o.kind) {
        Some(OpKind::Line { to, .. }) => *to,
        _ => unreachable!("the chords are lines"),
    };
    let mut p = planner();
    let capacity = (p.pieces.capacity(), p.markers.capacity());
    let (mut pieces, mut markers, mut waited, mut last) = (0usize, 0usize, 0u64, Pose::ZERO);
    let mut ops = ops.into_iter();
    loop {
        while p.needs_input() {
            match ops.next() {
                Some(op) => p.push(op).expect("a chord is accepted"),
                None => {
                    p.finish();
                    break;
                }
            }
        }
        pieces = pieces.max(p.pieces.len());
        markers = markers.max(p.markers.len());
        if ops.len() > 0 && p.committed_end - p.state.s < p.horizon {
            waited += 1;
        }
        match p.next_step() {
            Some(Step::Sample(s)) => last = s.pose,
            Some(Step::Event(_)) => {}
            None => break,
        }
    }
    // Neither queue grew, and the whole path was travelled.
    assert_eq!((p.pieces.capacity(), p.markers.capacity()), capacity);
    for i in 0..3 {
        assert!((last.0[i] - end.0[i]).abs() < 1e-6, "{last:?} {end:?}");
    }
    (pieces, markers, waited)
}

#[test]
fn the_look_ahead_stops_short_of_the_reserved_pieces_and_the_path_ends() {
    let (pieces, markers, waited) = run(12_000, 0.02);
    assert!(
        pieces + PIECE_MARGIN >= RESERVED_PIECES,
        "{pieces} pieces at most"
    );
    assert!(pieces <= RESERVED_PIECES, "{pieces} pieces at most");
    assert!(markers <= RESERVED_PIECES, "{markers} markers at most");
    assert!(waited > 0, "the look-ahead never waited for room");
}
