//! A CiA 402 axis in cyclic synchronous velocity mode (klar closes the position loop)
//! against the simulated drive on an in-memory bus: the PDO mapping set up by SDO, the
//! velocity law, a short move within a bound derived from the gain and the plant, the
//! following-error check klar does itself, and the configurations that are refused.

use std::sync::{Arc, Mutex};

use klar_drivers::can::memory::{FrameFate, MemoryBus};
use klar_drivers::cia402::{CanOpenConfig, Cia402Backend, Cia402Error};
use klar_motion::{AxisBackend, AxisFault, AxisFeedback, AxisState, Setpoint};
use klar_sim::cia402::{SimCia402Drive, SimDriveConfig, simulated_backend};
use klar_sim::plant::SimAxisParams;

const PERIOD: f64 = 0.001;
const CPU: f64 = 10_000.0;

fn config(extra: &str) -> CanOpenConfig {
    let text = format!(
        "bus = {{ adapter = \"sim\" }}\nheartbeat_ms = 50\n[[drives]]\nnode = 1\n\
         counts_per_unit = {CPU}\nmode = \"csv\"\n{extra}"
    );
    toml::from_str(&text).expect("test config parses")
}

/// The default mill-axis plant without a position loop of its own: a drive whose velocity
/// loop is all there is, so the position is held by klar alone.
fn velocity_only_plant() -> SimAxisParams {
    SimAxisParams {
        position_gain: 0.0,
        counts_per_unit: CPU,
        ..SimAxisParams::default()
    }
}

/// A rest-to-rest move from 0 to `length` with a cosine velocity profile over `duration`
/// seconds: peak velocity π·L/(2·D), peak acceleration π²·L/(2·D²).
fn cosine_move(length: f64, duration: f64, t: f64) -> Setpoint {
    let s = (t / duration).clamp(0.0, 1.0);
    let w = std::f64::consts::PI / duration;
    let moving = t > 0.0 && t < duration;
    Setpoint {
        position: length * 0.5 * (1.0 - (std::f64::consts::PI * s).cos()),
        velocity: if moving {
            length * 0.5 * w * (w * t).sin()
        } else {
            0.0
        },
        acceleration: if moving {
            length * 0.5 * w * w * (w * t).cos()
        } else {
            0.0
        },
    }
}

fn read_u32(backend: &Cia402Backend, index: u16, sub: u8) -> u32 {
    backend
        .with_master(|m| m.sdo_read_u32(1, index, sub))
        .expect("SDO read")
}

#[test]
fn the_receive_pdo_set_up_by_sdo_carries_the_target_velocity() {
    let (mut backend, _bus, _drives) = simulated_backend(&config(""), PERIOD, &[]).expect("starts");
    // Read back from the simulated drive's object dictionary: RPDO 1 maps controlword
    // (0x6040, 16 bits) and target velocity (0x60FF, 32 bits); TPDO 1 statusword and the
    // actual position (0x6064), which klar's position loop needs.
    assert_eq!(read_u32(&backend, 0x1600, 0), 2);
    assert_eq!(read_u32(&backend, 0x1600, 1), 0x6040_0010);
    assert_eq!(read_u32(&backend, 0x1600, 2), 0x60FF_0020);
    assert_eq!(read_u32(&backend, 0x1A00, 0), 2);
    assert_eq!(read_u32(&backend, 0x1A00, 1), 0x6041_0010);
    assert_eq!(read_u32(&backend, 0x1A00, 2), 0x6064_0020);
    backend.enable().expect("enables");
    // Mode of operation and its display: 9, cyclic synchronous velocity.
    assert_eq!(read_u32(&backend, 0x6060, 0), 9);
    assert_eq!(read_u32(&backend, 0x6061, 0), 9);
    let mut fb = vec![AxisFeedback::default()];
    backend
        .cycle(PERIOD, &[Setpoint::default()], &mut fb)
        .expect("cycle");
    // Operation enabled (0x27 in bits 0–6) and bit 12: the drive follows the target.
    let sw = read_u32(&backend, 0x6041, 0);
    assert_eq!(sw & 0x6F, 0x27, "statusword {sw:#06x}");
    assert_ne!(sw & (1 << 12), 0, "statusword {sw:#06x}");
}

