//! [`SimCia402Drive`]: a CiA 402 servo drive on a CAN bus, built on [`ServoPlant`].
//!
//! It answers NMT, SDO (through its [`ObjectDictionary`]), sends boot-up and heartbeats,
//! processes its receive PDOs and sends its transmit PDOs on SYNC while operational, using
//! whatever mapping the master configured. On each SYNC it applies the latest controlword,
//! target and mode, steps the plant by the interpolation period (0x60C2), and reports
//! statusword, position and mode. Plant faults and injected faults put it in Fault and send
//! an emergency.
//!
//! # Modes
//! - Cyclic synchronous position (8): the target position is the plant's command.
//! - Cyclic synchronous velocity (9): the target velocity (0x60FF) is the velocity loop's
//!   command (fed forward in full). The plant's controller works on positions, so the drive
//!   integrates the target velocity into its reference; the plant's position gain then acts
//!   on the integral of the velocity error, like the integral part of a PI velocity loop. A
//!   plant with `position_gain = 0` is a drive with a plain velocity loop. Statusword bit 12
//!   says the drive follows the target.
//! - Profile velocity (3): the drive ramps its velocity demand towards the target velocity
//!   at the profile acceleration (0x6083) while the speed grows and the profile
//!   deceleration (0x6084) while it shrinks (half the plant's force-limited acceleration when
//!   0); the demand drives the plant as in CSV. Bit 10 (target reached): the demand has
//!   reached the target and the actual velocity has stayed within the velocity window
//!   (0x606D) of it for the window time (0x606E, ms). Bit 12 (speed): the actual velocity
//!   is at most the velocity threshold (0x606F).
//! - Profile position (1) and homing (6): the drive's own profile and homing methods.
//!
//! Modes of operation outside the supported set ([`SimCia402Drive::with_modes`]) are
//! refused with SDO abort 0x0609_0030 (invalid value for parameter).

use klar_drivers::can::CanFrame;
use klar_drivers::can::memory::BusDevice;
use klar_drivers::canopen::pdo::{COB_INVALID, PdoEntry};
use klar_drivers::canopen::sdo::{SDO_RX_BASE, SDO_TX_BASE};
use klar_drivers::canopen::{
    EMCY_BASE, Emergency, HEARTBEAT_BASE, NMT_COB, NmtCommand, NmtState, SYNC_COB,
};
use klar_drivers::cia402::objects::*;
use klar_drivers::cia402::state::*;
use klar_motion::{AxisFault, AxisState, Setpoint};

use super::control::SimDriveControl;
use super::dictionary::drive_dictionary;
use super::od::{ObjectDictionary, SdoServer};
use super::profile::{Profile, VelocityRamp};
use super::touch_probe::TouchProbe;
use crate::plant::{ServoPlant, SimAxisParams};

/// EMCY code the simulated drive sends for a limit switch (device specific).
pub const EMCY_LIMIT_SWITCH: u16 = 0xFF01;
/// EMCY code for an e-stop (external error).
pub const EMCY_ESTOP: u16 = 0x9000;
/// Time constant of the velocity-actual filter, seconds.
pub const VELOCITY_FILTER_TIME: f64 = 0.01;
/// Quick-stop deceleration when the master sets none (0x6085 = 0), as a fraction of the
/// plant's largest acceleration (force limit over mass).
pub const DEFAULT_QUICK_STOP_FRACTION: f64 = 0.5;

/// Faults and misbehaviour a test can switch on in a running simulated drive.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Injection {
    /// Raise this EMCY error code as a drive fault at the next SYNC.
    pub fault: Option<u16>,
    /// Send nothing at all (as if the cable were cut).
    pub silent: bool,
    /// Leave out transmit PDOs (heartbeats still go out).
    pub drop_tpdos: bool,
    /// Send transmit PDOs one byte short (malformed).
    pub truncate_tpdos: bool,
    /// Do not answer SDO requests.
    pub ignore_sdo: bool,
}

/// The modes of operation a simulated drive supports unless told otherwise.
pub const SUPPORTED_MODES: [i8; 5] = [
    MODE_PROFILE_POSITION,
    MODE_PROFILE_VELOCITY,
    MODE_HOMING,
    MODE_CSP,
    MODE_CSV,
];

