//! Fault handling of the CiA 402 backend against simulated drives on an in-memory bus:
//! every fault stops all axes, names the node, and never panics.

use klar_drivers::can::memory::{FrameFate, MemoryBus};
use klar_drivers::canopen::CanOpenError;
use klar_drivers::cia402::{CanOpenConfig, Cia402Backend, Cia402Error, PowerState};
use klar_motion::{AxisBackend, AxisFault, AxisFeedback, AxisState, BackendError, Setpoint};
use klar_sim::cia402::{SimCia402Drive, SimDriveConfig, plant_for, simulated_backend};

const PERIOD: f64 = 0.001;

fn config(nodes: &[u8], extra: &str) -> CanOpenConfig {
    let mut text = format!(
        "bus = {{ adapter = \"sim\", bitrate = 1000000 }}\nheartbeat_ms = 50\nsdo_timeout_ms = 30\n{extra}\n"
    );
    for n in nodes {
        text.push_str(&format!(
            "[[drives]]\nnode = {n}\ncounts_per_unit = 1000.0\nhoming = {{ method = 35 }}\n"
        ));
    }
    toml::from_str(&text).expect("test config parses")
}

/// Runs `cycles` cycles commanding every axis to 0, from time `t`; returns the end time.
fn hold(backend: &mut Cia402Backend, t: f64, cycles: usize, fb: &mut [AxisFeedback]) -> f64 {
    let sps = vec![Setpoint::default(); fb.len()];
    let mut t = t;
    for _ in 0..cycles {
        t += PERIOD;
        backend
            .cycle(t, &sps, fb)
            .expect("cycle never fails on faults");
    }
    t
}

fn started(
    nodes: &[u8],
    extra: &str,
) -> (
    Cia402Backend,
    MemoryBus,
    Vec<klar_sim::cia402::SimDriveControl>,
) {
    let (mut b, bus, c) = simulated_backend(&config(nodes, extra), PERIOD, &[]).expect("starts");
    b.enable().expect("enables");
    (b, bus, c)
}

#[test]
fn heartbeat_loss_stops_all_axes_after_the_timeout() {
    let (mut backend, bus, _) = started(&[1, 2], "");
    let mut fb = vec![AxisFeedback::default(); 2];
    let t = hold(&mut backend, 0.0, 20, &mut fb);
    assert!(fb.iter().all(|f| f.fault.is_none()));
    // Node 2 keeps sending PDOs but its heartbeats vanish.
    bus.set_injector(|f| {
        if f.id().raw() == 0x702 {
            FrameFate::Drop
        } else {
            FrameFate::Deliver
        }
    });
    // Timeout is 3 × 50 ms: nothing may happen before 150 ms of silence …
    let t = hold(&mut backend, t, 100, &mut fb);
    assert!(
        fb.iter().all(|f| f.fault.is_none()),
        "{:?}",
        backend.stop_report()
    );
    // … and it must have happened by 150 ms plus one heartbeat period.
    hold(&mut backend, t, 110, &mut fb);
    assert_eq!(fb[1].fault, Some(AxisFault::CommunicationLost));
    assert!(matches!(fb[0].fault, Some(AxisFault::Drive { .. })));
    let report = backend.stop_report().expect("report");
    assert!(
        report.contains("node 2") && report.contains("heartbeat"),
        "{report}"
    );
}

#[test]
fn bus_off_stops_every_axis() {
    let (mut backend, bus, _) = started(&[1, 2, 3], "");
    let mut fb = vec![AxisFeedback::default(); 3];
    let t = hold(&mut backend, 0.0, 5, &mut fb);
    bus.set_bus_off(true);
    hold(&mut backend, t, 1, &mut fb);
    for f in &fb {
        assert_eq!(f.fault, Some(AxisFault::CommunicationLost));
        assert_eq!(f.state, AxisState::Faulted);
    }
    assert!(backend.stop_report().expect("report").contains("bus-off"));
}

