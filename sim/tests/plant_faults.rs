//! Faults and power states of the servo plant against closed forms: braking distance at
//! the force limit, the time a following-error fault must occur, coasting on friction.

mod plant_support;

use klar_motion::{AxisFault, AxisState, Setpoint};
use klar_sim::plant::{FAULT_INVALID_PARAMS, PlantError, ServoPlant, SimAxisParams};
use plant_support::{PERIOD, ramp_to_velocity, rest, time_of};

/// Metres per mm.
const S: f64 = 1e-3;

fn homed_defaults() -> SimAxisParams {
    SimAxisParams {
        start_homed: true,
        ..SimAxisParams::default()
    }
}

/// Drives `plant` along a run-up to `v` until `stop(cycle, plant)` says so; returns the
/// number of cycles run.
fn run_at_velocity(
    plant: &mut ServoPlant,
    start: f64,
    v: f64,
    max_cycles: u32,
    mut stop: impl FnMut(&ServoPlant) -> bool,
) -> u32 {
    for k in 1..=max_cycles {
        plant.step(
            ramp_to_velocity(start, v, 2000.0, 50_000.0, time_of(k)),
            PERIOD,
        );
        if stop(plant) {
            return k;
        }
    }
    max_cycles
}

#[test]
fn limit_switch_faults_and_brakes_within_the_force_limited_distance() {
    let params = SimAxisParams {
        limit_switch_positive: Some(50.0),
        limit_switch_negative: Some(-50.0),
        ..homed_defaults()
    };
    let (m, f_max, b, fc) = (
        params.mass,
        params.force_limit,
        params.viscous_friction,
        params.coulomb_friction,
    );
    let h = PERIOD / f64::from(params.substeps);
    let mut plant = ServoPlant::new(params, 0.0);
    plant.enable().expect("enable");
    let v0 = 150.0;
    let mut v_at_switch = 0.0;
    let k = run_at_velocity(&mut plant, 0.0, v0, 2000, |p| {
        if p.actual_position() < 50.0 {
            v_at_switch = p.actual_velocity();
        }
        p.state() == AxisState::Faulted
    });
    assert!(k < 2000, "never reached the switch");
    assert!((v_at_switch - v0).abs() < 0.5, "cruising at {v_at_switch}");
    // Braking (it takes v₀/a ≈ 7.5 ms, more than the cycle that reported the fault) uses
    // the full force against the motion.
    assert!(plant.actual_velocity() > 0.0);
    assert_eq!(plant.drive_force(), -f_max);
    // Let it come to rest; setpoints keep pushing beyond the switch and must be ignored.
    for j in 1..=500 {
        let fb = plant.step(
            ramp_to_velocity(0.0, v0, 2000.0, 50_000.0, time_of(k + j)),
            PERIOD,
        );
        assert_eq!(fb.state, AxisState::Faulted);
        assert_eq!(fb.fault, Some(AxisFault::LimitSwitch { positive: true }));
    }
    assert_eq!(plant.actual_velocity(), 0.0);
    let overrun = plant.actual_position() - 50.0;
    // Braking at the force limit alone: d = v²/(2a), a = F_max/m (in m/s², so ×1000 for
    // mm/s²). Friction only shortens it; detection costs at most one substep of travel.
    let a_force = f_max / m / S;
    let longest = v0 * v0 / (2.0 * a_force) + v0 * h;
    // With friction at its largest (start of braking) the deceleration is at most this.
    let a_most = (f_max + b * v0 * S + fc) / m / S;
    let shortest = v0 * v0 / (2.0 * a_most);
    assert!(
        overrun <= longest && overrun >= shortest,
        "overrun {overrun} outside [{shortest}, {longest}]"
    );
    // Cleared while on the switch it may move away but not further in.
    plant.reset_fault().expect("reset at rest");
    assert_eq!(plant.state(), AxisState::Disabled);
    plant.enable().expect("enable");
    let here = plant.measured_position();
    let mut k = 0;
    for j in 1..=300 {
        k = j;
        let fb = plant.step(
            ramp_to_velocity(here, -20.0, 2000.0, 50_000.0, time_of(j)),
            PERIOD,
        );
        assert_eq!(fb.fault, None, "moving off the switch must not fault");
    }
    assert!(plant.actual_position() < 50.0, "moved off the switch");
    let back = plant.measured_position();
    for j in 1..=500 {
        let fb = plant.step(
            ramp_to_velocity(back, 20.0, 2000.0, 50_000.0, time_of(j)),
            PERIOD,
        );
        if fb.fault.is_some() {
            assert_eq!(fb.fault, Some(AxisFault::LimitSwitch { positive: true }));
            return;
        }
    }
    panic!("driving into the switch again did not fault (after {k} cycles off it)");
}

