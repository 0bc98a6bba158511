//! A spindle drive on a simulated CANopen bus that feels the cut: the runtime's chip
//! cross-section ([`SpindleBackend::set_load`]) goes to the simulated drive, which slows by
//! the same load model as the built-in simulated spindle (`klar_sim::load::LoadDip`).

use klar_motion::{BackendError, SpindleBackend, SpindleFeedback};
use klar_sim::cia402::SimDriveControl;

/// The CiA 402 spindle backend with the handle of the simulated drive behind it.
struct SimLoaded {
    inner: Box<dyn SpindleBackend>,
    drive: SimDriveControl,
}

/// `backend` as it is when the drive is a real one (`drive` is `None`); on a simulated bus
/// the load reaches the simulated drive.
pub(super) fn with_sim_load(
    backend: Box<dyn SpindleBackend>,
    drive: Option<SimDriveControl>,
) -> Box<dyn SpindleBackend> {
    match drive {
        Some(drive) => Box::new(SimLoaded {
            inner: backend,
            drive,
        }),
        None => backend,
    }
}

impl SpindleBackend for SimLoaded {
    fn command(&mut self, rpm: f64) -> Result<(), BackendError> {
        self.inner.command(rpm)
    }

    fn cycle(&mut self, t: f64) -> Result<SpindleFeedback, BackendError> {
        self.inner.cycle(t)
    }

    fn stop_confirmed(&mut self) -> Result<(), BackendError> {
        self.inner.stop_confirmed()
    }

    fn fault_detail(&self) -> Option<String> {
        self.inner.fault_detail()
    }

    fn set_load(&mut self, section_mm2: f64) {
        self.inner.set_load(section_mm2);
        self.drive.set_load(section_mm2);
    }
}
