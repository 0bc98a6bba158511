//! Property test for dense code: random smooth curves in short chords with coordinates
//! rounded as a post-processor prints them, now and then a sharp corner, random limits and
//! feeds. The path stays within the tolerance of the programmed polyline, every axis within
//! its limits (finite differences, 1 % slack), and it ends exactly on the last point. The
//! same holds with feed holds and override changes at random times.

mod common;

use common::*;
use klar_interp::{Feed, Op, Pose};
use proptest::prelude::*;

/// A random dense program, described independently of the planner.
#[derive(Debug, Clone)]
struct Dense {
    /// Radius of the base circle (mm).
    radius: f64,
    /// Amplitude and wave number of a radial wave on it (a curvature that varies).
    wave: (f64, f64),
    /// Chord length (mm).
    chord: f64,
    /// Chords in all.
    chords: usize,
    /// Rounding step of the coordinates (mm).
    round: f64,
    /// Every how many chords the curve turns sharply (0: never).
    corner_every: usize,
    /// Feed (mm/s): below the axes' speed limit (a share of it), so that the curve's own
    /// limits and the feed decide the speed.
    feed: f64,
    /// Axis limits: speed, acceleration, jerk.
    limits: (f64, f64, f64),
    /// Rise in Z over the whole program (a helix-like curve when not 0).
    rise: f64,
}

fn dense_strategy() -> impl Strategy<Value = Dense> {
    (
        2.0f64..80.0,
        (0.0f64..0.3, 1.0f64..6.0),
        prop_oneof![0.005f64..0.02, 0.02f64..0.1, 0.1f64..0.4],
        200usize..2500,
        prop_oneof![Just(1e-3), Just(1e-4), Just(1e-6)],
        prop_oneof![Just(0usize), 50usize..400],
        (0.05f64..0.8),
        (50.0f64..300.0, 300.0f64..3000.0, 5e3f64..2e5),
        prop_oneof![Just(0.0), -5.0f64..5.0],
    )
        .prop_map(
            |(radius, wave, chord, chords, round, corner_every, share, limits, rise)| Dense {
                radius,
                wave,
                chord,
                chords,
                round,
                corner_every,
                feed: share * limits.0,
                limits,
                rise,
            },
        )
}

/// The program's points: a wavy circle (radius r·(1 + w·sin(k·φ))) walked in chords of
/// about `chord`, turning back by 90° every `corner_every` chords, rounded.
fn points(d: &Dense) -> Vec<Pose> {
    let q = |x: f64| (x / d.round).round() * d.round;
    let mut pts = Vec::with_capacity(d.chords + 1);
    let (mut phi, mut heading) = (0.0f64, 0.0f64);
    let mut at = [0.0f64, 0.0];
    for k in 0..=d.chords {
        if k > 0 {
            let r = d.radius * (1.0 + d.wave.0 * (d.wave.1 * phi).sin());
            let step = d.chord / r;
            phi += step;
            heading += step;
            if d.corner_every > 0 && k % d.corner_every == 0 {
                heading += std::f64::consts::FRAC_PI_2;
            }
            at[0] += d.chord * heading.cos();
            at[1] += d.chord * heading.sin();
        }
        let z = d.rise * k as f64 / d.chords as f64;
        pts.push(Pose::xyz(q(at[0]), q(at[1]), q(z)));
    }
    pts.dedup_by(|a, b| linear_distance(a, b) == 0.0);
    pts
}

/// The chords through `pts` at `d`'s feed, and the planner configuration with its limits.
fn program(d: &Dense, pts: &[Pose]) -> (Vec<Op>, klar_motion::PlannerConfig) {
    let ops = pts
        .windows(2)
        .enumerate()
        .map(|(k, w)| line(k as u32 + 1, w[0], w[1], Feed::Rate(d.feed)))
        .collect();
    let (v, a, j) = d.limits;
    (ops, config(limits_xyz(v, a, j)))
}

