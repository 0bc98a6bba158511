//! Configuration of a CANopen bus with CiA 402 drives, as it appears in the machine TOML.

use serde::Deserialize;

/// One CAN bus with its CiA 402 drives (one drive per machine axis, in axis order).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CanOpenConfig {
    /// How the bus is reached.
    pub bus: BusConfig,
    /// The drives, in the order of the axes this backend serves.
    #[serde(default)]
    pub drives: Vec<DriveConfig>,
    /// A spindle drive on the same bus (cyclic synchronous velocity mode).
    #[serde(default)]
    pub spindle: Option<SpindleConfig>,
    /// SDO answer timeout, ms.
    #[serde(default = "default_sdo_timeout_ms")]
    pub sdo_timeout_ms: u64,
    /// Time allowed for all boot-up messages after the reset, ms.
    #[serde(default = "default_boot_timeout_ms")]
    pub boot_timeout_ms: u64,
    /// Heartbeat period the drives are told to produce (object 0x1017), ms; 0 disables
    /// heartbeat supervision.
    #[serde(default = "default_heartbeat_ms")]
    pub heartbeat_ms: u16,
    /// Silence after which a drive counts as lost, ms (default: three heartbeat periods).
    #[serde(default)]
    pub heartbeat_timeout_ms: Option<u64>,
    /// How long each servo cycle waits for the drives' transmit PDOs after SYNC, ms
    /// (default: one servo period).
    #[serde(default)]
    pub pdo_wait_ms: Option<f64>,
    /// Consecutive cycles without a valid transmit PDO from a drive before it counts as lost.
    #[serde(default = "default_max_missed")]
    pub max_missed_pdos: u32,
    /// Time allowed for enable, disable and fault reset sequences, ms.
    #[serde(default = "default_state_timeout_ms")]
    pub state_timeout_ms: u64,
    /// How long start-up waits, sending SYNC every servo period, for the first transmit PDO
    /// of every drive, ms (a drive may take several SYNCs to answer after NMT start).
    #[serde(default = "default_tpdo_timeout_ms")]
    pub tpdo_timeout_ms: u64,
}

/// How the CAN bus is reached.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "adapter", rename_all = "lowercase", deny_unknown_fields)]
pub enum BusConfig {
    /// A Linux SocketCAN interface; its bitrate is set with `ip link`, and given here for
    /// the bus-load check.
    Socketcan {
        /// Interface name, e.g. `can0`.
        interface: String,
        /// Bitrate in bit/s.
        bitrate: u32,
    },
    /// An slcan (Lawicel) adapter on a serial port.
    Slcan {
        /// Serial device, e.g. `/dev/ttyACM0`.
        port: String,
        /// Bitrate in bit/s.
        bitrate: u32,
        /// Serial line speed (USB adapters ignore it).
        #[serde(default = "default_serial_baud")]
        serial_baud: u32,
    },
    /// Simulated drives on an in-memory bus (built by `klar_sim::cia402`).
    Sim {
        /// Bitrate in bit/s, for the bus-load check.
        #[serde(default = "default_bitrate")]
        bitrate: u32,
    },
    /// Simulated drives behind an slcan adapter emulated on a pseudo-terminal: the whole
    /// serial path of a real slcan adapter, with no hardware (built by the runtime from
    /// `klar_sim::cia402::serve_on_slcan`).
    #[serde(rename = "sim-slcan")]
    SimSlcan {
        /// Bitrate in bit/s, for the bus-load check.
        #[serde(default = "default_bitrate")]
        bitrate: u32,
    },
}

impl BusConfig {
    /// The bitrate in bit/s.
    pub fn bitrate(&self) -> u32 {
        match self {
            BusConfig::Socketcan { bitrate, .. }
            | BusConfig::Slcan { bitrate, .. }
            | BusConfig::Sim { bitrate }
            | BusConfig::SimSlcan { bitrate } => *bitrate,
        }
    }
}

