//! The machine's I/O: the axis backends a configuration names, addressed by machine axis
//! index, and the spindle. One [`MachineIo::cycle`] is one servo cycle for every backend.

mod touch;

use crate::config::{BackendConfig, MachineConfig, SimSpindleConfig, SpindleBackendConfig};
use crate::runtime::AxisStart;
use klar_drivers::modbus::limits as modbus_limits;
use klar_drivers::modbus::{ModbusServo, ModbusVfd};
use klar_drivers::stepdir::limits as stepdir_limits;
use klar_drivers::stepdir::{StepDirAxis, StepDirOutputs, SwitchInputs};
use klar_motion::{
    AxisBackend, AxisFeedback, BackendError, Setpoint, SpindleBackend, SpindleFeedback,
};
use klar_sim::axis::SimBackend;
use klar_sim::modbus::{PositioningLimits, simulate_servo};
use klar_sim::modbus::{SimSpindle, SpindleParams, simulate_vfd};
use klar_sim::stepper::{NoDelay, PinRole, SimPin, SwitchPositions, stepper};
use std::any::Any;
use std::collections::BTreeMap;

mod canopen;
mod loaded;

use canopen::{CanGroup, open_canopen};

/// One backend and the machine axes it serves.
struct BackendSlot {
    backend: Box<dyn AxisBackend>,
    axes: Vec<usize>,
    /// The axes stand where the devices say, not at the machine file's `start` (drives
    /// with their own position measurement: CANopen).
    measured: bool,
}

/// Why the machine's I/O could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum MachineError {
    /// A backend could not be opened.
    #[error("{what}: {message}")]
    Open {
        /// Which device.
        what: String,
        /// Why.
        message: String,
    },
}

/// The spindle backend.
///
/// Dropping it (every way out of a run, also a panic unwinding) stops the spindle and waits
/// for the device to confirm, unless [`Spindle::stop`] was already called since the last
/// command to turn; an unconfirmed stop prints a warning that the spindle may still turn.
pub struct Spindle {
    backend: Box<dyn SpindleBackend>,
    /// The device in words, for messages.
    name: String,
    /// The last speed commanded, signed rpm.
    commanded: f64,
    /// Highest speed, rpm.
    pub max_rpm: f64,
    /// How long reaching speed may take, s.
    pub at_speed_timeout: f64,
    last: SpindleFeedback,
    /// The sign of the last command to turn: 1 forward, -1 reverse, 0 never turned.
    direction: f64,
    /// A confirmed stop was tried since the last command to turn.
    stop_tried: bool,
    /// Why the last confirmed stop failed, if it did.
    unconfirmed: Option<String>,
}

impl Spindle {
    /// Commands a signed speed in rpm (positive M3, negative M4, zero M5).
    pub fn command(&mut self, rpm: f64) -> Result<(), BackendError> {
        self.backend.command(rpm)?;
        if rpm != 0.0 {
            self.stop_tried = false;
            self.direction = rpm.signum();
        }
        self.commanded = rpm;
        Ok(())
    }

    /// Commands the spindle to stop and waits (bounded) until the device confirms it. The
    /// error says why it could not be confirmed; [`Spindle::stop_warning`] keeps it.
    pub fn stop(&mut self) -> Result<(), BackendError> {
        self.stop_tried = true;
        self.commanded = 0.0;
        let result = self.backend.stop_confirmed();
        self.unconfirmed = result.as_ref().err().map(|e| match e {
            BackendError::Communication(m) => m.clone(),
            other => format!("{}: {other}", self.name),
        });
        result
    }

    /// The loud warning of a stop that could not be confirmed, if the last stop was not.
    pub fn stop_warning(&self) -> Option<String> {
        self.unconfirmed
            .as_ref()
            .map(|why| format!("WARNING: {why}: the spindle may still turn"))
    }

    /// The device in words, e.g. "spindle VFD (Modbus unit 1 on /dev/ttyUSB1)".
    pub fn name(&self) -> &str {
        &self.name
    }

    /// A spindle fault in words: the device, the fault and what the backend knows more.
    pub fn describe_fault(&self, fault: &klar_motion::AxisFault) -> String {
        match self.backend.fault_detail() {
            Some(detail) => format!("{}: {fault}: {detail}", self.name),
            None => format!("{}: {fault}", self.name),
        }
    }

