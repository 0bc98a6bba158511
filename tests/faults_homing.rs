//! Motion needs a reference: a machine whose axes power up unreferenced refuses to run a
//! program (nothing moves), the homing sequence references every axis at its home switch —
//! the encoder's power-on offset removed, to the count — and then the state machine lets a
//! program start.

mod common;

use common::{program, run};
use klar::config::{BackendConfig, MachineConfig};
use klar::machine::MachineIo;
use klar::runtime::RunError;
use klar::state::{Event, MachineState, home_axes};
use klar_interp::AxisLetter;

/// The built-in mill with incremental encoders that read `offset` too much at power-on and
/// home switches at `home` (X, Y, Z).
fn unreferenced_mill(offset: f64, home: [f64; 3]) -> MachineConfig {
    let mut m = MachineConfig::builtin_mill();
    m.start_homed = false;
    for (a, h) in m.axes.iter_mut().zip(home) {
        if let BackendConfig::Sim(p) = &mut a.backend {
            p.start_homed = false;
            p.unreferenced_offset = offset;
            p.home_switch = h;
            p.homing_velocity = 40.0;
        }
    }
    m
}

#[test]
fn an_unreferenced_machine_refuses_to_run() {
    let machine = unreferenced_mill(12.3456, [50.0, -20.0, 150.0]);
    let (result, trace) = run(&program("rectangle.h"), &machine);
    match result.expect_err("refused").error {
        RunError::NotHomed(axes) => {
            assert_eq!(axes, vec![AxisLetter::X, AxisLetter::Y, AxisLetter::Z])
        }
        other => panic!("expected NotHomed, got {other}"),
    }
    assert!(trace.t.is_empty(), "{} cycles ran", trace.t.len());
}

#[test]
fn homing_references_every_axis_at_its_switch_to_the_count() {
    let offset = 12.3456;
    let home = [50.0, -20.0, 150.0];
    let machine = unreferenced_mill(offset, home);
    let letters = machine.letters();
    let mut io = MachineIo::open(&machine).expect("machine opens");
    let mut state = MachineState::Off.apply(Event::PowerOn).unwrap();
    assert!(!state.may_start());
    // The tool axis first, then X and Y.
    let t = home_axes(
        &mut io,
        &letters,
        &[2, 0, 1],
        0.0,
        machine.servo_period,
        30.0,
    )
    .expect("homing");
    assert!(t > 0.0);
    let sim = io.sim_axes().expect("sim axes").clone();
    for (i, &l) in letters.iter().enumerate() {
        let f = &io.feedback()[i];
        assert!(f.homed, "axis {l} not homed");
        let p = sim.plant_of(l).unwrap();
        let cpu = p.params().counts_per_unit;
        // After referencing, the encoder reads the true position: the offset is gone.
        assert_eq!(
            (p.measured_position() * cpu).round() as i64,
            (p.actual_position() * cpu).round() as i64,
            "axis {l}"
        );
        // Homing ends back at the switch edge, which now reads as the switch position.
        assert!(
            (f.position - home[i]).abs() <= 1.0 / cpu + 1e-12,
            "axis {l} at {} after homing, switch at {}",
            f.position,
            home[i]
        );
    }
    state = state.apply(Event::Referenced).unwrap();
    assert!(state.may_start());
    assert_eq!(state.apply(Event::Start), Ok(MachineState::Running));
}
