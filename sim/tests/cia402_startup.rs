//! Start-up of the CiA 402 backend against simulated drives on an in-memory bus: the wait for
//! the drives' first transmit PDOs goes over several SYNCs and is bounded by
//! `tpdo_timeout_ms`, and the backend reports where the drives stand before they are enabled.

use klar_drivers::can::memory::{FrameFate, MemoryBus};
use klar_drivers::cia402::{CanOpenConfig, Cia402Backend, Cia402Error};
use klar_motion::{AxisBackend, AxisFeedback, Setpoint};
use klar_sim::cia402::{SimCia402Drive, SimDriveConfig, plant_for};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

const PERIOD: f64 = 0.001;

fn config(extra: &str) -> CanOpenConfig {
    let text = format!(
        "bus = {{ adapter = \"sim\", bitrate = 1000000 }}\nheartbeat_ms = 0\n{extra}\n\
         [[drives]]\nnode = 1\ncounts_per_unit = 1000.0\n\
         [[drives]]\nnode = 2\ncounts_per_unit = 1000.0\n"
    );
    toml::from_str(&text).expect("test config parses")
}

/// A bus with the two drives standing at `starts` (mm), whose frames pass `injector`.
fn bus_with(
    cfg: &CanOpenConfig,
    starts: [f64; 2],
    injector: impl FnMut(&klar_drivers::can::CanFrame) -> FrameFate + Send + 'static,
) -> MemoryBus {
    let bus = MemoryBus::new();
    for (i, d) in cfg.drives.iter().enumerate() {
        let (drive, _) = SimCia402Drive::new(SimDriveConfig {
            node: d.node,
            plant: plant_for(cfg, i),
            start_position: starts[i],
        });
        bus.attach(Box::new(drive));
    }
    bus.set_injector(injector);
    bus
}

#[test]
fn a_drive_answering_after_some_syncs_starts_and_reports_where_it_stands() {
    let cfg = config("tpdo_timeout_ms = 500");
    // Node 2's first five transmit PDOs are lost (a drive that needs a few SYNCs after NMT
    // start before its PDOs flow).
    let lost = Arc::new(AtomicUsize::new(0));
    let seen = Arc::clone(&lost);
    let bus = bus_with(&cfg, [12.5, -3.25], move |f| {
        if f.id().raw() == 0x182 && seen.fetch_add(1, Ordering::Relaxed) < 5 {
            FrameFate::Drop
        } else {
            FrameFate::Deliver
        }
    });
    let mut backend =
        Cia402Backend::with_bus(&cfg, PERIOD, Box::new(bus.endpoint())).expect("starts");
    assert!(lost.load(Ordering::Relaxed) > 5, "the wait went over SYNCs");
    // Disabled, one cycle reports the drives' own positions whatever the setpoints say.
    let mut fb = vec![AxisFeedback::default(); 2];
    backend
        .cycle(PERIOD, &[Setpoint::default(); 2], &mut fb)
        .expect("cycle");
    assert_eq!(fb[0].position, 12.5);
    assert_eq!(fb[1].position, -3.25);
    assert!(fb.iter().all(|f| f.fault.is_none()));
}

#[test]
fn a_drive_that_never_answers_is_named_after_the_timeout() {
    let cfg = config("tpdo_timeout_ms = 100");
    let bus = bus_with(&cfg, [0.0, 0.0], |f| {
        if f.id().raw() == 0x182 {
            FrameFate::Drop
        } else {
            FrameFate::Deliver
        }
    });
    match Cia402Backend::with_bus(&cfg, PERIOD, Box::new(bus.endpoint())) {
        Err(Cia402Error::Config(text)) => {
            assert!(
                text.starts_with("node 2: no transmit PDO within 100 ms"),
                "{text}"
            );
            // SYNC every servo period: about 100 of them, not one.
            let syncs: u32 = text
                .split('(')
                .nth(1)
                .and_then(|s| s.split(' ').next())
                .and_then(|n| n.parse().ok())
                .expect("the number of SYNCs");
            assert!(syncs >= 10, "{text}");
        }
        Err(e) => panic!("wrong error {e}"),
        Ok(_) => panic!("must not start"),
    }
}
