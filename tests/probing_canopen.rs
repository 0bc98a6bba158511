//! `klar run` of probing programs on simulated CiA 402 drives (`machines/canopen-probing.toml`:
//! the part of `machines/probing-mill.toml`, `[probe] latch`): each touch point is the
//! position the drives latched when their probe input switched, and the run stops each
//! probing move after the trigger. The drives' inputs switch where the simulated part
//! really is (`[workpiece]` moved by `actual_shift`), which these tests place away from the
//! model the test run measures: the results must be those of the part the drives feel.

mod common;

use common::probing::{C410, machine as load};
use klar::config::MachineConfig;
use klar::runtime::RunReport;

/// The encoders count 10 000 per mm: a latched position lies within half a count of the
/// trigger, and a result from several of them within a count.
const COUNT: f64 = 1e-4;

/// The CANopen machine with its drives' part moved by `shift` from the model.
fn can_machine(shift: [f64; 3]) -> MachineConfig {
    let mut can = load("canopen-probing.toml");
    if let Some(w) = can.workpiece.as_mut() {
        w.actual_shift = shift;
    }
    can
}

/// The simulated axes of `probing-mill.toml` with the probe of the CANopen machine and its
/// part placed where the drives find it (`shift` added to the model's offset): the peer run,
/// whose probe answers from the model of that part.
fn peer_machine(shift: [f64; 3]) -> MachineConfig {
    let can = load("canopen-probing.toml");
    let mut sim = load("probing-mill.toml");
    let mut probe = can.probe.clone().expect("[probe]");
    probe.latch = false;
    sim.probe = Some(probe);
    if let Some(w) = sim.workpiece.as_mut() {
        for (o, d) in w.offset.iter_mut().zip(shift) {
            *o += d;
        }
    }
    sim
}

/// Each result of `a` within `tol` of the same result of `b`.
fn same_results(a: &RunReport, b: &RunReport, tol: f64) {
    assert!(!a.probe_results.is_empty());
    assert_eq!(a.probe_results.len(), b.probe_results.len());
    for (x, y) in a.probe_results.iter().zip(&b.probe_results) {
        assert_eq!(x.params.len(), y.params.len());
        for (p, q) in x.params.iter().zip(&y.params) {
            assert_eq!(p.0, q.0);
            assert!((p.1 - q.1).abs() < tol, "Q{}: {} against {}", p.0, p.1, q.1);
        }
    }
}

/// Q parameter `n` of the first result of cycle `cycle`.
fn q(report: &RunReport, cycle: u32, n: u32) -> f64 {
    report
        .probe_results
        .iter()
        .filter(|r| r.cycle == cycle)
        .flat_map(|r| &r.params)
        .find(|p| p.0 == n)
        .map(|p| p.1)
        .unwrap_or(f64::NAN)
}

#[test]
fn cycle_412_takes_the_drive_latches_not_the_model() {
    // the drives feel the part 0.5 mm further +X and 0.3 mm further −Y than the model
    let shift = [0.5, -0.3, 0.0];
    let path = common::program("probing_412.h");
    let (result, trace) = common::run(&path, &can_machine(shift));
    let report = result.expect("runs on the CANopen drives");
    let (peer, _) = common::run(&path, &peer_machine(shift));
    let peer = peer.expect("runs on simulated axes");
    same_results(&report, &peer, COUNT);

    // Closed form: the bore's nominal centre (−25, −10) turned by 1.5° about preset 1 and
    // moved by the part's offset (3.2, −1.7) and the shift; its diameter 24.
    let (s, c) = 1.5f64.to_radians().sin_cos();
    let centre = [
        -25.0 * c + 10.0 * s + 3.2 + shift[0],
        -25.0 * s - 10.0 * c - 1.7 + shift[1],
    ];
    for (n, want) in [(151, centre[0]), (152, centre[1]), (153, 24.0)] {
        let got = q(&report, 412, n);
        assert!((got - want).abs() < COUNT, "Q{n} {got}, closed form {want}");
    }
    // the model alone would have given the unshifted centre: the test run's answer
    let (model, _) = common::run(&path, &peer_machine([0.0; 3]));
    let model = model.expect("runs on the model");
    assert!((q(&model, 412, 151) - q(&report, 412, 151) + shift[0]).abs() < COUNT);

    // The probe-axis touch: the top of the part lies 0.25 mm below preset 1's Z−60, so the
    // ball centre triggers at Z −60 − 0.25 + 2 (machine). The run brakes once it has read
    // the latch, at most a servo cycle after the touch, from 5 mm/s: jerk phases of √(v/j)
    // each (the stop never reaches Z's acceleration limit, a²/j = 56.25 mm/s) cover
    // v·√(v/j); the stylus's 1 mm overtravel is far off.
    let can = can_machine(shift);
    let v = can.probe.as_ref().map_or(0.0, |p| p.feed) / 60.0;
    let period = can.servo_period;
    let trigger = -60.0 - 0.25 + 2.0;
    let braking = v * (v / 40000.0f64).sqrt();
    let [x, y, z, z_act] = ["X", "Y", "Z", "Z_act"].map(|c| trace.column(c).expect("column"));
    // the probe-axis touch is at Q382/Q383 = X+30 Y+25 of preset 1 (machine X130 Y75)
    let over_it = |k: &usize| (x[*k] - 130.0).abs() < 1e-6 && (y[*k] - 75.0).abs() < 1e-6;
    let lowest = |col: &[f64]| {
        (0..col.len())
            .filter(over_it)
            .map(|k| col[k])
            .fold(f64::INFINITY, f64::min)
    };
    let past = trigger - lowest(&z);
    eprintln!("Z stopped {past} past the touch (braking alone {braking})");
    assert!(
        past >= braking - 1e-6 && past <= braking + v * period + 1e-6,
        "stopped {past} past the touch, braking {braking}, one cycle {}",
        v * period
    );
    // the drive stood there too, to its lag
    let lag = report
        .max_following_error
        .iter()
        .find(|(a, _)| a.index() == 2)
        .map_or(0.0, |&(_, e)| e);
    assert!((lowest(&z_act) - lowest(&z)).abs() <= lag + COUNT);
}