#[test]
fn each_cycle_sends_feed_forward_plus_gain_times_the_error() {
    let gain = 40.0;
    let (mut backend, bus, _drives) = simulated_backend(
        &config(&format!("position_gain = {gain}\n")),
        PERIOD,
        &[velocity_only_plant()],
    )
    .expect("starts");
    backend.enable().expect("enables");
    // Record the target velocities klar puts on the bus (RPDO 1 of node 1: 0x201).
    let sent: Arc<Mutex<Vec<i32>>> = Arc::default();
    let log = Arc::clone(&sent);
    bus.set_injector(move |f| {
        if f.id().standard() == Some(0x201)
            && let Some(b) = f.data().get(2..6)
        {
            let v = i32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            log.lock().unwrap_or_else(|p| p.into_inner()).push(v);
        }
        FrameFate::Deliver
    });
    let mut fb = vec![AxisFeedback::default()];
    let mut t = 0.0;
    backend
        .cycle(t, &[Setpoint::default()], &mut fb)
        .expect("cycle");
    let mut previous = (0.0, fb[0].position);
    let mut checked = 0;
    for k in 1..=300 {
        t = f64::from(k) * PERIOD;
        let sp = cosine_move(5.0, 0.25, t);
        backend.cycle(t, &[sp], &mut fb).expect("cycle");
        let (command, actual) = previous;
        // The brief's law, computed here from the setpoints and the feedback klar reported.
        let expected = ((sp.position - command) / PERIOD + gain * (command - actual)) * CPU;
        let got = *sent
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .last()
            .expect("a receive PDO went out");
        assert!(
            (f64::from(got) - expected).abs() <= 0.5 + 1e-6,
            "cycle {k}: sent {got} counts/s, law gives {expected}"
        );
        checked += 1;
        previous = (sp.position, fb[0].position);
    }
    assert_eq!(checked, 300);
    bus.clear_injector();
}

#[test]
fn a_csv_axis_follows_a_short_move_within_the_bound_the_gain_implies() {
    let gain = 50.0;
    let plant = velocity_only_plant();
    let (mut backend, _bus, drives) = simulated_backend(
        &config(&format!(
            "position_gain = {gain}\nfollowing_error_window = 0.5\n"
        )),
        PERIOD,
        std::slice::from_ref(&plant),
    )
    .expect("starts");
    backend.enable().expect("enables");
    // 20 mm in 0.3 s: peak velocity π·20/0.6 ≈ 105 mm/s, peak acceleration
    // π²·20/0.18 ≈ 1097 mm/s².
    let (length, duration) = (20.0, 0.3);
    let v_max = std::f64::consts::PI * length / (2.0 * duration);
    let a_max = std::f64::consts::PI.powi(2) * length / (2.0 * duration * duration);
    // Bound. Each cycle the error left after the feed-forward shrinks by (1 − K_p·T) and
    // grows by what the drive's velocity falls short of the command over the cycle,
    // δv·T, so |e| ≤ δv / K_p. The velocity loop (gain K_v, mass m) is ω = K_v/m fast; its
    // lag behind an acceleration a is at most a/ω, and a force F it must first overcome
    // (Coulomb plus viscous friction at v_max, no friction feed-forward) costs F/K_v.
    let si = plant.si_per_unit();
    let omega = plant.velocity_gain / plant.mass;
    let friction = plant.coulomb_friction + plant.viscous_friction * v_max * si;
    let dv = a_max / omega + friction / plant.velocity_gain / si;
    let bound = dv / gain + 2.0 / CPU;
    let mut fb = vec![AxisFeedback::default()];
    let mut worst: f64 = 0.0;
    let mut t = 0.0;
    for _ in 0..500 {
        t += PERIOD;
        let sp = cosine_move(length, duration, t);
        backend.cycle(t, &[sp], &mut fb).expect("cycle");
        assert_eq!(
            fb[0].state,
            AxisState::Enabled,
            "{:?}",
            backend.stop_report()
        );
        worst = worst.max(fb[0].following_error.abs());
    }
    eprintln!("CSV move: worst following error {worst:.5} mm, bound {bound:.5} mm");
    assert!(
        worst < bound,
        "worst following error {worst} mm, bound {bound} mm"
    );
    // It moved for real: the plant ended at the target, to the count.
    assert!(
        (drives[0].position() - length).abs() <= 2.0 / CPU,
        "{}",
        drives[0].position()
    );
    assert!(fb[0].following_error.abs() <= 2.0 / CPU);
}