/// One CiA 402 drive.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveConfig {
    /// CANopen node ID, 1..=127.
    pub node: u8,
    /// Encoder counts per mm (linear axis) or per degree (rotary axis), at the load.
    pub counts_per_unit: f64,
    /// True when positive counts move the axis in its negative direction.
    #[serde(default)]
    pub invert: bool,
    /// Following error window the drive enforces (object 0x6065), mm or degrees.
    #[serde(default)]
    pub following_error_window: Option<f64>,
    /// Homing: method and speeds (written to 0x6098, 0x6099, 0x609A, 0x607C).
    #[serde(default)]
    pub homing: Option<HomingConfig>,
    /// Mode of operation: cyclic synchronous position (the default), cyclic synchronous
    /// velocity (klar closes the position loop), or profile position for slow auxiliary
    /// axes. Profile velocity is accepted by the parser only to be refused with a clear
    /// message: it belongs to a spindle.
    #[serde(default)]
    pub mode: AxisMode,
    /// Cyclic synchronous velocity: gain of the position loop klar closes, 1/s (velocity
    /// command per unit of following error). Default [`DEFAULT_POSITION_GAIN`]; must be
    /// positive and, with the servo period T, satisfy gain·T ≤ [`MAX_GAIN_PERIOD_PRODUCT`].
    #[serde(default)]
    pub position_gain: Option<f64>,
    /// Profile position: velocity of the drive's own profile (0x6081), mm/s or degrees/s.
    #[serde(default)]
    pub profile_velocity: Option<f64>,
    /// Profile position: acceleration and deceleration of the drive's own profile
    /// (0x6083, 0x6084), mm/s² or degrees/s².
    #[serde(default)]
    pub profile_acceleration: Option<f64>,
    /// Quick-stop deceleration, mm/s² or degrees/s²: written at start-up as object 0x6085
    /// together with quick stop option code 6 (0x605A: brake on this ramp and stay in QUICK
    /// STOP ACTIVE), so that after a quick stop klar switches the drive off only once it
    /// stands still, or after the time this deceleration needs from the drive's speed.
    /// Unset: the drive keeps its own values.
    #[serde(default)]
    pub quick_stop_deceleration: Option<f64>,
    /// Receive PDO number used for controlword, target position and mode (1..=4).
    #[serde(default = "default_pdo_number")]
    pub rpdo: u16,
    /// Transmit PDO number used for statusword, actual position and mode display (1..=4).
    #[serde(default = "default_pdo_number")]
    pub tpdo: u16,
    /// True when the drive's position is referenced from power-on (an absolute encoder
    /// set up on the drive): the axis counts as homed without a homing run.
    #[serde(default)]
    pub absolute_encoder: bool,
}

/// How an axis drive follows the setpoints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AxisMode {
    /// Cyclic synchronous position: a new target every SYNC, interpolated by the drive.
    #[default]
    Csp,
    /// Profile position: the drive moves to the latest target on its own profile
    /// (velocity and acceleration from the configuration); for slow auxiliary axes.
    Pp,
    /// Cyclic synchronous velocity: a new target velocity every SYNC; klar closes the
    /// position loop on the actual position the drive reports.
    Csv,
    /// Profile velocity: refused for axes (the drive ramps on its own, so a path cannot be
    /// held); valid for a spindle ([`SpindleMode::Pv`]).
    Pv,
}

/// How a spindle drive follows the speed command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SpindleMode {
    /// Cyclic synchronous velocity: klar ramps the speed (at `acceleration`) and sends the
    /// ramped value every SYNC; at speed when the actual speed is inside the window.
    #[default]
    Csv,
    /// Profile velocity: klar sends the commanded speed, the drive ramps to it with its own
    /// profile acceleration (0x6083/0x6084, from `acceleration`); at speed when the drive
    /// reports "target reached" (statusword bit 10).
    Pv,
}

/// Default gain of the position loop klar closes around a CSV drive, 1/s.
pub const DEFAULT_POSITION_GAIN: f64 = 50.0;

/// Largest product of position gain (1/s) and servo period (s) accepted for a CSV axis.
///
/// Each cycle the error left after the feed-forward shrinks by the factor 1 − gain·T; at 1
/// it would be cancelled in one cycle (dead-beat), which leaves no margin for the drive's
/// velocity loop lag, and beyond 2 the loop diverges. Half of dead-beat keeps the
/// correction smooth.
pub const MAX_GAIN_PERIOD_PRODUCT: f64 = 0.5;

