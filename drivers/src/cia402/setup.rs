//! Start-up of the CANopen network: opening the bus, the bus-load check, boot-up, drive
//! parameters and PDO mappings over SDO, NMT start, and the first exchange.

use std::time::Duration;

use super::config::{AxisMode, BusConfig, CanOpenConfig, DriveConfig, SpindleConfig, SpindleMode};
use super::network::*;
use super::objects::*;
use super::scaling::Scaling;
use super::state::*;
use crate::can::CanBus;
use crate::canopen::busload;
use crate::canopen::pdo::{self, PdoConfig, PdoKind, TRANSMIT_EVERY_SYNC};
use crate::canopen::sdo::{ABORT_NO_OBJECT, ABORT_NO_SUBINDEX, ABORT_VALUE};
use crate::canopen::{CanOpenError, Master, NmtCommand, NodeEvent};

/// Communication cycle period (u32, µs), CiA 301.
const COMM_CYCLE_PERIOD: u16 = 0x1006;

/// Opens the bus the configuration names (SocketCAN or slcan). A simulated bus is built
/// by `klar_sim::cia402` instead.
pub(crate) fn open_bus(config: &CanOpenConfig) -> Result<Box<dyn CanBus>, Cia402Error> {
    {
        let bus: Box<dyn CanBus> = match &config.bus {
            BusConfig::Socketcan { interface, .. } => {
                Box::new(crate::can::socketcan::SocketCanBus::open(interface)?)
            }
            BusConfig::Slcan {
                port,
                bitrate,
                serial_baud,
            } => {
                let mut options = crate::can::slcan::SlcanOptions::host(*bitrate);
                options.serial_baud = *serial_baud;
                Box::new(
                    crate::can::slcan::SlcanBus::open(port, options).map_err(|error| {
                        Cia402Error::Adapter {
                            port: port.clone(),
                            error,
                        }
                    })?,
                )
            }
            BusConfig::Sim { .. } | BusConfig::SimSlcan { .. } => {
                return Err(Cia402Error::Config(
                    "a simulated bus is built by the simulation (klar_sim::cia402)".into(),
                ));
            }
        };
        Ok(bus)
    }
}