    /// The sign of the last command to turn: 1 forward (M3), -1 reverse (M4), 0 before
    /// the first.
    pub fn direction(&self) -> f64 {
        self.direction
    }

    /// The last commanded speed, signed rpm.
    pub fn commanded(&self) -> f64 {
        self.commanded
    }

    /// The feedback of the last cycle.
    pub fn feedback(&self) -> &SpindleFeedback {
        &self.last
    }

    /// Tells the backend the chip cross-section under cut, mm² (see
    /// [`SpindleBackend::set_load`]).
    pub fn set_load(&mut self, section_mm2: f64) {
        self.backend.set_load(section_mm2);
    }
}

impl Spindle {
    /// A simulated spindle of its own, outside any run (the dashboard keeps one turning
    /// between runs); `None` when the machine has no spindle or a spindle that is not
    /// simulated. It has no injected faults: those strike at a run's machine times.
    pub fn open_simulated(config: &MachineConfig) -> Option<Spindle> {
        let s = config.spindle.as_ref()?;
        let SpindleBackendConfig::Sim(sim) = &s.backend else {
            return None;
        };
        Some(Spindle {
            backend: Box::new(SimSpindle::new(sim_spindle_params(s.max_rpm, sim))),
            name: "simulated spindle".into(),
            commanded: 0.0,
            max_rpm: s.max_rpm,
            at_speed_timeout: s.at_speed_timeout,
            last: SpindleFeedback::default(),
            direction: 0.0,
            stop_tried: true,
            unconfirmed: None,
        })
    }

    /// One cycle of the spindle alone at time `t` (outside a run, where
    /// [`MachineIo::cycle`] does it); the feedback is then [`Spindle::feedback`].
    pub fn cycle(&mut self, t: f64) -> Result<(), BackendError> {
        self.last = self.backend.cycle(t)?;
        Ok(())
    }
}

impl Drop for Spindle {
    fn drop(&mut self) {
        if !self.stop_tried && self.stop().is_err() {
            // The last word of an exit that did not go through the run's end (a panic
            // unwinding, a run dropped unfinished): nobody else can report it.
            if let Some(w) = self.stop_warning() {
                eprintln!("{w}");
            }
        }
    }
}

/// All axis backends and the spindle of a machine.
pub struct MachineIo {
    slots: Vec<BackendSlot>,
    setpoints: Vec<Setpoint>,
    feedback: Vec<AxisFeedback>,
    slot_setpoints: Vec<Setpoint>,
    slot_feedback: Vec<AxisFeedback>,
    spindle: Option<Spindle>,
    /// The simulated axes (for fault injection and inspection), if any.
    sim: Option<crate::faults::SimAxes>,
    /// The probe inputs of simulated CiA 402 drives, by machine axis.
    probe_inputs: SimInputs,
    /// Simulated devices and buses running beside the backends (kept alive, dropped last).
    _companions: Vec<Box<dyn Any>>,
}

/// The probe inputs of simulated CiA 402 drives: machine axis and the drive's controls.
type SimInputs = Vec<(usize, klar_sim::cia402::SimDriveControl)>;

fn sim_spindle_params(max_rpm: f64, sim: &SimSpindleConfig) -> SpindleParams {
    SpindleParams {
        max_rpm,
        acceleration: sim.acceleration,
        at_speed_fraction: sim.at_speed_fraction,
        encoder_counts: sim.encoder_counts,
        load_droop: sim.load_droop,
        load_time_constant: sim.load_time_constant,
        ..SpindleParams::default()
    }
}

fn open_err(what: impl Into<String>, e: &dyn std::fmt::Display) -> MachineError {
    MachineError::Open {
        what: what.into(),
        message: e.to_string(),
    }
}

/// Where the axes of `config` stand, read from the drives that measure their own position
/// (CANopen and Modbus servo axes) by opening the machine without enabling any drive; `None`
/// when no axis has such a drive (simulated and step/dir axes stand at the file's `start`).
/// Axes without a drive of their own report their `start` in the list.
pub fn standing(config: &MachineConfig) -> Option<Result<Vec<AxisStart>, MachineError>> {
    let measured = config.axes.iter().any(|a| {
        matches!(
            a.backend,
            BackendConfig::Canopen(_) | BackendConfig::Modbus(_)
        )
    });
    if !measured {
        return None;
    }
    Some(MachineIo::open(config).map(|io| io.standing(config)))
}

