//! [`Cia402Backend`]: CiA 402 servo drives on one CANopen bus as a
//! [`klar_motion::AxisBackend`], one machine axis per drive, in cyclic synchronous position
//! mode (or cyclic synchronous velocity, or profile position), with homing by the drive.
//!
//! # Cyclic synchronous velocity
//! A CSV drive runs only its velocity loop; klar closes the position loop around it. With
//! the servo period T, the setpoint p(t) for the end of the coming cycle, the position
//! command p(t − T) of the cycle that just ended and the actual position x reported at its
//! end, klar sends
//! ```text
//! v = (p(t) − p(t − T)) / T  +  K_p · (p(t − T) − x)
//! ```
//! The first term is the velocity feed-forward: the mean velocity that moves the axis from
//! one setpoint to the next within the cycle. The second corrects what is left: if the
//! drive realises v exactly, the following error after the cycle is (1 − K_p·T) times the
//! one before, so it decays geometrically and a drive that lags only by a velocity error δv
//! settles at a following error of about δv / K_p. K_p (`position_gain`, 1/s) comes from the
//! drive's configuration. The following error (the setpoint minus the actual position after
//! the cycle, as in CSP) is checked by klar against the configured window, since a drive in
//! CSV does not know the position command.
//!
//! Enable, disable and fault reset run the CiA 402 power state machine through a few
//! PDO/SYNC exchanges and return when the drives got there (bounded by the configured state
//! timeout). A fault of any drive stops every drive (see [`super::network`]).

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use klar_motion::{
    AxisBackend, AxisFault, AxisFeedback, AxisState, BackendError, FaultOrigin, Setpoint,
};

use super::config::CanOpenConfig;
use super::network::{Cia402Error, DriveKind, Homing, Network};
use super::objects::{MODE_CSV, MODE_HOMING, MODE_PROFILE_POSITION, MODE_PROFILE_VELOCITY};
use super::setup::open_bus;
use super::spindle::Cia402Spindle;
use super::state::*;
use crate::can::CanBus;
use crate::canopen::{Emergency, Master};

/// CiA 402 drives on one CANopen bus, serving one machine axis each (and optionally a
/// spindle, reached through [`Cia402Backend::spindle`]).
pub struct Cia402Backend {
    pub(crate) net: Arc<Mutex<Network>>,
}

pub(crate) fn lock(net: &Mutex<Network>) -> MutexGuard<'_, Network> {
    // The network holds no invariant a panic elsewhere could break half-way that matters
    // more than stopping the machine, so a poisoned lock is taken over.
    net.lock().unwrap_or_else(|p| p.into_inner())
}

impl Cia402Backend {
    /// Opens the bus the configuration names (SocketCAN or slcan) and starts the drives.
    /// A simulated bus is built by `klar_sim::cia402::simulated_backend` instead.
    pub fn open(config: &CanOpenConfig, servo_period: f64) -> Result<Self, Cia402Error> {
        let bus = open_bus(config)?;
        let backend = Self::with_bus(config, servo_period, bus)?;
        backend.set_paced(true);
        lock(&backend.net).check_round_trip()?;
        Ok(backend)
    }

    /// Paces the exchanges outside the servo loop (enable, disable, fault reset, the wait
    /// for a quick stop) on the wall clock, one servo period apart: on for a real bus
    /// ([`Cia402Backend::open`]), off for buses built with [`Cia402Backend::with_bus`]
    /// until set here.
    pub fn set_paced(&self, paced: bool) {
        lock(&self.net).paced = paced;
    }

    /// Starts the drives of `config` on `bus` with SYNC every `servo_period` seconds.
    pub fn with_bus(
        config: &CanOpenConfig,
        servo_period: f64,
        bus: Box<dyn CanBus>,
    ) -> Result<Self, Cia402Error> {
        let net = Network::start(config, servo_period, bus)?;
        Ok(Self {
            net: Arc::new(Mutex::new(net)),
        })
    }

    /// The spindle drive on this bus, if the configuration has one. Its cyclic exchange
    /// happens in the axes' [`AxisBackend::cycle`] (or in its own cycle when the bus has
    /// no axes).
    pub fn spindle(&self) -> Option<Cia402Spindle> {
        let has = lock(&self.net)
            .drives
            .iter()
            .any(|d| d.kind == DriveKind::Spindle);
        has.then(|| Cia402Spindle::new(Arc::clone(&self.net)))
    }

