//! Fault injection on the simulated axes of a machine: the `[[fault]]` entries of a machine
//! file and the `--fault KIND[:AXIS]@SECONDS` option of `klar run`, and [`SimAxes`], the handle
//! through which a run (or a test, or a dashboard) reaches the simulated plants while the
//! runtime drives them.

use klar_interp::AxisLetter;
use klar_motion::{AxisBackend, AxisFeedback, BackendError, Setpoint};
use klar_sim::axis::SimBackend;
use klar_sim::faults::{FAULT_INJECTED, FaultSchedule, InjectedFault, ScheduledFault};
use klar_sim::plant::ServoPlant;
use serde::Deserialize;
use std::str::FromStr;
use std::sync::{Arc, Mutex, MutexGuard};

/// Default encoder noise amplitude in counts when a `noise` fault gives none.
pub const DEFAULT_NOISE_COUNTS: u32 = 5000;

/// The kinds of fault a machine file or the command line can inject.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FaultKind {
    /// Drive fault on one axis.
    Drive,
    /// Communication with one axis's drive lost.
    Comm,
    /// Encoder noise on one axis.
    Noise,
    /// One axis jams.
    Stuck,
    /// The limit switch of one axis trips.
    Limit,
    /// The e-stop chain opens (all axes).
    Estop,
    /// The servo loop stalls: the next setpoint comes `duration` seconds late (a setpoint
    /// underrun). Not an axis fault: the runtime handles it.
    Stall,
    /// The simulated spindle drive faults (fault `code`, default 1).
    Spindle,
    /// One commanded sample of a simulated axis is offset by `offset` (mm or degrees,
    /// default [`DEFAULT_JUMP_OFFSET`]) before the setpoint guard sees it: a planner jump, to
    /// test that the guard keeps it from the backend. Not an axis fault: the runtime handles
    /// it.
    Jump,
}

/// Offset of a `jump` fault when the entry gives none, mm or degrees.
pub const DEFAULT_JUMP_OFFSET: f64 = 1.0;

/// Default length of a `stall` fault when the entry gives none, s.
pub const DEFAULT_STALL_SECONDS: f64 = 0.05;

impl FaultKind {
    /// Every kind with the name the command line and machine files use for it.
    pub const NAMES: [(&'static str, FaultKind); 9] = [
        ("drive", FaultKind::Drive),
        ("comm", FaultKind::Comm),
        ("noise", FaultKind::Noise),
        ("stuck", FaultKind::Stuck),
        ("limit", FaultKind::Limit),
        ("estop", FaultKind::Estop),
        ("stall", FaultKind::Stall),
        ("spindle", FaultKind::Spindle),
        ("jump", FaultKind::Jump),
    ];

    fn parse(s: &str) -> Option<Self> {
        Self::NAMES.iter().find(|(n, _)| *n == s).map(|(_, k)| *k)
    }
}

/// One injected fault: a `[[fault]]` entry of a machine file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultConfig {
    /// Machine time in seconds at which it strikes.
    pub at: f64,
    /// What happens.
    pub kind: FaultKind,
    /// The axis (required for every kind but `estop`).
    #[serde(default)]
    pub axis: Option<AxisLetter>,
    /// Drive fault code (`drive` only).
    #[serde(default)]
    pub code: Option<u32>,
    /// Noise amplitude in encoder counts (`noise` only).
    #[serde(default)]
    pub amplitude: Option<u32>,
    /// How late the setpoint comes, s (`stall` only; default [`DEFAULT_STALL_SECONDS`]).
    #[serde(default)]
    pub duration: Option<f64>,
    /// How far the commanded sample is offset, mm or degrees (`jump` only; default
    /// [`DEFAULT_JUMP_OFFSET`]).
    #[serde(default)]
    pub offset: Option<f64>,
}