#[test]
fn lost_pdos_are_tolerated_up_to_the_limit() {
    let (mut backend, bus, _) = started(&[1], "max_missed_pdos = 3\npdo_wait_ms = 0.0");
    let mut fb = vec![AxisFeedback::default(); 1];
    let t = hold(&mut backend, 0.0, 5, &mut fb);
    let dropped = std::sync::Arc::new(std::sync::atomic::AtomicU32::new(0));
    let counter = dropped.clone();
    // Lose exactly two transmit PDOs of node 1.
    bus.set_injector(move |f| {
        if f.id().raw() == 0x181 && counter.load(std::sync::atomic::Ordering::SeqCst) < 2 {
            counter.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
            FrameFate::Drop
        } else {
            FrameFate::Deliver
        }
    });
    let t = hold(&mut backend, t, 10, &mut fb);
    assert_eq!(dropped.load(std::sync::atomic::Ordering::SeqCst), 2);
    assert!(fb[0].fault.is_none(), "{:?}", backend.stop_report());
    // Now lose them all: the third missing one stops the axis.
    bus.set_injector(|f| {
        if f.id().raw() == 0x181 {
            FrameFate::Drop
        } else {
            FrameFate::Deliver
        }
    });
    let t = hold(&mut backend, t, 2, &mut fb);
    assert!(fb[0].fault.is_none());
    hold(&mut backend, t, 1, &mut fb);
    assert_eq!(fb[0].fault, Some(AxisFault::CommunicationLost));
    assert!(
        backend
            .stop_report()
            .expect("report")
            .contains("node 1: no transmit PDO for 3")
    );
}

#[test]
fn malformed_pdo_stops_at_once() {
    let (mut backend, _bus, drives) = started(&[1, 5], "");
    let mut fb = vec![AxisFeedback::default(); 2];
    let t = hold(&mut backend, 0.0, 5, &mut fb);
    drives[1].inject(|i| i.truncate_tpdos = true);
    hold(&mut backend, t, 1, &mut fb);
    assert_eq!(fb[1].fault, Some(AxisFault::CommunicationLost));
    let report = backend.stop_report().expect("report");
    assert!(
        report.contains("node 5") && report.contains("5 bytes"),
        "{report}"
    );
    // The healthy drive got a quick stop.
    hold(&mut backend, t, 2, &mut fb);
    assert_eq!(drives[0].power_state(), Some(PowerState::QuickStopActive));
}

#[test]
fn malformed_emergency_is_a_protocol_fault() {
    let (mut backend, bus, _) = started(&[3], "");
    let mut fb = vec![AxisFeedback::default(); 1];
    let t = hold(&mut backend, 0.0, 5, &mut fb);
    // An EMCY shortened to 7 bytes breaks CiA 301.
    let mut once = true;
    bus.set_injector(move |f| {
        if f.id().raw() == 0x083 && once {
            once = false;
            FrameFate::Truncate
        } else {
            FrameFate::Deliver
        }
    });
    let mut ep = bus.endpoint();
    klar_drivers::can::CanBus::send(
        &mut ep,
        &klar_drivers::can::CanFrame::standard(0x083, &[0x10, 0x23, 1, 0, 0, 0, 0, 0])
            .expect("frame"),
    )
    .expect("send");
    hold(&mut backend, t, 1, &mut fb);
    let report = backend.stop_report().expect("report");
    assert!(
        report.contains("node 3") && report.contains("EMCY with 7 bytes"),
        "{report}"
    );
}

