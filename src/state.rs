//! The machine state machine: e-stop → off → on → homed → running / held / stopped /
//! faulted, with only the allowed transitions, and the homing sequence that takes a machine
//! from on to homed.
//!
//! [`MachineState::apply`] is the whole rule set: every event either moves the machine to
//! its next state or is refused with the reason. Motion ([`Event::Start`]) is allowed only
//! from [`MachineState::Homed`] or [`MachineState::Stopped`]; a machine whose axes start
//! referenced (simulation: `start_homed` in the machine file) enters `Homed` directly when
//! switched on.

use crate::machine::MachineIo;
use klar_interp::AxisLetter;
use klar_motion::{AxisState, BackendError};
use std::fmt;

/// The states of the machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MachineState {
    /// The e-stop chain is open: drives without power, nothing may move.
    EStop,
    /// E-stop released, drives not enabled.
    Off,
    /// Drives enabled, not all axes referenced: only homing and jogging are allowed.
    On,
    /// Every axis referenced: programs may start.
    Homed,
    /// A program runs.
    Running,
    /// A program is held (feed hold) on its path.
    Held,
    /// A program ended or was stopped; the axes are at rest and referenced.
    Stopped,
    /// A fault stopped the machine; it needs a reset.
    Faulted,
}

/// What happens to the machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Event {
    /// The e-stop chain opened (allowed in every state).
    EStopPressed,
    /// The e-stop chain closed again.
    EStopReleased,
    /// The operator switches the drives on.
    PowerOn,
    /// The operator switches the drives off.
    PowerOff,
    /// Every axis has a reference (homing done, or the axes start referenced).
    Referenced,
    /// A program starts.
    Start,
    /// Feed hold.
    Hold,
    /// Feed hold ends.
    Resume,
    /// The program ended or a requested stop came to rest.
    Stop,
    /// An axis, drive, link or monitor faulted (allowed in every powered state).
    Fault,
    /// The fault's cause is gone and the faults were reset.
    Reset,
}

/// A refused transition.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("{event:?} is not allowed while the machine is {state}")]
pub struct TransitionError {
    /// The state the machine is in.
    pub state: MachineState,
    /// The event refused.
    pub event: Event,
}

impl fmt::Display for MachineState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            MachineState::EStop => "in e-stop",
            MachineState::Off => "off",
            MachineState::On => "on (not homed)",
            MachineState::Homed => "homed",
            MachineState::Running => "running",
            MachineState::Held => "held",
            MachineState::Stopped => "stopped",
            MachineState::Faulted => "faulted",
        };
        f.write_str(s)
    }
}

impl MachineState {
    /// The state after `event`, or the refusal.
    pub fn apply(self, event: Event) -> Result<MachineState, TransitionError> {
        use Event as E;
        use MachineState as S;
        let next = match (self, event) {
            (_, E::EStopPressed) => S::EStop,
            (S::EStop, E::EStopReleased) => S::Off,
            (S::Off, E::PowerOn) => S::On,
            (S::On | S::Homed | S::Stopped | S::Faulted, E::PowerOff) => S::Off,
            (S::On, E::Referenced) => S::Homed,
            (S::Homed | S::Stopped, E::Start) => S::Running,
            (S::Running, E::Hold) => S::Held,
            (S::Held, E::Resume) => S::Running,
            (S::Running | S::Held, E::Stop) => S::Stopped,
            (S::On | S::Homed | S::Running | S::Held | S::Stopped, E::Fault) => S::Faulted,
            // A reset leaves the references alone: the drives kept counting (position
            // integrity), so a homed machine is homed again after its faults are cleared.
            (S::Faulted, E::Reset) => S::Stopped,
            _ => {
                return Err(TransitionError { state: self, event });
            }
        };
        Ok(next)
    }

    /// True when a program may start from this state.
    pub fn may_start(self) -> bool {
        matches!(self, MachineState::Homed | MachineState::Stopped)
    }
}

/// Why homing failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HomingError {
    /// The backend refused or failed.
    #[error("axis {axis}: {source}")]
    Backend {
        /// The axis.
        axis: AxisLetter,
        /// What the backend said.
        source: BackendError,
    },
    /// The axis faulted while homing.
    #[error("axis {axis} faulted while homing: {fault}")]
    Faulted {
        /// The axis.
        axis: AxisLetter,
        /// The fault.
        fault: String,
    },
    /// The axis did not finish homing in time.
    #[error("axis {axis} did not finish homing within {seconds} s")]
    Timeout {
        /// The axis.
        axis: AxisLetter,
        /// The time allowed.
        seconds: f64,
    },
}

