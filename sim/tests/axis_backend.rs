//! The simulated backend behind the axis boundary trait: argument checks, per-axis
//! requests, the servo period, and parameters read from TOML.

mod plant_support;

use klar_motion::{AxisBackend, AxisFault, AxisFeedback, AxisState, BackendError, Setpoint};
use klar_sim::axis::{SimBackend, SimBackendError};
use klar_sim::plant::{HOMING_SETTLE_TIMEOUT, SimAxisParams, SimParamsError};
use plant_support::rest;

fn two_axes(period: f64) -> SimBackend {
    let homed = SimAxisParams {
        start_homed: true,
        ..SimAxisParams::default()
    };
    SimBackend::new(vec![(homed.clone(), 10.0), (homed, -25.5)], period)
}

#[test]
fn cycle_checks_slice_lengths() {
    let mut backend = two_axes(0.001);
    assert_eq!(backend.axis_count(), 2);
    let mut feedback = vec![AxisFeedback::default(); 2];
    assert_eq!(
        backend.cycle(0.0, &[rest(0.0)], &mut feedback),
        Err(BackendError::AxisCount {
            expected: 2,
            got: 1
        })
    );
    let mut three = vec![AxisFeedback::default(); 3];
    assert_eq!(
        backend.cycle(0.0, &[rest(10.0), rest(-25.5)], &mut three),
        Err(BackendError::AxisCount {
            expected: 2,
            got: 3
        })
    );
    backend
        .cycle(0.001, &[rest(10.0), rest(-25.5)], &mut feedback)
        .expect("matching lengths");
    assert_eq!(feedback[0].position, 10.0);
    assert_eq!(feedback[1].position, -25.5);
    assert!(
        feedback
            .iter()
            .all(|f| f.homed && f.state == AxisState::Disabled)
    );
}

#[test]
fn requests_name_missing_axes() {
    let mut backend = two_axes(0.001);
    assert_eq!(backend.start_homing(2), Err(BackendError::NoSuchAxis(2)));
    assert_eq!(backend.reset_fault(7), Err(BackendError::NoSuchAxis(7)));
    assert_eq!(
        backend.inject_fault(2, AxisFault::EStop),
        Err(BackendError::NoSuchAxis(2))
    );
    assert!(backend.plant(2).is_none());
}

#[test]
fn axes_follow_independently_and_faults_stay_per_axis() {
    let mut backend = two_axes(0.001);
    backend.enable().expect("enable");
    let mut feedback = vec![AxisFeedback::default(); 2];
    // Axis 0 moves 1 mm on a smooth (cosine) path in 0.2 s, axis 1 holds.
    let path = |t: f64| {
        let s = (t / 0.2).min(1.0);
        let w = std::f64::consts::PI / 0.2;
        let on = if t < 0.2 { 1.0 } else { 0.0 };
        Setpoint {
            position: 10.0 + 0.5 * (1.0 - (std::f64::consts::PI * s).cos()),
            velocity: on * 0.5 * w * (std::f64::consts::PI * s).sin(),
            acceleration: on * 0.5 * w * w * (std::f64::consts::PI * s).cos(),
        }
    };
    for k in 1..=400 {
        let t = f64::from(k) * 0.001;
        backend
            .cycle(t, &[path(t), rest(-25.5)], &mut feedback)
            .expect("cycle");
        assert!(feedback.iter().all(|f| f.fault.is_none()));
    }
    assert!((feedback[0].position - 11.0).abs() <= 2e-4);
    assert!((feedback[1].position + 25.5).abs() <= 2e-4);
    backend
        .inject_fault(1, AxisFault::CommunicationLost)
        .expect("inject");
    backend
        .cycle(0.401, &[rest(11.0), rest(-25.5)], &mut feedback)
        .expect("cycle");
    assert_eq!(feedback[0].state, AxisState::Enabled);
    assert_eq!(feedback[1].fault, Some(AxisFault::CommunicationLost));
    // Enable only from Disabled: the faulted axis refuses, naming itself.
    backend.disable().expect("disable");
    match backend.enable() {
        Err(BackendError::InvalidState(text)) => assert!(text.starts_with("axis 1:"), "{text}"),
        other => panic!("expected a refusal, got {other:?}"),
    }
    assert_eq!(
        backend.plant(0).map(|p| p.state()),
        Some(AxisState::Enabled)
    );
    backend.reset_fault(1).expect("reset a stopped axis");
    backend.enable().expect("enable both");
    backend.set_estop(true);
    backend
        .cycle(0.402, &[rest(11.0), rest(-25.5)], &mut feedback)
        .expect("cycle");
    assert!(feedback.iter().all(|f| f.fault == Some(AxisFault::EStop)));
}

