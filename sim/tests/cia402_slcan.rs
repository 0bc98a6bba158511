//! The whole CANopen path over slcan on a pseudo-terminal: the CiA 402 backend as slcan
//! host on one end, simulated drives behind the adapter end on the other.

use klar_drivers::can::slcan::{SlcanBus, SlcanOptions};
use klar_drivers::cia402::{CanOpenConfig, Cia402Backend, PowerState};
use klar_motion::{AxisBackend, AxisFault, AxisFeedback, AxisState, Setpoint};
use klar_sim::cia402::{SimCia402Drive, SimDriveConfig, plant_for, serve_on_slcan};

const PERIOD: f64 = 0.002;

fn config() -> CanOpenConfig {
    toml::from_str(
        r#"
        bus = { adapter = "slcan", port = "(pty)", bitrate = 1000000 }
        heartbeat_ms = 100
        pdo_wait_ms = 200.0
        sdo_timeout_ms = 500
        [[drives]]
        node = 1
        counts_per_unit = 1000.0
        [[drives]]
        node = 2
        counts_per_unit = 500.0
        invert = true
        "#,
    )
    .expect("config parses")
}

#[test]
fn program_runs_over_slcan_and_a_fault_stops_it() {
    let cfg = config();
    let (host_end, adapter_end) = serialport::TTYPort::pair().expect("pty pair");
    let mut drives = Vec::new();
    let mut controls = Vec::new();
    for (i, d) in cfg.drives.iter().enumerate() {
        let (drive, control) = SimCia402Drive::new(SimDriveConfig {
            node: d.node,
            plant: plant_for(&cfg, i),
            start_position: 1.0,
        });
        drives.push(drive);
        controls.push(control);
    }
    let _runner = serve_on_slcan(adapter_end, 1_000_000, drives).expect("drives serve");
    let bus = SlcanBus::from_tty(host_end, SlcanOptions::host(1_000_000)).expect("host opens");
    let mut backend = Cia402Backend::with_bus(&cfg, PERIOD, Box::new(bus)).expect("starts");
    backend.enable().expect("enables");
    let mut fb = vec![AxisFeedback::default(); 2];
    let mut t = 0.0;
    // Drive 2 counts the other way round: its plant runs at minus the axis position.
    let start = [1.0, -1.0];
    let end = [3.0, 0.5];
    let steps = 150;
    for k in 0..=steps + 50 {
        t += PERIOD;
        let s = (f64::from(k) / f64::from(steps)).min(1.0);
        let blend = 0.5 * (1.0 - (std::f64::consts::PI * s).cos());
        let sps: Vec<Setpoint> = start
            .iter()
            .zip(&end)
            .map(|(a, b)| Setpoint {
                position: a + (b - a) * blend,
                ..Default::default()
            })
            .collect();
        backend.cycle(t, &sps, &mut fb).expect("cycle");
        assert!(
            fb.iter().all(|f| f.state == AxisState::Enabled),
            "{:?}",
            backend.stop_report()
        );
    }
    assert!((fb[0].position - 3.0).abs() < 2e-3, "{}", fb[0].position);
    assert!(
        (fb[1].position - 0.5).abs() < 2e-3 * 2.0,
        "{}",
        fb[1].position
    );
    assert!((controls[0].position() - 3.0).abs() < 2e-3);
    assert!(
        (controls[1].position() + 0.5).abs() < 4e-3,
        "{}",
        controls[1].position()
    );
    // An injected EMCY fault on node 1 stops both axes and names the node.
    controls[0].inject(|i| i.fault = Some(0x4310));
    for _ in 0..3 {
        t += PERIOD;
        let hold: Vec<Setpoint> = end
            .iter()
            .map(|&p| Setpoint {
                position: p,
                ..Default::default()
            })
            .collect();
        backend.cycle(t, &hold, &mut fb).expect("cycle");
    }
    assert!(
        matches!(&fb[0].fault, Some(AxisFault::Drive { code: 0x4310, .. })),
        "{:?}",
        fb[0].fault
    );
    assert!(fb[1].fault.is_some());
    assert!(backend.stop_report().expect("report").contains("node 1"));
    assert_eq!(controls[1].power_state(), Some(PowerState::QuickStopActive));
}
