//! Bad input never panics: arbitrary setpoints, periods, parameters and call orders leave
//! the plant with a finite state and a whole-count measured position.

use klar_motion::{AxisFault, AxisState, Setpoint};
use klar_sim::plant::{ServoPlant, SimAxisParams};
use proptest::prelude::*;

/// One call on the plant.
#[derive(Debug, Clone)]
enum Call {
    Step(Setpoint, f64),
    Enable,
    Disable,
    Home,
    Reset,
    Estop(bool),
    Inject,
}

fn any_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1e3..1e3f64,
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(-1e300),
        Just(0.0),
    ]
}

fn call() -> impl Strategy<Value = Call> {
    prop_oneof![
        6 => (any_f64(), any_f64(), any_f64(), prop_oneof![Just(0.001), any_f64()]).prop_map(
            |(p, v, a, dt)| Call::Step(
                Setpoint {
                    position: p,
                    velocity: v,
                    acceleration: a
                },
                dt
            )
        ),
        1 => Just(Call::Enable),
        1 => Just(Call::Disable),
        1 => Just(Call::Home),
        1 => Just(Call::Reset),
        1 => any::<bool>().prop_map(Call::Estop),
        1 => Just(Call::Inject),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn arbitrary_calls_never_panic_and_stay_finite(
        calls in proptest::collection::vec(call(), 1..60),
        start in any_f64(),
    ) {
        let params = SimAxisParams {
            limit_switch_negative: Some(-500.0),
            limit_switch_positive: Some(500.0),
            home_switch: 1.0,
            ..SimAxisParams::default()
        };
        let cpu = params.counts_per_unit;
        let mut plant = ServoPlant::new(params, start);
        for c in calls {
            match c {
                Call::Step(sp, dt) => {
                    let fb = plant.step(sp, dt);
                    prop_assert!(fb.position.is_finite());
                    let counts = fb.position * cpu;
                    prop_assert!((counts - counts.round()).abs() < 1e-3);
                }
                Call::Enable => { let _ = plant.enable(); }
                Call::Disable => plant.disable(),
                Call::Home => { let _ = plant.start_homing(); }
                Call::Reset => { let _ = plant.reset_fault(); }
                Call::Estop(on) => plant.set_estop(on),
                Call::Inject => plant.inject_fault(AxisFault::CommunicationLost),
            }
            prop_assert!(plant.actual_position().is_finite());
            prop_assert!(plant.actual_velocity().is_finite());
            prop_assert_eq!(plant.state() == AxisState::Faulted, plant.fault().is_some());
        }
    }

    #[test]
    fn arbitrary_parameters_never_panic(
        mass in any_f64(),
        gain in any_f64(),
        cpu in any_f64(),
        substeps in 0u32..20,
        sp in any_f64(),
    ) {
        let params = SimAxisParams {
            mass,
            velocity_gain: gain,
            counts_per_unit: cpu,
            substeps,
            ..SimAxisParams::default()
        };
        let valid = params.validate().is_ok();
        let mut plant = ServoPlant::new(params, 0.0);
        prop_assert_eq!(valid, plant.state() == AxisState::Disabled);
        let _ = plant.enable();
        for _ in 0..20 {
            let _ = plant.step(Setpoint { position: sp, ..Setpoint::default() }, 0.001);
        }
        prop_assert!(plant.actual_position().is_finite());
    }
}