    /// Why all drives were stopped, naming the node, until faults are reset.
    pub fn stop_report(&self) -> Option<String> {
        lock(&self.net).stop.clone()
    }

    /// The CiA 402 power state of each drive, axes in order, then the spindle.
    pub fn power_states(&self) -> Vec<PowerState> {
        lock(&self.net).drives.iter().map(|d| d.power()).collect()
    }

    /// The last emergency each drive sent, axes in order, then the spindle.
    pub fn last_emergencies(&self) -> Vec<Option<Emergency>> {
        lock(&self.net)
            .drives
            .iter()
            .map(|d| d.last_emcy.clone())
            .collect()
    }

    /// Runs `f` with the CANopen master (for diagnostics: SDO access to the drives, NMT).
    pub fn with_master<R>(&self, f: impl FnOnce(&mut Master) -> R) -> R {
        f(&mut lock(&self.net).master)
    }
}

/// Exchanges timed at start-up to measure the round trip through the adapter.
const ROUND_TRIP_SAMPLES: usize = 11;
/// The share of the servo period the round trip may take: pipelined, the answers must be
/// in before the next SYNC (a late one is waited for a quarter period); waiting for them,
/// the cycle's own work must fit as well.
const ROUND_TRIP_SHARE_PIPELINED: f64 = 1.0;
const ROUND_TRIP_SHARE_WAITING: f64 = 0.5;

impl Network {
    /// Times [`ROUND_TRIP_SAMPLES`] paced exchanges (SYNC to the last transmit PDO) and
    /// refuses a servo period even the fastest of them does not fit (the adapter and the
    /// drives can never answer in time), naming one that would; a median beyond it (a busy
    /// computer or bus) is a warning. Returns the median.
    pub(crate) fn check_round_trip(&mut self) -> Result<f64, Cia402Error> {
        let mut samples = Vec::with_capacity(ROUND_TRIP_SAMPLES);
        for _ in 0..ROUND_TRIP_SAMPLES {
            for d in self.drives.iter_mut() {
                d.target = d.hold_target();
            }
            self.pace();
            self.exchange();
            self.handle_events();
            if let Some(rt) = self.round_trip {
                samples.push(rt);
            }
        }
        samples.sort_by(f64::total_cmp);
        let (Some(&fastest), Some(&median)) = (samples.first(), samples.get(samples.len() / 2))
        else {
            return Err(Cia402Error::Config(
                "no exchange got every transmit PDO back while timing the round trip".into(),
            ));
        };
        let share = if self.pipelined() {
            ROUND_TRIP_SHARE_PIPELINED
        } else {
            ROUND_TRIP_SHARE_WAITING
        };
        tracing::info!(
            fastest_ms = fastest * 1e3,
            median_ms = median * 1e3,
            "SYNC to transmit PDO round trip through the adapter"
        );
        if fastest > share * self.servo_period {
            let fits = (fastest / share / 0.000_25).ceil() * 0.25;
            return Err(Cia402Error::Config(format!(
                "the round trip SYNC → transmit PDOs through the adapter takes at least \
                 {:.2} ms, more than {:.0} % of the {} ms servo period; a servo period of \
                 {fits} ms or longer would fit",
                fastest * 1e3,
                share * 100.0,
                self.servo_period * 1e3
            )));
        }
        if median > share * self.servo_period {
            tracing::warn!(
                "the round trip SYNC → transmit PDOs takes {:.2} ms (median), more than \
                 {:.0} % of the {} ms servo period: expect late answers",
                median * 1e3,
                share * 100.0,
                self.servo_period * 1e3
            );
        }
        Ok(median)
    }

    fn enable_axes(&mut self) -> Result<(), BackendError> {
        if let Some(stop) = &self.stop {
            return Err(BackendError::InvalidState(format!(
                "stopped ({stop}); reset faults first"
            )));
        }
        let modes: Vec<(u8, i8)> = self
            .drives
            .iter()
            .take(self.axes)
            .map(|d| (d.node, d.mode))
            .collect();
        for (node, mode) in modes {
            self.set_mode(node, mode)
                .map_err(|e| BackendError::Communication(e.to_string()))?;
        }
        for d in self.drives.iter_mut() {
            d.homing = Homing::Idle;
        }
        self.drive_sequence(
            None,
            |d| step_towards_enabled(d.power()).or(Some(CW_ENABLE_OPERATION)),
            |d| d.power() == PowerState::OperationEnabled,
        )?;
        let axes = self.axes;
        for d in self.drives.iter_mut().take(axes) {
            d.controlword = CW_ENABLE_OPERATION;
            d.commanded = d.scaling.to_units(d.actual);
        }
        match &self.stop {
            Some(stop) => Err(BackendError::InvalidState(stop.clone())),
            None => Ok(()),
        }
    }

