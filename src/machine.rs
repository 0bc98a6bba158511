//! The machine's I/O: the axis backends a configuration names, addressed by machine axis
//! index, and the spindle. One [`MachineIo::cycle`] is one servo cycle for every backend.

use crate::config::{BackendConfig, MachineConfig, SimSpindleConfig, SpindleBackendConfig};
use klar_drivers::modbus::ModbusVfd;
use klar_motion::{
    AxisBackend, AxisFeedback, BackendError, Setpoint, SpindleBackend, SpindleFeedback,
};
use klar_sim::axis::SimBackend;
use klar_sim::modbus::{SimSpindle, SpindleParams, simulate_vfd};
use std::any::Any;

/// One backend and the machine axes it serves.
struct BackendSlot {
    backend: Box<dyn AxisBackend>,
    axes: Vec<usize>,
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

/// The spindle backend with what it needs kept alive.
pub struct Spindle {
    backend: Box<dyn SpindleBackend>,
    /// Simulated devices running beside the backend (a VFD on a pseudo-terminal).
    _companions: Vec<Box<dyn Any>>,
    /// The last speed commanded, signed rpm.
    commanded: f64,
    /// Highest speed, rpm.
    pub max_rpm: f64,
    /// How long reaching speed may take, s.
    pub at_speed_timeout: f64,
    last: SpindleFeedback,
}

impl Spindle {
    /// Commands a signed speed in rpm (positive M3, negative M4, zero M5).
    pub fn command(&mut self, rpm: f64) -> Result<(), BackendError> {
        self.backend.command(rpm)?;
        self.commanded = rpm;
        Ok(())
    }

    /// The last commanded speed, signed rpm.
    pub fn commanded(&self) -> f64 {
        self.commanded
    }

    /// The feedback of the last cycle.
    pub fn feedback(&self) -> &SpindleFeedback {
        &self.last
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
}

fn sim_spindle_params(max_rpm: f64, sim: &SimSpindleConfig) -> SpindleParams {
    SpindleParams {
        max_rpm,
        acceleration: sim.acceleration,
        at_speed_fraction: sim.at_speed_fraction,
        ..SpindleParams::default()
    }
}

impl MachineIo {
    /// Opens the backends a machine config names.
    pub fn open(config: &MachineConfig) -> Result<Self, MachineError> {
        let mut sim_axes = Vec::new();
        let mut sim_index = Vec::new();
        for (i, a) in config.axes.iter().enumerate() {
            match &a.backend {
                BackendConfig::Sim(params) => {
                    let mut p = params.clone();
                    if config.start_homed {
                        p.start_homed = true;
                    }
                    sim_axes.push((p, a.start));
                    sim_index.push(i);
                }
            }
        }
        let mut slots = Vec::new();
        if !sim_axes.is_empty() {
            let backend = SimBackend::try_new(sim_axes, config.servo_period).map_err(|e| {
                MachineError::Open {
                    what: "simulated axes".into(),
                    message: e.to_string(),
                }
            })?;
            slots.push(BackendSlot {
                backend: Box::new(backend),
                axes: sim_index,
            });
        }
        let spindle = match &config.spindle {
            None => None,
            Some(s) => {
                let (backend, companions): (Box<dyn SpindleBackend>, Vec<Box<dyn Any>>) =
                    match &s.backend {
                        SpindleBackendConfig::Sim(sim) => (
                            Box::new(SimSpindle::new(sim_spindle_params(s.max_rpm, sim))),
                            Vec::new(),
                        ),
                        SpindleBackendConfig::Modbus(m) => {
                            let open_err = |e: &dyn std::fmt::Display| MachineError::Open {
                                what: "spindle VFD".into(),
                                message: e.to_string(),
                            };
                            match &m.simulate {
                                None => (
                                    Box::new(ModbusVfd::open(&m.vfd).map_err(|e| open_err(&e))?),
                                    Vec::new(),
                                ),
                                Some(sim) => {
                                    let simulated =
                                        simulate_vfd(&m.vfd, sim_spindle_params(m.vfd.max_rpm, sim))
                                            .map_err(|e| open_err(&e))?;
                                    let vfd = ModbusVfd::open(&simulated.config)
                                        .map_err(|e| open_err(&e))?;
                                    (Box::new(vfd), vec![Box::new(simulated) as Box<dyn Any>])
                                }
                            }
                        }
                    };
                Some(Spindle {
                    backend,
                    _companions: companions,
                    commanded: 0.0,
                    max_rpm: s.max_rpm,
                    at_speed_timeout: s.at_speed_timeout,
                    last: SpindleFeedback::default(),
                })
            }
        };
        let n = config.axes.len();
        let mut feedback = vec![AxisFeedback::default(); n];
        for (f, a) in feedback.iter_mut().zip(&config.axes) {
            f.position = a.start;
        }
        Ok(Self {
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
        })
    }

    /// Enables every axis backend.
    pub fn enable(&mut self) -> Result<(), BackendError> {
        self.slots.iter_mut().try_for_each(|s| s.backend.enable())
    }

    /// Stops the spindle and disables every backend (best effort: all are tried, the first
    /// error is returned).
    pub fn disable(&mut self) -> Result<(), BackendError> {
        let mut first = Ok(());
        if let Some(s) = &mut self.spindle
            && let Err(e) = s.command(0.0)
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

    /// The spindle, if the machine has one.
    pub fn spindle_mut(&mut self) -> Option<&mut Spindle> {
        self.spindle.as_mut()
    }
}