/// Parameters of a simulated drive.
#[derive(Debug, Clone, PartialEq)]
pub struct SimDriveConfig {
    /// Node ID, 1..=127.
    pub node: u8,
    /// The plant; its `counts_per_unit` is also the drive's position scaling.
    pub plant: SimAxisParams,
    /// True starting position (mm or degrees).
    pub start_position: f64,
}

/// A simulated CiA 402 drive.
pub struct SimCia402Drive {
    node: u8,
    od: ObjectDictionary,
    sdo: SdoServer,
    nmt: NmtState,
    plant: ServoPlant,
    plant_params: SimAxisParams,
    start_position: f64,
    power: PowerState,
    last_controlword: u16,
    /// Added to the plant's measured position to give the reported one (home offset).
    offset: f64,
    homed: bool,
    homing_started: bool,
    quick_stop: Option<(f64, f64)>,
    time: f64,
    next_heartbeat: f64,
    target_reached: bool,
    /// Previous setpoint position and velocity, for the finite-difference feed-forward.
    last_setpoint: Option<(f64, f64)>,
    /// Position setpoint integrated from the target velocity in CSV mode.
    csv_position: Option<f64>,
    /// The velocity ramp in profile velocity mode.
    ramp: Option<VelocityRamp>,
    /// Profile velocity: since when (drive time) the actual velocity is inside the window.
    in_window_since: Option<f64>,
    /// The modes of operation 0x6060 accepts.
    modes: Vec<i8>,
    /// The drive's own profile in profile position mode.
    profile: Option<Profile>,
    /// Profile position: the last new set-point is acknowledged (statusword bit 12).
    setpoint_ack: bool,
    /// Velocity actual as the drive reports it: the encoder's position change per cycle,
    /// low-pass filtered, and the position it was last taken at.
    velocity_filter: (f64, Option<f64>),
    /// Touch probe 1's latch.
    touch: TouchProbe,
    control: SimDriveControl,
}

impl SimCia402Drive {
    /// A drive that boots when attached; the returned handle inspects and disturbs it.
    pub fn new(config: SimDriveConfig) -> (Self, SimDriveControl) {
        let control = SimDriveControl::default();
        let plant = ServoPlant::new(config.plant.clone(), config.start_position);
        let mut drive = Self {
            node: config.node,
            od: ObjectDictionary::new(),
            sdo: SdoServer::default(),
            nmt: NmtState::BootUp,
            plant,
            plant_params: config.plant,
            start_position: config.start_position,
            power: PowerState::SwitchOnDisabled,
            last_controlword: 0,
            offset: 0.0,
            homed: false,
            homing_started: false,
            quick_stop: None,
            time: 0.0,
            next_heartbeat: 0.0,
            target_reached: false,
            last_setpoint: None,
            csv_position: None,
            ramp: None,
            in_window_since: None,
            modes: SUPPORTED_MODES.to_vec(),
            profile: None,
            setpoint_ack: false,
            velocity_filter: (0.0, None),
            touch: TouchProbe::default(),
            control: control.clone(),
        };
        drive.reset_dictionary();
        (drive, control)
    }

    /// The same drive supporting only `modes` (plus 0, "no mode"): writing another mode of
    /// operation is refused with SDO abort 0x0609_0030.
    pub fn with_modes(mut self, modes: &[i8]) -> Self {
        self.modes = modes.to_vec();
        self.restrict_modes();
        self
    }

    fn restrict_modes(&mut self) {
        let mut allowed: Vec<u32> = self.modes.iter().map(|&m| u32::from(m as u8)).collect();
        allowed.push(0);
        self.od.restrict(MODES_OF_OPERATION, 0, allowed);
    }

    /// The node ID.
    pub fn node(&self) -> u8 {
        self.node
    }

    fn counts_per_unit(&self) -> f64 {
        self.plant_params.counts_per_unit
    }

    fn reset_dictionary(&mut self) {
        self.od = drive_dictionary(self.node, self.plant_params.counts_per_unit);
        self.restrict_modes();
    }

