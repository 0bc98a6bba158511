//! Property test: random lines, arcs, helices and splines with random axis limits and feeds never
//! drive an axis past its velocity, acceleration or jerk limit (finite differences of the
//! sampled positions, 1 % slack), never exceed the feed, and end exactly; nor do they when the
//! feed override changes and feed holds come at random times.

mod common;

use common::*;
use klar_interp::op::SplineAxis;
use klar_interp::{AxisLetter, Feed, Op, OpKind, Plane, Pose};
use klar_motion::{AxisLimits, Planner, Sample};
use proptest::prelude::*;

/// One random move, described independently of the planner.
#[derive(Debug, Clone)]
enum Move {
    Line {
        to: [f64; 3],
        feed: Option<f64>,
    },
    Arc {
        plane: usize,
        radius: f64,
        sweep: f64,
        rise: f64,
        feed: f64,
    },
    Spline {
        /// Chord from start to end.
        chord: [f64; 3],
        /// K3 and K2 per axis; K1 follows from the start point.
        k: [[f64; 2]; 3],
        feed: f64,
    },
}

fn move_strategy() -> impl Strategy<Value = Move> {
    prop_oneof![
        (
            prop::array::uniform3(-60.0f64..60.0),
            prop::option::weighted(0.8, 5.0f64..150.0)
        )
            .prop_map(|(to, feed)| Move::Line { to, feed }),
        (
            0usize..3,
            0.5f64..30.0,
            -720.0f64..720.0,
            -10.0f64..10.0,
            5.0f64..150.0
        )
            .prop_map(|(plane, radius, sweep, rise, feed)| Move::Arc {
                plane,
                radius,
                sweep,
                rise,
                feed,
            }),
        (
            prop::array::uniform3(-1.0f64..1.0),
            20.0f64..60.0,
            prop::array::uniform3(prop::array::uniform2(-3.0f64..3.0)),
            5.0f64..150.0
        )
            .prop_filter("chord direction must be defined", |(d, ..)| {
                d.iter().map(|x| x * x).sum::<f64>() > 0.01
            })
            .prop_map(|(d, len, k, feed)| {
                // Chord of length ≥ 20 against |K3|, |K2| ≤ 3: the parameter speed
                // |dP/du| ≥ |chord| − 2|K3| − |K2| stays far from zero (no cusp).
                let n = d.iter().map(|x| x * x).sum::<f64>().sqrt();
                Move::Spline {
                    chord: d.map(|x| x / n * len),
                    k,
                    feed,
                }
            }),
    ]
}

fn limits_strategy() -> impl Strategy<Value = AxisLimits> {
    (20.0f64..400.0, 200.0f64..5000.0, 2000.0f64..200_000.0).prop_map(|(v, a, j)| AxisLimits {
        max_velocity: v,
        max_acceleration: a,
        max_jerk: j,
    })
}

/// The planner configuration with these limits for X, Y and Z.
fn config_xyz(lx: AxisLimits, ly: AxisLimits, lz: AxisLimits) -> klar_motion::PlannerConfig {
    let mut limits = [None; 9];
    limits[0] = Some(lx);
    limits[1] = Some(ly);
    limits[2] = Some(lz);
    config(limits)
}

