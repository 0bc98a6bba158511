//! The Modbus client backends of klar-drivers against the simulated Modbus devices on a
//! pseudo-terminal: a positioning servo drive (built on the servo plant) and a VFD.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use klar_drivers::modbus::{
    ModbusServo, ModbusServoConfig, ModbusVfd, ModbusVfdConfig, Parity, SerialLineConfig,
    ServoRegisterMap, VfdPreset, WordOrder,
};
use klar_motion::{AxisBackend, AxisFault, AxisFeedback, AxisState, Setpoint, SpindleBackend};
use klar_sim::modbus::{
    PositioningLimits, SharedDevice, SimModbusBus, SimModbusServo, SpindleParams, simulate_vfd,
};
use klar_sim::plant::SimAxisParams;

const WAIT: Duration = Duration::from_secs(10);

fn line(path: &str) -> SerialLineConfig {
    let mut l = SerialLineConfig::new(path);
    l.baud = 115_200;
    l.parity = Parity::None;
    l.timeout = 0.25;
    l.retries = 1;
    l
}

fn map(order: WordOrder) -> ServoRegisterMap {
    ServoRegisterMap {
        target_position: 0x0010,
        actual_position: 0x0020,
        status: 0x0022,
        status_table: Default::default(),
        control: 0x0030,
        fault_code: Some(0x0023),
        enable_bit: 0,
        fault_reset_bit: 7,
        home_bit: Some(4),
        enabled_bit: 1,
        fault_bit: 3,
        homed_bit: Some(12),
        counts_per_unit: 1000.0,
        word_order: order,
    }
}

struct Rig {
    servo: Arc<Mutex<SimModbusServo>>,
    backend: ModbusServo,
    _bus: SimModbusBus,
}

fn servo_rig(order: WordOrder, params: SimAxisParams, position: f64) -> Rig {
    let m = map(order);
    let device = Arc::new(Mutex::new(SimModbusServo::new(
        m.clone(),
        params,
        PositioningLimits {
            velocity: 100.0,
            acceleration: 500.0,
        },
        position,
    )));
    let shared: SharedDevice = device.clone();
    let bus = SimModbusBus::start(vec![(5, shared)]).expect("start the simulated line");
    let config = ModbusServoConfig {
        serial: line(bus.path()),
        unit: 5,
        poll_period: 0.01,
        registers: m,
    };
    let backend = ModbusServo::open(&config).expect("open the servo backend");
    Rig {
        servo: device,
        backend,
        _bus: bus,
    }
}

