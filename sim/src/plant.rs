//! The servo plant shared by every simulated axis and drive: the mechanics of one axis
//! (mass, viscous and Coulomb friction, force limit), the drive's cascaded position and
//! velocity controller acting on a quantised encoder, limit and home switches, homing,
//! faults and e-stop.
//!
//! The model is deterministic: the same sequence of calls gives bit-identical results
//! (no randomness, no clock). One call of [`ServoPlant::step`] is one servo cycle; inside it
//! the drive runs `substeps` control and integration steps of equal length.
//!
//! # Setpoint timing
//! A setpoint passed to [`ServoPlant::step`] is the command for the *end* of the cycle.
//! Between the previous setpoint and this one the drive interpolates with a quintic that
//! matches position, velocity and acceleration at both ends (like a drive interpolating
//! CSP setpoints), so the reported following error is the true tracking error at the
//! sample instant, not a sampling lag. Velocity and acceleration of the setpoint shape the
//! interpolation and drive the feed-forward; a stream with zero velocity/acceleration still
//! works, with the feed-forward seeing a smooth step inside each cycle.
//!
//! # Controller
//! Per substep of length `h`, with the command `c`, the measured position `y` and the
//! previous substep's values `c'`, `y'`:
//! ```text
//! e      = c − y                                   following error
//! v_ref  = k_vff·(c − c')/h + K_p·e                velocity command
//! e_v    = v_ref − (y − y')/h                      velocity error
//! F      = K_v·s·(e_v + ∫e_v/T_i) + k_aff·m·s·a_c + k_fff·(b·s·v_c + F_c·sgn v_c)
//! ```
//! `s` converts machine units to SI ([`SimAxisParams::si_per_unit`]), `a_c` and `v_c` are
//! the commanded acceleration (mid-substep) and velocity. `F` is clipped to the force
//! limit; the integrator stops while the output is clipped in the direction it would grow.
//!
//! # Mechanics
//! `m·s·ẍ = F − b·s·ẋ − F_c·sgn ẋ`, integrated with the force held over each substep. A
//! resting axis stays put while `|F| ≤ F_c`; a moving axis whose velocity would change sign
//! within a substep stops at zero for the rest of that substep.
//!
//! # States and faults
//! Disabled (no force, setpoints ignored, friction stops a moving axis) → [`enable`] →
//! Enabled (follows setpoints) → [`start_homing`] → Homing → Enabled. Following error beyond
//! the window, a limit switch hit while moving into it, an e-stop or an injected fault
//! switches to Faulted: the drive brakes at the force limit until the axis stands still, then
//! removes the force. [`reset_fault`] returns a stopped axis to Disabled once the cause is
//! gone.
//!
//! [`enable`]: ServoPlant::enable
//! [`start_homing`]: ServoPlant::start_homing
//! [`reset_fault`]: ServoPlant::reset_fault

mod command;
mod params;

pub use params::{SimAxisParams, SimParamsError};

use command::{HomingGoal, HomingProfile, QuinticSegment};
use klar_motion::{AxisFault, AxisFeedback, AxisState, Setpoint};

/// Drive fault code for parameters that fail [`SimAxisParams::validate`].
pub const FAULT_INVALID_PARAMS: u32 = 0xF001;
/// Drive fault code for a setpoint with a non-finite position.
pub const FAULT_INVALID_SETPOINT: u32 = 0xF002;
/// Drive fault code for a mechanical state that became non-finite (diverged integration).
pub const FAULT_DIVERGED: u32 = 0xF003;

/// In-position window (encoder counts) the axis must reach at the end of homing.
pub const HOMING_IN_POSITION_COUNTS: f64 = 1.0;
/// Longest wait (seconds) for the in-position window at the end of homing before homing
/// completes anyway.
pub const HOMING_SETTLE_TIMEOUT: f64 = 0.25;

/// Why a request to a [`ServoPlant`] was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlantError {
    /// The request is not possible in the axis's current state.
    #[error("cannot {action} while the axis is {state:?}")]
    WrongState {
        /// What was requested.
        action: &'static str,
        /// The state the axis is in.
        state: AxisState,
    },
    /// The fault cannot be cleared because its cause is still present.
    #[error("fault cannot be cleared: {0}")]
    FaultPersists(String),
    /// The axis parameters are invalid.
    #[error(transparent)]
    InvalidParams(#[from] SimParamsError),
}

