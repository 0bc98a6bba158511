//! A real touch probe on the simulated machine (`machines/probing-mill.toml` given a trigger
//! delay and an overtravel): the probing move runs past the touch point by the distance the
//! axes need to stop, the cycle still measures from the position latched at the touch, and a
//! probing feed whose stop would deflect the stylus too far is refused before any motion.
//!
//! The stop distance is worked out here from the axis limits of the machine file: the
//! trigger delay at the probing speed, then a jerk-limited stop from that speed.

mod common;

use common::probing::ORIGIN;

use klar::config::MachineConfig;
use klar_interp::Interpreter;
use std::path::Path;

/// Trigger delay given to the probe here, s.
const DELAY: f64 = 0.004;
/// Servo period of the machine file, s.
const DT: f64 = 0.001;

fn machine(feed: f64, overtravel: f64) -> MachineConfig {
    let mut m = common::probing::machine("probing-mill.toml");
    let probe = m.probe.as_mut().expect("[probe]");
    probe.feed = feed;
    probe.trigger_delay = Some(DELAY);
    probe.overtravel = Some(overtravel);
    m
}

/// The same machine whose axes stop on the trigger point.
fn ideal_machine(feed: f64) -> MachineConfig {
    let mut m = machine(feed, 1.0);
    let probe = m.probe.as_mut().expect("[probe]");
    probe.trigger_delay = None;
    probe.overtravel = None;
    m
}

/// Distance of a stop from `v` at zero acceleration under acceleration `a` and jerk `j`,
/// and its duration. The deceleration ramps up at `j`, holds `a` (when v > a²/j), and
/// ramps down; the speed is point-symmetric about the middle of the stop, so the distance
/// is duration·v/2. When `a` is not reached the two jerk phases last √(v/j) each.
fn stop_from(v: f64, a: f64, j: f64) -> (f64, f64) {
    let time = if v >= a * a / j {
        v / a + a / j
    } else {
        2.0 * (v / j).sqrt()
    };
    (v * time / 2.0, time)
}

/// Cycle 0 down onto the top at program X+30 Y+25 from Z+10, then cycle 1 along −X from
/// X+60 at Z−10 toward the part's +X face.
const PROGRAM: &str = "BEGIN PGM REAL MM
BLK FORM 0.1 Z X-50 Y-40 Z-30
BLK FORM 0.2 X+50 Y+40 Z+0
TOOL CALL 1 Z S0
L Z+50 R0 FMAX
TCH PROBE 0.0 REF. PLANE Q10 Z-
TCH PROBE 0.1 X+30 Y+25 Z+10
L Z+20 FMAX
L X+65 Y+0 FMAX
TCH PROBE 1.0 POLAR DATUM
TCH PROBE 1.1 X ANGLE: +180
TCH PROBE 1.2 X+65 Y+0 Z-10
M30
END PGM REAL MM
";

/// Runs the interpreter alone (the test run) and returns it for its Q parameters.
fn interpret(m: &MachineConfig, name: &str, text: &str) -> Interpreter {
    let path = common::temp_program(name, text);
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    for op in it.by_ref() {
        op.expect("the program runs");
    }
    it
}

/// One probing move found in the trace: the positions while it cruised at the probing
/// speed, then the point where it came to rest before turning back.
struct ProbingMove {
    /// Index of the first sample at the probing speed.
    first: usize,
    /// Index of the sample where the axes stand still at the far end.
    rest: usize,
}

/// Path speed of every sample (finite differences of X, Y, Z, mm/s).
fn speeds(xyz: &[Vec<f64>]) -> Vec<f64> {
    let n = xyz[0].len();
    let mut out = vec![0.0; n];
    for k in 1..n {
        let d: f64 = (0..3).map(|i| (xyz[i][k] - xyz[i][k - 1]).powi(2)).sum();
        out[k] = d.sqrt() / DT;
    }
    out
}

/// The probing moves: runs of samples at the probing speed `v` (within 0.1 %), each
/// followed by the last sample before the axes stand still or turn back against the
/// direction of the run.
fn probing_moves(xyz: &[Vec<f64>], speed: &[f64], v: f64) -> Vec<ProbingMove> {
    let at_speed = |k: usize| (speed[k] - v).abs() <= 1e-3 * v;
    let step = |k: usize| [0, 1, 2].map(|i| xyz[i][k] - xyz[i][k - 1]);
    let mut out = Vec::new();
    let mut k = 1;
    while k < speed.len() {
        if at_speed(k) {
            let first = k;
            let dir = step(k);
            while k < speed.len() && at_speed(k) {
                k += 1;
            }
            while k < speed.len() {
                let d = step(k);
                if speed[k] <= 1e-9 || (0..3).map(|i| d[i] * dir[i]).sum::<f64>() <= 0.0 {
                    break;
                }
                k += 1;
            }
            out.push(ProbingMove { first, rest: k - 1 });
        }
        k += 1;
    }
    out
}