#[test]
fn following_error_fault_occurs_when_the_closed_form_says() {
    // Command an acceleration five times what the force limit allows: A = 100 m/s².
    let params = homed_defaults();
    let limit = params.following_error_limit;
    let a_max = params.force_limit / params.mass / S;
    let a_cmd = 100_000.0;
    let mut plant = ServoPlant::new(params, 0.0);
    plant.enable().expect("enable");
    // e(t) ≤ ½·A·t² (the axis never moves backwards) and e(t) ≥ ½·(A − a_max)·t² (it
    // cannot accelerate faster than the force allows), so the window is crossed between:
    let earliest = (2.0 * limit / a_cmd).sqrt();
    let latest = (2.0 * limit / (a_cmd - a_max)).sqrt();
    for k in 1..=20 {
        let t = time_of(k);
        let sp = Setpoint {
            position: 0.5 * a_cmd * t * t,
            velocity: a_cmd * t,
            acceleration: a_cmd,
        };
        let fb = plant.step(sp, PERIOD);
        if let Some(fault) = fb.fault {
            assert!(t >= earliest, "faulted at {t}, earliest {earliest}");
            assert!(t - PERIOD <= latest, "faulted at {t}, latest {latest}");
            match fault {
                AxisFault::FollowingError(e) => assert!(e > limit && e < limit + 0.1, "{e}"),
                other => panic!("wrong fault {other:?}"),
            }
            assert_eq!(fb.state, AxisState::Faulted);
            return;
        }
    }
    panic!("no following-error fault");
}

#[test]
fn disabled_axis_coasts_to_a_stop_as_friction_predicts() {
    let params = homed_defaults();
    let (m, b, fc) = (
        params.mass,
        params.viscous_friction,
        params.coulomb_friction,
    );
    let mut plant = ServoPlant::new(params, 0.0);
    plant.enable().expect("enable");
    run_at_velocity(&mut plant, 0.0, 120.0, 300, |_| false);
    let v0 = plant.actual_velocity() * S; // m/s
    let x0 = plant.actual_position();
    plant.disable();
    assert_eq!(plant.state(), AxisState::Disabled);
    // m·v̇ = −b·v − F_c: stops after T = (m/b)·ln(1 + b·v₀/F_c) having travelled
    // d = (m/b)·(v₀ − (F_c/b)·ln(1 + b·v₀/F_c)).
    let log = (1.0 + b * v0 / fc).ln();
    let t_stop = m / b * log;
    let d = m / b * (v0 - fc / b * log) / S;
    let mut cycles = 0;
    while plant.actual_velocity() != 0.0 && cycles < 10_000 {
        // Setpoints are ignored while disabled.
        let fb = plant.step(rest(0.0), PERIOD);
        assert_eq!(fb.state, AxisState::Disabled);
        cycles += 1;
    }
    let travelled = plant.actual_position() - x0;
    assert!(
        (travelled - d).abs() < 1e-3 * d,
        "coasted {travelled} mm, closed form {d} mm"
    );
    let t = f64::from(cycles) * PERIOD;
    assert!(
        (t - t_stop).abs() <= PERIOD + 1e-3 * t_stop,
        "stopped after {t} s, {t_stop}"
    );
    // It stays put.
    let rest_at = plant.actual_position();
    for _ in 0..100 {
        plant.step(rest(0.0), PERIOD);
    }
    assert_eq!(plant.actual_position(), rest_at);
}