    /// The interpolation period from 0x60C2, seconds.
    fn period(&self) -> f64 {
        let value = f64::from(self.od.u32(INTERPOLATION_PERIOD, 1) as u8);
        let index = self.od.u32(INTERPOLATION_PERIOD, 2) as u8 as i8;
        value * 10f64.powi(i32::from(index))
    }

    fn reported(&self) -> f64 {
        self.plant.measured_position() + self.offset
    }

    fn boot(&mut self, out: &mut Vec<CanFrame>) {
        self.nmt = NmtState::PreOperational;
        self.next_heartbeat = self.time;
        out.push(CanFrame::fixed(
            HEARTBEAT_BASE + u16::from(self.node),
            &[NmtState::BootUp.code()],
        ));
    }

    fn emergency(&mut self, code: u16, out: &mut Vec<CanFrame>) {
        let register = if code == 0 {
            0
        } else {
            0x01 | if code >> 12 == 8 { 0x20 } else { 0 }
        };
        self.od.set(ERROR_CODE, 0, u32::from(code));
        self.od.set(0x1001, 0, u32::from(register));
        let e = Emergency {
            node: self.node,
            code,
            register,
            manufacturer: [0; 5],
        };
        out.push(CanFrame::fixed(
            EMCY_BASE + u16::from(self.node),
            &e.encode(),
        ));
    }

    fn enter_fault(&mut self, code: u16, out: &mut Vec<CanFrame>) {
        if self.power.is_fault() {
            return;
        }
        tracing::info!(node = self.node, code, "simulated drive fault");
        self.power = PowerState::FaultReactionActive;
        self.homing_started = false;
        self.quick_stop = None;
        self.emergency(code, out);
    }

    /// Maps the entries of a PDO from the dictionary; `None` if it is invalid.
    fn mapping(&self, comm: u16, map: u16) -> Option<(u16, Vec<PdoEntry>)> {
        let cob = self.od.u32(comm, 1);
        if cob & COB_INVALID != 0 {
            return None;
        }
        let count = self.od.u32(map, 0) as u8;
        let entries = (1..=count)
            .map(|s| PdoEntry::from_mapping_value(self.od.u32(map, s)))
            .collect();
        Some(((cob & 0x7FF) as u16, entries))
    }

    fn receive_pdo(&mut self, cob: u16, data: &[u8], out: &mut Vec<CanFrame>) -> bool {
        for p in 0..4u16 {
            let Some((pcob, entries)) = self.mapping(0x1400 + p, 0x1600 + p) else {
                continue;
            };
            if pcob != cob {
                continue;
            }
            let Some(values) = klar_drivers::canopen::pdo::unpack(&entries, data) else {
                // CiA 301: a PDO of the wrong length is not processed and reported.
                self.emergency(0x8210, out);
                return true;
            };
            for (e, v) in entries.iter().zip(values) {
                self.od.set(e.index, e.sub, v);
            }
            return true;
        }
        false
    }

    fn transmit_pdos(&mut self, out: &mut Vec<CanFrame>) {
        let inj = self.control.lock().injection.clone();
        if inj.drop_tpdos {
            return;
        }
        for p in 0..4u16 {
            let Some((cob, entries)) = self.mapping(0x1800 + p, 0x1A00 + p) else {
                continue;
            };
            if self.od.u32(0x1800 + p, 2) as u8 > 240 {
                continue;
            }
            let values: Vec<u32> = entries
                .iter()
                .map(|e| self.od.u32(e.index, e.sub))
                .collect();
            let mut data = klar_drivers::canopen::pdo::pack(&entries, &values);
            if inj.truncate_tpdos {
                data.pop();
            }
            out.push(CanFrame::fixed(cob, &data));
        }
    }