impl DriveConfig {
    /// Checks what can be checked without the bus: the mode suits an axis, and the CSV gain
    /// (if any) is positive, finite and fits `servo_period` (seconds; pass `None` to skip
    /// that part). The message names the node.
    pub fn check(&self, servo_period: Option<f64>) -> Result<(), String> {
        let node = self.node;
        if let Some(a) = self.quick_stop_deceleration
            && !(a.is_finite() && a > 0.0)
        {
            return Err(format!(
                "node {node}: quick_stop_deceleration must be a positive number (units/s²), \
                 got {a}"
            ));
        }
        match self.mode {
            AxisMode::Pv => {
                return Err(format!(
                    "node {node}: mode \"pv\" (profile velocity) cannot drive an axis: the \
                     drive ramps to a speed on its own, so klar cannot hold a path with it; use \
                     \"csp\" or \"csv\" (profile velocity is for a spindle: \
                     spindle drive mode = \"pv\")"
                ));
            }
            AxisMode::Csp | AxisMode::Pp if self.position_gain.is_some() => {
                return Err(format!(
                    "node {node}: position_gain applies only to mode = \"csv\" (in {:?} the \
                     drive closes the position loop)",
                    self.mode
                ));
            }
            AxisMode::Csp | AxisMode::Pp => return Ok(()),
            AxisMode::Csv => {}
        }
        let gain = self.gain();
        if !(gain.is_finite() && gain > 0.0) {
            return Err(format!(
                "node {node}: position_gain must be a positive number (1/s), got {gain}"
            ));
        }
        if let Some(t) = servo_period
            && gain * t > MAX_GAIN_PERIOD_PRODUCT
        {
            return Err(format!(
                "node {node}: position_gain {gain} 1/s is too high for a servo period of {t} s \
                 (at most {} 1/s)",
                MAX_GAIN_PERIOD_PRODUCT / t
            ));
        }
        Ok(())
    }

    /// The CSV position-loop gain, 1/s (the configured one or [`DEFAULT_POSITION_GAIN`]).
    pub fn gain(&self) -> f64 {
        self.position_gain.unwrap_or(DEFAULT_POSITION_GAIN)
    }
}

impl SpindleConfig {
    /// Checks what can be checked without the bus: the position PDO differs from the velocity PDO, and in profile
    /// velocity mode the drive needs a positive, finite acceleration for its own ramp.
    pub fn check(&self) -> Result<(), String> {
        if self.position_pdo() == self.tpdo {
            return Err(format!(
                "spindle node {}: position_tpdo {} is the transmit PDO of the velocity \
                 (tpdo); the position needs a PDO of its own",
                self.node, self.tpdo
            ));
        }
        let a = self.acceleration;
        if self.mode == SpindleMode::Pv && !(a.is_finite() && a > 0.0) {
            return Err(format!(
                "spindle node {}: mode \"pv\" needs a positive acceleration (rpm/s) for the \
                 drive's ramp, got {a}",
                self.node
            ));
        }
        Ok(())
    }

    /// The transmit PDO number carrying the actual position: `position_tpdo`, or the one
    /// after `tpdo` (4 wraps to 1).
    pub fn position_pdo(&self) -> u16 {
        self.position_tpdo.unwrap_or(self.tpdo % 4 + 1)
    }
}

/// A CiA 402 drive used as the spindle, in cyclic synchronous velocity mode (default) or
/// profile velocity mode.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpindleConfig {
    /// CANopen node ID, 1..=127.
    pub node: u8,
    /// Encoder counts per spindle revolution (at the spindle, gearing included): the
    /// scaling of the velocity (counts/s per rpm) and of the measured angle (0x6064).
    pub counts_per_rev: f64,
    /// True when positive counts turn the spindle counter-clockwise (M4).
    #[serde(default)]
    pub invert: bool,
    /// Mode of operation: `csv` (klar ramps the speed) or `pv` (the drive ramps).
    #[serde(default)]
    pub mode: SpindleMode,
    /// Acceleration of the speed ramp, rpm per second: the ramp klar sends in CSV, the
    /// drive's profile acceleration and deceleration (0x6083, 0x6084) in PV.
    #[serde(default = "default_spindle_acceleration")]
    pub acceleration: f64,
    /// At-speed window as a fraction of the commanded speed (CSV).
    #[serde(default = "default_at_speed_fraction")]
    pub at_speed_fraction: f64,
    /// Smallest at-speed window, rpm; in PV also the drive's velocity window (0x606D)
    /// behind "target reached".
    #[serde(default = "default_at_speed_min_rpm")]
    pub at_speed_min_rpm: f64,
    /// Receive PDO number used for controlword and target velocity (1..=4).
    #[serde(default = "default_pdo_number")]
    pub rpdo: u16,
    /// Transmit PDO number used for statusword and actual velocity (1..=4).
    #[serde(default = "default_pdo_number")]
    pub tpdo: u16,
    /// Transmit PDO number used for the actual position (0x6064), the measured spindle
    /// angle (1..=4, not `tpdo`; default: the one after `tpdo`, 4 wrapping to 1).
    #[serde(default)]
    pub position_tpdo: Option<u16>,
}

