//! The CANopen network of CiA 402 drives behind [`super::Cia402Backend`] (axes) and
//! [`super::Cia402Spindle`] (a spindle): the PDO layouts, the cyclic exchange, and the
//! fault handling shared by both (start-up is in `setup`).
//!
//! Each servo cycle: send every drive's receive PDO (controlword,
//! target position), send SYNC, collect every drive's transmit PDO (statusword, actual
//! position). The mode of operation changes rarely (CSP ↔ homing) and goes by SDO, which
//! keeps both PDOs at 6 bytes: three drives fit a 1 ms period at 1 Mbit/s. An axis in
//! cyclic synchronous velocity mode sends a target velocity in place of the target position
//! (klar closes the position loop, see `backend`). A spindle drive runs in cyclic
//! synchronous velocity or profile velocity mode with target velocity and actual velocity in
//! place of the positions. A drive's fault, an emergency, heartbeat loss, missing or
//! malformed PDOs or bus-off stop every drive: drives still enabled get a quick stop, and
//! the stop report names the node and the cause.

use std::time::{Duration, Instant};

use klar_motion::{AxisFault, BackendError};

use super::objects::*;
use super::scaling::Scaling;
use super::state::*;
use crate::can::{BusErrorKind, CanError, CanFrame};
use crate::canopen::busload::{BusLoadError, CyclicTraffic};
use crate::canopen::pdo::{self, PdoEntry};
use crate::canopen::{CanOpenError, Emergency, Master, NodeEvent};

/// The receive PDO layout klar maps for an axis: controlword, target position.
pub const RPDO_ENTRIES: [PdoEntry; 2] = [
    PdoEntry::new(CONTROLWORD, 0, 16),
    PdoEntry::new(TARGET_POSITION, 0, 32),
];
/// The transmit PDO layout klar maps for an axis: statusword, actual position.
pub const TPDO_ENTRIES: [PdoEntry; 2] = [
    PdoEntry::new(STATUSWORD, 0, 16),
    PdoEntry::new(POSITION_ACTUAL, 0, 32),
];
/// The receive PDO layout klar maps for an axis in cyclic synchronous velocity mode:
/// controlword, target velocity (its transmit PDO is the CSP one, [`TPDO_ENTRIES`]).
pub const CSV_RPDO_ENTRIES: [PdoEntry; 2] = [
    PdoEntry::new(CONTROLWORD, 0, 16),
    PdoEntry::new(TARGET_VELOCITY, 0, 32),
];
/// The receive PDO layout klar maps for a spindle: controlword, target velocity.
pub const SPINDLE_RPDO_ENTRIES: [PdoEntry; 2] = [
    PdoEntry::new(CONTROLWORD, 0, 16),
    PdoEntry::new(TARGET_VELOCITY, 0, 32),
];
/// The transmit PDO layout klar maps for a spindle: statusword, actual velocity.
pub const SPINDLE_TPDO_ENTRIES: [PdoEntry; 2] = [
    PdoEntry::new(STATUSWORD, 0, 16),
    PdoEntry::new(VELOCITY_ACTUAL, 0, 32),
];

/// The second transmit PDO klar maps for a spindle: the actual position (the measured
/// angle; statusword, velocity and position together would not fit one 8-byte frame).
pub const SPINDLE_POSITION_TPDO_ENTRIES: [PdoEntry; 1] = [PdoEntry::new(POSITION_ACTUAL, 0, 32)];

