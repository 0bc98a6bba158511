//! A simulated CANopen CiA 402 servo drive ([`SimCia402Drive`]) built on the same servo
//! plant as the simulated axis, and helpers that put simulated drives on an in-memory bus
//! ([`simulated_backend`]) or behind an slcan pseudo-terminal ([`serve_on_slcan`]).

pub mod control;
mod dictionary;
pub mod drive;
pub mod od;
mod profile;
mod touch_probe;

pub use control::SimDriveControl;
pub use drive::{Injection, SimCia402Drive, SimDriveConfig};
pub use touch_probe::ProbeInput;

use klar_drivers::can::CanError;
use klar_drivers::can::device::DeviceRunner;
use klar_drivers::can::memory::MemoryBus;
use klar_drivers::can::slcan::{SlcanBus, SlcanOptions};
use klar_drivers::cia402::{CanOpenConfig, Cia402Backend, Cia402Error};

use crate::plant::SimAxisParams;

/// Plant parameters for a simulated drive of `config`'s drive `index`: the defaults with
/// the drive's counts per unit, already referenced.
pub fn plant_for(config: &CanOpenConfig, index: usize) -> SimAxisParams {
    let mut p = SimAxisParams::default();
    if let Some(d) = config.drives.get(index) {
        p.counts_per_unit = d.counts_per_unit.abs();
    }
    p
}

/// Plant parameters for a simulated spindle drive: a rotary axis with a small chuck's
/// inertia and torque, an encoder of `counts_per_rev` counts per revolution, and a
/// following-error window wide enough for speed changes.
pub fn spindle_plant(counts_per_rev: f64) -> SimAxisParams {
    let inertia = 0.02;
    SimAxisParams {
        rotary: true,
        mass: inertia,
        viscous_friction: 0.002,
        coulomb_friction: 0.1,
        force_limit: 40.0,
        velocity_gain: inertia * 2.0 * std::f64::consts::PI * 100.0,
        counts_per_unit: counts_per_rev.abs() / 360.0,
        following_error_limit: 3600.0,
        ..SimAxisParams::default()
    }
}

/// Builds an in-memory bus with one simulated drive per configured drive (plant from
/// `plants`, or [`plant_for`] where `plants` has none) and, if configured, a simulated
/// spindle drive ([`spindle_plant`], its control handle last), starts the backend on it,
/// and returns the backend, the bus (for fault injection) and the drives' control handles.
pub fn simulated_backend(
    config: &CanOpenConfig,
    servo_period: f64,
    plants: &[SimAxisParams],
) -> Result<(Cia402Backend, MemoryBus, Vec<SimDriveControl>), Cia402Error> {
    let bus = MemoryBus::new();
    let endpoint = bus.endpoint();
    let mut controls = Vec::new();
    for (i, d) in config.drives.iter().enumerate() {
        let plant = plants
            .get(i)
            .cloned()
            .unwrap_or_else(|| plant_for(config, i));
        let (drive, control) = SimCia402Drive::new(SimDriveConfig {
            node: d.node,
            plant,
            start_position: 0.0,
        });
        bus.attach(Box::new(drive));
        controls.push(control);
    }
    if let Some(s) = &config.spindle {
        let (drive, control) = SimCia402Drive::new(SimDriveConfig {
            node: s.node,
            plant: spindle_plant(s.counts_per_rev),
            start_position: 0.0,
        });
        bus.attach(Box::new(drive));
        controls.push(control);
    }
    let backend = Cia402Backend::with_bus(config, servo_period, Box::new(endpoint))?;
    Ok((backend, bus, controls))
}

/// Runs `drives` behind the adapter end of an slcan line (for example the slave of a
/// pseudo-terminal pair whose master end a [`klar_drivers::can::slcan::SlcanBus`] host
/// uses). Every drive gets its own thread and its own view of the line through an
/// in-memory bus, so they behave like nodes sharing one CAN bus.
pub fn serve_on_slcan(
    port: serialport::TTYPort,
    bitrate: u32,
    drives: Vec<SimCia402Drive>,
) -> Result<DeviceRunner, CanError> {
    let line = SlcanBus::from_tty(port, SlcanOptions::adapter(bitrate))?;
    let hub = MemoryBus::new();
    for d in drives {
        hub.attach(Box::new(d));
    }
    let relay = Relay {
        hub_side: hub.endpoint(),
    };
    DeviceRunner::spawn(Box::new(relay), Box::new(line)).map_err(|e| CanError::Io(e.to_string()))
}

/// Carries frames between an slcan line and an in-memory bus of simulated drives.
struct Relay {
    hub_side: klar_drivers::can::memory::MemoryEndpoint,
}

impl klar_drivers::can::memory::BusDevice for Relay {
    fn start(&mut self, out: &mut Vec<klar_drivers::can::CanFrame>) {
        self.drain(out);
    }

    fn on_frame(
        &mut self,
        frame: &klar_drivers::can::CanFrame,
        out: &mut Vec<klar_drivers::can::CanFrame>,
    ) {
        use klar_drivers::can::CanBus;
        if let Err(e) = self.hub_side.send(frame) {
            tracing::warn!(error = %e, "simulated drives: relay failed");
        }
        self.drain(out);
    }
}

impl Relay {
    fn drain(&mut self, out: &mut Vec<klar_drivers::can::CanFrame>) {
        use klar_drivers::can::{CanBus, CanEvent};
        while let Ok(Some(ev)) = self.hub_side.try_recv() {
            if let CanEvent::Frame { frame, .. } = ev {
                out.push(frame);
            }
        }
    }
}