#[test]
fn estop_brakes_and_blocks_reset_until_released() {
    let params = homed_defaults();
    let a_force = params.force_limit / params.mass / S;
    let mut plant = ServoPlant::new(params, 0.0);
    plant.enable().expect("enable");
    let k = run_at_velocity(&mut plant, 0.0, 100.0, 300, |_| false);
    let x0 = plant.actual_position();
    let v0 = plant.actual_velocity();
    plant.set_estop(true);
    assert!(plant.estop_active());
    for j in 1..=200 {
        let fb = plant.step(
            ramp_to_velocity(0.0, 100.0, 2000.0, 50_000.0, time_of(k + j)),
            PERIOD,
        );
        assert_eq!(fb.fault, Some(AxisFault::EStop));
    }
    assert_eq!(plant.actual_velocity(), 0.0);
    let braked = plant.actual_position() - x0;
    assert!(
        braked > 0.0 && braked <= v0 * v0 / (2.0 * a_force) + 1e-9,
        "{braked}"
    );
    assert!(matches!(
        plant.reset_fault(),
        Err(PlantError::FaultPersists(_))
    ));
    assert!(plant.enable().is_err(), "enable only from Disabled");
    plant.set_estop(false);
    plant.reset_fault().expect("reset after release");
    assert_eq!(plant.state(), AxisState::Disabled);
    assert_eq!(plant.fault(), None);
    plant.enable().expect("enable");
    // After the reset the axis holds where it stopped.
    let here = plant.measured_position();
    let fb = plant.step(rest(here), PERIOD);
    assert_eq!(fb.state, AxisState::Enabled);
    assert!(fb.following_error.abs() < 1e-3);
}

#[test]
fn injected_fault_is_reported_and_resettable_once_stopped() {
    let mut plant = ServoPlant::new(homed_defaults(), 0.0);
    plant.enable().expect("enable");
    run_at_velocity(&mut plant, 0.0, 50.0, 200, |_| false);
    plant.inject_fault(AxisFault::CommunicationLost);
    // Still moving: the reset waits for standstill.
    assert!(plant.reset_fault().is_err());
    let fb = plant.step(rest(0.0), PERIOD);
    assert_eq!(fb.fault, Some(AxisFault::CommunicationLost));
    // A second fault does not overwrite the first.
    plant.inject_fault(AxisFault::EStop);
    for _ in 0..50 {
        plant.step(rest(0.0), PERIOD);
    }
    assert_eq!(plant.fault(), Some(&AxisFault::CommunicationLost));
    plant.reset_fault().expect("reset when stopped");
    assert_eq!(plant.state(), AxisState::Disabled);
}

#[test]
fn invalid_parameters_fault_the_axis_instead_of_panicking() {
    let params = SimAxisParams {
        mass: -1.0,
        ..SimAxisParams::default()
    };
    assert!(ServoPlant::try_new(params.clone(), 0.0).is_err());
    let mut plant = ServoPlant::new(params, 0.0);
    assert_eq!(plant.state(), AxisState::Faulted);
    assert!(matches!(
        plant.fault(),
        Some(AxisFault::Drive { code, .. }) if *code == FAULT_INVALID_PARAMS
    ));
    assert!(matches!(
        plant.reset_fault(),
        Err(PlantError::InvalidParams(_))
    ));
    assert!(plant.enable().is_err());
    let fb = plant.step(rest(1.0), PERIOD);
    assert_eq!(fb.state, AxisState::Faulted);
    assert_eq!(plant.actual_position(), 0.0);
}

#[test]
fn non_finite_input_never_panics() {
    let mut plant = ServoPlant::new(homed_defaults(), f64::NAN);
    assert_eq!(plant.actual_position(), 0.0);
    plant.enable().expect("enable");
    for dt in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let fb = plant.step(rest(1.0), dt);
        assert_eq!(fb.state, AxisState::Enabled);
        assert_eq!(plant.actual_position(), 0.0, "dt {dt} must not advance");
    }
    let fb = plant.step(
        Setpoint {
            position: 0.0,
            velocity: f64::NAN,
            acceleration: f64::INFINITY,
        },
        PERIOD,
    );
    assert_eq!(fb.fault, None, "non-finite feed-forward terms are dropped");
    let fb = plant.step(rest(f64::NAN), PERIOD);
    assert!(matches!(fb.fault, Some(AxisFault::Drive { .. })));
    assert!(plant.actual_position().is_finite());
}