impl Network {
    /// Starts the drives of `config` on `bus` with SYNC every `servo_period` seconds.
    pub(crate) fn start(
        config: &CanOpenConfig,
        servo_period: f64,
        bus: Box<dyn CanBus>,
    ) -> Result<Self, Cia402Error> {
        if !(servo_period.is_finite() && servo_period > 0.0) {
            return Err(Cia402Error::Config(format!(
                "servo period {servo_period} s"
            )));
        }
        if config.drives.is_empty() && config.spindle.is_none() {
            return Err(Cia402Error::Config("no drives".into()));
        }
        for d in &config.drives {
            d.check(Some(servo_period)).map_err(Cia402Error::Config)?;
        }
        if let Some(s) = &config.spindle {
            s.check().map_err(Cia402Error::Config)?;
        }
        let mut traffic =
            cyclic_traffic(config.drives.len() + usize::from(config.spindle.is_some()));
        if config.spindle.is_some() {
            spindle_position_traffic(&mut traffic);
        }
        let load = busload::check(&traffic, config.bus.bitrate(), servo_period)?;
        tracing::info!(
            load_percent = load * 100.0,
            "CAN bus load of cyclic traffic"
        );
        let mut drives = Vec::with_capacity(config.drives.len() + 1);
        for d in &config.drives {
            drives.push(new_drive(d)?);
        }
        if let Some(s) = &config.spindle {
            drives.push(new_spindle(s)?);
        }
        let mut nodes: Vec<u8> = drives.iter().map(|d| d.node).collect();
        nodes.sort_unstable();
        if nodes.windows(2).any(|w| w[0] == w[1]) {
            return Err(Cia402Error::Config(format!("node IDs repeat: {nodes:?}")));
        }
        let mut master = Master::new(bus, Duration::from_millis(config.sdo_timeout_ms));
        master.reset_and_wait_boot(&nodes, Duration::from_millis(config.boot_timeout_ms))?;
        for (d, cfg) in drives.iter().zip(&config.drives) {
            configure_drive(&mut master, d, Some(cfg), config, servo_period)?;
        }
        if let Some(s) = drives.get(config.drives.len()) {
            configure_drive(&mut master, s, None, config, servo_period)?;
        }
        for d in &drives {
            master.nmt(NmtCommand::Start, d.node)?;
        }
        // Boot-ups up to here belong to the start-up; later ones mean a drive reset.
        let mut kept = Vec::new();
        while let Some(ev) = master.next_event() {
            if !matches!(ev, NodeEvent::BootUp(_)) {
                kept.push(ev);
            }
        }
        master.requeue(kept);
        let heartbeat_timeout = (config.heartbeat_ms > 0).then(|| {
            config
                .heartbeat_timeout_ms
                .map_or(3.0 * f64::from(config.heartbeat_ms) / 1000.0, |ms| {
                    ms as f64 / 1000.0
                })
        });
        if let Some(timeout) = heartbeat_timeout {
            for d in &drives {
                master.watch_heartbeat(d.node, timeout);
            }
        }
        let pdo_wait = config.pdo_wait_ms.map_or(servo_period, |ms| ms / 1000.0);
        let mut backend = Self {
            master,
            drives,
            axes: config.drives.len(),
            spindle_at_speed: config
                .spindle
                .as_ref()
                .map_or((0.02, 5.0), |s| (s.at_speed_fraction, s.at_speed_min_rpm)),
            spindle_ramp_step: config
                .spindle
                .as_ref()
                .map_or(f64::INFINITY, |s| s.acceleration.abs() * servo_period),
            pdo_wait: Duration::from_secs_f64(pdo_wait.clamp(0.0, 10.0)),
            max_missed: config.max_missed_pdos.max(1),
            state_timeout: Duration::from_millis(config.state_timeout_ms),
            heartbeat_timeout,
            stop: None,
            servo_period,
            paced: false,
            last_sync: None,
            round_trip: None,
        };
        backend.first_exchange(Duration::from_millis(config.tpdo_timeout_ms))?;
        for d in backend.drives.iter_mut() {
            d.target = d.hold_target();
            d.commanded = match d.kind {
                DriveKind::Axis => d.scaling.to_units(d.actual),
                DriveKind::Spindle => 0.0,
            };
        }
        Ok(backend)
    }
}

impl Network {
    /// Exchanges (SYNC every servo period) until every drive has sent a transmit PDO with
    /// its state and position, for at most `timeout`. A drive may need a few SYNCs after NMT
    /// start before its PDOs flow; missing ones during this wait are not counted as lost.
    fn first_exchange(&mut self, timeout: Duration) -> Result<(), Cia402Error> {
        let start = std::time::Instant::now();
        let period = Duration::from_secs_f64(self.servo_period);
        let mut syncs = 0u32;
        loop {
            let cycle = std::time::Instant::now();
            let max_missed = std::mem::replace(&mut self.max_missed, u32::MAX);
            self.exchange();
            self.max_missed = max_missed;
            syncs += 1;
            self.handle_events();
            if let Some(stop) = &self.stop {
                return Err(Cia402Error::Config(format!("at start-up: {stop}")));
            }
            let silent: Vec<String> = self
                .drives
                .iter()
                .filter(|d| !d.seen)
                .map(|d| d.node.to_string())
                .collect();
            if silent.is_empty() {
                for d in self.drives.iter_mut() {
                    d.missed = 0;
                }
                return Ok(());
            }
            if start.elapsed() >= timeout {
                return Err(Cia402Error::Config(format!(
                    "node {}: no transmit PDO within {} ms ({syncs} SYNCs) after NMT start",
                    silent.join(", node "),
                    timeout.as_millis()
                )));
            }
            if let Some(rest) = period.checked_sub(cycle.elapsed()) {
                std::thread::sleep(rest);
            }
        }
    }
}