/// Errors of the CiA 402 backend's set-up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Cia402Error {
    /// The configuration cannot work.
    #[error("CANopen configuration: {0}")]
    Config(String),
    /// The cyclic traffic does not fit the bus.
    #[error(transparent)]
    BusLoad(#[from] BusLoadError),
    /// A CANopen exchange failed.
    #[error(transparent)]
    CanOpen(#[from] CanOpenError),
    /// The bus adapter failed.
    #[error(transparent)]
    Bus(#[from] CanError),
    /// The bus adapter on a serial port could not be opened or did not answer.
    #[error("CAN adapter on {port}: {error}")]
    Adapter {
        /// The serial port.
        port: String,
        /// What failed.
        error: CanError,
    },
}

/// The cyclic traffic of `drives` drives (axes and spindle) with klar's PDO layout: SYNC
/// plus one receive and one transmit PDO each (CSV and spindle PDOs have the same length).
/// A spindle adds its position PDO ([`spindle_position_traffic`]).
pub fn cyclic_traffic(drives: usize) -> CyclicTraffic {
    let rx: usize = RPDO_ENTRIES.iter().map(|e| e.bytes()).sum();
    let tx: usize = TPDO_ENTRIES.iter().map(|e| e.bytes()).sum();
    let mut frame_lengths = vec![0];
    for _ in 0..drives {
        frame_lengths.push(rx);
        frame_lengths.push(tx);
    }
    CyclicTraffic { frame_lengths }
}

/// Adds a spindle's second transmit PDO (its actual position) to `traffic`.
pub fn spindle_position_traffic(traffic: &mut CyclicTraffic) {
    let bytes = SPINDLE_POSITION_TPDO_ENTRIES
        .iter()
        .map(|e| e.bytes())
        .sum();
    traffic.frame_lengths.push(bytes);
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Homing {
    Idle,
    /// Homing mode is active; the start bit is low for one cycle.
    Arming,
    /// Start bit set; waiting for "homing attained".
    Running {
        answers: u32,
    },
}

/// What a drive serves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum DriveKind {
    /// A machine axis: the actual value is a position (counts); the target is a position
    /// (CSP, profile position) or a velocity (CSV, counts/s).
    Axis,
    /// The spindle in CSV or profile velocity: target and actual are velocities
    /// (counts/s); its scaling is counts per second per rpm.
    Spindle,
}

/// The receive PDO layout for a drive of `kind` in `mode`.
pub(crate) fn receive_entries(kind: DriveKind, mode: i8) -> [PdoEntry; 2] {
    match kind {
        DriveKind::Axis if mode == MODE_CSV => CSV_RPDO_ENTRIES,
        DriveKind::Axis => RPDO_ENTRIES,
        DriveKind::Spindle => SPINDLE_RPDO_ENTRIES,
    }
}

/// The transmit PDO layout for a drive of `kind`.
pub(crate) fn transmit_entries(kind: DriveKind) -> [PdoEntry; 2] {
    match kind {
        DriveKind::Axis => TPDO_ENTRIES,
        DriveKind::Spindle => SPINDLE_TPDO_ENTRIES,
    }
}

/// One drive's state as the master sees it.
#[derive(Debug, Clone)]
pub(crate) struct Drive {
    pub(crate) kind: DriveKind,
    pub(crate) node: u8,
    /// The main mode of operation (CSP, CSV or profile position for axes, CSV or profile
    /// velocity for a spindle).
    pub(crate) mode: i8,
    pub(crate) scaling: Scaling,
    pub(crate) rpdo_cob: u16,
    pub(crate) tpdo_cob: u16,
    pub(crate) controlword: u16,
    pub(crate) target: i32,
    pub(crate) actual: i32,
    pub(crate) status: u16,
    pub(crate) seen: bool,
    pub(crate) missed: u32,
    pub(crate) commanded: f64,
    pub(crate) velocity: f64,
    pub(crate) homed: bool,
    pub(crate) homing: Homing,
    pub(crate) has_homing: bool,
    pub(crate) fault: Option<AxisFault>,
    /// True when `fault` only reports that another drive's fault stopped this one.
    pub(crate) secondary: bool,
    /// The cause of `fault` in words, naming the node.
    pub(crate) cause: Option<String>,
    pub(crate) last_emcy: Option<Emergency>,
    /// CSV axis: gain of the position loop klar closes, 1/s.
    pub(crate) position_gain: f64,
    /// CSV axis: the following error klar tolerates (the configured window), units.
    pub(crate) following_window: Option<f64>,
    /// Spindle: exchanges since the target last changed (a "target reached" bit counts
    /// only once the drive has seen the target for a full cycle).
    pub(crate) same_target: u32,
    /// Axis: the configured quick-stop deceleration (0x6085), units/s².
    pub(crate) quick_stop_deceleration: Option<f64>,
    /// Consecutive transmit PDOs whose actual value moved by at most [`STILL_COUNTS`].
    pub(crate) still_for: u32,
    /// Axis: speed between the last two transmit PDOs, units/s (a spindle: unused).
    pub(crate) speed: f64,
    /// Axis: the position command the last actual position answers (the one sent with its
    /// SYNC), units: the reference of the reported following error.
    pub(crate) answered: f64,
    /// Spindle: the COB-ID of the transmit PDO with the actual position.
    pub(crate) position_cob: Option<u16>,
    /// Spindle: the last actual position the drive sent (counts, as it wraps at 32 bits).
    pub(crate) position_raw: Option<i32>,
    /// Spindle: the actual position unwrapped (counts; the first value the drive sent,
    /// then every change added).
    pub(crate) position_total: i64,
    /// Spindle: counts per degree with direction, for the measured angle.
    pub(crate) angle_scaling: Option<Scaling>,
}

/// Largest change of the actual position between two SYNCs (counts) that still counts as
/// standing still: an encoder dithering by a count at rest.
pub(crate) const STILL_COUNTS: i64 = 1;
/// Transmit PDOs in a row without motion that make a standstill.
pub(crate) const STILL_PDOS: u32 = 3;

impl Drive {
    pub(crate) fn power(&self) -> PowerState {
        PowerState::from_statusword(self.status)
    }

    /// True when the receive PDO carries a velocity (CSV axis, any spindle).
    pub(crate) fn sends_velocity(&self) -> bool {
        self.kind == DriveKind::Spindle || self.mode == MODE_CSV
    }

    /// The target that holds the drive where it is: its actual position, or zero velocity.
    pub(crate) fn hold_target(&self) -> i32 {
        if self.sends_velocity() {
            0
        } else {
            self.actual
        }
    }

    /// True when the drive stands still: its position has not moved for [`STILL_PDOS`]
    /// transmit PDOs, or (in QUICK STOP ACTIVE) it reports the quick stop done (bit 10).
    pub(crate) fn at_standstill(&self) -> bool {
        self.still_for >= STILL_PDOS
            || (self.power() == PowerState::QuickStopActive && self.status & SW_TARGET_REACHED != 0)
    }

    /// Longest a quick stop of this drive can still take from its present speed: the time
    /// its quick-stop deceleration needs, with half again as margin and a tenth of a
    /// second for the drive's reaction; `None` without a configured deceleration.
    pub(crate) fn quick_stop_bound(&self) -> Option<Duration> {
        let a = self.quick_stop_deceleration?;
        let t = 1.5 * self.speed.abs() / a + 0.1;
        Some(Duration::from_secs_f64(t.clamp(0.0, 60.0)))
    }
}

/// The drives on one CANopen bus: the axes first (in axis order), then the spindle.
pub(crate) struct Network {
    pub(crate) master: Master,
    pub(crate) drives: Vec<Drive>,
    pub(crate) axes: usize,
    pub(crate) pdo_wait: Duration,
    pub(crate) max_missed: u32,
    pub(crate) state_timeout: Duration,
    pub(crate) heartbeat_timeout: Option<f64>,
    pub(crate) stop: Option<String>,
    /// The spindle's at-speed window: fraction of the command, and minimum in rpm.
    pub(crate) spindle_at_speed: (f64, f64),
    /// The spindle's speed ramp per servo cycle, rpm.
    pub(crate) spindle_ramp_step: f64,
    /// The servo period (SYNC interval), seconds.
    pub(crate) servo_period: f64,
    /// Exchanges outside the servo loop (enable, disable, fault reset) keep one servo
    /// period between SYNCs on the wall clock (real buses; simulated ones run unpaced).
    pub(crate) paced: bool,
    /// When the last SYNC went out.
    pub(crate) last_sync: Option<Instant>,
    /// The time from the last SYNC to its last transmit PDO, s (the adapter's round trip
    /// plus the drives' reaction), when every drive answered.
    pub(crate) round_trip: Option<f64>,
}

impl Network {
    /// Stops all axes because of `cause` at drive `index`: that axis gets `fault`, the
    /// others a drive fault naming the cause, and enabled drives a quick stop.
    pub(crate) fn stop_all(&mut self, index: Option<usize>, fault: AxisFault, cause: String) {
        if self.stop.is_none() {
            tracing::error!("{cause}; quick stop of all CANopen axes");
            self.stop = Some(cause.clone());
        }
        for (i, d) in self.drives.iter_mut().enumerate() {
            if index.is_none_or(|k| k == i) {
                if d.fault.is_none() || d.secondary || index.is_some() {
                    d.fault = Some(fault.clone());
                    d.secondary = false;
                    d.cause = Some(if index.is_some() {
                        cause.clone()
                    } else {
                        format!("node {}: {cause}", d.node)
                    });
                }
            } else if d.fault.is_none() {
                d.fault = Some(AxisFault::Drive {
                    code: 0,
                    text: format!("stopped: {cause}"),
                });
                d.secondary = true;
                d.cause = Some(format!("node {}: stopped: {cause}", d.node));
            }
            d.homing = Homing::Idle;
            if d.kind == DriveKind::Spindle {
                // After a stop the spindle waits for a new command.
                d.commanded = 0.0;
                d.velocity = 0.0;
            }
        }
    }

    fn drive_index(&self, node: u8) -> Option<usize> {
        self.drives.iter().position(|d| d.node == node)
    }

    /// Sorts the master's queued node events into faults.
    pub(crate) fn handle_events(&mut self) {
        while let Some(ev) = self.master.next_event() {
            match ev {
                NodeEvent::Emergency(e) => {
                    let Some(i) = self.drive_index(e.node) else {
                        tracing::warn!("{e} (not a configured drive)");
                        continue;
                    };
                    if e.is_reset() {
                        continue;
                    }
                    let fault = AxisFault::Drive {
                        code: u32::from(e.code),
                        text: e.describe(),
                    };
                    let cause = e.describe();
                    if let Some(d) = self.drives.get_mut(i) {
                        d.last_emcy = Some(e);
                    }
                    self.stop_all(Some(i), fault, cause);
                }
                NodeEvent::HeartbeatLost { node, silent_for } => {
                    if let Some(i) = self.drive_index(node) {
                        let cause =
                            format!("node {node}: heartbeat lost (silent for {silent_for:.3} s)");
                        self.stop_all(Some(i), AxisFault::CommunicationLost, cause);
                    }
                }
                NodeEvent::Malformed { node, what } => {
                    let cause = match node {
                        Some(n) => format!("node {n}: malformed frame: {what}"),
                        None => format!("malformed frame: {what}"),
                    };
                    match node.and_then(|n| self.drive_index(n)) {
                        Some(i) => self.stop_all(Some(i), AxisFault::CommunicationLost, cause),
                        None => tracing::warn!("{cause}"),
                    }
                }
                NodeEvent::Bus(BusErrorKind::BusOff) => {
                    self.stop_all(None, AxisFault::CommunicationLost, "CAN bus-off".into());
                }
                NodeEvent::Bus(kind) => tracing::warn!(%kind, "CAN bus error"),
                NodeEvent::BootUp(node) => {
                    if let Some(i) = self.drive_index(node) {
                        let cause = format!("node {node}: unexpected boot-up (drive reset)");
                        self.stop_all(Some(i), AxisFault::CommunicationLost, cause);
                    }
                }
                NodeEvent::StateChanged(node, state) => {
                    tracing::info!(node, ?state, "NMT state");
                }
            }
        }
    }

    /// Sends every receive PDO and SYNC, then collects the transmit PDOs.
    pub(crate) fn exchange(&mut self) {
        if self.send_cyclic() {
            self.collect(self.pdo_wait);
        }
    }

    /// True when the servo cycle runs pipelined: each cycle uses the transmit PDOs of the
    /// SYNC before and sends its setpoints with a new SYNC without waiting for the answers.
    /// Paced (real) buses whose axes all run in CSP or profile position do; a CSV axis, whose
    /// position loop klar closes, keeps the exchange that waits for the answers.
    pub(crate) fn pipelined(&self) -> bool {
        self.paced
            && self
                .drives
                .iter()
                .all(|d| d.kind == DriveKind::Spindle || d.mode != MODE_CSV)
    }

    /// Sends every receive PDO and SYNC; false when sending failed (every drive stopped).
    pub(crate) fn send_cyclic(&mut self) -> bool {
        for i in 0..self.drives.len() {
            let Some(d) = self.drives.get(i) else {
                continue;
            };
            let data = pdo::pack(
                &receive_entries(d.kind, d.mode),
                &[u32::from(d.controlword), d.target as u32],
            );
            let frame = CanFrame::fixed(d.rpdo_cob, &data);
            if let Err(e) = self.master.bus_send(&frame) {
                let node = d.node;
                self.stop_all(
                    None,
                    AxisFault::CommunicationLost,
                    format!("node {node}: send failed: {e}"),
                );
                return false;
            }
        }
        let sent = self.master.sync();
        self.last_sync = Some(Instant::now());
        if let Err(e) = sent {
            self.stop_all(
                None,
                AxisFault::CommunicationLost,
                format!("SYNC not sent: {e}"),
            );
            return false;
        }
        true
    }

    /// Collects the transmit PDOs answering the last SYNC, waiting up to `wait` for them.
    pub(crate) fn collect(&mut self, wait: Duration) {
        let cobs: Vec<u16> = self
            .drives
            .iter()
            .flat_map(|d| std::iter::once(d.tpdo_cob).chain(d.position_cob))
            .collect();
        let answered = self.master.await_pdos(&cobs, wait);
        self.round_trip = self
            .last_sync
            .filter(|_| answered.as_ref().is_ok_and(Vec::is_empty))
            .map(|sync| sync.elapsed().as_secs_f64());
        if let Err(e) = answered {
            self.stop_all(
                None,
                AxisFault::CommunicationLost,
                format!("CAN receive failed: {e}"),
            );
            return;
        }
        let sync = self.master.sync_count();
        for i in 0..self.drives.len() {
            let Some(d) = self.drives.get(i) else {
                continue;
            };
            let fresh_pdo = |cob: u16| {
                self.master
                    .pdo(cob)
                    .filter(|s| s.sync_count >= sync)
                    .map(|s| s.frame)
            };
            let fresh_position = d.position_cob.map(fresh_pdo);
            // A spindle's cycle counts as answered only with both of its PDOs.
            let fresh = fresh_pdo(d.tpdo_cob).filter(|_| !matches!(fresh_position, Some(None)));
            let (node, missed_before, kind) = (d.node, d.missed, d.kind);
            if let Some(Some(frame)) = fresh_position {
                match pdo::unpack(&SPINDLE_POSITION_TPDO_ENTRIES, frame.data()) {
                    Some(v) => {
                        if let (Some(d), [raw]) = (self.drives.get_mut(i), v.as_slice()) {
                            let raw = *raw as i32;
                            // The drive's counter wraps at 32 bits: the change since the
                            // last PDO is the wrapping difference.
                            d.position_total = match d.position_raw {
                                Some(last) => d.position_total + i64::from(raw.wrapping_sub(last)),
                                None => i64::from(raw),
                            };
                            d.position_raw = Some(raw);
                        }
                    }
                    None => {
                        let cause = format!(
                            "node {node}: position transmit PDO with {} bytes, mapping needs 4",
                            frame.data().len()
                        );
                        self.stop_all(Some(i), AxisFault::CommunicationLost, cause);
                        continue;
                    }
                }
            }
            match fresh {
                None => {
                    let missed = missed_before + 1;
                    if let Some(d) = self.drives.get_mut(i) {
                        d.missed = missed;
                    }
                    tracing::debug!(node, missed, "transmit PDO missing");
                    if missed >= self.max_missed {
                        let cause =
                            format!("node {node}: no transmit PDO for {missed} SYNC cycles");
                        self.stop_all(Some(i), AxisFault::CommunicationLost, cause);
                    }
                }
                Some(frame) => match pdo::unpack(&transmit_entries(kind), frame.data()) {
                    Some(v) => {
                        if let (Some(d), [status, actual]) = (self.drives.get_mut(i), v.as_slice())
                        {
                            let actual = *actual as i32;
                            let moved = i64::from(actual) - i64::from(d.actual);
                            d.still_for = if d.seen && moved.abs() <= STILL_COUNTS {
                                d.still_for.saturating_add(1)
                            } else {
                                0
                            };
                            if d.seen && d.kind == DriveKind::Axis {
                                d.speed = d.scaling.to_units(actual) - d.scaling.to_units(d.actual);
                                d.speed /= self.servo_period;
                            }
                            d.status = *status as u16;
                            d.actual = actual;
                            d.seen = true;
                            d.missed = 0;
                        }
                    }
                    None => {
                        let cause = format!(
                            "node {node}: transmit PDO with {} bytes, mapping needs {}",
                            frame.data().len(),
                            TPDO_ENTRIES.iter().map(|e| e.bytes()).sum::<usize>()
                        );
                        self.stop_all(Some(i), AxisFault::CommunicationLost, cause);
                    }
                },
            }
        }
    }

    /// Turns statusword bits into faults and follows homing.
    pub(crate) fn evaluate(&mut self) {
        let mut finished_homing = Vec::new();
        // Answers that may still predate the homing start bit.
        let lag = u32::from(self.pipelined());
        for i in 0..self.drives.len() {
            let Some(d) = self.drives.get_mut(i) else {
                continue;
            };
            let power = d.power();
            let node = d.node;
            let mut raised: Option<(AxisFault, String)> = None;
            if power.is_fault() && d.fault.is_none() {
                let (code, text) = match &d.last_emcy {
                    Some(e) => (u32::from(e.code), e.describe()),
                    None => (
                        0,
                        format!("node {node}: drive fault (no emergency message)"),
                    ),
                };
                raised = Some((
                    AxisFault::Drive {
                        code,
                        text: text.clone(),
                    },
                    text,
                ));
            } else if power == PowerState::OperationEnabled
                && d.fault.is_none()
                && d.kind == DriveKind::Axis
            {
                let csv_error = (d.mode == MODE_CSV && is_enable_operation(d.controlword))
                    .then(|| d.commanded - d.scaling.to_units(d.actual))
                    .filter(|fe| d.following_window.is_some_and(|w| fe.abs() > w));
                match d.homing {
                    // In CSV the drive knows no position command: klar watches the error.
                    Homing::Idle if csv_error.is_some() => {
                        let fe = csv_error.unwrap_or_default();
                        raised = Some((
                            AxisFault::FollowingError(fe),
                            format!(
                                "node {node}: following error {fe:.4} beyond the window {:.4}",
                                d.following_window.unwrap_or_default()
                            ),
                        ));
                    }
                    // Bit 13 means "following error" in CSP and PP; it is reserved in CSV.
                    Homing::Idle if d.status & SW_OMS2 != 0 && d.mode != MODE_CSV => {
                        let fe = d.commanded - d.scaling.to_units(d.actual);
                        raised = Some((
                            AxisFault::FollowingError(fe),
                            format!("node {node}: following error {fe:.4} reported by the drive"),
                        ));
                    }
                    Homing::Idle if d.status & SW_INTERNAL_LIMIT != 0 => {
                        raised = Some((
                            AxisFault::LimitSwitch {
                                positive: d.velocity >= 0.0,
                            },
                            format!("node {node}: internal limit active"),
                        ));
                    }
                    Homing::Arming => {
                        d.controlword = CW_ENABLE_OPERATION | CW_HOMING_START;
                        d.homing = Homing::Running { answers: 0 };
                    }
                    Homing::Running { answers } => {
                        if d.status & SW_OMS2 != 0 {
                            raised = Some((
                                AxisFault::Drive {
                                    code: 0,
                                    text: format!("node {node}: homing error"),
                                },
                                format!("node {node}: homing error"),
                            ));
                        } else if answers > lag
                            && d.status & SW_OMS1 != 0
                            && d.status & SW_TARGET_REACHED != 0
                        {
                            d.homing = Homing::Idle;
                            d.homed = true;
                            d.controlword = CW_ENABLE_OPERATION;
                            d.target = d.hold_target();
                            d.commanded = d.scaling.to_units(d.actual);
                            tracing::info!(node, position = d.commanded, "homed");
                            finished_homing.push(i);
                        } else {
                            d.homing = Homing::Running {
                                answers: answers + 1,
                            };
                        }
                    }
                    _ => {}
                }
            } else if power != PowerState::OperationEnabled
                && d.kind == DriveKind::Axis
                && self.stop.is_none()
                && is_enable_operation(d.controlword)
                && d.fault.is_none()
            {
                raised = Some((
                    AxisFault::Drive {
                        code: 0,
                        text: format!("node {node}: left operation enabled ({power:?})"),
                    },
                    format!("node {node}: left operation enabled ({power:?})"),
                ));
            }
            if let Some((fault, cause)) = raised {
                self.stop_all(Some(i), fault, cause);
            }
        }
        for i in finished_homing {
            let Some((node, mode)) = self.drives.get(i).map(|d| (d.node, d.mode)) else {
                continue;
            };
            if let Err(e) = self.set_mode(node, mode) {
                let cause = format!("node {node}: back to mode {mode} after homing: {e}");
                self.stop_all(
                    Some(i),
                    AxisFault::Drive {
                        code: 0,
                        text: cause.clone(),
                    },
                    cause,
                );
            }
        }
    }

    /// Sets the mode of operation over SDO and waits until the drive shows it.
    pub(crate) fn set_mode(&mut self, node: u8, mode: i8) -> Result<(), CanOpenError> {
        self.master
            .sdo_write(node, MODES_OF_OPERATION, 0, &[mode as u8])?;
        let deadline = Instant::now() + self.state_timeout;
        loop {
            let shown = self.master.sdo_read(node, MODES_DISPLAY, 0)?;
            if shown.first().map(|&b| b as i8) == Some(mode) {
                return Ok(());
            }
            if Instant::now() >= deadline {
                return Err(CanOpenError::SdoProtocol {
                    node,
                    index: MODES_DISPLAY,
                    sub: 0,
                    what: format!("mode {mode} not shown within the state timeout"),
                });
            }
        }
    }

    /// Sets the next controlword of every drive while stopped: quick stop for enabled
    /// drives, hold otherwise.
    pub(crate) fn apply_stop(&mut self) {
        if self.stop.is_none() {
            return;
        }
        for d in self.drives.iter_mut() {
            d.target = d.hold_target();
            if d.kind == DriveKind::Axis {
                d.commanded = d.scaling.to_units(d.actual);
            }
            match d.power() {
                PowerState::OperationEnabled | PowerState::QuickStopActive => {
                    d.controlword = CW_QUICK_STOP
                }
                _ => d.controlword = CW_DISABLE_VOLTAGE,
            }
        }
    }

    /// Runs exchanges until `done` holds for the selected drives (`which`: one drive by
    /// index, or `None` for all axes), setting their controlwords with `next`, or until the
    /// state timeout passes.
    pub(crate) fn drive_sequence(
        &mut self,
        which: Option<usize>,
        mut next: impl FnMut(&Drive) -> Option<u16>,
        done: impl Fn(&Drive) -> bool,
    ) -> Result<(), BackendError> {
        let deadline = Instant::now() + self.state_timeout;
        loop {
            self.handle_events();
            let axes = self.axes;
            let selected = |i: usize| which.map_or(i < axes, |w| w == i);
            let all_done = self
                .drives
                .iter()
                .enumerate()
                .all(|(i, d)| !selected(i) || done(d));
            if all_done {
                return Ok(());
            }
            if Instant::now() >= deadline {
                let stuck: Vec<String> = self
                    .drives
                    .iter()
                    .enumerate()
                    .filter(|(i, d)| selected(*i) && !done(d))
                    .map(|(_, d)| format!("node {} in {:?}", d.node, d.power()))
                    .collect();
                return Err(BackendError::InvalidState(format!(
                    "state change timed out: {}",
                    stuck.join(", ")
                )));
            }
            for (i, d) in self.drives.iter_mut().enumerate() {
                if selected(i)
                    && let Some(cw) = next(d)
                {
                    d.controlword = cw;
                }
                if d.kind == DriveKind::Axis {
                    d.target = d.hold_target();
                }
            }
            self.pace();
            self.exchange();
        }
    }

    /// On a paced network, sleeps until one servo period after the last SYNC.
    pub(crate) fn pace(&self) {
        if !self.paced {
            return;
        }
        if let Some(last) = self.last_sync {
            let due = last + Duration::from_secs_f64(self.servo_period);
            let now = Instant::now();
            if due > now {
                std::thread::sleep(due - now);
            }
        }
    }

    /// Holds every axis drive in QUICK STOP ACTIVE (exchanging once per servo period) until
    /// it stands still, or for at most the time its quick-stop deceleration needs from its
    /// present speed (the state timeout without a configured deceleration). Drives still
    /// moving at the bound are named in a warning.
    pub(crate) fn wait_quick_stops(&mut self) {
        let start = Instant::now();
        let bounds: Vec<Duration> = self
            .drives
            .iter()
            .map(|d| d.quick_stop_bound().unwrap_or(self.state_timeout))
            .collect();
        loop {
            let elapsed = start.elapsed();
            let mut waiting = false;
            for (d, bound) in self.drives.iter().zip(&bounds) {
                if d.kind != DriveKind::Axis
                    || d.power() != PowerState::QuickStopActive
                    || d.at_standstill()
                {
                    continue;
                }
                if elapsed < *bound {
                    waiting = true;
                } else if d.still_for == 0 {
                    tracing::warn!(
                        node = d.node,
                        speed = d.speed,
                        "still moving {:.3} s after the quick stop began; switched off",
                        elapsed.as_secs_f64()
                    );
                }
            }
            if !waiting {
                return;
            }
            for d in self.drives.iter_mut() {
                if d.kind == DriveKind::Axis && d.power() == PowerState::QuickStopActive {
                    d.controlword = CW_QUICK_STOP;
                    d.target = d.hold_target();
                }
            }
            self.pace();
            self.exchange();
            self.handle_events();
        }
    }
}