/// Homing parameters of one drive.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HomingConfig {
    /// CiA 402 homing method (e.g. 35/37: current position; 17/18: limit switch;
    /// 19–30: home switch; 1–14: with index pulse).
    pub method: i8,
    /// Speed while searching the switch, mm/s or degrees/s.
    #[serde(default = "default_search_speed")]
    pub speed_search: f64,
    /// Speed while searching zero (index pulse), mm/s or degrees/s.
    #[serde(default = "default_zero_speed")]
    pub speed_zero: f64,
    /// Homing acceleration, mm/s² or degrees/s².
    #[serde(default = "default_homing_acceleration")]
    pub acceleration: f64,
    /// Position the home point gets, mm or degrees.
    #[serde(default)]
    pub offset: f64,
}

fn default_sdo_timeout_ms() -> u64 {
    200
}
fn default_boot_timeout_ms() -> u64 {
    3000
}
fn default_heartbeat_ms() -> u16 {
    100
}
fn default_max_missed() -> u32 {
    3
}
fn default_state_timeout_ms() -> u64 {
    1000
}
fn default_tpdo_timeout_ms() -> u64 {
    500
}
fn default_serial_baud() -> u32 {
    115_200
}
fn default_bitrate() -> u32 {
    1_000_000
}
fn default_pdo_number() -> u16 {
    1
}
fn default_spindle_acceleration() -> f64 {
    2000.0
}
fn default_at_speed_fraction() -> f64 {
    0.02
}
fn default_at_speed_min_rpm() -> f64 {
    5.0
}
fn default_search_speed() -> f64 {
    10.0
}
fn default_zero_speed() -> f64 {
    1.0
}
fn default_homing_acceleration() -> f64 {
    100.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drive(extra: &str) -> DriveConfig {
        toml::from_str(&format!("node = 7\ncounts_per_unit = 1000.0\n{extra}")).expect("parses")
    }

    #[test]
    fn csv_gain_defaults_and_range() {
        let d = drive("mode = \"csv\"\n");
        assert_eq!(d.gain(), DEFAULT_POSITION_GAIN);
        assert!(d.check(Some(0.001)).is_ok());
        // 0.5 / 2 ms = 250 1/s is the largest gain at 2 ms.
        assert!(
            drive("mode = \"csv\"\nposition_gain = 250.0\n")
                .check(Some(0.002))
                .is_ok()
        );
        let e = drive("mode = \"csv\"\nposition_gain = 251.0\n")
            .check(Some(0.002))
            .expect_err("too high");
        assert!(e.contains("node 7") && e.contains("250"), "{e}");
        for bad in ["0.0", "-1.0", "inf"] {
            let e = drive(&format!("mode = \"csv\"\nposition_gain = {bad}\n"))
                .check(None)
                .expect_err(bad);
            assert!(e.contains("position_gain"), "{e}");
        }
    }

    #[test]
    fn profile_velocity_is_for_spindles_only() {
        let e = drive("mode = \"pv\"\n").check(None).expect_err("pv axis");
        assert!(e.contains("node 7") && e.contains("spindle"), "{e}");
        let s: SpindleConfig =
            toml::from_str("node = 5\ncounts_per_rev = 4096.0\nmode = \"pv\"\n").expect("parses");
        assert_eq!(s.mode, SpindleMode::Pv);
        assert!(s.check().is_ok());
        // A CSP axis with a gain is a mistake worth a message; without one it is fine at any
        // period.
        assert!(drive("position_gain = 20.0\n").check(None).is_err());
        assert!(drive("").check(Some(1.0)).is_ok());
    }
}