fn new_drive(cfg: &DriveConfig) -> Result<Drive, Cia402Error> {
    let scaling = Scaling::new(cfg.counts_per_unit, cfg.invert)
        .map_err(|e| Cia402Error::Config(format!("node {}: {e}", cfg.node)))?;
    let mode = match cfg.mode {
        AxisMode::Csp => MODE_CSP,
        AxisMode::Csv => MODE_CSV,
        AxisMode::Pp => MODE_PROFILE_POSITION,
        AxisMode::Pv => {
            // `DriveConfig::check` refuses it first; this keeps the match honest.
            return Err(Cia402Error::Config(format!(
                "node {}: profile velocity cannot drive an axis",
                cfg.node
            )));
        }
    };
    let mut drive = make_drive(
        DriveKind::Axis,
        mode,
        cfg.node,
        scaling,
        cfg.rpdo,
        cfg.tpdo,
        cfg.homing.is_some(),
    )?;
    drive.position_gain = cfg.gain();
    drive.following_window = cfg.following_error_window.map(f64::abs);
    drive.homed = cfg.absolute_encoder;
    drive.quick_stop_deceleration = cfg.quick_stop_deceleration;
    Ok(drive)
}

fn new_spindle(cfg: &SpindleConfig) -> Result<Drive, Cia402Error> {
    // Target and actual velocity are counts per second: counts per revolution / 60 per rpm.
    let scaling = Scaling::new(cfg.counts_per_rev / 60.0, cfg.invert)
        .map_err(|e| Cia402Error::Config(format!("spindle node {}: {e}", cfg.node)))?;
    let mode = match cfg.mode {
        SpindleMode::Csv => MODE_CSV,
        SpindleMode::Pv => MODE_PROFILE_VELOCITY,
    };
    let mut drive = make_drive(
        DriveKind::Spindle,
        mode,
        cfg.node,
        scaling,
        cfg.rpdo,
        cfg.tpdo,
        false,
    )?;
    let number = cfg.position_pdo();
    drive.position_cob = Some(
        pdo::default_cob_id(PdoKind::Transmit, number, cfg.node).ok_or_else(|| {
            Cia402Error::Config(format!(
                "spindle node {}: position transmit PDO {number} not in 1..=4",
                cfg.node
            ))
        })?,
    );
    drive.angle_scaling = Some(
        Scaling::new(cfg.counts_per_rev / 360.0, cfg.invert)
            .map_err(|e| Cia402Error::Config(format!("spindle node {}: {e}", cfg.node)))?,
    );
    Ok(drive)
}

fn make_drive(
    kind: DriveKind,
    mode: i8,
    node: u8,
    scaling: Scaling,
    rpdo: u16,
    tpdo: u16,
    has_homing: bool,
) -> Result<Drive, Cia402Error> {
    if node == 0 || node > 127 {
        return Err(Cia402Error::Config(format!(
            "node ID {node} outside 1..=127"
        )));
    }
    let rpdo_cob = pdo::default_cob_id(PdoKind::Receive, rpdo, node).ok_or_else(|| {
        Cia402Error::Config(format!("node {node}: receive PDO {rpdo} not in 1..=4"))
    })?;
    let tpdo_cob = pdo::default_cob_id(PdoKind::Transmit, tpdo, node).ok_or_else(|| {
        Cia402Error::Config(format!("node {node}: transmit PDO {tpdo} not in 1..=4"))
    })?;
    Ok(Drive {
        kind,
        mode,
        node,
        scaling,
        rpdo_cob,
        tpdo_cob,
        controlword: CW_DISABLE_VOLTAGE,
        target: 0,
        actual: 0,
        status: 0,
        seen: false,
        missed: 0,
        commanded: 0.0,
        velocity: 0.0,
        homed: false,
        homing: Homing::Idle,
        has_homing,
        fault: None,
        secondary: false,
        cause: None,
        last_emcy: None,
        position_gain: 0.0,
        following_window: None,
        same_target: 0,
        quick_stop_deceleration: None,
        still_for: 0,
        speed: 0.0,
        answered: 0.0,
        position_cob: None,
        position_raw: None,
        position_total: 0,
        angle_scaling: None,
    })
}