#[test]
fn the_axes_stop_past_the_touch_point_by_the_delay_and_the_braking_distance() {
    // 5400 mm/min = 90 mm/s: above a²/j on X (80 mm/s) and on Z (56.25 mm/s), so both
    // stops hold the acceleration limit for a while (and below Z's rapid speed of 100 mm/s,
    // so that no rapid move passes for a probing move)
    let feed = 5400.0;
    let v = feed / 60.0;
    let m = machine(feed, 10.0);
    let path = common::temp_program("probe_real_trace.h", PROGRAM);
    let (result, trace) = common::run(&path, &m);
    let report = result.expect("the program runs");
    let xyz = common::commanded(&trace, &["X", "Y", "Z"]);
    let speed = speeds(&xyz);
    let moves = probing_moves(&xyz, &speed, v);
    assert_eq!(moves.len(), 2, "two probing moves at the probing speed");

    // where the cycles latched the trigger (program coordinates of the ball centre)
    let q = |cycle: u32, n: u32| {
        report
            .probe_results
            .iter()
            .filter(|r| r.cycle == cycle)
            .flat_map(|r| r.params.iter())
            .find(|p| p.0 == n)
            .map(|p| p.1)
            .expect("result written")
    };
    // axis index, direction sign, trigger (machine coordinates), a, j of that axis
    let cases = [
        (2, -1.0, q(0, 117) + ORIGIN[2], 1500.0, 40000.0),
        (0, -1.0, q(1, 115) + ORIGIN[0], 2000.0, 50000.0),
    ];
    for (pm, &(axis, sign, trigger, a, j)) in moves.iter().zip(&cases) {
        let (brake, brake_time) = stop_from(v, a, j);
        let overshoot = DELAY * v + brake;
        let stop = xyz[axis][pm.rest];
        eprintln!(
            "axis {axis}: trigger {trigger}, stop {stop}, overshoot {} (closed form {overshoot})",
            sign * (stop - trigger)
        );
        // the move ends exactly where it was sent: the planner lands on the end point
        assert!(
            (sign * (stop - trigger) - overshoot).abs() < 1e-6,
            "axis {axis}: stopped {} past the touch point, closed form {overshoot}",
            sign * (stop - trigger)
        );
        // it still runs at the probing speed until the trigger delay is over: the sample
        // one period before the braking should begin is at the full speed
        let along = |k: usize| sign * (xyz[axis][k] - trigger);
        let reacts = (pm.first..pm.rest)
            .find(|&k| along(k) >= DELAY * v - v * DT)
            .expect("passes the reaction point");
        assert!(
            (speed[reacts] - v).abs() <= 1e-3 * v,
            "axis {axis}: speed {} at the reaction point",
            speed[reacts]
        );
        // and brakes the way the closed form says: the time from passing the touch point
        // to rest is the delay plus the braking time, to two servo periods (one for where
        // the touch falls between samples, one for where rest is first sampled)
        let touched = (pm.first..pm.rest)
            .find(|&k| along(k) >= 0.0)
            .expect("passes the touch point");
        let took = trace.t[pm.rest] - trace.t[touched];
        assert!(
            (took - (DELAY + brake_time)).abs() <= 2.0 * DT + 1e-9,
            "axis {axis}: {took} s from touch to rest, closed form {}",
            DELAY + brake_time
        );
        // then the probe goes back toward where the probing move started
        let after = xyz[axis][(pm.rest + 50).min(xyz[axis].len() - 1)];
        assert!(sign * (after - stop) < 0.0, "axis {axis}: retracts");
    }
}

#[test]
fn the_measurement_is_the_latched_touch_point_not_the_stop() {
    // slow probing (300 mm/min: the stops never reach the acceleration limit) and fast
    let c400 = "BEGIN PGM R400 MM
BLK FORM 0.1 Z X-50 Y-40 Z-30
BLK FORM 0.2 X+50 Y+40 Z+0
TOOL CALL 1 Z S0
L Z+50 R0 FMAX
TCH PROBE 400 BASIC ROTATION ~
  Q263=-30 ;1ST POINT 1ST AXIS ~
  Q264=-40 ;1ST POINT 2ND AXIS ~
  Q265=+30 ;2ND POINT 1ST AXIS ~
  Q266=-40 ;2ND POINT 2ND AXIS ~
  Q272=+1 ;MEASURING AXIS ~
  Q267=+1 ;TRAVERSE DIRECTION ~
  Q261=-10 ;MEASURING HEIGHT ~
  Q320=+5 ;SET-UP CLEARANCE ~
  Q260=+20 ;CLEARANCE HEIGHT ~
  Q301=+1 ;MOVE TO CLEARANCE ~
  Q307=+0 ;PRESET ROTATION ANG. ~
  Q305=+0 ;NUMBER IN TABLE
M30
END PGM R400 MM
";
    for feed in [300.0, 5400.0] {
        let real = interpret(&machine(feed, 10.0), "probe_real_q.h", PROGRAM);
        let ideal = interpret(&ideal_machine(feed), "probe_ideal_q.h", PROGRAM);
        for n in [10, 115, 116, 117] {
            assert!(
                (real.q(n) - ideal.q(n)).abs() < 1e-6,
                "feed {feed}: Q{n} {} against {}",
                real.q(n),
                ideal.q(n)
            );
        }
        let real = interpret(&machine(feed, 10.0), "probe_real_400.h", c400);
        let ideal = interpret(&ideal_machine(feed), "probe_ideal_400.h", c400);
        assert!(
            (real.q(150) - ideal.q(150)).abs() < 1e-9,
            "feed {feed}: Q150 {} against {}",
            real.q(150),
            ideal.q(150)
        );
        // and the cycle found the part's turn of 1.5° at all
        assert!((real.q(150) - 1.5).abs() < 1e-3, "Q150 {}", real.q(150));
    }
}

