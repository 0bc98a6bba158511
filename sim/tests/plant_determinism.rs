//! Determinism: the same sequence of calls gives bit-identical feedback.

mod plant_support;

use klar_motion::AxisFault;
use klar_sim::plant::{ServoPlant, SimAxisParams};
use plant_support::{PERIOD, SCurve, rest, time_of};

/// A scenario exercising every state: homing, a jerk-limited move, a fault and a reset,
/// a coast while disabled. Returns every reported quantity as raw bits.
fn scenario() -> Vec<u64> {
    let params = SimAxisParams {
        home_switch: 5.0,
        unreferenced_offset: -3.3,
        ..SimAxisParams::default()
    };
    let mut plant = ServoPlant::new(params, 1.0);
    let mut bits = Vec::new();
    let mut record = |plant: &ServoPlant, fb: &klar_motion::AxisFeedback| {
        bits.push(fb.position.to_bits());
        bits.push(fb.following_error.to_bits());
        bits.push(plant.actual_position().to_bits());
        bits.push(plant.actual_velocity().to_bits());
        bits.push(fb.state as u64);
    };
    plant.enable().expect("enable");
    plant.start_homing().expect("home");
    while plant.state() == klar_motion::AxisState::Homing {
        let fb = plant.step(rest(0.0), PERIOD);
        record(&plant, &fb);
    }
    let profile = SCurve::new(plant.measured_position(), 60.0, 166.0, 2000.0, 50_000.0);
    for k in 1..=300 {
        let fb = plant.step(profile.at(time_of(k)), PERIOD);
        record(&plant, &fb);
    }
    plant.inject_fault(AxisFault::CommunicationLost);
    for _ in 0..100 {
        let fb = plant.step(rest(0.0), PERIOD);
        record(&plant, &fb);
    }
    plant.reset_fault().expect("reset");
    plant.enable().expect("enable");
    let here = plant.measured_position();
    for k in 1..=200 {
        let fb = plant.step(rest(here + 0.001 * f64::from(k)), PERIOD);
        record(&plant, &fb);
    }
    plant.disable();
    for _ in 0..300 {
        let fb = plant.step(rest(0.0), PERIOD);
        record(&plant, &fb);
    }
    bits
}

#[test]
fn two_runs_are_bit_identical() {
    let first = scenario();
    let second = scenario();
    assert!(first.len() > 5 * 1000);
    assert_eq!(first, second);
}
