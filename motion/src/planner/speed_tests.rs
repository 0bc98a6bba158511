//! Unit tests of the speed generator's checks and actions.

use super::*;

/// A hard limit at `at` with speed `speed` and the same grip and jerk everywhere.
fn limit(at: f64, speed: f64) -> Limit {
    Limit::uniform(at, speed, 1000.0, 1e5, false)
}

/// A window over `limits` for a period of 1 ms with 1000 mm/s² and 1e5 mm/s³.
fn window(limits: Vec<Limit>) -> Window {
    Window {
        limits,
        grip: Grip::constant(1000.0),
        jerk: 1e5,
        period: 1e-3,
    }
}

#[test]
fn a_limit_passed_while_speeding_up_does_not_vouch_for_a_stop_behind_it() {
    // A limit 0.5 mm ahead, settled against a stop 7 mm ahead, and a state still
    // speeding up below the settled speed: it passes the limit with a positive
    // acceleration, where the settled speed vouches for nothing.
    let mut w = window(vec![limit(0.5, 150.0), limit(7.0, 0.0)]);
    settle(&mut w.limits);
    let x = Motion {
        s: 0.0,
        v: 100.0,
        a: 1000.0,
    };
    let first = w.limits[0];
    assert!(first.speed < 150.0, "settled: {}", first.speed);
    assert!(
        !slows_for(&x, &first),
        "the state need not slow down for it"
    );
    // No motion within the limits stops the state in time: the time-optimal stop from
    // it (ease the acceleration, then brake) is longer than the way to the stop.
    let stop = Ramp::new(x.v, x.a, 0.0, 1000.0, 1e5).distance();
    assert!(stop > 7.0, "{stop}");
    assert!(!check(&x, &w));
    // The same state a little slower is safe.
    let slower = Motion { v: 80.0, ..x };
    assert!(Ramp::new(slower.v, slower.a, 0.0, 1000.0, 1e5).distance() < 6.5);
    assert!(check(&slower, &w));
}

#[test]
fn the_braking_need_does_not_jump_where_the_easing_reaches_a_drop_in_jerk() {
    // The current piece allows a jerk of 5000 mm/s³, the pieces from 3 mm on only 2000;
    // a limit of 10 mm/s at 6 mm. A state speeding up eases its acceleration with the
    // higher jerk as far as 3 mm, then with the lower one. Where braking ends must move
    // with the state as it passes the place where its easing reaches 3 mm, not jump.
    let grip = Grip::constant(1000.0);
    let at = |at: f64, speed: f64, soft: bool| Limit::uniform(at, speed, 1000.0, 2000.0, soft);
    let w = Window {
        limits: vec![at(3.0, 100.0, true), at(6.0, 10.0, false)],
        grip,
        jerk: 5000.0,
        period: 1e-3,
    };
    let far = w.limits[1];
    let ends = |s: f64| {
        let x = Motion {
            s,
            v: 20.0,
            a: 200.0,
        };
        s + brake_need(&x, &far, &w, JUDGE, f64::NEG_INFINITY)
    };
    let (mut crossed, mut prev) = (false, ends(1.0));
    for k in 1..=1500 {
        let s = 1.0 + 1e-3 * k as f64;
        let x = Motion {
            s,
            v: 20.0,
            a: 200.0,
        };
        crossed |= s + easing_distance(&x, 0.0, JUDGE * 5000.0) > 3.0;
        let now = ends(s);
        assert!(
            (now - prev).abs() < 5e-3,
            "braking ends at {prev} mm, then at {now} mm from {s} mm"
        );
        prev = now;
    }
    assert!(crossed, "the easing never reached the drop in jerk");
}

/// States from `x` heading for `target` in the fixed window `w` while `go` holds.
fn run(mut x: Motion, target: f64, w: &Window, go: impl Fn(&Motion) -> bool) -> Vec<Motion> {
    let mut out = vec![x];
    while go(&x) && out.len() < 10_000 {
        x = advance(&x, target, w, w.period);
        out.push(x);
    }
    out
}