/// Why a fault specification is not usable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FaultSpecError {
    /// The text does not have the form `KIND[:AXIS]@SECONDS`.
    #[error("fault `{0}`: expected KIND[:AXIS]@SECONDS, e.g. drive:X@0.5 or estop@1.2")]
    Form(String),
    /// Unknown kind.
    #[error(
        "fault `{0}`: unknown kind (drive, comm, noise, stuck, limit, estop, stall, spindle, jump)"
    )]
    Kind(String),
    /// The time is not a finite number >= 0.
    #[error("fault `{0}`: the time must be a number of seconds >= 0")]
    Time(String),
    /// The axis letter is not one of A B C U V W X Y Z.
    #[error("fault `{0}`: unknown axis letter")]
    Axis(String),
    /// An axis fault without an axis.
    #[error("fault {0:?} at {1} s needs an axis")]
    NeedsAxis(FaultKind, f64),
    /// The axis is not a simulated axis of the machine.
    #[error("fault {0:?} at {1} s: axis {2} is not a simulated axis of this machine")]
    NotSimulated(FaultKind, f64, AxisLetter),
}

impl FromStr for FaultConfig {
    type Err = FaultSpecError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let form = || FaultSpecError::Form(s.to_string());
        let (head, time) = s.split_once('@').ok_or_else(form)?;
        let at: f64 = time
            .trim()
            .parse()
            .map_err(|_| FaultSpecError::Time(s.to_string()))?;
        if !(at.is_finite() && at >= 0.0) {
            return Err(FaultSpecError::Time(s.to_string()));
        }
        let (kind, axis) = match head.split_once(':') {
            Some((k, a)) => (k, Some(a)),
            None => (head, None),
        };
        let kind = FaultKind::parse(kind.trim().to_ascii_lowercase().as_str())
            .ok_or_else(|| FaultSpecError::Kind(s.to_string()))?;
        let axis = match axis {
            None => None,
            Some(a) => {
                let mut chars = a.trim().chars();
                let letter = match (chars.next(), chars.next()) {
                    (Some(c), None) => AxisLetter::from_char(c.to_ascii_uppercase()),
                    _ => None,
                };
                Some(letter.ok_or_else(|| FaultSpecError::Axis(s.to_string()))?)
            }
        };
        Ok(FaultConfig {
            at,
            kind,
            axis,
            code: None,
            amplitude: None,
            duration: None,
            offset: None,
        })
    }
}

impl FaultConfig {
    /// The fault as the simulator injects it; `None` for a fault of the runtime itself
    /// (`stall`, `spindle`, `jump`).
    pub fn injected(&self) -> Option<InjectedFault> {
        Some(match self.kind {
            FaultKind::Drive => InjectedFault::Drive {
                code: self.code.unwrap_or(FAULT_INJECTED),
            },
            FaultKind::Comm => InjectedFault::CommunicationLost,
            FaultKind::Noise => InjectedFault::EncoderNoise {
                amplitude: self.amplitude.unwrap_or(DEFAULT_NOISE_COUNTS),
            },
            FaultKind::Stuck => InjectedFault::Stuck,
            FaultKind::Limit => InjectedFault::LimitSwitch,
            FaultKind::Estop => InjectedFault::EStop,
            FaultKind::Stall | FaultKind::Spindle | FaultKind::Jump => return None,
        })
    }

    /// The length of a `stall` fault, s.
    pub fn stall_seconds(&self) -> f64 {
        self.duration.unwrap_or(DEFAULT_STALL_SECONDS)
    }

    /// The offset of a `jump` fault, mm or degrees.
    pub fn jump_offset(&self) -> f64 {
        self.offset.unwrap_or(DEFAULT_JUMP_OFFSET)
    }
}

/// The simulated axes of a machine, shared between the runtime (which cycles them) and
/// whoever injects faults or inspects the plants.
#[derive(Clone)]
pub struct SimAxes {
    backend: Arc<Mutex<SimBackend>>,
    /// Machine axis index of each simulated axis, in the backend's order.
    machine_axes: Vec<usize>,
    letters: Vec<AxisLetter>,
}