/// A simulated servo axis: plant plus position controller plus encoder.
#[derive(Debug, Clone)]
pub struct ServoPlant {
    /// The parameters as given.
    params: SimAxisParams,
    /// Validation failure of `params`, if any: the axis then stays faulted.
    invalid: Option<SimParamsError>,
    /// SI units per machine unit.
    si: f64,
    /// True position (machine units): the physical truth, not what the encoder says.
    position: f64,
    /// True velocity (machine units per second).
    velocity: f64,
    /// Encoder counts subtracted from the raw count to give the referenced count.
    reference_counts: i64,
    /// The axis has a valid reference.
    homed: bool,
    /// Operating state.
    state: AxisState,
    /// Active fault.
    fault: Option<AxisFault>,
    /// E-stop input active.
    estop: bool,
    /// Command at the end of the last cycle (measured coordinates), start of the next
    /// interpolation segment.
    command: Setpoint,
    /// Command of the previous substep (for the velocity feed-forward difference).
    last_command: f64,
    /// Measured position of the previous substep (for the velocity estimate).
    last_measured: f64,
    /// Velocity-loop integrator (machine units: ∫e_v dt).
    integral: f64,
    /// Homing profile while homing.
    homing: Option<HomingProfile>,
    /// The home cam's state when homing started.
    homing_cam_start: bool,
    /// Time spent waiting for the in-position window at the end of homing.
    homing_settled_for: f64,
    /// Position of the last setpoint received (for reporting while not following).
    last_setpoint: f64,
    /// Drive force (N or N·m) applied during the last substep.
    force: f64,
    /// Injected: the slide is jammed and does not move.
    stuck: bool,
    /// Injected: encoder noise generator.
    noise: Option<crate::faults::EncoderNoise>,
    /// Current encoder noise in counts (redrawn every substep).
    noise_counts: i64,
}

impl ServoPlant {
    /// A plant at rest at true position `position`, Disabled. Invalid parameters do not
    /// panic: the axis starts Faulted with a [`AxisFault::Drive`] fault
    /// ([`FAULT_INVALID_PARAMS`]) that cannot be reset; use [`ServoPlant::try_new`] to get
    /// the error instead.
    pub fn new(params: SimAxisParams, position: f64) -> Self {
        let invalid = params.validate().err();
        let position = if position.is_finite() { position } else { 0.0 };
        let si = params.si_per_unit();
        let reference_counts = if params.start_homed {
            count_of(params.unreferenced_offset, params.counts_per_unit)
        } else {
            0
        };
        let mut plant = Self {
            homed: params.start_homed,
            params,
            invalid,
            si,
            position,
            velocity: 0.0,
            reference_counts,
            state: AxisState::Disabled,
            fault: None,
            estop: false,
            command: Setpoint::default(),
            last_command: 0.0,
            last_measured: 0.0,
            integral: 0.0,
            homing: None,
            homing_cam_start: false,
            homing_settled_for: 0.0,
            last_setpoint: position,
            force: 0.0,
            stuck: false,
            noise: None,
            noise_counts: 0,
        };
        if let Some(e) = &plant.invalid {
            tracing::error!("simulated axis: {e}");
            plant.state = AxisState::Faulted;
            plant.fault = Some(AxisFault::Drive {
                code: FAULT_INVALID_PARAMS,
                text: e.to_string(),
            });
        }
        plant.hold_here();
        plant
    }

    /// Like [`ServoPlant::new`], but refuses invalid parameters.
    pub fn try_new(params: SimAxisParams, position: f64) -> Result<Self, PlantError> {
        params.validate()?;
        Ok(Self::new(params, position))
    }

    /// The parameters the plant was built with.
    pub fn params(&self) -> &SimAxisParams {
        &self.params
    }

    /// The true (physical) position, free of encoder quantisation and reference offset.
    pub fn actual_position(&self) -> f64 {
        self.position
    }

    /// The true (physical) velocity.
    pub fn actual_velocity(&self) -> f64 {
        self.velocity
    }

    /// The drive force (N, linear) or torque (N·m, rotary) applied during the last
    /// substep, after the force limit: what a drive reports as its actual torque.
    pub fn drive_force(&self) -> f64 {
        self.force
    }