    /// One SYNC: apply the received commands, step the plant, publish the state.
    fn on_sync(&mut self, out: &mut Vec<CanFrame>) {
        let dt = self.period();
        self.time += dt;
        let injected = self.control.lock().injection.fault.take();
        if let Some(code) = injected {
            self.plant.inject_fault(AxisFault::Drive {
                code: u32::from(code),
                text: "injected".into(),
            });
            self.enter_fault(code, out);
        }
        let cw = self.od.u32(CONTROLWORD, 0) as u16;
        let reset_edge = cw & CW_FAULT_RESET != 0 && self.last_controlword & CW_FAULT_RESET == 0;
        let homing_edge = cw & CW_HOMING_START != 0 && self.last_controlword & CW_HOMING_START == 0;
        self.last_controlword = cw;
        let mode = self.od.u32(MODES_OF_OPERATION, 0) as u8 as i8;
        let before = self.power;
        if self.power == PowerState::FaultReactionActive {
            if self.plant.state() != AxisState::Faulted || self.plant.actual_velocity() == 0.0 {
                self.power = PowerState::Fault;
            }
        } else if self.power == PowerState::Fault {
            if reset_edge && self.plant.reset_fault().is_ok() {
                self.power = PowerState::SwitchOnDisabled;
                self.emergency(0, out);
            }
        } else {
            self.power = transition(self.power, cw, reset_edge);
        }
        if self.power != before {
            tracing::debug!(node = self.node, from = ?before, to = ?self.power, "CiA 402 state");
            match self.power {
                PowerState::OperationEnabled => {
                    let _ = self.plant.enable();
                }
                PowerState::QuickStopActive => {
                    self.quick_stop = Some((self.reported(), self.plant.actual_velocity()));
                }
                PowerState::Fault | PowerState::FaultReactionActive => {}
                _ => self.plant.disable(),
            }
        }
        let reported = self.reported();
        let target_units =
            f64::from(self.od.u32(TARGET_POSITION, 0) as i32) / self.counts_per_unit();
        let enabled = self.power == PowerState::OperationEnabled;
        if !(enabled && mode == MODE_CSV) {
            self.csv_position = None;
        }
        if !(enabled && mode == MODE_PROFILE_VELOCITY) {
            self.ramp = None;
            self.in_window_since = None;
        }
        if !(enabled && mode == MODE_PROFILE_POSITION) {
            self.profile = None;
            self.setpoint_ack = false;
        }
        let setpoint_units = match self.power {
            PowerState::OperationEnabled if mode == MODE_CSP => {
                self.target_reached = true;
                target_units
            }
            PowerState::OperationEnabled if mode == MODE_CSV => {
                let v = f64::from(self.od.u32(TARGET_VELOCITY, 0) as i32) / self.counts_per_unit();
                let p =
                    self.csv_position.unwrap_or(reported) + v * self.control.load_factor(dt) * dt;
                self.csv_position = Some(p);
                p
            }
            PowerState::OperationEnabled if mode == MODE_PROFILE_VELOCITY => {
                self.ramp_step(reported, dt)
            }
            PowerState::OperationEnabled if mode == MODE_PROFILE_POSITION => {
                if cw & CW_NEW_SETPOINT == 0 {
                    self.setpoint_ack = false;
                }
                let mut profile = self.profile.unwrap_or(Profile {
                    target: reported,
                    position: reported,
                    velocity: 0.0,
                });
                if homing_edge && !self.setpoint_ack {
                    // Bit 4 rises: take the new target (absolute; always "immediately").
                    profile.target = target_units;
                    self.setpoint_ack = true;
                }
                self.profile_step(&mut profile, dt);

                self.profile = Some(profile);
                profile.position
            }
            PowerState::OperationEnabled if mode == MODE_HOMING => {
                self.homing_step(homing_edge);
                self.last_setpoint = None;
                self.reported()
            }
            PowerState::QuickStopActive => self.quick_stop_step(dt),
            _ => reported,
        };
        // Like a CSP drive, derive velocity and acceleration from consecutive targets.
        let position = setpoint_units - self.offset;
        let (velocity, acceleration) = match self.last_setpoint {
            Some((p, v))
                if (self.power == PowerState::OperationEnabled
                    && matches!(
                        mode,
                        MODE_CSP | MODE_CSV | MODE_PROFILE_POSITION | MODE_PROFILE_VELOCITY
                    ))
                    || self.power == PowerState::QuickStopActive =>
            {
                let vel = (position - p) / dt;
                (vel, (vel - v) / dt)
            }
            _ => (0.0, 0.0),
        };
        self.last_setpoint = Some((position, velocity));
        let before = self.plant.actual_position();
        let fb = self.plant.step(
            Setpoint {
                position,
                velocity,
                acceleration,
            },
            dt,
        );
        if self.power == PowerState::OperationEnabled
            && mode == MODE_HOMING
            && self.homing_started
            && self.plant.state() == AxisState::Enabled
            && self.plant.homed()
        {
            let home_offset =
                f64::from(self.od.u32(HOME_OFFSET, 0) as i32) / self.counts_per_unit();
            self.offset = home_offset - self.plant_params.home_switch;
            self.homing_started = false;
            self.homed = true;
            self.target_reached = true;
        }
        if let Some(fault) = fb.fault.clone()
            && !self.power.is_fault()
        {
            let code = match fault {
                AxisFault::FollowingError(_) => 0x8611,
                AxisFault::LimitSwitch { .. } => EMCY_LIMIT_SWITCH,
                AxisFault::EStop => EMCY_ESTOP,
                AxisFault::CommunicationLost => 0x8130,
                AxisFault::DeviceException { .. } => 0x8100,
                AxisFault::Drive { code, .. } => u16::try_from(code).unwrap_or(0xFF00),
            };
            self.enter_fault(code, out);
        }
        let measured = self.reported();
        let (filtered, last) = self.velocity_filter;
        let raw = last.map_or(0.0, |p| (measured - p) / dt);
        let alpha = (dt / VELOCITY_FILTER_TIME).min(1.0);
        self.velocity_filter = (filtered + (raw - filtered) * alpha, Some(measured));
        let input = self.control.lock().probe_input;
        self.touch.step(
            self.od.u32(TOUCH_PROBE_FUNCTION, 0) as u16,
            input,
            (before, self.plant.actual_position()),
            self.offset,
            self.counts_per_unit(),
        );
        self.touch.publish(&mut self.od);
        self.publish(mode, target_units);
        let mut shared = self.control.lock();
        shared.position = self.plant.actual_position();
        shared.velocity = self.plant.actual_velocity();
        shared.state = Some(self.power);
        shared.syncs += 1;
    }