/// Turns the random moves into ops; arcs start where the tool is, with the centre placed
/// `radius` away at a fixed angle.
fn build(moves: &[Move]) -> (Vec<Op>, Vec<Option<f64>>, Pose) {
    let mut p = Pose::xyz(1.0, 2.0, 3.0);
    let mut ops = Vec::new();
    let mut feeds = Vec::new();
    for (k, m) in moves.iter().enumerate() {
        let n = k as u32 + 1;
        match *m {
            Move::Line { to, feed } => {
                let q = Pose::xyz(to[0], to[1], to[2]);
                ops.push(line(n, p, q, feed.map_or(Feed::Rapid, Feed::Rate)));
                feeds.push(feed);
                p = q;
            }
            Move::Arc {
                plane,
                radius,
                sweep,
                rise,
                feed,
            } => {
                let (plane, a, b, c) = match plane {
                    0 => (Plane::XY, 0, 1, 2),
                    1 => (Plane::ZX, 2, 0, 1),
                    _ => (Plane::YZ, 1, 2, 0),
                };
                let phi0: f64 = 0.7;
                let center = [p.0[a] - radius * phi0.cos(), p.0[b] - radius * phi0.sin()];
                let phi1 = phi0 + sweep.to_radians();
                let mut q = p;
                q.0[a] = center[0] + radius * phi1.cos();
                q.0[b] = center[1] + radius * phi1.sin();
                q.0[c] += rise;
                ops.push(arc(n, p, q, center, plane, sweep, Feed::Rate(feed)));
                feeds.push(Some(feed));
                p = q;
            }
            Move::Spline { chord, k, feed } => {
                let mut q = p;
                let mut axes = Vec::new();
                for (i, letter) in [AxisLetter::X, AxisLetter::Y, AxisLetter::Z]
                    .into_iter()
                    .enumerate()
                {
                    q.0[i] = p.0[i] + chord[i];
                    // Start = end + K3 + K2 + K1.
                    let k1 = p.0[i] - q.0[i] - k[i][0] - k[i][1];
                    axes.push(SplineAxis {
                        axis: letter,
                        k: [k[i][0], k[i][1], k1],
                    });
                }
                ops.push(op(
                    n,
                    OpKind::Spline {
                        from: p,
                        to: q,
                        axes,
                        feed: Feed::Rate(feed),
                    },
                ));
                feeds.push(Some(feed));
                p = q;
            }
        }
    }
    (ops, feeds, p)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn random_moves_respect_every_limit(
        moves in prop::collection::vec(move_strategy(), 1..4),
        lx in limits_strategy(),
        ly in limits_strategy(),
        lz in limits_strategy(),
    ) {
        let cfg = config_xyz(lx, ly, lz);
        let start = Pose::xyz(1.0, 2.0, 3.0);
        let (ops, feeds, end) = build(&moves);
        let r = run(cfg.clone(), start, ops);
        assert_within_limits(&cfg, &start, &r.samples, 1.01);
        for s in &r.samples {
            let idx = s.loc.line as usize - 1;
            if let Some(Some(f)) = feeds.get(idx) {
                let v = (s.velocity[0].powi(2) + s.velocity[1].powi(2) + s.velocity[2].powi(2)).sqrt();
                prop_assert!(v <= f * (1.0 + 1e-9), "speed {} above feed {}", v, f);
            }
        }
        if let Some(last) = r.samples.last() {
            for i in 0..3 {
                prop_assert!((last.pose.0[i] - end.0[i]).abs() <= 1e-9);
            }
        }
    }
}

/// A short spline, then a tight helix (r 0.5 mm) on axes with a jerk limit of 2000 mm/s³:
/// braking hard into the helix, with no ramp within every limit, the generator once took a
/// plain stop that overshot below zero speed, and the path turned back (X at 4.7 times its
/// jerk limit).
#[test]
fn braking_into_a_tight_helix_never_turns_the_path_back() {
    let moves = vec![
        Move::Spline {
            chord: [5.560822038288019, -16.169881472665363, 10.373629616409278],
            k: [[0.0, 0.0], [-1.9925931192762814, 0.0], [0.0, 0.0]],
            feed: 72.56598635528401,
        },
        Move::Arc {
            plane: 0,
            radius: 0.5,
            sweep: -332.8175074365912,
            rise: 2.450765307417682,
            feed: 117.2553635290041,
        },
    ];
    let axis = |v: f64, j: f64| AxisLimits {
        max_velocity: v,
        max_acceleration: 200.0,
        max_jerk: j,
    };
    let cfg = config_xyz(
        axis(20.0, 2000.0),
        axis(200.14302916465493, 112015.04087795762),
        axis(90.61147354321417, 2000.0),
    );
    let start = Pose::xyz(1.0, 2.0, 3.0);
    let (ops, _, end) = build(&moves);
    let r = run(cfg.clone(), start, ops);
    assert_within_limits(&cfg, &start, &r.samples, 1.01);
    let last = r.samples.last().map(|s| s.pose);
    assert!(last.is_some_and(|p| (0..3).all(|i| (p.0[i] - end.0[i]).abs() <= 1e-9)));
}

/// An operator's action at a time into the run.
#[derive(Debug, Clone, Copy)]
enum Control {
    /// Sets the feed override to this factor.
    Override(f64),
    /// Holds the feed for this many seconds, then resumes.
    Hold(f64),
}