/// A plant lock that failed because another user panicked while holding it.
fn poisoned() -> BackendError {
    BackendError::InvalidState("simulated axes: lock poisoned".into())
}

impl SimAxes {
    /// Wraps a backend whose axes are the machine axes `machine_axes` named `letters`.
    pub fn new(backend: SimBackend, machine_axes: Vec<usize>, letters: Vec<AxisLetter>) -> Self {
        Self {
            backend: Arc::new(Mutex::new(backend)),
            machine_axes,
            letters,
        }
    }

    /// Locks the backend.
    pub fn lock(&self) -> Result<MutexGuard<'_, SimBackend>, BackendError> {
        self.backend.lock().map_err(|_| poisoned())
    }

    /// The backend's axis index of a machine axis letter.
    pub fn index_of(&self, letter: AxisLetter) -> Option<usize> {
        self.letters.iter().position(|&l| l == letter)
    }

    /// The machine axis index of each simulated axis.
    pub fn machine_axes(&self) -> &[usize] {
        &self.machine_axes
    }

    /// A copy of the plant of a machine axis (for inspection: true position, counts).
    pub fn plant_of(&self, letter: AxisLetter) -> Option<ServoPlant> {
        let i = self.index_of(letter)?;
        self.lock().ok()?.plant(i).cloned()
    }

    /// Schedules `faults`; refuses a fault on an axis that is not simulated.
    pub fn schedule(&self, faults: &[FaultConfig]) -> Result<(), FaultSpecError> {
        let mut entries = Vec::new();
        for f in faults {
            if f.kind == FaultKind::Jump {
                // A jump offsets a commanded sample: only of a simulated axis, never of a
                // real drive.
                match f.axis {
                    None => return Err(FaultSpecError::NeedsAxis(f.kind, f.at)),
                    Some(l) if self.index_of(l).is_none() => {
                        return Err(FaultSpecError::NotSimulated(f.kind, f.at, l));
                    }
                    Some(_) => {}
                }
            }
            let Some(fault) = f.injected() else {
                continue;
            };
            let axis = match (f.kind, f.axis) {
                (FaultKind::Estop, _) => 0,
                (k, None) => return Err(FaultSpecError::NeedsAxis(k, f.at)),
                (k, Some(l)) => self
                    .index_of(l)
                    .ok_or(FaultSpecError::NotSimulated(k, f.at, l))?,
            };
            entries.push(ScheduledFault {
                at: f.at,
                axis,
                fault,
            });
        }
        if let Ok(mut b) = self.backend.lock() {
            b.set_fault_schedule(FaultSchedule::new(entries));
        }
        Ok(())
    }

    /// Injects a fault now on a machine axis (any axis for the e-stop).
    pub fn inject(&self, letter: AxisLetter, fault: &InjectedFault) -> Result<(), BackendError> {
        let i = match fault {
            InjectedFault::EStop => 0,
            _ => self.index_of(letter).ok_or_else(|| {
                BackendError::InvalidState(format!("axis {letter} is not simulated"))
            })?,
        };
        self.lock()?.inject(i, fault)
    }

    /// Removes the causes of every injected fault and releases the e-stop.
    pub fn repair_all(&self) -> Result<(), BackendError> {
        let mut b = self.lock()?;
        b.set_estop(false);
        for i in 0..b.axis_count() {
            b.repair(i)?;
        }
        Ok(())
    }

    /// A backend view for the runtime's servo loop.
    pub fn backend(&self) -> SharedSimBackend {
        SharedSimBackend(self.backend.clone())
    }
}

/// The runtime's side of [`SimAxes`]: an [`AxisBackend`] that locks the shared backend for
/// each call.
pub struct SharedSimBackend(Arc<Mutex<SimBackend>>);