#[test]
fn a_probing_feed_too_high_for_the_overtravel_is_refused_before_motion() {
    // 3000 mm/min = 50 mm/s along Z (a²/j = 56.25 mm/s: the stop never holds the
    // acceleration limit): 0.2 mm in the delay plus 50·√(50/40000) mm braking ≈ 1.968 mm
    let v: f64 = 50.0;
    let stop = DELAY * v + stop_from(v, 1500.0, 40000.0).0;
    assert!(stop > 1.9 && stop < 2.0);
    let dir = common::temp_program("probe_too_fast.h", PROGRAM);
    let toml = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing-mill.toml"),
    )
    .expect("machine file");
    let toml = toml.replace(
        "feed = 300.0           # probing feed, mm/min",
        "feed = 3000.0\ntrigger_delay = 0.004\novertravel = 1.5",
    );
    assert!(toml.contains("overtravel = 1.5"));
    let machine_path = dir.with_file_name("too_fast.toml");
    std::fs::write(&machine_path, toml).expect("write machine");
    // the preset table sits next to the machine file
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing.pr"),
        machine_path.with_file_name("probing.pr"),
    )
    .expect("copy preset table");
    let (ok, out, err) = common::klar_cli(&[
        "check",
        common::arg(&dir),
        "--machine",
        common::arg(&machine_path),
    ]);
    let said = format!("{out}{err}");
    assert!(!ok, "refused: {said}");
    assert!(
        said.contains("probe_too_fast.h:7:")
            && said.contains("stylus deflection exceeds overtravel"),
        "{said}"
    );
    assert!(said.contains(&format!("{stop:.4} mm")), "{said}");
    assert!(said.contains("probing feed too high"), "{said}");

    // a run refuses it in its test run: no sample is written
    let m = MachineConfig::load(&machine_path).expect("loads");
    let (result, trace) = common::run(&dir, &m);
    assert!(result.is_err());
    assert!(trace.rows.is_empty(), "no motion before the refusal");

    // at the same feed with an overtravel of 2 mm the program runs
    let mut m = m;
    m.probe.as_mut().expect("[probe]").overtravel = Some(2.0);
    let (result, trace) = common::run(&dir, &m);
    result.expect("runs");
    assert!(!trace.rows.is_empty());
}

#[test]
fn a_touch_before_the_probing_feed_is_reached_asks_for_more_clearance() {
    // at 90 mm/s along Z the probe needs 4.39 mm to reach its feed; from Z+5 it touches the
    // top (the ball centre at −0.25 + 2) after 3.25 mm
    let (run_up, _) = stop_from(90.0, 1500.0, 40000.0);
    assert!(run_up > 3.25);
    let text = PROGRAM.replace("Z+10\n", "Z+5\n");
    let m = machine(5400.0, 10.0);
    let path = common::temp_program("probe_short.h", &text);
    let mut it = m.open_program(&path, m.start_pose()).expect("opens");
    let err = it.find_map(Result::err).expect("refused");
    assert!(
        err.message.contains("too little clearance"),
        "{}",
        err.message
    );
    assert!(
        err.message.contains(&format!("needs {run_up:.4} mm")),
        "{}",
        err.message
    );
    assert_eq!(err.line, 7);
}

#[test]
fn bad_trigger_delay_and_overtravel_values_are_refused_when_the_machine_loads() {
    let toml = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing-mill.toml"),
    )
    .expect("machine file");
    // the preset table is not read by parse; only [probe] matters here
    let toml = toml.replace("preset_table = \"probing.pr\"\nactive_preset = 1\n", "");
    for (keys, says) in [
        (
            "trigger_delay = -0.001",
            "trigger_delay must lie in 0 … 1 s",
        ),
        ("trigger_delay = 2.0", "trigger_delay must lie in 0 … 1 s"),
        (
            "overtravel = 0.0",
            "probe overtravel must be a positive number",
        ),
        (
            "overtravel = nan",
            "probe overtravel must be a positive number",
        ),
        ("overtravel = \"1\"", "overtravel"),
    ] {
        let text = toml.replace(
            "feed = 300.0           # probing feed, mm/min",
            &format!("feed = 300.0\n{keys}"),
        );
        let err = MachineConfig::parse("bad.toml", &text).expect_err(keys);
        assert!(err.to_string().contains(says), "{keys}: {err}");
    }
}