    fn disable_axes(&mut self) -> Result<(), BackendError> {
        // A drive in QUICK STOP ACTIVE is still braking: voltage goes off at standstill.
        self.wait_quick_stops();
        self.drive_sequence(
            None,
            |d| match d.power() {
                PowerState::OperationEnabled | PowerState::SwitchedOn => Some(CW_SHUTDOWN),
                PowerState::QuickStopActive => Some(CW_DISABLE_VOLTAGE),
                _ => None,
            },
            |d| {
                !matches!(
                    d.power(),
                    PowerState::OperationEnabled
                        | PowerState::SwitchedOn
                        | PowerState::QuickStopActive
                )
            },
        )
    }

    fn start_homing_axis(&mut self, axis: usize) -> Result<(), BackendError> {
        let d = self
            .drives
            .get(axis)
            .filter(|_| axis < self.axes)
            .ok_or(BackendError::NoSuchAxis(axis))?;
        if let Some(stop) = &self.stop {
            return Err(BackendError::InvalidState(format!("stopped ({stop})")));
        }
        let node = d.node;
        if !d.has_homing {
            return Err(BackendError::InvalidState(format!(
                "node {node}: no homing configured"
            )));
        }
        if d.power() != PowerState::OperationEnabled {
            return Err(BackendError::InvalidState(format!(
                "node {node}: not enabled"
            )));
        }
        self.set_mode(node, MODE_HOMING)
            .map_err(|e| BackendError::Communication(e.to_string()))?;
        if let Some(d) = self.drives.get_mut(axis) {
            d.controlword = CW_ENABLE_OPERATION;
            d.homing = Homing::Arming;
            d.homed = false;
        }
        Ok(())
    }

    /// Resets the fault of drive `index` (an axis or the spindle).
    pub(crate) fn reset_drive_fault(&mut self, index: usize) -> Result<(), BackendError> {
        let node = self
            .drives
            .get(index)
            .ok_or(BackendError::NoSuchAxis(index))?
            .node;
        // Bit 7 must rise: send it low, then high, then low again.
        let mut phase = 0u8;
        self.drive_sequence(
            Some(index),
            |d| {
                phase = phase.saturating_add(1);
                match (phase, d.power()) {
                    (1, _) => Some(CW_DISABLE_VOLTAGE),
                    (_, p) if p.is_fault() => Some(if phase.is_multiple_of(2) {
                        CW_FAULT_RESET
                    } else {
                        CW_DISABLE_VOLTAGE
                    }),
                    _ => Some(CW_DISABLE_VOLTAGE),
                }
            },
            |d| {
                d.missed == 0
                    && d.seen
                    && !d.power().is_fault()
                    && d.power() != PowerState::QuickStopActive
                    && d.power() != PowerState::OperationEnabled
            },
        )?;
        if let Some(d) = self.drives.get_mut(index) {
            d.fault = None;
            d.secondary = false;
            d.cause = None;
            d.last_emcy = None;
            d.controlword = CW_DISABLE_VOLTAGE;
        }
        if let Some(t) = self.heartbeat_timeout {
            self.master.watch_heartbeat(node, t);
        }
        // Once the axes are clear, a spindle that was only stopped with them is clear too
        // (it stays off until commanded again).
        let axes_clear = self
            .drives
            .iter()
            .take(self.axes)
            .all(|d| d.fault.is_none());
        for d in self.drives.iter_mut().skip(self.axes) {
            if axes_clear && d.secondary {
                d.fault = None;
                d.secondary = false;
                d.cause = None;
            }
        }
        if self.drives.iter().all(|d| d.fault.is_none()) {
            self.stop = None;
        }
        Ok(())
    }