/// Runs servo cycles holding `target` until `pred` holds (wall clock, bounded).
fn drive_until(
    backend: &mut ModbusServo,
    target: f64,
    pred: impl Fn(&AxisFeedback) -> bool,
) -> AxisFeedback {
    let start = Instant::now();
    let mut fb = [AxisFeedback::default()];
    let sp = [Setpoint {
        position: target,
        ..Setpoint::default()
    }];
    loop {
        backend
            .cycle(start.elapsed().as_secs_f64(), &sp, &mut fb)
            .expect("servo cycle");
        if pred(&fb[0]) {
            return fb[0].clone();
        }
        assert!(start.elapsed() < WAIT, "not reached in time: {:?}", fb[0]);
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn homed_params() -> SimAxisParams {
    SimAxisParams {
        start_homed: true,
        ..SimAxisParams::default()
    }
}

#[test]
fn modbus_axis_positions_the_simulated_drive() {
    for order in [WordOrder::HighFirst, WordOrder::LowFirst] {
        let mut rig = servo_rig(order, homed_params(), 12.5);
        // Before enabling, the actual position is read back through the register map.
        let fb = drive_until(&mut rig.backend, 12.5, |f| f.position != 0.0);
        assert!((fb.position - 12.5).abs() < 1e-3 + 1e-9, "{fb:?}");
        assert_eq!(fb.state, AxisState::Disabled);

        rig.backend.enable().expect("enable");
        // Enabling writes target = actual: the drive does not move.
        assert!((rig.servo.lock().unwrap().target() - 12.5).abs() < 1e-9);

        let fb = drive_until(&mut rig.backend, -40.25, |f| {
            f.state == AxisState::Enabled && (f.position + 40.25).abs() < 2e-3
        });
        let dev = rig.servo.lock().unwrap();
        // The drive received exactly -40.25 mm = -40250 counts in this word order.
        assert_eq!(dev.target(), -40.25, "{order:?}");
        // klar's reading agrees with the drive's encoder to one count.
        assert!((fb.position - dev.plant().measured_position()).abs() <= 1e-3 + 1e-9);
        assert!((fb.following_error - (-40.25 - fb.position)).abs() < 1e-12);
        assert!(fb.homed);
        assert_eq!(fb.fault, None);
        drop(dev);
        // Closing the backend leaves the drive disabled.
        let Rig {
            servo,
            backend,
            _bus: bus,
        } = rig;
        drop(backend);
        assert_eq!(servo.lock().unwrap().plant().state(), AxisState::Disabled);
        drop(bus);
    }
}

#[test]
fn silent_drive_faults_the_axis_and_reset_recovers() {
    let mut rig = servo_rig(WordOrder::HighFirst, homed_params(), 0.0);
    rig.backend.enable().expect("enable");
    drive_until(&mut rig.backend, 5.0, |f| (f.position - 5.0).abs() < 2e-3);

    rig.servo.lock().unwrap().set_responding(false);
    let fb = drive_until(&mut rig.backend, 5.0, |f| f.fault.is_some());
    assert_eq!(fb.fault, Some(AxisFault::CommunicationLost));
    assert_eq!(fb.state, AxisState::Faulted);
    let err = rig.backend.snapshot().last_error.unwrap_or_default();
    assert!(err.contains("giving up after 2 attempts"), "{err}");

    rig.servo.lock().unwrap().set_responding(true);
    rig.backend.reset_fault(0).expect("reset");
    let fb = drive_until(&mut rig.backend, 5.0, |f| f.fault.is_none());
    assert_ne!(fb.state, AxisState::Faulted);
    rig.backend.enable().expect("enable again");
    drive_until(&mut rig.backend, 7.0, |f| {
        f.state == AxisState::Enabled && (f.position - 7.0).abs() < 2e-3
    });
}

#[test]
fn drive_fault_code_is_reported() {
    let mut rig = servo_rig(WordOrder::HighFirst, homed_params(), 0.0);
    rig.backend.enable().expect("enable");
    drive_until(&mut rig.backend, 0.0, |f| f.state == AxisState::Enabled);
    rig.servo.lock().unwrap().plant_mut().set_estop(true);
    let fb = drive_until(&mut rig.backend, 0.0, |f| f.fault.is_some());
    // The simulated drive reports an e-stop as code 0x0301 in its fault-code register.
    assert!(
        matches!(fb.fault, Some(AxisFault::Drive { code: 0x0301, .. })),
        "{fb:?}"
    );
    assert_eq!(fb.state, AxisState::Faulted);

    // Release the e-stop, acknowledge, enable again: the axis follows once more.
    rig.servo.lock().unwrap().plant_mut().set_estop(false);
    let start = Instant::now();
    while rig.backend.reset_fault(0).is_err()
        || drive_until(&mut rig.backend, 0.0, |_| true).fault.is_some()
    {
        assert!(start.elapsed() < WAIT, "the fault does not clear");
        std::thread::sleep(Duration::from_millis(20));
    }
    rig.backend.enable().expect("enable after the fault");
    let fb = drive_until(&mut rig.backend, 3.0, |f| {
        f.state == AxisState::Enabled && (f.position - 3.0).abs() < 2e-3
    });
    assert_eq!(fb.fault, None);
}

#[test]
fn homing_over_modbus() {
    let params = SimAxisParams {
        start_homed: false,
        home_switch: 0.0,
        homing_velocity: 20.0,
        ..SimAxisParams::default()
    };
    let mut rig = servo_rig(WordOrder::HighFirst, params, -3.0);
    rig.backend.enable().expect("enable");
    let fb = drive_until(&mut rig.backend, -3.0, |f| f.state == AxisState::Enabled);
    assert!(!fb.homed);
    rig.backend.start_homing(0).expect("start homing");
    let fb = drive_until(&mut rig.backend, 0.0, |f| f.homed);
    assert_eq!(fb.fault, None);
    let fb = drive_until(&mut rig.backend, 0.0, |f| {
        f.state == AxisState::Enabled && f.position.abs() < 2e-3
    });
    assert!(fb.homed);
}

#[test]
fn vfd_over_the_simulated_line_ramps_to_speed() {
    let profile = VfdPreset::Delta { rpm_per_hz: 60.0 };
    let params = SpindleParams {
        max_rpm: 24_000.0,
        acceleration: 10_000.0,
        ..SpindleParams::default()
    };
    let mut wanted = ModbusVfdConfig::new(line("to be replaced"), 2, 24_000.0, profile);
    wanted.poll_period = 0.01;
    let sim = simulate_vfd(&wanted, params).expect("start the simulated VFD");
    let (device, bus, config) = (sim.device, sim.bus, sim.config);
    assert_eq!(config.serial.port, bus.path());
    let mut vfd = ModbusVfd::open(&config).expect("open the VFD backend");
    vfd.command(-9_000.0).unwrap();
    let start = Instant::now();
    let mut ramp_seen = false;
    loop {
        let fb = vfd.cycle(start.elapsed().as_secs_f64()).unwrap();
        ramp_seen |= fb.rpm < -100.0 && fb.rpm > -8_000.0;
        if fb.at_speed && (fb.rpm + 9_000.0).abs() <= 0.6 {
            break;
        }
        assert!(start.elapsed() < WAIT, "{fb:?}");
        std::thread::sleep(Duration::from_millis(2));
    }
    assert!(ramp_seen);
    // The reading is one register resolution (0.01 Hz = 0.6 rpm) from the end of the ramp;
    // the device reaches the command itself with the next polls.
    let start = Instant::now();
    while device.lock().unwrap().model().rpm() != -9_000.0 {
        assert!(
            start.elapsed() < WAIT,
            "the device stays at {} rpm",
            device.lock().unwrap().model().rpm()
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    device.lock().unwrap().inject_fault(9);
    let start = Instant::now();
    loop {
        let fb = vfd.cycle(0.0).unwrap();
        if let Some(f) = fb.fault {
            assert!(matches!(f, AxisFault::Drive { code: 9, .. }), "{f:?}");
            break;
        }
        assert!(start.elapsed() < WAIT);
        std::thread::sleep(Duration::from_millis(2));
    }
    assert!(bus.counters().answered.get(&2).copied().unwrap_or(0) > 10);
}