impl MachineIo {
    /// Opens the backends a machine config names.
    pub fn open(config: &MachineConfig) -> Result<Self, MachineError> {
        let period = config.servo_period;
        let mut slots = Vec::new();
        let mut companions: Vec<Box<dyn Any>> = Vec::new();
        let mut probe_inputs = Vec::new();
        let mut sim_axes = Vec::new();
        let mut sim_index = Vec::new();
        let mut can: BTreeMap<String, CanGroup> = BTreeMap::new();
        for (i, a) in config.axes.iter().enumerate() {
            let l = a.letter;
            match &a.backend {
                BackendConfig::Sim(params) => {
                    let mut p = params.clone();
                    if config.start_homed {
                        p.start_homed = true;
                    }
                    sim_axes.push((p, a.start));
                    sim_index.push(i);
                }
                BackendConfig::Canopen(c) => {
                    let g = can.entry(c.bus.clone()).or_default();
                    g.axes.push(i);
                    g.letters.push(l);
                    g.drives.push(c.drive.clone());
                    let mut plant = c.plant.clone().unwrap_or_default();
                    plant.start_homed = plant.start_homed || config.start_homed;
                    g.plants.push((plant, a.start));
                }
                BackendConfig::Modbus(m) => {
                    let what = format!("axis {l} (Modbus)");
                    modbus_limits::check_servo(&m.servo, period, false)
                        .map_err(|e| open_err(what.clone(), &e))?;
                    let backend = match &m.simulate {
                        None => ModbusServo::open(&m.servo),
                        Some(plant) => {
                            let limits = PositioningLimits {
                                velocity: a.max_velocity,
                                acceleration: a.max_acceleration,
                            };
                            let sim = simulate_servo(&m.servo, plant.clone(), limits, a.start)
                                .map_err(|e| open_err(what.clone(), &e))?;
                            let backend = ModbusServo::open(&sim.config);
                            companions.push(Box::new(sim));
                            backend
                        }
                    }
                    .map_err(|e| open_err(what, &e))?;
                    slots.push(BackendSlot {
                        backend: Box::new(backend),
                        axes: vec![i],
                        measured: false,
                    });
                }
                BackendConfig::Stepdir(s) => {
                    let what = format!("axis {l} (step/dir)");
                    stepdir_limits::check(&s.stepdir, period, a.max_velocity)
                        .map_err(|e| open_err(what.clone(), &e))?;
                    if !s.simulate {
                        return Err(open_err(
                            what,
                            &"GPIO step/dir needs a build with the linux-gpio feature and a \
                              [pins] table; set simulate = true to run without hardware",
                        ));
                    }
                    let (_motor, pin) = stepper(SwitchPositions::default());
                    let outputs = StepDirOutputs {
                        step: pin(PinRole::Step),
                        dir: pin(PinRole::Dir),
                        enable: Some(pin(PinRole::Enable)),
                        enable_active_low: false,
                    };
                    let axis: StepDirAxis<SimPin, SimPin, NoDelay> = StepDirAxis::new(
                        &s.stepdir,
                        period,
                        outputs,
                        SwitchInputs::default(),
                        NoDelay,
                    )
                    .map_err(|e| open_err(what, &e))?;
                    slots.push(BackendSlot {
                        backend: Box::new(axis),
                        axes: vec![i],
                        measured: false,
                    });
                }
            }
        }
        let mut sim = None;
        if !sim_axes.is_empty() {
            let backend = SimBackend::try_new(sim_axes, period)
                .map_err(|e| open_err("simulated axes", &e))?;
            let letters = sim_index
                .iter()
                .filter_map(|&i| config.axes.get(i).map(|a| a.letter))
                .collect();
            let shared = crate::faults::SimAxes::new(backend, sim_index.clone(), letters);
            slots.push(BackendSlot {
                backend: Box::new(shared.backend()),
                axes: sim_index,
                measured: false,
            });
            sim = Some(shared);
        }
        if let Some(SpindleBackendConfig::Canopen(c)) = config.spindle.as_ref().map(|s| &s.backend)
        {
            let group = can.entry(c.bus.clone()).or_default();
            group.spindle = Some(c.drive.clone());
            group.spindle_load = (c.load_droop, c.load_time_constant);
        }
        let mut can_spindle: Option<Box<dyn SpindleBackend>> = None;
        for (name, group) in can {
            let Some(network) = config.canopen.get(&name) else {
                return Err(open_err(format!("CANopen bus {name}"), &"not configured"));
            };
            let axes = group.axes.clone();
            let has_spindle = group.spindle.is_some();
            let opened = open_canopen(&name, network, group, period)?;
            let (backend, control) = (opened.backend, opened.spindle);
            companions.extend(opened.companions);
            probe_inputs.extend(opened.probe_inputs);
            if has_spindle && let Some(sp) = backend.spindle() {
                can_spindle = Some(loaded::with_sim_load(Box::new(sp), control));
            }
            slots.push(BackendSlot {
                backend: Box::new(backend),
                axes,
                measured: true,
            });
        }
        let spindle = match &config.spindle {
            None => None,
            Some(s) => {
                let name = match &s.backend {
                    SpindleBackendConfig::Sim(_) => "simulated spindle".to_string(),
                    SpindleBackendConfig::Canopen(c) => {
                        format!("spindle drive (CANopen bus {})", c.bus)
                    }
                    SpindleBackendConfig::Modbus(m) => format!(
                        "spindle VFD (Modbus unit {} on {})",
                        m.vfd.unit,
                        if m.simulate.is_some() {
                            "a simulated line"
                        } else {
                            m.vfd.serial.port.as_str()
                        }
                    ),
                };
                let backend: Box<dyn SpindleBackend> = match &s.backend {
                    SpindleBackendConfig::Sim(sim) => {
                        Box::new(crate::faults::ScheduledSpindle::new(
                            SimSpindle::new(sim_spindle_params(s.max_rpm, sim)),
                            &config.faults,
                        ))
                    }
                    SpindleBackendConfig::Canopen(_) => can_spindle.take().ok_or_else(|| {
                        open_err("spindle", &"the CANopen backend has no spindle drive")
                    })?,
                    SpindleBackendConfig::Modbus(m) => match &m.simulate {
                        None => Box::new(
                            ModbusVfd::open(&m.vfd).map_err(|e| open_err("spindle VFD", &e))?,
                        ),
                        Some(sim) => {
                            let simulated =
                                simulate_vfd(&m.vfd, sim_spindle_params(m.vfd.max_rpm, sim))
                                    .map_err(|e| open_err("spindle VFD", &e))?;
                            let vfd = ModbusVfd::open(&simulated.config)
                                .map_err(|e| open_err("spindle VFD", &e))?;
                            companions.push(Box::new(simulated));
                            Box::new(vfd)
                        }
                    },
                };
                Some(Spindle {
                    backend,
                    name,
                    commanded: 0.0,
                    max_rpm: s.max_rpm,
                    at_speed_timeout: s.at_speed_timeout,
                    last: SpindleFeedback::default(),
                    // Never commanded to turn: nothing to stop (the VFD backend stops
                    // the device when it opens).
                    direction: 0.0,
                    stop_tried: true,
                    unconfirmed: None,
                })
            }
        };
        let n = config.axes.len();
        let mut feedback = vec![AxisFeedback::default(); n];
        for (f, a) in feedback.iter_mut().zip(&config.axes) {
            f.position = a.start;
        }
        let mut io = Self {
            slots,
            setpoints: config
                .axes
                .iter()
                .map(|a| Setpoint {
                    position: a.start,
                    ..Setpoint::default()
                })
                .collect(),
            feedback,
            slot_setpoints: Vec::with_capacity(n),
            slot_feedback: Vec::with_capacity(n),
            spindle,
            sim,
            probe_inputs,
            _companions: companions,
        };
        let letters: Vec<_> = config.axes.iter().map(|a| a.letter).collect();
        io.read_positions(&letters)
            .map_err(|e| open_err("reading the drives' positions", &e))?;
        Ok(io)
    }

