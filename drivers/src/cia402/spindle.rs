//! [`Cia402Spindle`]: a CiA 402 drive in cyclic synchronous velocity or profile velocity
//! mode as the machine's [`klar_motion::SpindleBackend`], sharing the bus (and the SYNC
//! cycle) with the axes of its [`super::Cia402Backend`].
//!
//! A non-zero command switches the drive on through the power state machine, one step per
//! cycle, then sends the speed as target velocity; zero keeps it enabled at standstill.
//! In CSV klar ramps the target at the configured acceleration and reports "at speed" when
//! the actual speed is inside the window around the command. In profile velocity the
//! command goes out unramped, the drive ramps with its own profile acceleration, and "at
//! speed" is the drive's "target reached" (statusword bit 10), taken only once the drive
//! has had the current target for a full cycle (so a bit earned by the previous target does
//! not count).
//!
//! In both modes the drive's actual position (0x6064, on a transmit PDO of its own) is the
//! measured spindle angle: counts through `counts_per_rev` to degrees, unwrapped across the
//! drive's 32-bit counter, so thread cutting and rigid tapping can follow it.

use std::sync::{Arc, Mutex};

use klar_motion::{BackendError, SpindleBackend, SpindleFeedback};

use super::backend::lock;
use super::network::{DriveKind, Network};
use super::objects::MODE_PROFILE_VELOCITY;
use super::state::{PowerState, SW_TARGET_REACHED};

/// The spindle drive of a CANopen bus.
pub struct Cia402Spindle {
    net: Arc<Mutex<Network>>,
}

impl Cia402Spindle {
    pub(crate) fn new(net: Arc<Mutex<Network>>) -> Self {
        Self { net }
    }

    /// Clears the spindle drive's fault if its cause is gone.
    pub fn reset_fault(&mut self) -> Result<(), BackendError> {
        let mut net = lock(&self.net);
        let index = spindle_index(&net)?;
        net.reset_drive_fault(index)
    }
}

fn spindle_index(net: &Network) -> Result<usize, BackendError> {
    net.drives
        .iter()
        .position(|d| d.kind == DriveKind::Spindle)
        .ok_or_else(|| BackendError::InvalidState("no spindle drive on this bus".into()))
}

impl SpindleBackend for Cia402Spindle {
    fn command(&mut self, rpm: f64) -> Result<(), BackendError> {
        if !rpm.is_finite() {
            return Err(BackendError::InvalidState(format!(
                "spindle speed {rpm} rpm"
            )));
        }
        let mut net = lock(&self.net);
        let index = spindle_index(&net)?;
        if let Some(d) = net.drives.get_mut(index) {
            d.commanded = rpm;
        }
        Ok(())
    }

    fn cycle(&mut self, t: f64) -> Result<SpindleFeedback, BackendError> {
        let mut net = lock(&self.net);
        if net.axes == 0 {
            net.cycle(t, &[]);
        }
        let index = spindle_index(&net)?;
        let at_speed_fraction = net.spindle_at_speed.0;
        let at_speed_min = net.spindle_at_speed.1;
        let d = net
            .drives
            .get(index)
            .ok_or_else(|| BackendError::InvalidState("no spindle drive on this bus".into()))?;
        let rpm = d.scaling.to_units(d.actual);
        let enabled = d.power() == PowerState::OperationEnabled;
        let at_speed = if d.mode == MODE_PROFILE_VELOCITY {
            let sent = d.scaling.to_counts(d.commanded).ok() == Some(d.target);
            if d.commanded == 0.0 && !enabled {
                rpm.abs() <= at_speed_min
            } else {
                enabled && sent && d.same_target >= 1 && d.status & SW_TARGET_REACHED != 0
            }
        } else {
            let window = (d.commanded.abs() * at_speed_fraction).max(at_speed_min);
            (d.commanded == 0.0 || enabled) && (rpm - d.commanded).abs() <= window
        };
        // The measured angle: the unwrapped actual position (0x6064) in degrees, once the
        // drive has sent it.
        let position = d
            .position_raw
            .and(d.angle_scaling)
            .map(|s| s.wide_to_units(d.position_total));
        Ok(SpindleFeedback {
            rpm,
            position,
            at_speed: d.fault.is_none() && at_speed,
            fault: d.fault.clone(),
        })
    }
}
