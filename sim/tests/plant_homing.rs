//! Homing of the servo plant: the reference lands on the home switch from either side,
//! removing the encoder's power-on offset.

mod plant_support;

use klar_motion::{AxisFeedback, AxisState};
use klar_sim::plant::{PlantError, ServoPlant, SimAxisParams};
use plant_support::{PERIOD, ramp_to_velocity, rest, time_of};

const HOME: f64 = 50.0;
const OFFSET: f64 = 7.25;
const COUNT: f64 = 1e-4;

fn unhomed() -> SimAxisParams {
    SimAxisParams {
        home_switch: HOME,
        unreferenced_offset: OFFSET,
        limit_switch_negative: Some(-100.0),
        limit_switch_positive: Some(200.0),
        ..SimAxisParams::default()
    }
}

/// Runs cycles (setpoints are ignored while homing) until the axis is Enabled again.
fn home(plant: &mut ServoPlant) -> (AxisFeedback, u32) {
    plant.start_homing().expect("start homing");
    assert_eq!(plant.state(), AxisState::Homing);
    assert!(!plant.homed());
    for k in 1..=60_000 {
        let fb = plant.step(rest(-999.0), PERIOD);
        assert_eq!(fb.fault, None, "fault while homing");
        if fb.state != AxisState::Homing {
            return (fb, k);
        }
    }
    panic!("homing did not finish");
}

fn check_homes_from(start: f64) {
    let params = unhomed();
    let (v_home, a_home) = (params.homing_velocity, params.homing_acceleration);
    let mut plant = ServoPlant::new(params, start);
    assert!(!plant.homed());
    // Before homing the encoder reads the truth plus its power-on offset.
    assert!((plant.measured_position() - (start + OFFSET)).abs() <= COUNT / 2.0 + 1e-12);
    assert!(plant.start_homing().is_err(), "homing needs power");
    plant.enable().expect("enable");
    let (fb, cycles) = home(&mut plant);
    assert_eq!(fb.state, AxisState::Enabled);
    assert!(fb.homed);
    // The reference: the measured position at the switch edge is the switch position, so
    // the measured position equals the truth to within a count from now on.
    assert!(
        (fb.position - HOME).abs() <= COUNT + 1e-12,
        "measured {}",
        fb.position
    );
    assert!((plant.actual_position() - HOME).abs() <= 2.0 * COUNT);
    assert!((fb.position - plant.actual_position()).abs() <= COUNT);
    // Duration: at least the search at homing speed from the start to the switch.
    let t = f64::from(cycles) * PERIOD;
    assert!(t >= (HOME - start).abs() / v_home, "homed after {t} s");
    assert!(t <= (HOME - start).abs() / v_home + 4.0 * v_home / a_home + 0.5);
    // The reference holds during a move: measured tracks the truth.
    for k in 1..=1500 {
        let fb = plant.step(
            ramp_to_velocity(fb.position, 40.0, 2000.0, 50_000.0, time_of(k)),
            PERIOD,
        );
        assert_eq!(fb.fault, None);
        assert!((fb.position - plant.actual_position()).abs() <= COUNT);
    }
}

#[test]
fn homing_from_below_the_switch_lands_on_it() {
    check_homes_from(20.0);
}

#[test]
fn homing_from_above_the_switch_lands_on_it() {
    check_homes_from(80.0);
}

#[test]
fn homing_is_abandoned_by_disable_and_refused_when_faulted() {
    let mut plant = ServoPlant::new(unhomed(), 0.0);
    plant.enable().expect("enable");
    plant.start_homing().expect("start");
    for _ in 0..100 {
        plant.step(rest(0.0), PERIOD);
    }
    plant.disable();
    assert_eq!(plant.state(), AxisState::Disabled);
    assert!(!plant.homed());
    plant.inject_fault(klar_motion::AxisFault::EStop);
    assert!(matches!(
        plant.start_homing(),
        Err(PlantError::WrongState {
            state: AxisState::Faulted,
            ..
        })
    ));
}

#[test]
fn start_homed_axis_reads_the_truth_at_once() {
    let params = SimAxisParams {
        start_homed: true,
        ..unhomed()
    };
    let plant = ServoPlant::new(params, 12.345_67);
    assert!(plant.homed());
    assert!((plant.measured_position() - 12.345_67).abs() <= COUNT);
}
