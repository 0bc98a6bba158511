//! The touch-probe latches of the machine's axes (CiA 402 drives: 0x60B8 … 0x60BA), and the
//! probe inputs of simulated drives, which a simulated part switches.

use super::MachineIo;
use klar_motion::BackendError;
use klar_sim::cia402::ProbeInput;

impl MachineIo {
    /// Arms the touch-probe latch of machine axis `axis`; false when it has none.
    pub fn arm_touch_probe(&mut self, axis: usize) -> Result<bool, BackendError> {
        let (slot, k) = self.slot_of(axis)?;
        slot.backend.arm_touch_probe(k)
    }

    /// The position machine axis `axis` latched since it was armed, once it has.
    pub fn touch_probe_position(&mut self, axis: usize) -> Result<Option<f64>, BackendError> {
        let (slot, k) = self.slot_of(axis)?;
        slot.backend.touch_probe_position(k)
    }

    /// Switches the touch-probe latch of machine axis `axis` off.
    pub fn disarm_touch_probe(&mut self, axis: usize) -> Result<(), BackendError> {
        let (slot, k) = self.slot_of(axis)?;
        slot.backend.disarm_touch_probe(k)
    }

    /// Wires the probe input of the simulated drive of machine axis `axis` (`None`: nothing
    /// connected). False when the axis has no simulated CiA 402 drive.
    pub fn set_sim_probe_input(&self, axis: usize, input: Option<ProbeInput>) -> bool {
        match self.probe_inputs.iter().find(|(a, _)| *a == axis) {
            Some((_, control)) => {
                control.set_probe_input(input);
                true
            }
            None => false,
        }
    }
}