impl SharedSimBackend {
    fn with<T>(
        &self,
        f: impl FnOnce(&mut SimBackend) -> Result<T, BackendError>,
    ) -> Result<T, BackendError> {
        let mut b = self.0.lock().map_err(|_| poisoned())?;
        f(&mut b)
    }
}

impl AxisBackend for SharedSimBackend {
    fn axis_count(&self) -> usize {
        self.0.lock().map(|b| b.axis_count()).unwrap_or(0)
    }
    fn enable(&mut self) -> Result<(), BackendError> {
        self.with(|b| b.enable())
    }
    fn disable(&mut self) -> Result<(), BackendError> {
        self.with(|b| b.disable())
    }
    fn start_homing(&mut self, axis: usize) -> Result<(), BackendError> {
        self.with(|b| b.start_homing(axis))
    }
    fn reset_fault(&mut self, axis: usize) -> Result<(), BackendError> {
        self.with(|b| b.reset_fault(axis))
    }
    fn cycle(
        &mut self,
        t: f64,
        setpoints: &[Setpoint],
        feedback: &mut [AxisFeedback],
    ) -> Result<(), BackendError> {
        self.with(|b| b.cycle(t, setpoints, feedback))
    }
}

/// A simulated spindle that faults at scheduled machine times (`spindle` faults).
pub struct ScheduledSpindle {
    inner: klar_sim::modbus::SimSpindle,
    /// (machine time, fault code), by time.
    pending: std::collections::VecDeque<(f64, u16)>,
}

impl ScheduledSpindle {
    /// Wraps `inner`; the `spindle` entries of `faults` strike at their times.
    pub fn new(inner: klar_sim::modbus::SimSpindle, faults: &[FaultConfig]) -> Self {
        let mut pending: Vec<(f64, u16)> = faults
            .iter()
            .filter(|f| f.kind == FaultKind::Spindle)
            .map(|f| {
                let code = f.code.and_then(|c| u16::try_from(c).ok()).unwrap_or(1);
                (f.at, code)
            })
            .collect();
        pending.sort_by(|a, b| a.0.total_cmp(&b.0));
        Self {
            inner,
            pending: pending.into(),
        }
    }
}

impl klar_motion::SpindleBackend for ScheduledSpindle {
    fn command(&mut self, rpm: f64) -> Result<(), BackendError> {
        self.inner.command(rpm)
    }

    fn cycle(&mut self, t: f64) -> Result<klar_motion::SpindleFeedback, BackendError> {
        while let Some(&(at, code)) = self.pending.front() {
            if at > t {
                break;
            }
            self.pending.pop_front();
            self.inner.model_mut().inject_fault(code);
        }
        self.inner.cycle(t)
    }

    fn set_load(&mut self, section_mm2: f64) {
        self.inner.set_load(section_mm2);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_line_faults_parse() {
        let f: FaultConfig = "drive:X@0.5".parse().unwrap();
        assert_eq!(
            (f.kind, f.axis, f.at),
            (FaultKind::Drive, Some(AxisLetter::X), 0.5)
        );
        let f: FaultConfig = "estop@1.25".parse().unwrap();
        assert_eq!((f.kind, f.axis, f.at), (FaultKind::Estop, None, 1.25));
        let f: FaultConfig = "Noise:y@0".parse().unwrap();
        assert_eq!((f.kind, f.axis), (FaultKind::Noise, Some(AxisLetter::Y)));
    }

    #[test]
    fn malformed_faults_are_refused_with_the_reason() {
        for (text, want) in [
            ("drive:X", "expected KIND"),
            ("melt:X@1", "unknown kind"),
            ("drive:X@-1", "time must be"),
            ("drive:X@nan", "time must be"),
            ("drive:Q@1", "unknown axis"),
            ("drive:XY@1", "unknown axis"),
        ] {
            let e = text.parse::<FaultConfig>().unwrap_err().to_string();
            assert!(e.contains(want), "{text}: {e}");
        }
    }
}
