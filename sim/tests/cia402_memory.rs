//! The whole CANopen path on an in-memory bus: CiA 402 backend ↔ simulated drives.

use klar_drivers::cia402::{CanOpenConfig, PowerState};
use klar_motion::{AxisBackend, AxisFault, AxisFeedback, AxisState, Setpoint};
use klar_sim::cia402::simulated_backend;

const PERIOD: f64 = 0.001;

fn config(nodes: &[u8]) -> CanOpenConfig {
    let mut text =
        String::from("bus = { adapter = \"sim\", bitrate = 1000000 }\nheartbeat_ms = 50\n");
    for n in nodes {
        text.push_str(&format!(
            "[[drives]]\nnode = {n}\ncounts_per_unit = 10000.0\nhoming = {{ method = 35, offset = 5.0 }}\n"
        ));
    }
    toml::from_str(&text).expect("test config parses")
}

/// A smooth rest-to-rest move (cosine profile) from `a` to `b` over `T` seconds.
fn cosine_move(a: f64, b: f64, duration: f64, t: f64) -> Setpoint {
    let s = (t / duration).clamp(0.0, 1.0);
    let w = std::f64::consts::PI / duration;
    let moving = t > 0.0 && t < duration;
    Setpoint {
        position: a + (b - a) * 0.5 * (1.0 - (std::f64::consts::PI * s).cos()),
        velocity: if moving {
            (b - a) * 0.5 * w * (w * t).sin()
        } else {
            0.0
        },
        acceleration: if moving {
            (b - a) * 0.5 * w * w * (w * t).cos()
        } else {
            0.0
        },
    }
}

#[test]
fn three_drives_enable_and_follow_a_move() {
    let (mut backend, bus, drives) =
        simulated_backend(&config(&[1, 2, 3]), PERIOD, &[]).expect("starts");
    assert_eq!(backend.axis_count(), 3);
    backend.enable().expect("enables");
    assert!(
        backend
            .power_states()
            .iter()
            .all(|s| *s == PowerState::OperationEnabled)
    );
    let mut fb = vec![AxisFeedback::default(); 3];
    let targets = [10.0, -4.0, 2.5];
    let duration = 0.5;
    let mut worst_error: f64 = 0.0;
    let mut t = 0.0;
    for _ in 0..800 {
        t += PERIOD;
        let sps: Vec<Setpoint> = targets
            .iter()
            .map(|&b| cosine_move(0.0, b, duration, t))
            .collect();
        backend.cycle(t, &sps, &mut fb).expect("cycle");
        for (f, sp) in fb.iter().zip(&sps) {
            assert_eq!(f.state, AxisState::Enabled, "{:?}", backend.stop_report());
            assert!(f.fault.is_none());
            worst_error = worst_error.max((sp.position - f.position).abs());
        }
    }
    // The move ends at the targets; the reported positions are the plant's to the count.
    for ((f, &b), d) in fb.iter().zip(&targets).zip(&drives) {
        assert!(
            (f.position - b).abs() < 1e-3,
            "axis at {} instead of {b}",
            f.position
        );
        assert!((d.position() - f.position).abs() <= 1.0 / 10000.0 + 1e-12);
    }
    // The drive's plant lags a little but stays far inside its 1 mm window.
    assert!(worst_error < 0.2, "worst error {worst_error}");
    assert!(worst_error > 0.0, "a real plant never follows perfectly");
    // SYNC + 3 RPDO + 3 TPDO per cycle, plus heartbeats: at least 7 frames a cycle.
    assert!(bus.frames_carried() >= 7 * 800);
    backend.disable().expect("disables");
    assert!(
        backend
            .power_states()
            .iter()
            .all(|s| *s == PowerState::ReadyToSwitchOn)
    );
}