#[test]
fn following_error_in_the_drive_surfaces_with_its_code() {
    let cfg = config(&[1], "");
    let mut plant = plant_for(&cfg, 0);
    plant.following_error_limit = 0.01;
    plant.force_limit = 500.0;
    let (mut backend, _bus, _) = simulated_backend(&cfg, PERIOD, &[plant]).expect("starts");
    backend.enable().expect("enables");
    let mut fb = vec![AxisFeedback::default(); 1];
    // A 20 mm jump cannot be followed within 10 µm.
    let sp = [Setpoint {
        position: 20.0,
        ..Default::default()
    }];
    let mut t = 0.0;
    for _ in 0..20 {
        t += PERIOD;
        backend.cycle(t, &sp, &mut fb).expect("cycle");
    }
    match &fb[0].fault {
        Some(AxisFault::Drive { code, text }) => {
            assert_eq!(*code, 0x8611);
            assert!(text.contains("following error"), "{text}");
        }
        other => panic!("expected the drive's following error, got {other:?}"),
    }
}

#[test]
fn sdo_timeout_at_start_names_the_node() {
    let cfg = config(&[1, 2], "");
    let bus = MemoryBus::new();
    let ep = bus.endpoint();
    for (i, d) in cfg.drives.iter().enumerate() {
        let (drive, control) = SimCia402Drive::new(SimDriveConfig {
            node: d.node,
            plant: plant_for(&cfg, i),
            start_position: 0.0,
        });
        if d.node == 2 {
            control.inject(|i| i.ignore_sdo = true);
        }
        bus.attach(Box::new(drive));
    }
    match Cia402Backend::with_bus(&cfg, PERIOD, Box::new(ep)) {
        Err(Cia402Error::CanOpen(CanOpenError::SdoTimeout {
            node, timeout_ms, ..
        })) => {
            assert_eq!(node, 2);
            assert_eq!(timeout_ms, 30);
        }
        Err(e) => panic!("wrong error {e}"),
        Ok(_) => panic!("must not start"),
    }
}

#[test]
fn sdo_timeout_while_running_is_reported_not_panicked() {
    let (mut backend, _bus, drives) = started(&[1], "");
    drives[0].inject(|i| i.ignore_sdo = true);
    match backend.start_homing(0) {
        Err(BackendError::Communication(msg)) => assert!(msg.contains("node 1"), "{msg}"),
        other => panic!("expected a communication error, got {other:?}"),
    }
}

#[test]
fn missing_node_fails_the_boot_wait() {
    let cfg = config(&[1, 9], "boot_timeout_ms = 50");
    let bus = MemoryBus::new();
    let ep = bus.endpoint();
    let (drive, _) = SimCia402Drive::new(SimDriveConfig {
        node: 1,
        plant: plant_for(&cfg, 0),
        start_position: 0.0,
    });
    bus.attach(Box::new(drive));
    match Cia402Backend::with_bus(&cfg, PERIOD, Box::new(ep)) {
        Err(Cia402Error::CanOpen(CanOpenError::BootTimeout { nodes, .. })) => {
            assert_eq!(nodes, vec![9])
        }
        Err(e) => panic!("wrong error {e}"),
        Ok(_) => panic!("must not start"),
    }
}

#[test]
fn bus_load_check_refuses_six_drives_at_one_millisecond() {
    let cfg = config(&[1, 2, 3, 4, 5, 6], "");
    let err = match simulated_backend(&cfg, PERIOD, &[]) {
        Err(Cia402Error::BusLoad(e)) => e,
        Err(e) => panic!("wrong error {e}"),
        Ok(_) => panic!("must refuse"),
    };
    // SYNC: 55 bits; 6-byte PDO: 47 + 48 + ⌊(34 + 48 − 1)/4⌋ = 115 bits; 12 PDOs.
    let bits = 55.0 + 12.0 * 115.0;
    assert!((err.load_percent - bits / 1000.0 * 100.0).abs() < 1e-9);
    // 1435 bits at 80 % of 1 Mbit/s need 1.794 ms: 2 ms is the next 0.25 ms step.
    assert!((err.fitting_ms - 2.0).abs() < 1e-9);
    assert!(err.to_string().contains("2 ms"), "{err}");
    // And at that period it starts.
    assert!(simulated_backend(&cfg, 0.002, &[]).is_ok());
}