    /// Reads where the axes of drives with their own position measurement stand (one cycle
    /// of those backends with the drives disabled) and makes it their feedback and their
    /// commanded position: a run starts there, not at the machine file's `start`.
    fn read_positions(&mut self, letters: &[klar_interp::AxisLetter]) -> Result<(), BackendError> {
        for slot in self.slots.iter_mut().filter(|s| s.measured) {
            let setpoints: Vec<Setpoint> = slot.axes.iter().map(|&i| self.setpoints[i]).collect();
            let mut feedback: Vec<AxisFeedback> = slot
                .axes
                .iter()
                .map(|&i| self.feedback[i].clone())
                .collect();
            slot.backend.cycle(0.0, &setpoints, &mut feedback)?;
            for (k, &i) in slot.axes.iter().enumerate() {
                let f = feedback[k].clone();
                if let Some(fault) = &f.fault {
                    let origin = slot
                        .backend
                        .fault_origin(k)
                        .map(|o| format!(" ({})", o.detail))
                        .unwrap_or_default();
                    let letter = letters.get(i).map(|l| l.to_string()).unwrap_or_default();
                    return Err(BackendError::InvalidState(format!(
                        "axis {letter}: {fault}{origin}"
                    )));
                }
                self.setpoints[i].position = f.position;
                self.feedback[i] = f;
            }
        }
        Ok(())
    }