    /// The position the encoder reports: a whole number of counts over the resolution,
    /// relative to the current reference.
    pub fn measured_position(&self) -> f64 {
        self.measured_at(self.position)
    }

    /// Operating state.
    pub fn state(&self) -> AxisState {
        self.state
    }

    /// The active fault, if any.
    pub fn fault(&self) -> Option<&AxisFault> {
        self.fault.as_ref()
    }

    /// True once the axis has a valid reference.
    pub fn homed(&self) -> bool {
        self.homed
    }

    /// True while the e-stop input is active.
    pub fn estop_active(&self) -> bool {
        self.estop
    }

    /// Powers the axis so it follows setpoints. Only from Disabled (a no-op when already
    /// Enabled or Homing); a Faulted axis needs [`ServoPlant::reset_fault`] first. The
    /// interpolation starts from the measured position at rest, so the first setpoint should
    /// be near it.
    pub fn enable(&mut self) -> Result<(), PlantError> {
        match self.state {
            AxisState::Disabled => {
                self.hold_here();
                self.state = AxisState::Enabled;
                tracing::debug!(position = self.measured_position(), "sim axis enabled");
                Ok(())
            }
            AxisState::Enabled | AxisState::Homing => Ok(()),
            AxisState::Faulted => Err(PlantError::WrongState {
                action: "enable",
                state: self.state,
            }),
        }
    }

    /// Removes power at once: no force, the axis coasts to a stop on friction. A homing
    /// run is abandoned (the axis stays unhomed). A Faulted axis stays Faulted.
    pub fn disable(&mut self) {
        if self.state != AxisState::Faulted {
            if self.state == AxisState::Homing {
                self.homing = None;
            }
            self.state = AxisState::Disabled;
            self.integral = 0.0;
            tracing::debug!("sim axis disabled");
        }
    }

    /// Starts homing: the axis drops its reference, moves toward the home switch edge at
    /// the homing speed (positive if the cam is inactive, negative if it is active), latches
    /// the reference at the edge so the measured position there equals
    /// [`SimAxisParams::home_switch`] (to the count), returns to that position, settles
    /// (see [`HOMING_IN_POSITION_COUNTS`]) and becomes Enabled with `homed = true`. Requires Enabled (a no-op while already homing).
    pub fn start_homing(&mut self) -> Result<(), PlantError> {
        match self.state {
            AxisState::Enabled => {
                let cam = self.home_cam(self.position);
                let direction = if cam { -1.0 } else { 1.0 };
                self.homed = false;
                self.homing_cam_start = cam;
                self.homing_settled_for = 0.0;
                self.homing = Some(HomingProfile::search(
                    self.command.position,
                    direction,
                    self.params.homing_velocity,
                    self.params.homing_acceleration,
                ));
                self.command.velocity = 0.0;
                self.command.acceleration = 0.0;
                self.state = AxisState::Homing;
                tracing::debug!(direction, "sim axis homing");
                Ok(())
            }
            AxisState::Homing => Ok(()),
            AxisState::Disabled | AxisState::Faulted => Err(PlantError::WrongState {
                action: "start homing",
                state: self.state,
            }),
        }
    }

    /// Clears the fault and returns the axis to Disabled, if the cause is gone: the axis
    /// must stand still, the e-stop must be released and the parameters valid. A limit
    /// switch fault can be cleared while on the switch so the axis can be moved off it;
    /// moving further into the switch faults again. A no-op when not Faulted.
    pub fn reset_fault(&mut self) -> Result<(), PlantError> {
        if self.state != AxisState::Faulted {
            return Ok(());
        }
        if let Some(e) = &self.invalid {
            return Err(PlantError::InvalidParams(e.clone()));
        }
        if self.estop {
            return Err(PlantError::FaultPersists("e-stop is active".into()));
        }
        if self.velocity != 0.0 {
            return Err(PlantError::FaultPersists(
                "the axis is still braking".into(),
            ));
        }
        self.state = AxisState::Disabled;
        self.fault = None;
        self.hold_here();
        tracing::debug!("sim axis fault reset");
        Ok(())
    }

    /// Sets the e-stop input. Activating it faults the axis with [`AxisFault::EStop`] (it
    /// brakes to a stop); releasing it only allows [`ServoPlant::reset_fault`].
    pub fn set_estop(&mut self, active: bool) {
        self.estop = active;
        if active {
            self.raise(AxisFault::EStop);
        }
    }