/// Runs `d` and checks the samples: within the axis limits (1 % slack), within the
/// tolerance of the polyline, ending exactly on its last point.
fn check_dense(d: &Dense) -> Result<(), TestCaseError> {
    let pts = points(d);
    prop_assume!(pts.len() > 10);
    let (ops, cfg) = program(d, &pts);
    let run = run(cfg.clone(), pts[0], ops);
    assert_within_limits(&cfg, &pts[0], &run.samples, 1.01);
    let last = run.samples.last().expect("samples");
    let end = pts[pts.len() - 1];
    prop_assert!(
        linear_distance(&last.pose, &end) <= 1e-9,
        "ends at {:?}",
        last.pose
    );
    in_band(d, &cfg, &pts, &run.samples, 1.1)
}

/// Checks that every sample lies within the tolerance of the polyline `pts` near where the
/// path is: the nearest chord among those one period's travel (at `speed` times the feed)
/// can reach from the last one (the curve may cross itself).
fn in_band(
    d: &Dense,
    cfg: &klar_motion::PlannerConfig,
    pts: &[Pose],
    samples: &[klar_motion::Sample],
    speed: f64,
) -> Result<(), TestCaseError> {
    let reach = (speed * d.feed * cfg.period / d.chord).ceil() as usize + 8;
    let mut k = 0usize;
    for s in samples {
        let from = k.saturating_sub(4);
        let to = (k + reach).min(pts.len() - 1);
        let (best, dist) = (from..to)
            .map(|i| (i, segment_distance(&s.pose, &pts[i], &pts[i + 1])))
            .fold((k, f64::INFINITY), |m, x| if x.1 < m.1 { x } else { m });
        prop_assert!(
            dist <= cfg.tolerance + 1e-6,
            "{dist} mm off the polyline near chord {best}"
        );
        k = best;
    }
    Ok(())
}

