//! The CiA 402 touch-probe function end to end on the in-memory bus: klar's backend arms
//! touch probe 1 of a simulated drive (0x60B8), the axis moves across the drive's probe
//! input, and the backend reads the latched position (0x60B9, 0x60BA) in mm. The simulated
//! drive knows where its input switches, so the latched position must be that trigger
//! position to a count, wherever it falls between two SYNCs.

use klar_drivers::cia402::CanOpenConfig;
use klar_drivers::cia402::touch_probe::TouchProbeStatus;
use klar_motion::{AxisBackend, AxisFeedback, Setpoint};
use klar_sim::cia402::{ProbeInput, simulated_backend};

const PERIOD: f64 = 0.001;
const COUNTS: f64 = 10000.0;

fn config() -> CanOpenConfig {
    let text = format!(
        "bus = {{ adapter = \"sim\", bitrate = 1000000 }}\nheartbeat_ms = 50\n\
         [[drives]]\nnode = 1\ncounts_per_unit = {COUNTS}\n\
         [[drives]]\nnode = 2\ncounts_per_unit = {COUNTS}\ninvert = true\n"
    );
    toml::from_str(&text).expect("test config parses")
}

/// Moves both axes from `a` to `b` over `duration` s (cosine profile), calling `each`
/// after every cycle with the feedback.
fn travel(
    backend: &mut klar_drivers::cia402::Cia402Backend,
    t: &mut f64,
    a: f64,
    b: f64,
    duration: f64,
    mut each: impl FnMut(&klar_drivers::cia402::Cia402Backend, &[AxisFeedback]),
) {
    let start = *t;
    let mut fb = vec![AxisFeedback::default(); 2];
    let steps = (duration / PERIOD).round() as usize + 50;
    for _ in 0..steps {
        *t += PERIOD;
        let s = ((*t - start) / duration).clamp(0.0, 1.0);
        let position = a + (b - a) * 0.5 * (1.0 - (std::f64::consts::PI * s).cos());
        let sp = Setpoint {
            position,
            velocity: 0.0,
            acceleration: 0.0,
        };
        backend.cycle(*t, &[sp, sp], &mut fb).expect("cycle");
        each(backend, &fb);
    }
}

#[test]
fn the_drive_latches_the_trigger_position_once_and_the_backend_reads_it_in_mm() {
    let (mut backend, _bus, drives) = simulated_backend(&config(), PERIOD, &[]).expect("starts");
    backend.enable().expect("enables");
    let mut t = 0.0;
    // a trigger position between counts, and between the SYNCs of the move below
    let at = 3.234_567_8;
    drives[0].set_probe_input(Some(ProbeInput { at, above: true }));
    // the inverted axis's drive counts the other way: its input sits at −at, reached from above
    drives[1].set_probe_input(Some(ProbeInput {
        at: -at,
        above: false,
    }));
    assert!(!backend.touch_probe_status(0).expect("status").enabled);
    backend.arm_touch_probe(0).expect("arms");
    backend.arm_touch_probe(1).expect("arms");
    travel(&mut backend, &mut t, 0.0, 0.0, 0.01, |_, _| {});
    assert_eq!(
        backend.touch_probe_status(0).expect("status"),
        TouchProbeStatus {
            enabled: true,
            positive: false,
            negative: false
        }
    );
    // polled every cycle of the move: nothing until the true position passed the trigger
    let mut first_seen = None;
    let d0 = drives[0].clone();
    travel(&mut backend, &mut t, 0.0, 5.0, 0.5, |b, fb| {
        let got = b.touch_probe_position(0).expect("reads");
        if got.is_some() && first_seen.is_none() {
            first_seen = Some((got, fb[0].position, d0.position()));
        }
        if got.is_none() {
            assert!(d0.position() < at, "not latched at {}", d0.position());
        }
    });
    let (got, reported, truth) = first_seen.expect("latched during the move");
    let got = got.expect("a position");
    eprintln!("latched {got} for trigger {at}: off by {:e}", got - at);
    assert!(truth >= at && reported >= at - 1.0 / COUNTS);
    assert!(
        (got - at).abs() <= 0.5 / COUNTS + 1e-12,
        "latched {got}, trigger {at}"
    );
    // the inverted axis latches the same place in its own count direction
    let got1 = backend
        .touch_probe_position(1)
        .expect("reads")
        .expect("latched");
    assert!(
        (got1 - at).abs() <= 0.5 / COUNTS + 1e-12,
        "inverted: {got1}"
    );

    // back and across a moved trigger: first event only, the first value stays
    travel(&mut backend, &mut t, 5.0, 0.0, 0.5, |_, _| {});
    drives[0].set_probe_input(Some(ProbeInput {
        at: 4.0,
        above: true,
    }));
    travel(&mut backend, &mut t, 0.0, 5.0, 0.5, |_, _| {});
    assert_eq!(backend.touch_probe_position(0).expect("reads"), Some(got));

    // re-armed: the stored flag clears and the next edge latches the new trigger
    travel(&mut backend, &mut t, 5.0, 0.0, 0.5, |_, _| {});
    backend.arm_touch_probe(0).expect("re-arms");
    travel(&mut backend, &mut t, 0.0, 0.0, 0.01, |_, _| {});
    assert_eq!(backend.touch_probe_position(0).expect("reads"), None);
    travel(&mut backend, &mut t, 0.0, 5.0, 0.5, |_, _| {});
    let again = backend
        .touch_probe_position(0)
        .expect("reads")
        .expect("latched");
    assert!((again - 4.0).abs() <= 0.5 / COUNTS + 1e-12, "{again}");

    // disarmed: status cleared, and a crossing stores nothing
    backend.disarm_touch_probe(0).expect("disarms");
    travel(&mut backend, &mut t, 5.0, 0.0, 0.5, |_, _| {});
    travel(&mut backend, &mut t, 0.0, 5.0, 0.5, |_, _| {});
    assert_eq!(
        backend.touch_probe_status(0).expect("status"),
        TouchProbeStatus {
            enabled: false,
            positive: false,
            negative: false
        }
    );
    assert_eq!(backend.touch_probe_position(0).expect("reads"), None);
    // a drive that does not exist on the bus is an error, not a panic
    assert!(backend.arm_touch_probe(5).is_err());
}