    /// Faults the axis with `fault` as if the drive had detected it: it brakes at the force
    /// limit to a stop. An axis already faulted keeps its first fault.
    pub fn inject_fault(&mut self, fault: AxisFault) {
        self.raise(fault);
    }

    /// Fault injection: jams (`true`) or frees the slide. A jammed slide stands still
    /// whatever the force, so a powered axis builds up following error.
    pub fn set_stuck(&mut self, stuck: bool) {
        self.stuck = stuck;
        if stuck {
            self.velocity = 0.0;
        }
    }

    /// True while the slide is jammed.
    pub fn is_stuck(&self) -> bool {
        self.stuck
    }

    /// Fault injection: adds noise of up to `amplitude` counts to every encoder reading
    /// (`None` removes it).
    pub fn set_encoder_noise(&mut self, noise: Option<crate::faults::EncoderNoise>) {
        self.noise = noise;
        if self.noise.is_none() {
            self.noise_counts = 0;
        }
    }

    /// Advances the plant by `dt` seconds (one servo cycle) following `setpoint`, the
    /// command for the end of the cycle, and reports the feedback at the end of the cycle.
    /// The setpoint is followed only while Enabled (ignored while Disabled, Homing or
    /// Faulted); a non-finite position faults an Enabled axis ([`FAULT_INVALID_SETPOINT`]),
    /// non-finite velocity or acceleration count as zero. A `dt` that is not finite and
    /// positive advances nothing.
    pub fn step(&mut self, setpoint: Setpoint, dt: f64) -> AxisFeedback {
        if !(dt.is_finite() && dt > 0.0) {
            tracing::warn!(dt, "sim axis: ignoring a cycle with an invalid duration");
            return self.feedback();
        }
        let n = self.params.substeps.max(1);
        let h = dt / f64::from(n);
        if setpoint.position.is_finite() {
            self.last_setpoint = setpoint.position;
        } else if self.state == AxisState::Enabled {
            self.raise(AxisFault::Drive {
                code: FAULT_INVALID_SETPOINT,
                text: format!("non-finite setpoint position {}", setpoint.position),
            });
        }
        let finite_or_zero = |v: f64| if v.is_finite() { v } else { 0.0 };
        let target = Setpoint {
            position: setpoint.position,
            velocity: finite_or_zero(setpoint.velocity),
            acceleration: finite_or_zero(setpoint.acceleration),
        };
        let segment = (self.state == AxisState::Enabled)
            .then(|| QuinticSegment::new(self.command, target, dt));
        for k in 0..n {
            let tau = h * f64::from(k);
            match self.state {
                AxisState::Enabled => {
                    // Position at the substep start; velocity and acceleration at its middle,
                    // the best constant stand-ins over the substep.
                    let mid = tau + 0.5 * h;
                    let (c, v, a) = match &segment {
                        Some(seg) => (seg.position(tau), seg.velocity(mid), seg.acceleration(mid)),
                        None => (self.command.position, 0.0, 0.0),
                    };
                    self.substep(c, v, a, h);
                }
                AxisState::Homing => {
                    let (c, v, a) = match &mut self.homing {
                        Some(profile) => {
                            let c = profile.position;
                            let v0 = profile.velocity;
                            let a = profile.advance(h);
                            (c, v0 + 0.5 * a * h, a)
                        }
                        None => (self.command.position, 0.0, 0.0),
                    };
                    self.substep(c, v, a, h);
                    self.finish_homing_if_done(h);
                }
                AxisState::Disabled | AxisState::Faulted => {
                    let y = self.measured_position();
                    self.substep(y, 0.0, 0.0, h);
                }
            }
        }
        match (self.state, segment) {
            (AxisState::Enabled, Some(_)) => self.command = target,
            (AxisState::Homing, _) => {
                if let Some(profile) = &self.homing {
                    self.command = Setpoint {
                        position: profile.position,
                        velocity: profile.velocity,
                        acceleration: 0.0,
                    };
                }
            }
            _ => {}
        }
        self.feedback()
    }