/// Homes the axes of `io` one after the other in `order` (machine axis indices; the tool
/// axis usually first), each with the backend's own sequence — home switch and index pulse
/// for simulated and step/dir axes, the drive's homing method for CiA 402 drives — waiting
/// up to `timeout` seconds of machine time per axis. The drives are switched off first, the
/// positions read and commanded, then the drives enabled. Time starts at `t0` and advances
/// by `period` per cycle; returns the machine time at the end.
pub fn home_axes(
    io: &mut MachineIo,
    letters: &[AxisLetter],
    order: &[usize],
    t0: f64,
    period: f64,
    timeout: f64,
) -> Result<f64, HomingError> {
    let mut t = t0;
    // Read where the (unreferenced) encoders stand with the drives off, command exactly that,
    // then power the drives: enabling never pulls an axis toward a stale setpoint.
    let any = |source| HomingError::Backend {
        axis: letters.first().copied().unwrap_or(AxisLetter::X),
        source,
    };
    io.disable().map_err(any)?;
    t += period;
    io.cycle(t).map_err(any)?;
    let measured: Vec<f64> = io.feedback().iter().map(|f| f.position).collect();
    for (sp, x) in io.setpoints_mut().iter_mut().zip(measured) {
        sp.position = x;
        sp.velocity = 0.0;
        sp.acceleration = 0.0;
    }
    io.enable().map_err(any)?;
    for &axis in order {
        let letter = letters.get(axis).copied().unwrap_or(AxisLetter::X);
        let backend = |source| HomingError::Backend {
            axis: letter,
            source,
        };
        io.start_homing(axis).map_err(backend)?;
        io.hold();
        let start = t;
        loop {
            t += period;
            io.cycle(t).map_err(backend)?;
            let Some(f) = io.feedback().get(axis) else {
                return Err(backend(BackendError::NoSuchAxis(axis)));
            };
            if let Some(fault) = &f.fault {
                return Err(HomingError::Faulted {
                    axis: letter,
                    fault: fault.to_string(),
                });
            }
            if f.homed && f.state == AxisState::Enabled {
                let position = f.position;
                // Hold where homing left the axis.
                if let Some(sp) = io.setpoints_mut().get_mut(axis) {
                    sp.position = position;
                    sp.velocity = 0.0;
                    sp.acceleration = 0.0;
                }
                tracing::info!(axis = %letter, position, "homed");
                break;
            }
            if t - start > timeout {
                return Err(HomingError::Timeout {
                    axis: letter,
                    seconds: timeout,
                });
            }
        }
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use Event as E;
    use MachineState as S;

    const STATES: [S; 8] = [
        S::EStop,
        S::Off,
        S::On,
        S::Homed,
        S::Running,
        S::Held,
        S::Stopped,
        S::Faulted,
    ];
    const EVENTS: [E; 11] = [
        E::EStopPressed,
        E::EStopReleased,
        E::PowerOn,
        E::PowerOff,
        E::Referenced,
        E::Start,
        E::Hold,
        E::Resume,
        E::Stop,
        E::Fault,
        E::Reset,
    ];

    /// The allowed transitions written out as a table, independent of the `match` above.
    const ALLOWED: &[(S, E, S)] = &[
        (S::EStop, E::EStopReleased, S::Off),
        (S::Off, E::PowerOn, S::On),
        (S::On, E::PowerOff, S::Off),
        (S::Homed, E::PowerOff, S::Off),
        (S::Stopped, E::PowerOff, S::Off),
        (S::Faulted, E::PowerOff, S::Off),
        (S::On, E::Referenced, S::Homed),
        (S::Homed, E::Start, S::Running),
        (S::Stopped, E::Start, S::Running),
        (S::Running, E::Hold, S::Held),
        (S::Held, E::Resume, S::Running),
        (S::Running, E::Stop, S::Stopped),
        (S::Held, E::Stop, S::Stopped),
        (S::On, E::Fault, S::Faulted),
        (S::Homed, E::Fault, S::Faulted),
        (S::Running, E::Fault, S::Faulted),
        (S::Held, E::Fault, S::Faulted),
        (S::Stopped, E::Fault, S::Faulted),
        (S::Faulted, E::Reset, S::Stopped),
    ];

    #[test]
    fn every_state_event_pair_follows_the_table() {
        for s in STATES {
            for e in EVENTS {
                let want = if e == E::EStopPressed {
                    Some(S::EStop)
                } else {
                    ALLOWED
                        .iter()
                        .find(|(a, b, _)| *a == s && *b == e)
                        .map(|(_, _, n)| *n)
                };
                match (s.apply(e), want) {
                    (Ok(got), Some(w)) => assert_eq!(got, w, "{s:?} + {e:?}"),
                    (Err(err), None) => {
                        assert_eq!((err.state, err.event), (s, e));
                        assert!(err.to_string().contains(&s.to_string()));
                    }
                    (got, w) => panic!("{s:?} + {e:?}: got {got:?}, table says {w:?}"),
                }
            }
        }
    }

    #[test]
    fn motion_needs_a_reference() {
        // Off → On → Start is refused; only after Referenced may a program start.
        let on = S::EStop
            .apply(E::EStopReleased)
            .and_then(|s| s.apply(E::PowerOn))
            .unwrap();
        assert!(on.apply(E::Start).is_err());
        assert!(!on.may_start());
        let homed = on.apply(E::Referenced).unwrap();
        assert!(homed.may_start());
        assert_eq!(homed.apply(E::Start), Ok(S::Running));
    }

    #[test]
    fn a_fault_needs_a_reset_before_the_next_start() {
        let faulted = S::Running.apply(E::Fault).unwrap();
        assert!(faulted.apply(E::Start).is_err());
        assert!(faulted.apply(E::Resume).is_err());
        let reset = faulted.apply(E::Reset).unwrap();
        assert_eq!(reset.apply(E::Start), Ok(S::Running));
    }
}