    /// One servo cycle at `t`: axis setpoints (one per axis) and the spindle command go
    /// out, feedback comes in.
    ///
    /// Pipelined ([`Network::pipelined`]): the transmit PDOs answering the last SYNC are
    /// collected and evaluated first (they had a servo period to arrive), then this cycle's
    /// receive PDOs and SYNC go out without waiting for their answers.
    pub(crate) fn cycle(&mut self, t: f64, setpoints: &[Setpoint]) {
        self.master.set_time(t);
        let pipelined = self.pipelined();
        if pipelined {
            // The answers had a servo period to arrive: a late one is not waited for beyond
            // a quarter period (the cycle must keep its deadline); it counts as missing.
            let grace = Duration::from_secs_f64(self.servo_period / 4.0);
            let wait = self.last_sync.map_or(Duration::ZERO, |s| {
                (s + self.pdo_wait)
                    .saturating_duration_since(Instant::now())
                    .min(grace)
            });
            self.collect(wait);
            self.handle_events();
            self.evaluate();
            self.apply_stop();
            for d in self.drives.iter_mut() {
                d.answered = d.commanded;
            }
        } else if let Err(e) = self.master.poll() {
            self.stop_all(
                None,
                AxisFault::CommunicationLost,
                format!("CAN receive failed: {e}"),
            );
        }
        self.handle_events();
        let mut out_of_range = None;
        let stopped = self.stop.is_some();
        let ramp = self.spindle_ramp_step;
        let period = self.servo_period;
        for (i, d) in self.drives.iter_mut().enumerate() {
            match d.kind {
                DriveKind::Axis => {
                    let following = d.power() == PowerState::OperationEnabled
                        && d.homing == Homing::Idle
                        && is_enable_operation(d.controlword);
                    match setpoints.get(i) {
                        Some(sp) if following && !stopped => match d.scaling.to_counts(sp.position)
                        {
                            Ok(c) if d.mode == MODE_PROFILE_POSITION => {
                                d.commanded = sp.position;
                                d.velocity = sp.velocity;
                                profile_setpoint(d, c);
                            }
                            Ok(_) if d.mode == MODE_CSV => {
                                let v = csv_velocity(d, sp.position, period);
                                match d.scaling.to_counts(v) {
                                    Ok(counts) => {
                                        d.target = counts;
                                        d.commanded = sp.position;
                                        d.velocity = sp.velocity;
                                    }
                                    Err(e) => {
                                        d.target = 0;
                                        out_of_range = Some((
                                            i,
                                            format!("node {}: velocity {v}: {e}", d.node),
                                        ));
                                    }
                                }
                            }
                            Ok(c) => {
                                d.target = c;
                                d.commanded = sp.position;
                                d.velocity = sp.velocity;
                            }
                            Err(e) => out_of_range = Some((i, format!("node {}: {e}", d.node))),
                        },
                        _ if d.mode == MODE_PROFILE_POSITION => {
                            // Without a fresh set-point the drive keeps its last target.
                            d.controlword &= !(CW_NEW_SETPOINT | CW_CHANGE_IMMEDIATELY);
                        }
                        _ => d.target = d.hold_target(),
                    }
                }
                DriveKind::Spindle if !stopped && d.fault.is_none() => {
                    let wanted = d.commanded != 0.0 || d.power() == PowerState::OperationEnabled;
                    if wanted {
                        d.controlword =
                            step_towards_enabled(d.power()).unwrap_or(CW_ENABLE_OPERATION);
                    }
                    // `velocity` holds the ramped speed (rpm) on its way to the command; in
                    // profile velocity the drive ramps, so the command goes out as it is.
                    if d.power() == PowerState::OperationEnabled {
                        let ramp = if d.mode == MODE_PROFILE_VELOCITY {
                            f64::INFINITY
                        } else {
                            ramp
                        };
                        let step = (d.commanded - d.velocity).clamp(-ramp, ramp);
                        d.velocity += step;
                    } else {
                        d.velocity = 0.0;
                    }
                    let before = d.target;
                    d.target = if d.power() == PowerState::OperationEnabled {
                        match d.scaling.to_counts(d.velocity) {
                            Ok(c) => c,
                            Err(e) => {
                                out_of_range = Some((i, format!("spindle node {}: {e}", d.node)));
                                0
                            }
                        }
                    } else {
                        0
                    };
                    d.same_target = if d.target == before {
                        d.same_target.saturating_add(1)
                    } else {
                        0
                    };
                }
                DriveKind::Spindle => {}
            }
        }
        if let Some((i, cause)) = out_of_range {
            self.stop_all(
                Some(i),
                AxisFault::Drive {
                    code: 0,
                    text: cause.clone(),
                },
                cause,
            );
        }
        self.apply_stop();
        if pipelined {
            self.send_cyclic();
            self.handle_events();
            self.apply_stop();
            return;
        }
        self.exchange();
        self.handle_events();
        self.evaluate();
        self.apply_stop();
        for d in self.drives.iter_mut() {
            d.answered = d.commanded;
        }
    }
}

