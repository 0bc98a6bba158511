//! [`SimDriveControl`]: the handle a test or a simulated machine holds on a running
//! simulated drive, to disturb it (injected faults, the touch-probe input, the load of a
//! spindle under cut) and to look at its true state.

use std::sync::{Arc, Mutex, MutexGuard};

use klar_drivers::cia402::state::PowerState;

use super::drive::Injection;
use super::touch_probe::ProbeInput;
use crate::load::LoadDip;

/// A handle to inspect and disturb a simulated drive from outside.
#[derive(Debug, Clone, Default)]
pub struct SimDriveControl {
    shared: Arc<Mutex<Shared>>,
}

#[derive(Debug, Clone, Default)]
pub(super) struct Shared {
    pub(super) injection: Injection,
    pub(super) position: f64,
    pub(super) velocity: f64,
    pub(super) state: Option<PowerState>,
    pub(super) syncs: u64,
    pub(super) probe_input: Option<ProbeInput>,
    /// The speed dip under cut (a spindle drive in CSV).
    load: LoadDip,
}

impl SimDriveControl {
    pub(super) fn lock(&self) -> MutexGuard<'_, Shared> {
        self.shared.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Changes the injected faults.
    pub fn inject(&self, f: impl FnOnce(&mut Injection)) {
        f(&mut self.lock().injection);
    }

    /// The drive's true (physical) plant position.
    pub fn position(&self) -> f64 {
        self.lock().position
    }

    /// The drive's true (physical) plant velocity, units per second.
    pub fn velocity(&self) -> f64 {
        self.lock().velocity
    }

    /// The drive's CiA 402 state (`None` before the first SYNC).
    pub fn power_state(&self) -> Option<PowerState> {
        self.lock().state
    }

    /// Wires the drive's touch-probe input to a trigger position (`None`: nothing
    /// connected); see [`ProbeInput`].
    pub fn set_probe_input(&self, input: Option<ProbeInput>) {
        self.lock().probe_input = input;
    }

    /// SYNCs processed while operational.
    pub fn syncs(&self) -> u64 {
        self.lock().syncs
    }

    /// Makes the drive feel the cut like a spindle: in cyclic synchronous velocity its
    /// speed sinks by `droop` per mm² of chip cross-section with time constant
    /// `time_constant` s (see [`LoadDip`]). Without this the drive keeps its speed.
    pub fn set_load_model(&self, droop: f64, time_constant: f64) {
        self.lock().load = LoadDip::new(droop, time_constant);
    }

    /// Sets the chip cross-section the tool cuts now, mm² (0 out of the cut).
    pub fn set_load(&self, section_mm2: f64) {
        self.lock().load.set_load(section_mm2);
    }

    /// Advances the speed dip by `dt` s and returns the speed as a fraction of the
    /// commanded one.
    pub(super) fn load_factor(&self, dt: f64) -> f64 {
        let mut shared = self.lock();
        shared.load.advance(dt);
        shared.load.factor()
    }
}