/// Programs the random search found over a limit, each with the defect it showed. They
/// must stay within the limits now.
#[test]
fn programs_that_once_went_over_a_limit_stay_within_them() {
    let cases = [
        // A wave on an R61.7 circle in 0.056 mm chords rounded to 1 µm, turning by 90° every
        // 330 chords: the path sped up past a limit below the feed while braking was already
        // due for the stop at a corner behind it, and came to that stop 17 µm late.
        Dense {
            radius: 61.74933444004471,
            wave: (0.20465218032954327, 1.4037864411151797),
            chord: 0.056150680552710844,
            chords: 2178,
            round: 1e-3,
            corner_every: 330,
            feed: 157.55663479439542,
            limits: (257.81248534603805, 1272.3965890980344, 87100.46479903525),
            rise: 0.0,
        },
        // A wavy helix at twice the speed its axes allow, turning towards Y piece by piece:
        // each chord's limit lies less than 1 % below the one before, and Y ran 16 % over its
        // speed limit when such drifts were met one by one.
        Dense {
            radius: 53.06535771774638,
            wave: (0.2809871097343579, 1.5933403735231297),
            chord: 0.1650731956526395,
            chords: 2277,
            round: 1e-6,
            corner_every: 0,
            feed: 403.0874464628135,
            limits: (209.75679908986623, 1377.9813573101528, 122899.06280688435),
            rise: 3.401951554819407,
        },
        // A wavy R75 curve on axes with a jerk limit of 5000 mm/s³: which pieces counted as
        // limits started from the piece the path was on, so a piece ahead faster than that
        // one, settled low by those after it, turned up as a limit only once the path moved
        // on, below the braking curve it was on; the end stop came 0.6 µm late.
        Dense {
            radius: 74.92106417021758,
            wave: (0.24087883247913486, 3.841300145829078),
            chord: 0.1782975312219559,
            chords: 1519,
            round: 1e-3,
            corner_every: 0,
            feed: 133.82636955824557,
            limits: (269.6383370920166, 2757.0302019127835, 5000.0),
            rise: 0.0,
        },
        // An R5.4 wave in 0.009 mm chords rounded to 1 µm with a corner 4 chords before the
        // end, on axes with a jerk limit of 5000 mm/s³: a positive acceleration was eased
        // with the current piece's jerk only when the whole easing ended before the next
        // drop in jerk, else with the lower jerk throughout; one period's difference made
        // the braking need jump and the X axis reached 2.7 times its acceleration limit.
        Dense {
            radius: 5.3704993233560305,
            wave: (0.15800004887159919, 1.9839535801376817),
            chord: 0.00907285852196737,
            chords: 302,
            round: 1e-3,
            corner_every: 298,
            feed: 75.88231113854242,
            limits: (179.05984749738616, 1751.718113843781, 5000.0),
            rise: 0.0,
        },
        // An R43.8 wave in 0.011 mm chords rounded to 0.1 µm, 4.9 mm long: speeding up from
        // the start, the path missed a limit 2.1 mm ahead that it was still below but could
        // no longer ease into, and that limit stood for the end stop behind it: the ramp
        // towards it kept speeding up and the stop came late (X at 2.4 times its
        // acceleration limit).
        Dense {
            radius: 43.80170480554279,
            wave: (0.18608837117747404, 1.9027203329403946),
            chord: 0.010796272075360717,
            chords: 457,
            round: 1e-4,
            corner_every: 0,
            feed: 201.3063054452971,
            limits: (289.97783326230194, 2163.95378598907, 34234.84344396176),
            rise: 0.0,
        },
        // An R33.5 wave rising 4.3 mm in 0.069 mm chords rounded to 0.1 µm, a 90° corner
        // every 174 chords, jerk 8186 mm/s³: speeding up towards a limit above its speed
        // but too close to ease into with the limit's jerk, the path followed a ramp
        // planned with the window's higher jerk, which eases later than the check allows
        // where the jerk drops on the way; it missed the next corner stop (X at 5.7 times
        // its acceleration limit).
        Dense {
            radius: 33.454902131552885,
            wave: (0.12128059884669713, 3.5119368628822767),
            chord: 0.06850298159695997,
            chords: 1590,
            round: 1e-4,
            corner_every: 174,
            feed: 141.26508652634485,
            limits: (275.9535598148392, 2727.9536006849726, 8185.699948426571),
            rise: 4.3017607983292745,
        },
        // An R66.8 wave falling 3.6 mm in 0.38 mm chords, jerk 12 550 mm/s³: braking for the
        // end stop, the path passed limits the backward pass had settled for an arrival
        // without acceleration faster than they allow, which no ramp could then keep; the
        // fallback followed the worst of them, not the stop's braking curve, and the stop
        // came 0.3 µm late (in finite differences X at 21 times its jerk limit).
        Dense {
            radius: 66.78495622843249,
            wave: (0.2576040076918281, 5.982709978828662),
            chord: 0.3773164044014886,
            chords: 458,
            round: 1e-6,
            corner_every: 0,
            feed: 153.7911767347449,
            limits: (267.5722154692818, 1095.9250289235347, 12549.75181647992),
            rise: -3.6362599350070384,
        },
        // The same on a short R36.8 wave in 0.015 mm chords rounded to 1 µm (the end stop
        // 1 µm late, X at 28 times its jerk limit).
        Dense {
            radius: 36.83150400716625,
            wave: (0.125350112728669, 3.8087282492445436),
            chord: 0.015327608568816768,
            chords: 240,
            round: 1e-3,
            corner_every: 0,
            feed: 122.03410221495456,
            limits: (289.3032123015573, 1629.1210260430203, 23011.238861272443),
            rise: -3.961609539573245,
        },
        // An R4.5 wave in 0.015 mm chords rounded to 0.1 µm with a 90° corner every 80
        // chords, jerk limit 66 500 mm/s³: when a piece shared a lower jerk limit only with
        // its neighbour's own limit (not one the neighbour took from the piece before it),
        // a corner stop was reached still braking (0.04 mm/s, −59 mm/s²) and X stepped to
        // 2.2× its jerk limit.
        Dense {
            radius: 4.498684721188688,
            wave: (0.1281693087960613, 3.0306814211467725),
            chord: 0.014790542576292311,
            chords: 320,
            round: 0.0001,
            corner_every: 80,
            feed: 113.98166087593096,
            limits: (174.3009624168831, 736.787290489304, 66496.85960544352),
            rise: 0.0,
        },
        // An R59.8 wave rising 5 mm in 0.005 mm chords rounded to 1 µm with a 90° corner
        // every 328 chords, and an R56.5 circle falling 1.5 mm in 0.011 mm chords rounded to
        // 0.1 µm with one every 55: braking through the limits before a corner stop towards
        // the stop itself, the path rode the stop's exact braking curve from far away, came
        // 0.08 µm late and was clamped onto it (Y at 1.35 and Z at 1.7 times their jerk
        // limit in the first, X at 1.13 times in the second).
        Dense {
            radius: 59.8352538744643,
            wave: (0.282689831557529, 1.0),
            chord: 0.005,
            chords: 1298,
            round: 1e-6,
            corner_every: 328,
            feed: 33.00504868683263,
            limits: (289.0502449671166, 1778.7752998269586, 110204.7844104287),
            rise: 4.974922652860331,
        },
        Dense {
            radius: 56.53982469982262,
            wave: (0.0, 1.0),
            chord: 0.010642020812181598,
            chords: 298,
            round: 0.0001,
            corner_every: 55,
            feed: 114.86939337916027,
            limits: (164.85082992795742, 2366.1739316392864, 66255.69628637403),
            rise: -1.4570029130362996,
        },
    ];
    for d in &cases {
        if let Err(e) = check_dense(d) {
            panic!("{e} in {d:?}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn dense_code_stays_in_the_band_and_the_limits_and_ends_exactly(d in dense_strategy()) {
        check_dense(&d)?;
    }
}

/// An operator's actions during a dense program: at a time (s), a feed hold (for
/// 0.01–0.5 s, by the second number) or an override (0.1–1.5, by it).
type Controls = Vec<(f64, bool, f64)>;

/// Controls at shares of a program's time at the feed.
fn controls_strategy() -> impl Strategy<Value = Controls> {
    prop::collection::vec((0.0f64..1.0, any::<bool>(), 0.0f64..1.0), 1..5)
}

/// Runs `d` with `controls` and checks the axis limits (1 % slack), the tolerance band and
/// the exact end.
fn check_controlled(d: &Dense, controls: &Controls) -> Result<(), TestCaseError> {
    let pts = points(d);
    prop_assume!(pts.len() > 10);
    let (ops, cfg) = program(d, &pts);
    let act = |planner: &mut klar_motion::Planner, samples: &[klar_motion::Sample]| {
        let t = samples.last().map_or(0.0, |s| s.t);
        let (mut factor, mut held) = (1.0, false);
        for &(at, hold, x) in controls.iter().filter(|c| c.0 <= t) {
            if hold {
                held |= t < at + 0.01 + 0.49 * x;
            } else {
                factor = 0.1 + 1.4 * x;
            }
        }
        planner.set_feed_override(factor);
        if held {
            planner.hold();
        } else {
            planner.resume();
        }
    };
    let run = run_controlled(cfg.clone(), pts[0], ops, act);
    assert_within_limits(&cfg, &pts[0], &run.samples, 1.01);
    let last = run.samples.last().expect("samples");
    prop_assert!(
        linear_distance(&last.pose, &pts[pts.len() - 1]) <= 1e-9,
        "ends at {:?}",
        last.pose
    );
    // On the path whatever the speed: the override goes up to 1.5 times the feed.
    in_band(d, &cfg, &pts, &run.samples, 1.6)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]
    #[test]
    fn dense_code_under_override_and_hold_stays_in_the_band_and_the_limits(
        d in dense_strategy(),
        shares in controls_strategy(),
    ) {
        let length = d.chord * d.chords as f64 / d.feed;
        let controls = shares.iter().map(|&(t, hold, x)| (t * length, hold, x)).collect();
        check_controlled(&d, &controls)?;
    }
}

/// A wavy R25 helix in 0.09 mm chords whose jerk limits fall chord by chord (4772, 4519,
/// 4288, 4079, 3915 mm/s³ …), with three feed holds. Braking for the third, the path's
/// deceleration was judged with the current jerk up to the next drop and with that one's
/// jerk after it, though its easing ran over several drops: it could not be eased in time,
/// the speed went below zero and was clamped (X at three times its jerk limit). Now each
/// drop along the easing is taken in turn.
#[test]
fn a_hold_over_a_staircase_of_falling_jerk_limits_stops_smoothly() {
    let d = Dense {
        radius: 24.918227552403327,
        wave: (0.2174059533928404, 5.710191022646967),
        chord: 0.09098185999989765,
        chords: 1676,
        round: 1e-4,
        corner_every: 0,
        feed: 190.1376551777259,
        limits: (255.944554146952, 1175.9410766214291, 11163.832348370086),
        rise: -1.5665005625217696,
    };
    let controls = vec![
        (0.021534364451351554, true, 0.8764552265892327),
        (0.6148503121103078, true, 0.5394841940731187),
        (0.7860783303919491, true, 0.30533013909446766),
    ];
    let result = check_controlled(&d, &controls);
    assert!(result.is_ok(), "{result:?}");
}

/// A wavy R36.6 curve in 0.011 mm chords at F5140 whose feed override drops to 10 % near
/// the end, while the jerk limit falls from 80 356 to 52 817 mm/s³ a little ahead. Braking
/// for the new speed, the path may not brake any harder before that drop, but the only ramp
/// that eased the deceleration aimed at the new speed, below where easing at once ends: it
/// went on braking, and once the drop came within a period the speed went through zero (X
/// at 8.8 times its jerk limit, the path turning back). The easing ramp now aims where it
/// ends whenever the state is faster than the new speed.
#[test]
fn an_override_drop_before_a_lower_jerk_limit_eases_in_time() {
    let d = Dense {
        radius: 36.598493778897776,
        wave: (0.1980753094338526, 4.1082297688769565),
        chord: 0.011381281071706538,
        chords: 2241,
        round: 0.001,
        corner_every: 0,
        feed: 85.70737034469988,
        limits: (168.41811954190925, 2322.287543842611, 100435.38171011482),
        rise: 0.0,
    };
    assert_controlled_at_shares(&d, &[(0.9718992358727077, false, 0.0)]);
}

/// An R12.5 wave in 0.24 mm chords with two feed holds and then the override dropped to
/// 10 %. A first version of the ramp that holds the current deceleration (see
/// `speed::advance`) kept that deceleration as its limit even where the window's grip was
/// lower, and X went 1 % over its acceleration limit; the ramp now takes the lower of the two.
#[test]
fn holding_a_deceleration_keeps_the_grip_of_the_window() {
    let d = Dense {
        radius: 12.49662037694364,
        wave: (0.07345185296829783, 5.039303511842893),
        chord: 0.24064692833734033,
        chords: 995,
        round: 0.001,
        corner_every: 0,
        feed: 122.63868978321351,
        limits: (173.95718364355216, 518.5977435792572, 121105.94742161404),
        rise: 0.0,
    };
    assert_controlled_at_shares(
        &d,
        &[
            (0.17443771039008266, true, 0.65755574581524),
            (0.15317164088912144, true, 0.5751151868617747),
            (0.7989956168560376, false, 0.0),
        ],
    );
}

/// Runs `d` with controls at shares of its time at the feed (as the property test draws
/// them) and asserts what [`check_controlled`] checks.
fn assert_controlled_at_shares(d: &Dense, shares: &[(f64, bool, f64)]) {
    let length = d.chord * d.chords as f64 / d.feed;
    let controls = shares
        .iter()
        .map(|&(t, hold, x)| (t * length, hold, x))
        .collect();
    let result = check_controlled(d, &controls);
    assert!(result.is_ok(), "{result:?}");
}