    fn homing_step(&mut self, edge: bool) {
        if !edge {
            return;
        }
        self.target_reached = false;
        let method = self.od.u32(HOMING_METHOD, 0) as u8 as i8;
        if method == 35 || method == 37 {
            let home_offset =
                f64::from(self.od.u32(HOME_OFFSET, 0) as i32) / self.counts_per_unit();
            self.offset = home_offset - self.plant.measured_position();
            self.homed = true;
            self.target_reached = true;
        } else if self.plant.start_homing().is_ok() {
            self.homing_started = true;
            self.homed = false;
        }
    }

    /// One cycle of the profile position generator with the profile velocity and
    /// acceleration from the dictionary (the plant's homing speed and acceleration when 0).
    fn profile_step(&self, profile: &mut Profile, dt: f64) {
        let cpu = self.counts_per_unit();
        let v_max = match self.od.u32(PROFILE_VELOCITY, 0) {
            0 => self.plant_params.homing_velocity,
            c => f64::from(c) / cpu,
        };
        let accel = match self.od.u32(PROFILE_ACCELERATION, 0) {
            0 => self.plant_params.homing_acceleration,
            c => f64::from(c) / cpu,
        };
        profile.step(v_max, accel, 1.0 / cpu, dt);
    }

    /// One cycle of profile velocity: ramps the demand, follows "target reached", and
    /// returns the position reference for the plant.
    fn ramp_step(&mut self, reported: f64, dt: f64) -> f64 {
        let cpu = self.counts_per_unit();
        let p = &self.plant_params;
        let fallback = DEFAULT_QUICK_STOP_FRACTION * p.force_limit / (p.mass * p.si_per_unit());
        let rate = |c: u32| if c == 0 { fallback } else { f64::from(c) / cpu };
        let accel = rate(self.od.u32(PROFILE_ACCELERATION, 0));
        let decel = rate(self.od.u32(PROFILE_DECELERATION, 0));
        let target = f64::from(self.od.u32(TARGET_VELOCITY, 0) as i32) / cpu;
        let mut ramp = self.ramp.unwrap_or(VelocityRamp {
            velocity: 0.0,
            position: reported,
        });
        let reached = ramp.step(target, accel, decel, dt);
        self.ramp = Some(ramp);
        let window = f64::from(self.od.u32(VELOCITY_WINDOW, 0)) / cpu;
        let inside = reached && (self.plant.actual_velocity() - target).abs() <= window;
        self.in_window_since = match (inside, self.in_window_since) {
            (false, _) => None,
            (true, None) => Some(self.time),
            (true, since) => since,
        };
        ramp.position
    }