    /// The origin of machine axis `axis`'s fault, when its backend knows it.
    pub fn fault_origin(&self, axis: usize) -> Option<klar_motion::FaultOrigin> {
        self.slots.iter().find_map(|s| {
            let k = s.axes.iter().position(|&i| i == axis)?;
            s.backend.fault_origin(k)
        })
    }

    /// Puts `spindle` in place of the machine's spindle and returns the one it had (a
    /// spindle kept turning from one run to the next changes hands here).
    pub fn replace_spindle(&mut self, spindle: Option<Spindle>) -> Option<Spindle> {
        std::mem::replace(&mut self.spindle, spindle)
    }

    /// Enables every axis backend.
    pub fn enable(&mut self) -> Result<(), BackendError> {
        self.slots.iter_mut().try_for_each(|s| s.backend.enable())
    }

    /// Stops the spindle (confirmed by the device where it can, see [`Spindle::stop`]) and
    /// disables every backend (best effort: all are tried, the first error is returned).
    pub fn disable(&mut self) -> Result<(), BackendError> {
        let mut first = Ok(());
        if let Some(s) = &mut self.spindle
            && let Err(e) = s.stop()
        {
            first = Err(e);
        }
        for s in &mut self.slots {
            if let Err(e) = s.backend.disable()
                && first.is_ok()
            {
                first = Err(e);
            }
        }
        first
    }

    /// One servo cycle at time `t` with the setpoints held in [`MachineIo::setpoints_mut`].
    pub fn cycle(&mut self, t: f64) -> Result<(), BackendError> {
        for slot in &mut self.slots {
            self.slot_setpoints.clear();
            self.slot_setpoints
                .extend(slot.axes.iter().map(|&i| self.setpoints[i]));
            self.slot_feedback.clear();
            self.slot_feedback
                .extend(slot.axes.iter().map(|&i| self.feedback[i].clone()));
            slot.backend
                .cycle(t, &self.slot_setpoints, &mut self.slot_feedback)?;
            for (k, &i) in slot.axes.iter().enumerate() {
                self.feedback[i] = self.slot_feedback[k].clone();
            }
        }
        if let Some(s) = &mut self.spindle {
            s.last = s.backend.cycle(t)?;
        }
        Ok(())
    }

    /// The simulated axes, for fault injection and inspection (None without sim axes).
    pub fn sim_axes(&self) -> Option<&crate::faults::SimAxes> {
        self.sim.as_ref()
    }

    /// The backend slot serving a machine axis and the axis's index within it.
    fn slot_of(&mut self, axis: usize) -> Result<(&mut BackendSlot, usize), BackendError> {
        self.slots
            .iter_mut()
            .find_map(|s| {
                let k = s.axes.iter().position(|&i| i == axis)?;
                Some((s, k))
            })
            .ok_or(BackendError::NoSuchAxis(axis))
    }

    /// Clears the fault of one machine axis if its cause is gone.
    pub fn reset_fault(&mut self, axis: usize) -> Result<(), BackendError> {
        let (slot, k) = self.slot_of(axis)?;
        slot.backend.reset_fault(k)
    }

    /// Starts the homing sequence of one machine axis.
    pub fn start_homing(&mut self, axis: usize) -> Result<(), BackendError> {
        let (slot, k) = self.slot_of(axis)?;
        slot.backend.start_homing(k)
    }