#[test]
fn cycle_410_takes_the_drive_latches_not_the_model() {
    let text = format!(
        "BEGIN PGM P410 MM
BLK FORM 0.1 Z X-50 Y-40 Z-30
BLK FORM 0.2 X+50 Y+40 Z+0
TOOL CALL 1 Z S0
L Z+50 R0 FMAX
{C410}L Z+50 FMAX
END PGM P410 MM
"
    );
    let path = common::temp_program("p410.h", &text);
    let shift = [-0.5, 0.4, 0.0];
    let (result, _) = common::run(&path, &can_machine(shift));
    let report = result.expect("runs on the CANopen drives");
    let (peer, _) = common::run(&path, &peer_machine(shift));
    let peer = peer.expect("runs on simulated axes");
    same_results(&report, &peer, COUNT);
    let (model, _) = common::run(&path, &peer_machine([0.0; 3]));
    let model = model.expect("runs on the model");
    // The pocket is turned by 1.5°: a wall x·cos θ + y·sin θ = c moved by (dx, dy) crosses
    // the probing line y = const dx + dy·tan θ further on, a wall −x·sin θ + y·cos θ = c
    // crosses x = const dy − dx·tan θ further on; both walls of a pair move alike, so the
    // centre moves by that and the sides keep their length.
    let t = 1.5f64.to_radians().tan();
    let moved = [
        (151, shift[0] + shift[1] * t),
        (152, shift[1] - shift[0] * t),
        (154, 0.0),
        (155, 0.0),
    ];
    for (n, d) in moved {
        let (got, was) = (q(&report, 410, n), q(&model, 410, n));
        assert!((got - was - d).abs() < COUNT, "Q{n} {got}, model {was}");
    }
}

#[test]
fn a_probing_move_that_finds_nothing_runs_its_distance_and_stops_the_program() {
    // cycle 0 downward onto the top of the part, which the drives feel 25 mm lower than
    // the model: nothing within the probing distance of 20 mm
    let text = "BEGIN PGM P0 MM
BLK FORM 0.1 Z X-50 Y-40 Z-30
BLK FORM 0.2 X+50 Y+40 Z+0
TOOL CALL 1 Z S0
L X+10 Y+10 Z+50 R0 FMAX
TCH PROBE 0.0 REF. PLANE Q10 Z-
TCH PROBE 0.1 X+10 Y+10 Z+8
L Z+50 FMAX
END PGM P0 MM
";
    let path = common::temp_program("p0.h", text);
    let shift = [0.0, 0.0, -25.0];
    let (result, trace) = common::run(&path, &can_machine(shift));
    let failure = result.expect_err("the program stops");
    let message = failure.error.to_string();
    assert!(
        message.contains(":7:") && message.contains("touch point inaccessible"),
        "{message}"
    );
    // the probe started at Z+8 of preset 1 (machine Z −52) and went down 20 mm, no further
    let z = trace.column("Z").expect("Z");
    let lowest = z.iter().copied().fold(f64::INFINITY, f64::min);
    assert!((lowest - (-52.0 - 20.0)).abs() < 1e-9, "lowest Z {lowest}");
    // the model finds the top: the test run before the run passed
    let (model, _) = common::run(&path, &peer_machine([0.0; 3]));
    let model = model.expect("the model has the top within reach");
    assert!((model.probe_results.len()) == 1);
}