    fn quick_stop_step(&mut self, dt: f64) -> f64 {
        let p = &self.plant_params;
        let decel = match self.od.u32(QUICK_STOP_DECELERATION, 0) {
            0 => DEFAULT_QUICK_STOP_FRACTION * p.force_limit / (p.mass * p.si_per_unit()),
            c => f64::from(c) / self.counts_per_unit(),
        };
        let Some((pos, vel)) = self.quick_stop else {
            return self.reported();
        };
        let dv = decel * dt;
        let v = if vel.abs() <= dv {
            0.0
        } else {
            vel - dv * vel.signum()
        };
        let p = pos + 0.5 * (vel + v) * dt;
        self.quick_stop = Some((p, v));
        p
    }

    fn publish(&mut self, mode: i8, target_units: f64) {
        // The mode display follows the mode at once (see on_frame).
        let mut sw = self.power.statusword_bits() | SW_REMOTE;
        if matches!(
            self.power,
            PowerState::SwitchedOn | PowerState::OperationEnabled | PowerState::QuickStopActive
        ) {
            sw |= SW_VOLTAGE_ENABLED;
        }
        if self.power.is_fault() {
            sw &= !SW_QUICK_STOP;
        }
        let reported = self.reported();
        let in_mode = self.power == PowerState::OperationEnabled;
        if in_mode && mode == MODE_CSP {
            sw |= SW_OMS1;
            if (target_units - reported).abs() <= 1.0 / self.counts_per_unit() {
                sw |= SW_TARGET_REACHED;
            }
        }
        if in_mode && mode == MODE_CSV {
            sw |= SW_OMS1;
        }
        if in_mode && mode == MODE_PROFILE_VELOCITY {
            let hold = f64::from(self.od.u32(VELOCITY_WINDOW_TIME, 0) as u16) / 1000.0;
            if self
                .in_window_since
                .is_some_and(|since| self.time - since + 1e-9 >= hold)
            {
                sw |= SW_TARGET_REACHED;
            }
            let threshold =
                f64::from(self.od.u32(VELOCITY_THRESHOLD, 0) as u16) / self.counts_per_unit();
            if self.plant.actual_velocity().abs() <= threshold {
                sw |= SW_OMS1;
            }
        }
        if in_mode && mode == MODE_PROFILE_POSITION {
            if self.setpoint_ack {
                sw |= SW_OMS1;
            }
            if self
                .profile
                .is_none_or(|p| p.position == p.target && p.velocity == 0.0)
            {
                sw |= SW_TARGET_REACHED;
            }
        }
        if in_mode && mode == MODE_HOMING {
            if self.homed && !self.homing_started {
                sw |= SW_OMS1;
            }
            if self.target_reached {
                sw |= SW_TARGET_REACHED;
            }
        }
        if matches!(self.plant.fault(), Some(AxisFault::FollowingError(_))) {
            sw |= SW_OMS2;
        }
        let cpu = self.counts_per_unit();
        let to_counts = |u: f64| {
            (u * cpu)
                .round()
                .clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
        };
        self.od.set(STATUSWORD, 0, u32::from(sw));
        // The position counter wraps at 32 bits like a real drive's (a spindle turning
        // one way for long passes i32::MAX); the other values saturate.
        let wrapped = ((reported * cpu).round() as i64) as i32;
        self.od.set(POSITION_ACTUAL, 0, wrapped as u32);
        self.od.set(
            VELOCITY_ACTUAL,
            0,
            to_counts(self.plant.actual_velocity()) as u32,
        );
        self.od.set(
            FOLLOWING_ERROR_ACTUAL,
            0,
            to_counts(target_units - reported) as u32,
        );
    }