    /// Setpoints of the last (or next) cycle, one per machine axis.
    pub fn setpoints(&self) -> &[Setpoint] {
        &self.setpoints
    }

    /// Setpoints of the next cycle, one per machine axis.
    pub fn setpoints_mut(&mut self) -> &mut [Setpoint] {
        &mut self.setpoints
    }

    /// Sets every axis to hold its last commanded position (zero velocity and acceleration).
    pub fn hold(&mut self) {
        for s in &mut self.setpoints {
            s.velocity = 0.0;
            s.acceleration = 0.0;
        }
    }

    /// Feedback of the last cycle, one per machine axis.
    pub fn feedback(&self) -> &[AxisFeedback] {
        &self.feedback
    }

    /// Where each axis of `config` stands by the last feedback, and whether its position is
    /// referenced (homed, an absolute encoder, or `start_homed` in the machine file).
    pub fn standing(&self, config: &MachineConfig) -> Vec<AxisStart> {
        self.feedback
            .iter()
            .zip(&config.axes)
            .map(|(f, a)| AxisStart {
                axis: a.letter,
                position: f.position,
                referenced: f.homed || config.start_homed,
            })
            .collect()
    }

    /// Per machine axis: how many servo cycles its feedback lags behind its setpoints
    /// ([`AxisBackend::feedback_lag`]).
    pub fn feedback_lags(&self) -> Vec<u32> {
        let mut lags = vec![0; self.feedback.len()];
        for slot in &self.slots {
            let lag = slot.backend.feedback_lag();
            for &i in &slot.axes {
                if let Some(l) = lags.get_mut(i) {
                    *l = lag;
                }
            }
        }
        lags
    }

    /// The spindle, if the machine has one.
    pub fn spindle_mut(&mut self) -> Option<&mut Spindle> {
        self.spindle.as_mut()
    }
}

/// What a recording backend saw: (time, machine axis, setpoint) per axis and cycle.
#[cfg(test)]
pub(crate) type Recorded = std::sync::Arc<std::sync::Mutex<Vec<(f64, usize, Setpoint)>>>;

/// A backend that hands everything on to the backend it wraps and records each setpoint it
/// was given (tests only: what the backends really received).
#[cfg(test)]
struct Recording {
    inner: Box<dyn AxisBackend>,
    axes: Vec<usize>,
    seen: Recorded,
}

#[cfg(test)]
impl AxisBackend for Recording {
    fn feedback_lag(&self) -> u32 {
        self.inner.feedback_lag()
    }

    fn axis_count(&self) -> usize {
        self.inner.axis_count()
    }
    fn enable(&mut self) -> Result<(), BackendError> {
        self.inner.enable()
    }
    fn disable(&mut self) -> Result<(), BackendError> {
        self.inner.disable()
    }
    fn start_homing(&mut self, axis: usize) -> Result<(), BackendError> {
        self.inner.start_homing(axis)
    }
    fn reset_fault(&mut self, axis: usize) -> Result<(), BackendError> {
        self.inner.reset_fault(axis)
    }
    fn fault_origin(&self, axis: usize) -> Option<klar_motion::FaultOrigin> {
        self.inner.fault_origin(axis)
    }
    fn cycle(
        &mut self,
        t: f64,
        setpoints: &[Setpoint],
        feedback: &mut [AxisFeedback],
    ) -> Result<(), BackendError> {
        if let Ok(mut seen) = self.seen.lock() {
            seen.extend(self.axes.iter().zip(setpoints).map(|(&i, sp)| (t, i, *sp)));
        }
        self.inner.cycle(t, setpoints, feedback)
    }
}

#[cfg(test)]
impl MachineIo {
    /// Wraps every axis backend in a recorder of the setpoints it receives from now on.
    pub(crate) fn record(&mut self) -> Recorded {
        let seen = Recorded::default();
        for slot in &mut self.slots {
            let inner = std::mem::replace(
                &mut slot.backend,
                Box::new(klar_sim::axis::SimBackend::new(Vec::new(), 0.001)),
            );
            slot.backend = Box::new(Recording {
                inner,
                axes: slot.axes.clone(),
                seen: seen.clone(),
            });
        }
        seen
    }
}