#[test]
fn a_following_error_beyond_the_window_stops_the_axis() {
    let (mut backend, _bus, _drives) = simulated_backend(
        &config("following_error_window = 0.01\n"),
        PERIOD,
        // The plant's own 1 mm limit would fault the drive first; here klar must catch it.
        &[SimAxisParams {
            following_error_limit: 100.0,
            ..velocity_only_plant()
        }],
    )
    .expect("starts");
    backend.enable().expect("enables");
    let mut fb = vec![AxisFeedback::default()];
    // A 2 mm jump in one cycle asks for 2000 mm/s at once: 400 kg at 8 kN reach 20 mm/s
    // in that millisecond, so the error after it is far outside 0.01 mm.
    let sp = Setpoint {
        position: 2.0,
        ..Setpoint::default()
    };
    backend.cycle(PERIOD, &[sp], &mut fb).expect("cycle");
    assert!(
        matches!(fb[0].fault, Some(AxisFault::FollowingError(e)) if e > 0.01),
        "{:?}",
        fb[0]
    );
    let report = backend.stop_report().expect("stopped");
    assert!(
        report.contains("node 1") && report.contains("following error"),
        "{report}"
    );
}

fn refused(extra: &str) -> String {
    match simulated_backend(&config(extra), PERIOD, &[]) {
        Err(Cia402Error::Config(m)) => m,
        Err(e) => panic!("refused for another reason: {e}"),
        Ok(_) => panic!("{extra:?} was accepted"),
    }
}

#[test]
fn bad_configurations_are_refused_with_a_clear_message() {
    let text = "bus = { adapter = \"sim\" }\n[[drives]]\nnode = 3\ncounts_per_unit = 1000.0\n\
                mode = \"pv\"\n";
    let cfg: CanOpenConfig = toml::from_str(text).expect("parses");
    let m = match simulated_backend(&cfg, PERIOD, &[]) {
        Err(Cia402Error::Config(m)) => m,
        other => panic!("pv on an axis: {:?}", other.err()),
    };
    assert!(m.contains("node 3") && m.contains("pv"), "{m}");
    for gain in ["0.0", "-5.0", "nan"] {
        let m = refused(&format!("position_gain = {gain}\n"));
        assert!(m.contains("position_gain"), "{gain}: {m}");
    }
    // At 1 ms the gain may be at most 0.5/T = 500 1/s.
    let m = refused("position_gain = 600.0\n");
    assert!(m.contains("too high") && m.contains("500"), "{m}");
    // A gain on a drive that closes its own position loop means a mistake.
    let text = "bus = { adapter = \"sim\" }\n[[drives]]\nnode = 1\ncounts_per_unit = 1000.0\n\
                position_gain = 30.0\n";
    let cfg: CanOpenConfig = toml::from_str(text).expect("parses");
    assert!(matches!(
        simulated_backend(&cfg, PERIOD, &[]),
        Err(Cia402Error::Config(m)) if m.contains("only to mode")
    ));
}

#[test]
fn a_drive_without_csv_refuses_the_mode_and_start_up_says_so() {
    let bus = MemoryBus::new();
    let endpoint = bus.endpoint();
    let (drive, _control) = SimCia402Drive::new(SimDriveConfig {
        node: 1,
        plant: SimAxisParams::default(),
        start_position: 0.0,
    });
    // A drive with position modes only.
    bus.attach(Box::new(drive.with_modes(&[1, 6, 8])));
    let m = match Cia402Backend::with_bus(&config(""), PERIOD, Box::new(endpoint)) {
        Err(Cia402Error::Config(m)) => m,
        Err(e) => panic!("other error: {e}"),
        Ok(_) => panic!("a drive without CSV was accepted"),
    };
    assert!(
        m.contains("node 1") && m.contains("mode of operation 9"),
        "{m}"
    );
}
