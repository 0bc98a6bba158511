//! The step/dir limits check: refusals with their reasons, figures from closed forms.

use klar_drivers::stepdir::limits::{StepDirLimitError, check};
use klar_drivers::stepdir::{StepClock, StepDirConfig};

fn base() -> StepDirConfig {
    let mut c = StepDirConfig::new(400.0, 50_000.0);
    c.tick = 10e-6;
    c.pulse_width = 2e-6;
    c
}

#[test]
fn a_fitting_axis_is_accepted_with_its_figures() {
    // 100 mm/s x 400 steps/mm = 40000 steps/s <= 50000; tick 10 us allows 50000.
    let t = check(&base(), 0.001, 100.0).expect("fits");
    assert_eq!(t.needed_rate, 40_000.0);
    assert_eq!(t.ticks_per_period, 100);
    assert_eq!(t.edge_error, 10e-6);
    assert_eq!(
        t.to_string(),
        "step/dir: up to 40000 steps/s, 100 generator ticks per servo period, edges within \
         10.0 us of their ideal time"
    );
}

#[test]
fn too_fast_for_the_drive() {
    let e = check(&base(), 0.001, 200.0).unwrap_err();
    assert!(
        matches!(e, StepDirLimitError::StepRate { needed, .. } if needed == 80_000.0),
        "{e:?}"
    );
    assert!(e.to_string().contains("80000 steps/s"), "{e}");
}

#[test]
fn tick_too_coarse() {
    let mut c = base();
    c.tick = 25e-6; // at most 20000 steps/s
    let e = check(&c, 0.001, 100.0).unwrap_err();
    assert!(
        matches!(e, StepDirLimitError::TickTooCoarse { tick_rate, .. } if (tick_rate - 20_000.0).abs() < 1e-6),
        "{e:?}"
    );
}

#[test]
fn servo_period_must_hold_whole_ticks() {
    let e = check(&base(), 0.001_005, 10.0).unwrap_err();
    assert!(
        matches!(e, StepDirLimitError::PeriodNotMultiple { .. }),
        "{e:?}"
    );
}

#[test]
fn linux_thread_jitter_refuses_fast_stepping() {
    let mut c = base();
    c.clock = StepClock::LinuxThread;
    c.linux_jitter = 100e-6;
    c.tick = 100e-6;
    // Jitter-limited rate: 1 / (2 (2 us + 100 us)) = 4902 steps/s; the 100 us tick alone
    // would allow 5000 steps/s.
    let e = check(&c, 0.001, 12.4).unwrap_err(); // 4960 steps/s
    match &e {
        StepDirLimitError::Jitter { rate, .. } => assert!((rate - 1.0 / 204e-6).abs() < 1e-6),
        other => panic!("{other:?}"),
    }
    assert!(e.to_string().contains("Linux thread"));
    // 10 mm/s = 4000 steps/s fits, with an edge error of tick + jitter.
    let t = check(&c, 0.001, 10.0).expect("slow enough");
    assert!((t.edge_error - 200e-6).abs() < 1e-12);
    // A tick shorter than the jitter is refused even for slow axes.
    c.tick = 50e-6;
    assert!(matches!(
        check(&c, 0.001, 1.0),
        Err(StepDirLimitError::Jitter { .. })
    ));
}

#[test]
fn bad_timing_is_a_config_error_not_a_panic() {
    let mut c = base();
    c.pulse_width = 20e-6; // 2 x 20 us > 1 / 50000 = 20 us
    assert!(matches!(
        check(&c, 0.001, 1.0),
        Err(StepDirLimitError::Config(_))
    ));
    c = base();
    c.steps_per_unit = f64::NAN;
    assert!(matches!(
        check(&c, 0.001, 1.0),
        Err(StepDirLimitError::Config(_))
    ));
    assert!(matches!(
        check(&base(), -1.0, 1.0),
        Err(StepDirLimitError::Config(_))
    ));
}

#[test]
fn toml_shape_with_pins() {
    let text = r#"
steps_per_unit = 400.0
max_step_rate = 50000
tick = 20e-6
clock = "linux_thread"
homing_velocity = -10.0
[pins]
chip = "/dev/gpiochip0"
step = 17
dir = 27
enable = 22
enable_active_low = true
home = 13
inputs_active_low = true
"#;
    let c: StepDirConfig = toml::from_str(text).expect("parse");
    assert_eq!(c.clock, StepClock::LinuxThread);
    assert_eq!(c.pulse_width, 5e-6, "default");
    let pins = c.pins.as_ref().expect("pins");
    assert_eq!(
        (pins.step, pins.dir, pins.enable, pins.home),
        (17, 27, Some(22), Some(13))
    );
    assert!(toml::from_str::<StepDirConfig>(&text.replace("tick", "tic")).is_err());
    // A 20 us tick is shorter than the assumed 100 us jitter of a Linux thread.
    assert!(matches!(
        check(&c, 0.001, 20.0),
        Err(StepDirLimitError::Jitter { .. })
    ));
}