    /// The feedback for the current instant without advancing time.
    pub fn feedback(&self) -> AxisFeedback {
        let measured = self.measured_position();
        let commanded = match self.state {
            AxisState::Enabled | AxisState::Homing => self.command.position,
            AxisState::Disabled | AxisState::Faulted => self.last_setpoint,
        };
        AxisFeedback {
            position: measured,
            following_error: commanded - measured,
            state: self.state,
            homed: self.homed,
            fault: self.fault.clone(),
        }
    }

    /// One control and integration substep of length `h` with command position `c`,
    /// commanded velocity `v_c` and acceleration `a_c` for the substep.
    fn substep(&mut self, c: f64, v_c: f64, a_c: f64, h: f64) {
        if let Some(noise) = &mut self.noise {
            self.noise_counts = noise.next_counts();
        }
        let y = self.measured_position();
        let following = matches!(self.state, AxisState::Enabled | AxisState::Homing);
        if following {
            let e = c - y;
            if !e.is_finite() || e.abs() > self.params.following_error_limit {
                tracing::warn!(error = e, "sim axis: following error beyond limit");
                self.raise(AxisFault::FollowingError(e));
            }
        }
        let force = match self.state {
            AxisState::Enabled | AxisState::Homing => self.control(c, y, v_c, a_c, h),
            AxisState::Faulted if self.velocity != 0.0 => {
                -self.velocity.signum() * self.params.force_limit
            }
            AxisState::Faulted | AxisState::Disabled => 0.0,
        };
        self.last_command = c;
        self.last_measured = y;
        self.force = force;
        let before = self.position;
        self.integrate(force, h);
        if !(self.position.is_finite() && self.velocity.is_finite()) {
            self.position = before;
            self.velocity = 0.0;
            self.raise(AxisFault::Drive {
                code: FAULT_DIVERGED,
                text: "the simulated mechanics diverged".into(),
            });
            return;
        }
        self.check_limit_switches();
        self.check_home_edge(before);
    }

    /// The cascaded position/velocity controller: returns the clipped drive force.
    fn control(&mut self, c: f64, y: f64, v_c: f64, a_c: f64, h: f64) -> f64 {
        let p = &self.params;
        let e = c - y;
        let v_ref = p.velocity_feedforward * (c - self.last_command) / h + p.position_gain * e;
        let e_v = v_ref - (y - self.last_measured) / h;
        let friction = p.viscous_friction * self.si * v_c
            + if v_c != 0.0 {
                p.coulomb_friction * v_c.signum()
            } else {
                0.0
            };
        let feedforward =
            p.acceleration_feedforward * p.mass * self.si * a_c + p.friction_feedforward * friction;
        let gain = p.velocity_gain * self.si;
        let integral = if p.velocity_integral_time > 0.0 {
            self.integral + e_v * h
        } else {
            0.0
        };
        let i_term = if p.velocity_integral_time > 0.0 {
            integral / p.velocity_integral_time
        } else {
            0.0
        };
        let raw = gain * (e_v + i_term) + feedforward;
        let limit = p.force_limit;
        let clipped_up = raw > limit && e_v > 0.0;
        let clipped_down = raw < -limit && e_v < 0.0;
        if !(clipped_up || clipped_down) {
            self.integral = integral;
        }
        raw.clamp(-limit, limit)
    }

    /// Integrates the mechanics over `h` with the drive force held constant.
    fn integrate(&mut self, force: f64, h: f64) {
        if self.stuck {
            self.velocity = 0.0;
            return;
        }
        let p = &self.params;
        let inertia = p.mass * self.si;
        let v = self.velocity;
        if v == 0.0 {
            if force.abs() <= p.coulomb_friction {
                return;
            }
            let a = (force - p.coulomb_friction * force.signum()) / inertia;
            self.position += 0.5 * a * h * h;
            self.velocity = a * h;
            return;
        }
        let a =
            (force - p.viscous_friction * self.si * v - p.coulomb_friction * v.signum()) / inertia;
        let v_next = v + a * h;
        if v_next == 0.0 || v_next.signum() != v.signum() {
            // Stops inside the substep; friction holds it there until the next one.
            let t_stop = -v / a;
            self.position += v * t_stop + 0.5 * a * t_stop * t_stop;
            self.velocity = 0.0;
        } else {
            self.position += v * h + 0.5 * a * h * h;
            self.velocity = v_next;
        }
    }