/// The CSV velocity command (units/s) towards `setpoint` (see the module documentation):
/// feed-forward from the last position command (`d.commanded`) plus the gain times the
/// error of the cycle that just ended.
fn csv_velocity(d: &super::network::Drive, setpoint: f64, period: f64) -> f64 {
    let actual = d.scaling.to_units(d.actual);
    (setpoint - d.commanded) / period + d.position_gain * (d.commanded - actual)
}

/// The profile-position handshake for one cycle: a new target goes out with a rising
/// "new set-point" bit (and "change set immediately"); the bit drops once the drive
/// acknowledges (statusword bit 12), and the next target waits until the acknowledge is gone.
fn profile_setpoint(d: &mut super::network::Drive, wanted: i32) {
    let acknowledged = d.status & SW_OMS1 != 0;
    if d.controlword & CW_NEW_SETPOINT != 0 {
        if acknowledged {
            d.controlword &= !(CW_NEW_SETPOINT | CW_CHANGE_IMMEDIATELY);
        }
    } else if !acknowledged && wanted != d.target {
        d.target = wanted;
        d.controlword |= CW_NEW_SETPOINT | CW_CHANGE_IMMEDIATELY;
    }
}

impl AxisBackend for Cia402Backend {
    fn axis_count(&self) -> usize {
        lock(&self.net).axes
    }

    /// Touch probe 1 of the axis's drive (see [`super::touch_probe`]).
    fn arm_touch_probe(&mut self, axis: usize) -> Result<bool, BackendError> {
        Cia402Backend::arm_touch_probe(self, axis)
            .map(|()| true)
            .map_err(|e| BackendError::Communication(e.to_string()))
    }

    fn touch_probe_position(&mut self, axis: usize) -> Result<Option<f64>, BackendError> {
        Cia402Backend::touch_probe_position(self, axis)
            .map_err(|e| BackendError::Communication(e.to_string()))
    }

    fn disarm_touch_probe(&mut self, axis: usize) -> Result<(), BackendError> {
        Cia402Backend::disarm_touch_probe(self, axis)
            .map_err(|e| BackendError::Communication(e.to_string()))
    }

    /// 1 when the exchange is pipelined (the positions answer the SYNC before), else 0.
    fn feedback_lag(&self) -> u32 {
        u32::from(lock(&self.net).pipelined())
    }

    fn enable(&mut self) -> Result<(), BackendError> {
        lock(&self.net).enable_axes()
    }

    fn disable(&mut self) -> Result<(), BackendError> {
        lock(&self.net).disable_axes()
    }

    fn start_homing(&mut self, axis: usize) -> Result<(), BackendError> {
        lock(&self.net).start_homing_axis(axis)
    }

    fn reset_fault(&mut self, axis: usize) -> Result<(), BackendError> {
        let mut net = lock(&self.net);
        if axis >= net.axes {
            return Err(BackendError::NoSuchAxis(axis));
        }
        net.reset_drive_fault(axis)
    }

    fn cycle(
        &mut self,
        t: f64,
        setpoints: &[Setpoint],
        feedback: &mut [AxisFeedback],
    ) -> Result<(), BackendError> {
        let mut net = lock(&self.net);
        let n = net.axes;
        if setpoints.len() != n || feedback.len() != n {
            return Err(BackendError::AxisCount {
                expected: n,
                got: setpoints.len().min(feedback.len()),
            });
        }
        net.cycle(t, setpoints);
        for (d, fb) in net.drives.iter().zip(feedback.iter_mut()) {
            let position = d.scaling.to_units(d.actual);
            fb.position = position;
            fb.following_error = d.answered - position;
            fb.homed = d.homed;
            fb.fault = d.fault.clone();
            fb.state = if d.fault.is_some() || d.power().is_fault() {
                AxisState::Faulted
            } else if d.homing != Homing::Idle {
                AxisState::Homing
            } else if d.power() == PowerState::OperationEnabled {
                AxisState::Enabled
            } else {
                AxisState::Disabled
            };
        }
        Ok(())
    }

    fn fault_origin(&self, axis: usize) -> Option<FaultOrigin> {
        let net = lock(&self.net);
        let d = net.drives.get(axis).filter(|_| axis < net.axes)?;
        d.fault.as_ref()?;
        Some(FaultOrigin {
            primary: !d.secondary,
            detail: d.cause.clone()?,
        })
    }
}