fn control_strategy() -> impl Strategy<Value = (f64, Control)> {
    (
        0.0f64..2.0,
        prop_oneof![
            (0.1f64..1.5).prop_map(Control::Override),
            (0.01f64..0.5).prop_map(Control::Hold),
        ],
    )
}

/// Runs `ops` from `start`, acting on the planner as `controls` say before every step.
fn run_with_controls(
    cfg: &klar_motion::PlannerConfig,
    start: Pose,
    ops: Vec<Op>,
    controls: &[(f64, Control)],
) -> Vec<Sample> {
    let act = |planner: &mut Planner, samples: &[Sample]| {
        let t = samples.last().map_or(0.0, |s| s.t);
        let mut factor = 1.0;
        let mut held = false;
        for &(at, c) in controls.iter().filter(|(at, _)| *at <= t) {
            match c {
                Control::Override(f) => factor = f,
                Control::Hold(d) => held |= t < at + d,
            }
        }
        planner.set_feed_override(factor);
        if held {
            planner.hold();
        } else {
            planner.resume();
        }
    };
    run_controlled(cfg.clone(), start, ops, act).samples
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    #[ignore = "known defect: see a_feed_hold_before_a_piece_with_a_lower_jerk_stops_smoothly; the search finds such a case every few dozen programs; run with --ignored"]
    fn override_and_hold_keep_every_limit_and_end_exactly(
        moves in prop::collection::vec(move_strategy(), 1..4),
        lx in limits_strategy(),
        ly in limits_strategy(),
        lz in limits_strategy(),
        controls in prop::collection::vec(control_strategy(), 1..5),
    ) {
        let cfg = config_xyz(lx, ly, lz);
        let start = Pose::xyz(1.0, 2.0, 3.0);
        let (ops, _, end) = build(&moves);
        let samples = run_with_controls(&cfg, start, ops, &controls);
        assert_within_limits(&cfg, &start, &samples, 1.01);
        let last = samples.last().map(|s| s.pose);
        prop_assert!(
            last.is_some_and(|p| (0..3).all(|i| (p.0[i] - end.0[i]).abs() <= 1e-9)),
            "ends at {last:?}, not {end:?}"
        );
    }
}

/// A line into a helix, with a feed hold 1.15 s into the run. Known defect: while the path
/// brakes for the hold, a limit with a lower jerk 10 mm further on enters the look-ahead,
/// and the check judges the deceleration unable to come to rest with that jerk, although
/// the path stops long before it; the ramps it then takes ease too slowly, the speed
/// reaches zero with a deceleration of 357 mm/s² left and Y goes to twice its jerk limit.
/// Judging the easing with the current jerk where it ends before that limit fixes this case
/// but lets other random programs over a limit (`random_moves_respect_every_limit`).
#[test]
#[ignore = "known defect: a feed hold can stop with a step in acceleration where a piece with a lower jerk lies beyond the stopping point; run with --ignored"]
fn a_feed_hold_before_a_piece_with_a_lower_jerk_stops_smoothly() {
    let moves = vec![
        Move::Line {
            to: [-34.12316811727813, -27.448352241434456, 47.554127245210815],
            feed: Some(64.37070244450602),
        },
        Move::Arc {
            plane: 2,
            radius: 29.081123428483988,
            sweep: 569.9205884286991,
            rise: 8.563387815356618,
            feed: 67.1057191290921,
        },
    ];
    let axis = |v: f64, a: f64, j: f64| AxisLimits {
        max_velocity: v,
        max_acceleration: a,
        max_jerk: j,
    };
    let cfg = config_xyz(
        axis(373.7321125649325, 2838.995392178491, 159017.51344755257),
        axis(21.52127099835181, 2301.531620260747, 60296.352331347705),
        axis(46.05032508190075, 686.6150231507412, 6810.752370122756),
    );
    let start = Pose::xyz(1.0, 2.0, 3.0);
    let (ops, _, end) = build(&moves);
    let controls = [(1.1491671832354273, Control::Hold(0.28340385516935857))];
    let samples = run_with_controls(&cfg, start, ops, &controls);
    assert_within_limits(&cfg, &start, &samples, 1.01);
    let last = samples.last().map(|s| s.pose);
    assert!(last.is_some_and(|p| (0..3).all(|i| (p.0[i] - end.0[i]).abs() <= 1e-9)));
}
