//! Cost of simulating servo cycles: one plant cycle (default parameters, 10 substeps) and
//! one backend cycle of a three-axis mill.

use klar_motion::{AxisBackend, AxisFeedback, Setpoint};
use klar_sim::axis::SimBackend;
use klar_sim::plant::{ServoPlant, SimAxisParams};

fn main() {
    divan::main();
}

const PERIOD: f64 = 0.001;

/// A smooth back-and-forth command (amplitude 10 mm, 1 Hz) sampled at cycle `k`.
fn command(k: u32) -> Setpoint {
    let w = 2.0 * std::f64::consts::PI;
    let t = f64::from(k) * PERIOD;
    Setpoint {
        position: 10.0 * (1.0 - (w * t).cos()),
        velocity: 10.0 * w * (w * t).sin(),
        acceleration: 10.0 * w * w * (w * t).cos(),
    }
}

fn homed() -> SimAxisParams {
    SimAxisParams {
        start_homed: true,
        ..SimAxisParams::default()
    }
}

/// 1000 servo cycles (one simulated second) of one axis.
#[divan::bench]
fn plant_one_second(bencher: divan::Bencher) {
    bencher
        .with_inputs(|| {
            let mut plant = ServoPlant::new(homed(), 0.0);
            let _ = plant.enable();
            plant
        })
        .bench_local_refs(|plant| {
            for k in 1..=1000 {
                divan::black_box(plant.step(command(k), PERIOD));
            }
        });
}

/// 1000 servo cycles of a three-axis backend.
#[divan::bench]
fn backend_three_axes_one_second(bencher: divan::Bencher) {
    bencher
        .with_inputs(|| {
            let mut backend = SimBackend::new(vec![(homed(), 0.0); 3], PERIOD);
            let _ = backend.enable();
            (backend, vec![AxisFeedback::default(); 3])
        })
        .bench_local_refs(|(backend, feedback)| {
            for k in 1..=1000 {
                let sp = command(k);
                let _ = backend.cycle(f64::from(k) * PERIOD, &[sp, sp, sp], feedback);
            }
            divan::black_box(&feedback);
        });
}