#[test]
fn braking_into_a_staircase_of_limits_goes_on_through_its_steps() {
    // Limits stepping down by 3–4 mm/s every 0.3 mm (the parts of a blend running into
    // a corner), with less acceleration and jerk there than on the way in. The path
    // brakes through the steps: at the inner ones it is still decelerating, where a
    // ramp meeting each step with zero acceleration would have none. Every step is met
    // and the acceleration and jerk stay within the limits.
    let (a, j) = (600.0, 5e4);
    let mut w = window(vec![
        Limit::uniform(0.0, 100.0, 1000.0, 1e5, true),
        Limit::uniform(10.0, 40.0, 1000.0, 1e5, false),
        Limit::uniform(10.3, 36.0, a, j, false),
        Limit::uniform(10.6, 33.0, a, j, false),
        Limit::uniform(10.9, 31.0, a, j, false),
        Limit::uniform(30.0, 0.0, a, j, false),
    ]);
    settle(&mut w.limits);
    let start = Motion {
        s: 0.0,
        v: 100.0,
        a: 0.0,
    };
    let states = run(start, 100.0, &w, |x| x.s < 10.9);
    for pair in states.windows(2) {
        let (x, y) = (pair[0], pair[1]);
        assert!(
            (y.a - x.a).abs() <= 1e5 * 1e-3 * (1.0 + 1e-9),
            "{x:?} {y:?}"
        );
        assert!(y.a.abs() <= 1000.0 * (1.0 + 1e-9), "{y:?}");
        if y.s > 10.0 {
            assert!(y.a >= -a * (1.0 + 1e-9), "{y:?}");
        }
        for l in &w.limits[1..] {
            assert!(
                y.s < l.at || y.v <= l.own * (1.0 + 1e-9),
                "{y:?} past {l:?}"
            );
        }
    }
    for at in [10.3, 10.6] {
        let Some(x) = states.iter().find(|x| x.s >= at) else {
            panic!("{at} not reached")
        };
        assert!(x.a < -50.0, "at {at}: {x:?}");
    }
}

#[test]
fn leaving_a_slow_piece_for_a_faster_one_goes_on_speeding_up() {
    // A piece limited to 30 mm/s ends at 0.3 mm, where one of 60 mm/s begins (out of a
    // corner); the path enters the slow piece at 22 mm/s. It leaves the slow piece
    // speeding up at full acceleration, never faster than its limit on it: the last
    // state on it eases at once to the end within the limit, the first state past it
    // is no faster.
    let w = window(vec![
        Limit::uniform(0.0, 30.0, 1000.0, 1e5, true),
        Limit::uniform(0.3, 60.0, 1000.0, 1e5, false),
        Limit::uniform(50.0, 0.0, 1000.0, 1e5, false),
    ]);
    let start = Motion {
        s: 0.0,
        v: 22.0,
        a: 0.0,
    };
    let states = run(start, 60.0, &w, |x| x.s < 0.3);
    let (on, past): (Vec<Motion>, Vec<Motion>) = states.iter().partition(|x| x.s < 0.3);
    assert!(on.iter().all(|x| x.v <= 30.0 * (1.0 + 1e-9)), "{on:?}");
    let (Some(last), Some(first)) = (on.last(), past.first()) else {
        panic!("{states:?}")
    };
    assert!(last.a > 900.0 && first.a > 900.0, "{last:?} {first:?}");
    // Meeting the limit with zero acceleration would have held the last state to
    // settle within it.
    assert!(settled_speed(last, 1e5) > 31.0, "{last:?}");
    assert!(first.v <= 30.0 * (1.0 + 1e-9), "{first:?}");
    assert!(eased_by(last, 0.3 - last.s, JUDGE * 1e5).v <= 30.0 * (1.0 + 1e-9));
}

#[test]
fn braking_speed_is_where_the_ramp_fills_the_room() {
    // Both cases of the S-curve (peak acceleration reached or not), against the ramp's
    // own integrated distance.
    for &(w, room, a, j) in &[
        (0.0, 5.0, 1000.0, 1e5),
        (20.0, 0.3, 1000.0, 1e5),
        (47.0, 0.01, 900.0, 1e9),
        (3.0, 1e-4, 500.0, 2000.0),
        (100.0, 50.0, 2000.0, 5e4),
    ] {
        let v = braking_speed(w, room, a, j);
        assert!(v >= w);
        let d = Ramp::new(v, 0.0, w, a, j).distance();
        assert!((d - room).abs() <= 1e-9 * room.max(1.0), "{w} {room}: {d}");
    }
}