    fn heartbeat(&mut self, out: &mut Vec<CanFrame>) {
        let ms = self.od.u32(PRODUCER_HEARTBEAT, 0);
        if ms == 0 || self.time + 1e-9 < self.next_heartbeat {
            return;
        }
        self.next_heartbeat = self.time + f64::from(ms) / 1000.0;
        out.push(CanFrame::fixed(
            HEARTBEAT_BASE + u16::from(self.node),
            &[self.nmt.code()],
        ));
    }

    fn nmt_command(&mut self, data: &[u8], out: &mut Vec<CanFrame>) {
        let (Some(&cs), Some(&target)) = (data.first(), data.get(1)) else {
            return;
        };
        if target != 0 && target != self.node {
            return;
        }
        match NmtCommand::from_specifier(cs) {
            Some(NmtCommand::Start) => self.nmt = NmtState::Operational,
            Some(NmtCommand::Stop) => self.nmt = NmtState::Stopped,
            Some(NmtCommand::PreOperational) => self.nmt = NmtState::PreOperational,
            Some(NmtCommand::ResetNode) => {
                self.reset_dictionary();
                self.plant = ServoPlant::new(self.plant_params.clone(), self.start_position);
                self.power = PowerState::SwitchOnDisabled;
                self.offset = 0.0;
                self.homed = false;
                self.touch = TouchProbe::default();
                self.boot(out);
            }
            Some(NmtCommand::ResetCommunication) => {
                let keep = self.od.clone();
                self.reset_dictionary();
                // Only the communication area (0x1000..0x1FFF) returns to defaults.
                for index in [
                    CONTROLWORD,
                    MODES_OF_OPERATION,
                    TARGET_POSITION,
                    HOME_OFFSET,
                    HOMING_METHOD,
                    INTERPOLATION_PERIOD,
                    FOLLOWING_ERROR_WINDOW,
                ] {
                    for sub in 0..=2u8 {
                        if let Some(e) = keep.get(index, sub) {
                            let mut b = [0u8; 4];
                            for (d, s) in b.iter_mut().zip(&e.value) {
                                *d = *s;
                            }
                            self.od.set(index, sub, u32::from_le_bytes(b));
                        }
                    }
                }
                self.boot(out);
            }
            None => {}
        }
    }
}

impl BusDevice for SimCia402Drive {
    fn start(&mut self, out: &mut Vec<CanFrame>) {
        self.boot(out);
    }

    fn on_frame(&mut self, frame: &CanFrame, out: &mut Vec<CanFrame>) {
        let Some(cob) = frame.id().standard() else {
            return;
        };
        let inj = self.control.lock().injection.clone();
        let mut produced = Vec::new();
        let node = u16::from(self.node);
        if cob == NMT_COB {
            self.nmt_command(frame.data(), &mut produced);
        } else if cob == SDO_RX_BASE + node {
            if !inj.ignore_sdo
                && self.nmt != NmtState::Stopped
                && let Some(answer) = self.sdo.handle(&mut self.od, frame.data())
            {
                produced.push(CanFrame::fixed(SDO_TX_BASE + node, &answer));
                // The touch-probe function acts at once as well.
                self.touch
                    .apply(self.od.u32(TOUCH_PROBE_FUNCTION, 0) as u16);
                self.touch.publish(&mut self.od);
                // The drive takes a new mode of operation at once.
                let mode = self.od.u32(MODES_OF_OPERATION, 0);
                self.od.set(MODES_DISPLAY, 0, mode);
            }
        } else if cob == SYNC_COB {
            if self.nmt == NmtState::Operational {
                self.on_sync(&mut produced);
                self.transmit_pdos(&mut produced);
            }
            self.heartbeat(&mut produced);
        } else if self.nmt == NmtState::Operational {
            self.receive_pdo(cob, frame.data(), &mut produced);
        }
        if !inj.silent {
            out.append(&mut produced);
        }
    }
}
