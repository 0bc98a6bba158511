//! The measured angle of a CiA 402 spindle drive (actual position 0x6064 on its own
//! transmit PDO), in cyclic synchronous velocity and profile velocity mode, against the
//! simulated drive's true plant angle.

use klar_drivers::cia402::{CanOpenConfig, Cia402Spindle};
use klar_motion::{SpindleBackend, SpindleFeedback};
use klar_sim::cia402::simulated_backend;

const PERIOD: f64 = 0.001;

fn config(spindle: &str) -> CanOpenConfig {
    toml::from_str(&format!(
        "bus = {{ adapter = \"sim\" }}\nheartbeat_ms = 50\nspindle = {{ node = 5, {spindle} }}\n"
    ))
    .expect("config parses")
}

fn run(spindle: &mut Cia402Spindle, t: &mut f64, cycles: usize) -> SpindleFeedback {
    let mut last = None;
    for _ in 0..cycles {
        *t += PERIOD;
        last = Some(spindle.cycle(*t).expect("spindle cycle"));
    }
    last.expect("ran")
}

/// Runs the spindle at `rpm` and checks that the reported angle follows the plant: the
/// angle advanced over 0.5 s at speed equals the plant's within two encoder counts, and
/// equals rpm · 6 °/s · 0.5 s within the speed's at-speed window.
fn angle_follows_the_plant(spindle: &str, rpm: f64, counts_per_rev: f64, sign: f64) {
    let (backend, _bus, drives) = simulated_backend(&config(spindle), PERIOD, &[]).expect("starts");
    let mut spindle = backend.spindle().expect("spindle configured");
    let mut t = 0.0;
    let idle = run(&mut spindle, &mut t, 5);
    let start = idle.position.expect("the drive reports its position");
    assert!(start.abs() < 1e-9, "starts at 0°: {idle:?}");
    spindle.command(rpm).expect("command");
    run(&mut spindle, &mut t, 2000);
    let plant_before = drives[0].position();
    let before = run(&mut spindle, &mut t, 1);
    let plant_after_first = drives[0].position();
    let after = run(&mut spindle, &mut t, 500);
    let plant_after = drives[0].position();
    assert!(after.at_speed, "{after:?}");
    let measured = after.position.expect("position") - before.position.expect("position");
    // The transmit PDO of a cycle reports the plant after that cycle's step: compare with
    // the plant's advance over the same 500 steps.
    let plant = sign * (plant_after - plant_after_first);
    let count = 360.0 / counts_per_rev;
    assert!(
        (measured - plant).abs() <= 2.0 * count,
        "measured {measured}°, plant {plant}° (before {plant_before})"
    );
    let expected = rpm * 6.0 * 0.5;
    assert!(
        (measured - expected).abs() <= 0.02 * expected.abs(),
        "measured {measured}°, {rpm} rpm for 0.5 s is {expected}°"
    );
}

#[test]
fn csv_spindle_reports_its_angle() {
    angle_follows_the_plant("counts_per_rev = 65536.0", 600.0, 65536.0, 1.0);
    angle_follows_the_plant("counts_per_rev = 65536.0", -900.0, 65536.0, 1.0);
}

#[test]
fn pv_spindle_reports_its_angle() {
    angle_follows_the_plant(
        "counts_per_rev = 1048576.0, mode = \"pv\", acceleration = 4000.0",
        800.0,
        1048576.0,
        1.0,
    );
}

#[test]
fn inverted_spindle_reports_the_angle_in_spindle_direction() {
    // With `invert` positive counts turn the spindle the other way: M3 turns the drive's
    // counter down, the reported angle still rises.
    angle_follows_the_plant(
        "counts_per_rev = 65536.0, invert = true",
        600.0,
        65536.0,
        -1.0,
    );
}

#[test]
fn angle_unwraps_across_the_32_bit_counter() {
    // 2^27 counts per revolution: the drive's i32 counter wraps after 16 revolutions, 1.6 s
    // at 600 rpm; after 3 s the angle has kept rising without a jump.
    let counts_per_rev = 134_217_728.0;
    let (backend, _bus, drives) = simulated_backend(
        &config("counts_per_rev = 134217728.0, acceleration = 6000.0"),
        PERIOD,
        &[],
    )
    .expect("starts");
    let mut spindle = backend.spindle().expect("spindle configured");
    let mut t = 0.0;
    spindle.command(600.0).expect("command");
    let mut last = run(&mut spindle, &mut t, 1).position.expect("position");
    for _ in 0..3000 {
        let angle = run(&mut spindle, &mut t, 1).position.expect("position");
        // At most 600 rpm = 3.6° per millisecond, never backwards.
        assert!(
            (-1e-6..=3.7).contains(&(angle - last)),
            "jump {last} → {angle}"
        );
        last = angle;
    }
    assert!(last > 16.0 * 360.0, "past the wrap: {last}°");
    let plant = drives[0].position();
    assert!(
        (last - plant).abs() <= 3.6 + 2.0 * 360.0 / counts_per_rev,
        "measured {last}°, plant {plant}°"
    );
}

#[test]
fn position_pdo_must_differ_from_the_velocity_pdo() {
    let e = simulated_backend(
        &config("counts_per_rev = 4096.0, tpdo = 2, position_tpdo = 2"),
        PERIOD,
        &[],
    )
    .err()
    .expect("refused");
    assert!(e.to_string().contains("position_tpdo 2"), "{e}");
}
