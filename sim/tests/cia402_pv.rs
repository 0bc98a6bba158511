//! A CiA 402 spindle drive in profile velocity mode against the simulated drive on an
//! in-memory bus: klar sends the speed unramped, the drive ramps with the profile
//! acceleration klar wrote at set-up, and "at speed" is the drive's "target reached".

use klar_drivers::cia402::{CanOpenConfig, Cia402Backend, Cia402Spindle};
use klar_motion::SpindleBackend;
use klar_sim::cia402::simulated_backend;

const PERIOD: f64 = 0.001;
const COUNTS_PER_REV: f64 = 1_048_576.0;
const ACCELERATION: f64 = 2000.0;

fn config() -> CanOpenConfig {
    toml::from_str(&format!(
        "bus = {{ adapter = \"sim\" }}\nheartbeat_ms = 50\n\
         spindle = {{ node = 5, counts_per_rev = {COUNTS_PER_REV}, mode = \"pv\", \
         acceleration = {ACCELERATION} }}\n"
    ))
    .expect("config parses")
}

fn read(backend: &Cia402Backend, index: u16) -> u32 {
    backend
        .with_master(|m| m.sdo_read_u32(5, index, 0))
        .expect("SDO read")
}

/// Cycles until the spindle reports at speed; returns how many cycles that took.
fn cycles_to_speed(spindle: &mut Cia402Spindle, t: &mut f64, limit: usize) -> usize {
    for n in 1..=limit {
        *t += PERIOD;
        let fb = spindle.cycle(*t).expect("cycle");
        assert!(fb.fault.is_none(), "{fb:?}");
        if fb.at_speed {
            return n;
        }
    }
    panic!("not at speed after {limit} cycles");
}

#[test]
fn the_drive_ramps_and_reports_target_reached_after_the_ramp_time() {
    let (backend, _bus, drives) = simulated_backend(&config(), PERIOD, &[]).expect("starts");
    let mut spindle = backend.spindle().expect("spindle");
    // Set-up wrote the drive's ramp: 2000 rpm/s is 2000 · 2^20 / 60 counts/s².
    let counts_per_s2 = (ACCELERATION * COUNTS_PER_REV / 60.0).round() as u32;
    assert_eq!(read(&backend, 0x6083), counts_per_s2);
    assert_eq!(read(&backend, 0x6084), counts_per_s2);
    assert_eq!(read(&backend, 0x6060), 3);
    let mut t = 0.0;
    // Switch on and get to a first speed.
    spindle.command(300.0).expect("command");
    cycles_to_speed(&mut spindle, &mut t, 2000);
    assert_eq!(read(&backend, 0x6061), 3, "mode display: profile velocity");
    // 300 → 1500 rpm at 2000 rpm/s takes 0.6 s: 600 cycles, give or take one.
    spindle.command(1500.0).expect("command");
    let n = cycles_to_speed(&mut spindle, &mut t, 2000);
    assert!((599..=601).contains(&n), "at speed after {n} cycles");
    // klar sent the speed unramped; the drive says target reached.
    assert_eq!(
        read(&backend, 0x60FF) as i32,
        (1500.0 * COUNTS_PER_REV / 60.0).round() as i32
    );
    let sw = read(&backend, 0x6041);
    assert_ne!(sw & (1 << 10), 0, "statusword {sw:#06x}");
    let fb = spindle.cycle(t + PERIOD).expect("cycle");
    t += PERIOD;
    assert!((fb.rpm - 1500.0).abs() <= 5.0, "{fb:?}");
    // The plant turns at that speed: degrees per second = rpm · 6.
    assert!((drives[0].velocity() / 6.0 - 1500.0).abs() <= 5.0);
    // Down to 0 at the same rate: 0.75 s.
    spindle.command(0.0).expect("command");
    let n = cycles_to_speed(&mut spindle, &mut t, 2000);
    assert!((749..=751).contains(&n), "stopped after {n} cycles");
    assert!(drives[0].velocity().abs() / 6.0 <= 5.0);
}

#[test]
fn half_way_up_the_ramp_the_spindle_is_not_at_speed() {
    let (backend, _bus, _drives) = simulated_backend(&config(), PERIOD, &[]).expect("starts");
    let mut spindle = backend.spindle().expect("spindle");
    let mut t = 0.0;
    spindle.command(1000.0).expect("command");
    // Three cycles switch the drive on; 250 more ramp it to about 500 rpm.
    let mut fb = None;
    for _ in 0..253 {
        t += PERIOD;
        fb = Some(spindle.cycle(t).expect("cycle"));
    }
    let fb = fb.expect("ran");
    assert!(!fb.at_speed, "{fb:?}");
    assert!((fb.rpm - 500.0).abs() < 15.0, "{fb:?}");
    let sw = read(&backend, 0x6041);
    assert_eq!(sw & (1 << 10), 0, "statusword {sw:#06x}");
    // The ramp is the drive's: klar already sent the full speed.
    assert_eq!(
        read(&backend, 0x60FF) as i32,
        (1000.0 * COUNTS_PER_REV / 60.0).round() as i32
    );
}

#[test]
fn pv_without_an_acceleration_is_refused() {
    let cfg: CanOpenConfig = toml::from_str(
        "bus = { adapter = \"sim\" }\n\
         spindle = { node = 5, counts_per_rev = 4096.0, mode = \"pv\", acceleration = 0.0 }\n",
    )
    .expect("parses");
    let err = simulated_backend(&cfg, PERIOD, &[]).err().expect("refused");
    assert!(err.to_string().contains("acceleration"), "{err}");
}