#[test]
fn homing_method_35_sets_the_home_offset() {
    let (mut backend, _bus, _drives) =
        simulated_backend(&config(&[4]), PERIOD, &[]).expect("starts");
    backend.enable().expect("enables");
    let mut fb = vec![AxisFeedback::default(); 1];
    let mut t = 0.0;
    let mut sp = Setpoint::default();
    for _ in 0..100 {
        t += PERIOD;
        sp = cosine_move(0.0, 3.0, 0.05, t);
        backend.cycle(t, &[sp], &mut fb).expect("cycle");
    }
    assert!((fb[0].position - 3.0).abs() < 1e-3, "{}", fb[0].position);
    backend.start_homing(0).expect("homing starts");
    let mut homed_at = None;
    for i in 0..50 {
        t += PERIOD;
        backend.cycle(t, &[sp], &mut fb).expect("cycle");
        if fb[0].homed {
            homed_at = Some(i);
            break;
        }
        assert_eq!(
            fb[0].state,
            AxisState::Homing,
            "{:?}",
            backend.stop_report()
        );
    }
    assert!(homed_at.is_some(), "homing did not finish");
    assert_eq!(fb[0].state, AxisState::Enabled);
    // Method 35: the current position becomes the home offset (5 mm); the axis was still
    // settling by fractions of a micrometre from the move before.
    assert!((fb[0].position - 5.0).abs() < 1e-3, "{}", fb[0].position);
    // And CSP resumes from there.
    for i in 1..=100 {
        t += PERIOD;
        let sp = cosine_move(5.0, 6.0, 0.05, f64::from(i) * PERIOD);
        backend.cycle(t, &[sp], &mut fb).expect("cycle");
    }
    assert!((fb[0].position - 6.0).abs() < 1e-3);
}

#[test]
fn injected_drive_fault_stops_all_axes_and_names_the_node() {
    let (mut backend, _bus, drives) =
        simulated_backend(&config(&[1, 2]), PERIOD, &[]).expect("starts");
    backend.enable().expect("enables");
    let mut fb = vec![AxisFeedback::default(); 2];
    let mut t = 0.0;
    for _ in 0..50 {
        t += PERIOD;
        let sp = cosine_move(0.0, 50.0, 1.0, t);
        backend.cycle(t, &[sp, sp], &mut fb).expect("cycle");
    }
    drives[1].inject(|i| i.fault = Some(0x2310));
    t += PERIOD;
    let sp = cosine_move(0.0, 50.0, 1.0, t);
    backend.cycle(t, &[sp, sp], &mut fb).expect("cycle");
    match &fb[1].fault {
        Some(AxisFault::Drive { code, text }) => {
            assert_eq!(*code, 0x2310);
            assert!(
                text.contains("node 2") && text.contains("over-current"),
                "{text}"
            );
        }
        other => panic!("expected a drive fault, got {other:?}"),
    }
    assert_eq!(fb[1].state, AxisState::Faulted);
    assert!(fb[0].fault.is_some(), "the healthy axis is stopped too");
    let report = backend.stop_report().expect("a stop report");
    assert!(report.contains("node 2"), "{report}");
    // The healthy drive is quick-stopped within a cycle or two and comes to rest.
    for _ in 0..200 {
        t += PERIOD;
        backend.cycle(t, &[sp, sp], &mut fb).expect("cycle");
    }
    assert_eq!(drives[0].power_state(), Some(PowerState::QuickStopActive));
    let rest = drives[0].position();
    t += PERIOD;
    backend.cycle(t, &[sp, sp], &mut fb).expect("cycle");
    assert!((drives[0].position() - rest).abs() < 1e-6, "still moving");
    // Enabling is refused until the faults are reset.
    assert!(backend.enable().is_err());
    backend.reset_fault(0).expect("reset healthy axis");
    backend.reset_fault(1).expect("reset faulted axis");
    assert!(backend.stop_report().is_none());
    backend.enable().expect("enables again");
    t += PERIOD;
    let hold = [
        Setpoint {
            position: fb[0].position,
            ..Default::default()
        },
        Setpoint {
            position: fb[1].position,
            ..Default::default()
        },
    ];
    backend.cycle(t, &hold, &mut fb).expect("cycle");
    assert!(
        fb.iter()
            .all(|f| f.state == AxisState::Enabled && f.fault.is_none())
    );
}