    /// Faults the axis when it moves into an active limit switch while powered.
    fn check_limit_switches(&mut self) {
        if !matches!(self.state, AxisState::Enabled | AxisState::Homing) {
            return;
        }
        let x = self.position;
        if self.velocity > 0.0 && self.params.limit_switch_positive.is_some_and(|s| x >= s) {
            tracing::warn!(position = x, "sim axis: positive limit switch");
            self.raise(AxisFault::LimitSwitch { positive: true });
        } else if self.velocity < 0.0 && self.params.limit_switch_negative.is_some_and(|s| x <= s) {
            tracing::warn!(position = x, "sim axis: negative limit switch");
            self.raise(AxisFault::LimitSwitch { positive: false });
        }
    }

    /// While searching, latches the reference when the home cam changes state between
    /// `before` and the current position.
    fn check_home_edge(&mut self, before: f64) {
        if self.state != AxisState::Homing {
            return;
        }
        if self.home_cam(self.position) == self.homing_cam_start {
            return;
        }
        let Some(profile) = &mut self.homing else {
            return;
        };
        if !matches!(profile.goal, HomingGoal::Search { .. }) {
            return;
        }
        let home = self.params.home_switch;
        let cpu = self.params.counts_per_unit;
        // The drive latches the raw count at the edge in hardware; the reference makes that
        // count read as the home switch position.
        let latched = count_of(home + self.params.unreferenced_offset, cpu);
        let reference = latched - count_of(home, cpu);
        let delta = (self.reference_counts - reference) as f64 / cpu;
        self.reference_counts = reference;
        profile.shift(delta);
        profile.goal = HomingGoal::Return {
            target: count_of(home, cpu) as f64 / cpu,
        };
        self.last_command += delta;
        self.last_measured += delta;
        self.command.position += delta;
        tracing::debug!(edge = home, from = before, "sim axis: home switch latched");
    }

    /// Completes homing once the return move has stopped at the reference position and the
    /// axis has settled there: |following error| within [`HOMING_IN_POSITION_COUNTS`]
    /// counts, or [`HOMING_SETTLE_TIMEOUT`] seconds after the command arrived, whichever
    /// comes first.
    fn finish_homing_if_done(&mut self, h: f64) {
        if self.state != AxisState::Homing {
            return;
        }
        let Some(profile) = &self.homing else {
            return;
        };
        if !profile.finished() {
            return;
        }
        let target = profile.position;
        self.homing_settled_for += h;
        let window = HOMING_IN_POSITION_COUNTS / self.params.counts_per_unit;
        let error = target - self.measured_position();
        if error.abs() > window + 1e-12 && self.homing_settled_for < HOMING_SETTLE_TIMEOUT {
            return;
        }
        self.command = Setpoint {
            position: target,
            velocity: 0.0,
            acceleration: 0.0,
        };
        self.homing = None;
        self.homed = true;
        self.state = AxisState::Enabled;
        tracing::debug!(position = target, "sim axis homed");
    }

    /// Enters Faulted with `fault` unless already faulted.
    fn raise(&mut self, fault: AxisFault) {
        if self.state == AxisState::Faulted {
            return;
        }
        self.state = AxisState::Faulted;
        self.fault = Some(fault);
        self.homing = None;
        self.integral = 0.0;
    }

    /// Sets the command and the controller memory to the measured position at rest.
    fn hold_here(&mut self) {
        let y = self.measured_position();
        self.command = Setpoint {
            position: y,
            velocity: 0.0,
            acceleration: 0.0,
        };
        self.last_command = y;
        self.last_measured = y;
        self.integral = 0.0;
    }

    /// The home cam's state at true position `x`: active at and above the switch.
    fn home_cam(&self, x: f64) -> bool {
        x >= self.params.home_switch
    }

    /// The referenced encoder reading for true position `x`.
    fn measured_at(&self, x: f64) -> f64 {
        let cpu = self.params.counts_per_unit;
        let raw =
            count_of(x + self.params.unreferenced_offset, cpu).saturating_add(self.noise_counts);
        (raw - self.reference_counts) as f64 / cpu
    }
}

/// The encoder count nearest to `x` at `cpu` counts per unit (saturating for absurd values).
fn count_of(x: f64, cpu: f64) -> i64 {
    // `as` saturates for out-of-range values and maps NaN to 0: no panic.
    (x * cpu).round() as i64
}