#[test]
fn each_cycle_advances_one_servo_period() {
    // Homing from 0 to a switch at 5 mm at 10 mm/s takes at least 0.5 s of search: at a
    // 2 ms period that is at least 250 cycles. The ramps and the return move add at most
    // 4·v/a = 0.08 s and settling at most HOMING_SETTLE_TIMEOUT (0.25 s): at most 415
    // cycles. (A backend stepping 1 ms per cycle would need at least 500.)
    let params = SimAxisParams {
        home_switch: 5.0,
        ..SimAxisParams::default()
    };
    let period = 0.002;
    let mut backend = SimBackend::new(vec![(params, 0.0)], period);
    backend.enable().expect("enable");
    backend.start_homing(0).expect("home");
    let mut feedback = vec![AxisFeedback::default()];
    let mut cycles = 0u32;
    while feedback[0].state != AxisState::Enabled || !feedback[0].homed {
        cycles += 1;
        backend
            .cycle(f64::from(cycles) * period, &[rest(0.0)], &mut feedback)
            .expect("cycle");
        assert!(cycles < 1000, "homing did not finish");
    }
    let most = ((0.5 + 0.08 + HOMING_SETTLE_TIMEOUT) / period).ceil() as u32;
    assert!((250..=most).contains(&cycles), "{cycles} cycles");
    assert!((feedback[0].position - 5.0).abs() <= 1e-4 + 1e-12);
}

#[test]
fn invalid_configuration_is_reported_not_panicked() {
    assert_eq!(
        SimBackend::try_new(vec![], 0.0).err(),
        Some(SimBackendError::InvalidPeriod(0.0))
    );
    assert!(matches!(
        SimBackend::try_new(vec![(SimAxisParams::default(), f64::INFINITY)], 0.001),
        Err(SimBackendError::InvalidStart { axis: 0, .. })
    ));
    let bad = SimAxisParams {
        counts_per_unit: 0.0,
        ..SimAxisParams::default()
    };
    assert!(matches!(
        SimBackend::try_new(vec![(SimAxisParams::default(), 0.0), (bad, 0.0)], 0.001),
        Err(SimBackendError::InvalidParams {
            axis: 1,
            source: SimParamsError::OutOfRange {
                name: "counts_per_unit",
                ..
            }
        })
    ));
    let mut backend = SimBackend::new(vec![(SimAxisParams::default(), 0.0)], f64::NAN);
    assert!(matches!(
        backend.enable(),
        Err(BackendError::InvalidState(_))
    ));
    let mut feedback = vec![AxisFeedback::default()];
    assert!(matches!(
        backend.cycle(0.0, &[rest(0.0)], &mut feedback),
        Err(BackendError::InvalidState(_))
    ));
}

#[test]
fn params_read_from_toml_with_defaults_and_unknown_keys_refused() {
    let params: SimAxisParams = toml::from_str(
        r#"
        mass = 120.0
        counts_per_unit = 1000.0
        limit_switch_positive = 310.0
        start_homed = true
        "#,
    )
    .expect("valid params");
    assert_eq!(params.mass, 120.0);
    assert_eq!(params.counts_per_unit, 1000.0);
    assert_eq!(params.limit_switch_positive, Some(310.0));
    assert_eq!(params.limit_switch_negative, None);
    assert!(params.start_homed);
    assert_eq!(params.substeps, SimAxisParams::default().substeps);
    assert!(params.validate().is_ok());
    let err = toml::from_str::<SimAxisParams>("mas = 1.0").expect_err("unknown key");
    assert!(err.to_string().contains("mas"), "{err}");
    let empty: SimAxisParams = toml::from_str("").expect("all defaults");
    assert_eq!(empty, SimAxisParams::default());
}

#[test]
fn validation_names_the_offending_parameter() {
    let crossed = SimAxisParams {
        limit_switch_negative: Some(10.0),
        limit_switch_positive: Some(-10.0),
        ..SimAxisParams::default()
    };
    assert_eq!(
        crossed.validate(),
        Err(SimParamsError::LimitsCrossed {
            negative: 10.0,
            positive: -10.0
        })
    );
    let home_outside = SimAxisParams {
        limit_switch_positive: Some(100.0),
        home_switch: 150.0,
        ..SimAxisParams::default()
    };
    assert_eq!(
        home_outside.validate(),
        Err(SimParamsError::HomeOutsideTravel { home: 150.0 })
    );
    let no_substeps = SimAxisParams {
        substeps: 0,
        ..SimAxisParams::default()
    };
    let message = no_substeps
        .validate()
        .expect_err("zero substeps")
        .to_string();
    assert!(message.contains("substeps"), "{message}");
    let nan_gain = SimAxisParams {
        position_gain: f64::NAN,
        ..SimAxisParams::default()
    };
    assert!(matches!(
        nan_gain.validate(),
        Err(SimParamsError::OutOfRange {
            name: "position_gain",
            ..
        })
    ));
    assert!(SimAxisParams::default().validate().is_ok());
}