/// The CiA 402 name of a mode of operation, for messages.
fn mode_name(mode: i8) -> &'static str {
    match mode {
        MODE_PROFILE_POSITION => "profile position",
        MODE_PROFILE_VELOCITY => "profile velocity",
        MODE_HOMING => "homing",
        MODE_CSP => "cyclic synchronous position",
        MODE_CSV => "cyclic synchronous velocity",
        _ => "unknown mode",
    }
}

/// Writes an object that a drive may lack; "no such object" aborts are only logged.
fn write_optional(
    master: &mut Master,
    node: u8,
    index: u16,
    sub: u8,
    data: &[u8],
) -> Result<(), CanOpenError> {
    match master.sdo_write(node, index, sub, data) {
        Err(CanOpenError::SdoAbort { code, .. })
            if code == ABORT_NO_OBJECT || code == ABORT_NO_SUBINDEX =>
        {
            tracing::debug!(node, index, sub, "optional object missing");
            Ok(())
        }
        other => other,
    }
}

/// Writes a drive's parameters and PDOs; `cfg` is the axis configuration (`None` for the
/// spindle, whose PDO numbers come from the spindle configuration).
fn configure_drive(
    master: &mut Master,
    d: &Drive,
    cfg: Option<&DriveConfig>,
    bus: &CanOpenConfig,
    period: f64,
) -> Result<(), Cia402Error> {
    let node = d.node;
    let mode = d.mode;
    let rx_entries = receive_entries(d.kind, mode);
    let tx_entries = transmit_entries(d.kind);
    let (rpdo, tpdo, position_tpdo) = match (d.kind, cfg, &bus.spindle) {
        (DriveKind::Axis, Some(c), _) => (c.rpdo, c.tpdo, None),
        (DriveKind::Spindle, _, Some(s)) => (s.rpdo, s.tpdo, Some(s.position_pdo())),
        _ => {
            return Err(Cia402Error::Config(format!(
                "node {node}: no configuration"
            )));
        }
    };
    master.sdo_write(node, PRODUCER_HEARTBEAT, 0, &bus.heartbeat_ms.to_le_bytes())?;
    let micros = (period * 1e6).round() as u32;
    write_optional(master, node, COMM_CYCLE_PERIOD, 0, &micros.to_le_bytes())?;
    let (value, index) = interpolation_period(period).ok_or_else(|| {
        Cia402Error::Config(format!(
            "servo period {period} s cannot be given to a drive as 0x60C2"
        ))
    })?;
    master.sdo_write(node, INTERPOLATION_PERIOD, 1, &[value])?;
    master.sdo_write(node, INTERPOLATION_PERIOD, 2, &[index as u8])?;
    match master.sdo_write(node, MODES_OF_OPERATION, 0, &[mode as u8]) {
        Err(CanOpenError::SdoAbort { code, .. }) if code == ABORT_VALUE => {
            return Err(Cia402Error::Config(format!(
                "node {node}: the drive does not support mode of operation {mode} ({})",
                mode_name(mode)
            )));
        }
        other => other?,
    }
    if d.kind == DriveKind::Spindle
        && mode == MODE_PROFILE_VELOCITY
        && let Some(s) = &bus.spindle
    {
        // The drive's own ramp: rpm/s through the spindle scaling (counts/s per rpm) gives
        // counts/s².
        let accel = d.scaling.magnitude_counts(s.acceleration).to_le_bytes();
        master.sdo_write(node, PROFILE_ACCELERATION, 0, &accel)?;
        master.sdo_write(node, PROFILE_DECELERATION, 0, &accel)?;
        let window = d.scaling.magnitude_counts(s.at_speed_min_rpm).to_le_bytes();
        write_optional(master, node, VELOCITY_WINDOW, 0, &window)?;
    }
    if let Some(w) = cfg.and_then(|c| c.following_error_window) {
        master.sdo_write(
            node,
            FOLLOWING_ERROR_WINDOW,
            0,
            &d.scaling.magnitude_counts(w).to_le_bytes(),
        )?;
    }
    if let Some(a) = cfg.and_then(|c| c.quick_stop_deceleration) {
        master.sdo_write(
            node,
            QUICK_STOP_DECELERATION,
            0,
            &d.scaling.magnitude_counts(a).to_le_bytes(),
        )?;
        master.sdo_write(
            node,
            QUICK_STOP_OPTION,
            0,
            &QUICK_STOP_HOLD_OPTION.to_le_bytes(),
        )?;
    }
    if let Some(v) = cfg.and_then(|c| c.profile_velocity) {
        master.sdo_write(
            node,
            PROFILE_VELOCITY,
            0,
            &d.scaling.magnitude_counts(v).to_le_bytes(),
        )?;
    }
    if let Some(a) = cfg.and_then(|c| c.profile_acceleration) {
        let counts = d.scaling.magnitude_counts(a).to_le_bytes();
        master.sdo_write(node, PROFILE_ACCELERATION, 0, &counts)?;
        master.sdo_write(node, PROFILE_DECELERATION, 0, &counts)?;
    }
    if let Some(h) = cfg.and_then(|c| c.homing.as_ref()) {
        master.sdo_write(node, HOMING_METHOD, 0, &[h.method as u8])?;
        master.sdo_write(
            node,
            HOMING_SPEEDS,
            1,
            &d.scaling.magnitude_counts(h.speed_search).to_le_bytes(),
        )?;
        master.sdo_write(
            node,
            HOMING_SPEEDS,
            2,
            &d.scaling.magnitude_counts(h.speed_zero).to_le_bytes(),
        )?;
        master.sdo_write(
            node,
            HOMING_ACCELERATION,
            0,
            &d.scaling.magnitude_counts(h.acceleration).to_le_bytes(),
        )?;
        let offset = d
            .scaling
            .to_counts(h.offset)
            .map_err(|e| Cia402Error::Config(format!("node {node}: home offset: {e}")))?;
        master.sdo_write(node, HOME_OFFSET, 0, &offset.to_le_bytes())?;
    }
    for n in 1..=4u16 {
        for kind in [PdoKind::Receive, PdoKind::Transmit] {
            let used = match kind {
                PdoKind::Receive => rpdo,
                PdoKind::Transmit => tpdo,
            };
            if n == used || (kind == PdoKind::Transmit && Some(n) == position_tpdo) {
                continue;
            }
            match master.disable_pdo(node, kind, n) {
                Err(CanOpenError::SdoAbort { code, .. })
                    if code == ABORT_NO_OBJECT || code == ABORT_NO_SUBINDEX => {}
                other => other?,
            }
        }
    }
    master.configure_pdo(
        node,
        &PdoConfig {
            kind: PdoKind::Receive,
            number: rpdo,
            cob_id: d.rpdo_cob,
            transmission: TRANSMIT_EVERY_SYNC,
            entries: rx_entries.to_vec(),
        },
    )?;
    master.configure_pdo(
        node,
        &PdoConfig {
            kind: PdoKind::Transmit,
            number: tpdo,
            cob_id: d.tpdo_cob,
            transmission: TRANSMIT_EVERY_SYNC,
            entries: tx_entries.to_vec(),
        },
    )?;
    if let (Some(number), Some(cob_id)) = (position_tpdo, d.position_cob) {
        master.configure_pdo(
            node,
            &PdoConfig {
                kind: PdoKind::Transmit,
                number,
                cob_id,
                transmission: TRANSMIT_EVERY_SYNC,
                entries: SPINDLE_POSITION_TPDO_ENTRIES.to_vec(),
            },
        )?;
    }
    Ok(())
}
