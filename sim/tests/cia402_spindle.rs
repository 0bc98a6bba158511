//! A CiA 402 spindle drive in cyclic synchronous velocity mode, sharing the bus with an
//! axis or alone, against the simulated drive on an in-memory bus.

use klar_drivers::cia402::CanOpenConfig;
use klar_motion::{AxisBackend, AxisFault, AxisFeedback, Setpoint, SpindleBackend};
use klar_sim::cia402::simulated_backend;

const PERIOD: f64 = 0.001;

fn config(with_axis: bool) -> CanOpenConfig {
    let axis = if with_axis {
        "[[drives]]\nnode = 1\ncounts_per_unit = 1000.0\n"
    } else {
        ""
    };
    toml::from_str(&format!(
        "bus = {{ adapter = \"sim\" }}\nheartbeat_ms = 50\nspindle = {{ node = 5, counts_per_rev = 1048576.0 }}\n{axis}"
    ))
    .expect("config parses")
}

#[test]
fn spindle_reaches_speed_both_ways_and_stops() {
    let (mut backend, _bus, drives) =
        simulated_backend(&config(true), PERIOD, &[]).expect("starts");
    let mut spindle = backend.spindle().expect("spindle configured");
    backend.enable().expect("axis enables");
    let mut fb = vec![AxisFeedback::default(); 1];
    let mut t = 0.0;
    let mut run = |backend: &mut klar_drivers::cia402::Cia402Backend,
                   spindle: &mut klar_drivers::cia402::Cia402Spindle,
                   cycles: usize| {
        let mut last = None;
        for _ in 0..cycles {
            t += PERIOD;
            backend
                .cycle(t, &[Setpoint::default()], &mut fb)
                .expect("axis cycle");
            last = Some(spindle.cycle(t).expect("spindle cycle"));
        }
        last.expect("ran")
    };
    let idle = run(&mut backend, &mut spindle, 5);
    assert!(idle.at_speed && idle.rpm == 0.0);
    for rpm in [1200.0, -600.0, 0.0] {
        spindle.command(rpm).expect("command");
        let first = run(&mut backend, &mut spindle, 1);
        if rpm != 0.0 {
            assert!(
                !first.at_speed,
                "cannot be at {rpm} rpm one cycle after the command"
            );
        }
        if rpm == 1200.0 {
            // The speed ramps at the default 2000 rpm/s: 0.3 s later about 600 rpm (less
            // the three cycles the power state machine takes to switch on).
            let ramping = run(&mut backend, &mut spindle, 299);
            assert!((ramping.rpm - 600.0).abs() < 20.0, "{ramping:?}");
        }
        run(&mut backend, &mut spindle, 1500);
        let start = drives[1].position();
        let fb = run(&mut backend, &mut spindle, 200);
        assert!(fb.at_speed, "{rpm}: {fb:?}");
        assert!(
            (fb.rpm - rpm).abs() <= (0.02 * rpm).abs().max(5.0),
            "{fb:?}"
        );
        // The plant turned at that speed over the last 0.2 s: degrees per second = rpm · 6.
        let mean_rpm = (drives[1].position() - start) / 0.2 / 6.0;
        assert!(
            (mean_rpm - rpm).abs() < 0.002 * rpm.abs() + 0.1,
            "plant {mean_rpm} rpm for {rpm}"
        );
        assert!(fb.fault.is_none());
    }
}

#[test]
fn spindle_alone_cycles_by_itself() {
    let (backend, _bus, drives) = simulated_backend(&config(false), PERIOD, &[]).expect("starts");
    let mut spindle = backend.spindle().expect("spindle");
    drop(backend);
    spindle.command(3000.0).expect("command");
    let mut t = 0.0;
    let mut fb = None;
    for _ in 0..3000 {
        t += PERIOD;
        fb = Some(spindle.cycle(t).expect("cycle"));
    }
    let fb = fb.expect("ran");
    assert!(fb.at_speed && (fb.rpm - 3000.0).abs() <= 60.0, "{fb:?}");
    assert!((drives[0].velocity() / 6.0 - 3000.0).abs() < 0.03 * 3000.0);
    assert!(!f64::NAN.is_finite() && spindle.command(f64::NAN).is_err());
}

#[test]
fn spindle_fault_stops_the_axes_too() {
    let (mut backend, _bus, drives) =
        simulated_backend(&config(true), PERIOD, &[]).expect("starts");
    let mut spindle = backend.spindle().expect("spindle");
    backend.enable().expect("enables");
    spindle.command(1000.0).expect("command");
    let mut fb = vec![AxisFeedback::default(); 1];
    let mut t = 0.0;
    for _ in 0..200 {
        t += PERIOD;
        backend
            .cycle(t, &[Setpoint::default()], &mut fb)
            .expect("cycle");
        spindle.cycle(t).expect("cycle");
    }
    drives[1].inject(|i| i.fault = Some(0x4310));
    t += PERIOD;
    backend
        .cycle(t, &[Setpoint::default()], &mut fb)
        .expect("cycle");
    let s = spindle.cycle(t).expect("cycle");
    assert!(
        matches!(&s.fault, Some(AxisFault::Drive { code: 0x4310, text }) if text.contains("node 5")),
        "{s:?}"
    );
    assert!(!s.at_speed);
    assert!(fb[0].fault.is_some(), "the axis is stopped as well");
    assert!(backend.stop_report().expect("report").contains("node 5"));
}

#[test]
fn axis_fault_stops_the_spindle_until_commanded_again() {
    let (mut backend, _bus, drives) =
        simulated_backend(&config(true), PERIOD, &[]).expect("starts");
    let mut spindle = backend.spindle().expect("spindle");
    backend.enable().expect("enables");
    spindle.command(800.0).expect("command");
    let mut fb = vec![AxisFeedback::default(); 1];
    let mut t = 0.0;
    let mut step = |backend: &mut klar_drivers::cia402::Cia402Backend,
                    spindle: &mut klar_drivers::cia402::Cia402Spindle,
                    fb: &mut [AxisFeedback],
                    n: usize| {
        let mut s = None;
        for _ in 0..n {
            t += PERIOD;
            backend.cycle(t, &[Setpoint::default()], fb).expect("cycle");
            s = Some(spindle.cycle(t).expect("cycle"));
        }
        s.expect("ran")
    };
    assert!(step(&mut backend, &mut spindle, &mut fb, 1000).at_speed);
    drives[0].inject(|i| i.fault = Some(0x7121));
    let s = step(&mut backend, &mut spindle, &mut fb, 1);
    assert!(
        matches!(&s.fault, Some(AxisFault::Drive { code: 0, text }) if text.contains("node 1")),
        "{s:?}"
    );
    // The spindle brakes with its quick stop and comes to rest.
    let s = step(&mut backend, &mut spindle, &mut fb, 1000);
    assert!(s.rpm.abs() < 1.0, "{s:?}");
    backend.reset_fault(0).expect("axis reset");
    assert!(
        backend.stop_report().is_none(),
        "the spindle's stop was only a consequence"
    );
    let s = step(&mut backend, &mut spindle, &mut fb, 500);
    assert!(
        s.fault.is_none() && s.rpm.abs() < 1.0,
        "stays off until commanded: {s:?}"
    );
    spindle.command(800.0).expect("command");
    let s = step(&mut backend, &mut spindle, &mut fb, 1000);
    assert!(s.at_speed && (s.rpm - 800.0).abs() < 16.0, "{s:?}");
}
