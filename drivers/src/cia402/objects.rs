//! CiA 402 object dictionary indices and the mode-of-operation codes klar uses.

/// Controlword (u16).
pub const CONTROLWORD: u16 = 0x6040;
/// Statusword (u16).
pub const STATUSWORD: u16 = 0x6041;
/// Quick stop option code (i16).
pub const QUICK_STOP_OPTION: u16 = 0x605A;
/// Quick stop option code 6: brake on the quick-stop deceleration (0x6085) and stay in
/// QUICK STOP ACTIVE (the master switches the drive off once it stands still).
pub const QUICK_STOP_HOLD_OPTION: i16 = 6;
/// Modes of operation (i8).
pub const MODES_OF_OPERATION: u16 = 0x6060;
/// Modes of operation display (i8).
pub const MODES_DISPLAY: u16 = 0x6061;
/// Position actual value (i32, counts).
pub const POSITION_ACTUAL: u16 = 0x6064;
/// Following error window (u32, counts).
pub const FOLLOWING_ERROR_WINDOW: u16 = 0x6065;
/// Velocity actual value (i32, counts/s).
pub const VELOCITY_ACTUAL: u16 = 0x606C;
/// Velocity window (u32, counts/s): profile velocity "target reached" holds while the
/// actual velocity stays this close to the target.
pub const VELOCITY_WINDOW: u16 = 0x606D;
/// Velocity window time (u16, ms): how long the actual velocity must stay in the window
/// before "target reached" is set.
pub const VELOCITY_WINDOW_TIME: u16 = 0x606E;
/// Velocity threshold (u16, counts/s): below it profile velocity reports "speed = 0"
/// (statusword bit 12).
pub const VELOCITY_THRESHOLD: u16 = 0x606F;
/// Target position (i32, counts).
pub const TARGET_POSITION: u16 = 0x607A;
/// Home offset (i32, counts).
pub const HOME_OFFSET: u16 = 0x607C;
/// Profile velocity (u32, counts/s) for profile position mode.
pub const PROFILE_VELOCITY: u16 = 0x6081;
/// Profile acceleration (u32, counts/s²), for profile position and profile velocity.
pub const PROFILE_ACCELERATION: u16 = 0x6083;
/// Profile deceleration (u32, counts/s²).
pub const PROFILE_DECELERATION: u16 = 0x6084;
/// Quick stop deceleration (u32, counts/s²).
pub const QUICK_STOP_DECELERATION: u16 = 0x6085;
/// Homing method (i8).
pub const HOMING_METHOD: u16 = 0x6098;
/// Homing speeds (u32, counts/s): sub 1 search for switch, sub 2 search for zero.
pub const HOMING_SPEEDS: u16 = 0x6099;
/// Homing acceleration (u32, counts/s²).
pub const HOMING_ACCELERATION: u16 = 0x609A;
/// Interpolation time period: sub 1 value (u8), sub 2 index (i8, power of ten of seconds).
pub const INTERPOLATION_PERIOD: u16 = 0x60C2;
/// Following error actual value (i32, counts).
pub const FOLLOWING_ERROR_ACTUAL: u16 = 0x60F4;
/// Target velocity (i32, counts/s) for CSV and profile velocity.
pub const TARGET_VELOCITY: u16 = 0x60FF;
/// Error code (u16): the last error, as in EMCY.
pub const ERROR_CODE: u16 = 0x603F;
/// Producer heartbeat time (u16, ms), CiA 301.
pub const PRODUCER_HEARTBEAT: u16 = 0x1017;

/// Touch probe function (u16, CiA 402-2): how the drive's touch-probe latches are armed.
pub const TOUCH_PROBE_FUNCTION: u16 = 0x60B8;
/// Touch probe status (u16): which latches are enabled and which hold a value.
pub const TOUCH_PROBE_STATUS: u16 = 0x60B9;
/// Touch probe 1 position latched at the positive edge (i32, counts).
pub const TOUCH_PROBE_1_POSITIVE: u16 = 0x60BA;
/// Touch probe 1 position latched at the negative edge (i32, counts).
pub const TOUCH_PROBE_1_NEGATIVE: u16 = 0x60BB;

/// 0x60B8 bit 0: touch probe 1 enabled.
pub const TP_ENABLE: u16 = 1 << 0;
/// 0x60B8 bit 1: keep latching every event (continuous); clear: only the first event.
pub const TP_CONTINUOUS: u16 = 1 << 1;
/// 0x60B8 bits 2–3: the trigger source of touch probe 1 (0: its touch-probe input).
pub const TP_SOURCE_MASK: u16 = 0b11 << 2;
/// 0x60B8 bit 4: latch at the positive edge of touch probe 1.
pub const TP_POSITIVE_EDGE: u16 = 1 << 4;
/// 0x60B8 bit 5: latch at the negative edge of touch probe 1.
pub const TP_NEGATIVE_EDGE: u16 = 1 << 5;
/// 0x60B9 bit 0: touch probe 1 is enabled.
pub const TPS_ENABLED: u16 = 1 << 0;
/// 0x60B9 bit 1: touch probe 1 holds a position latched at a positive edge (0x60BA).
pub const TPS_POSITIVE_STORED: u16 = 1 << 1;
/// 0x60B9 bit 2: touch probe 1 holds a position latched at a negative edge (0x60BB).
pub const TPS_NEGATIVE_STORED: u16 = 1 << 2;

/// Mode of operation: profile position.
pub const MODE_PROFILE_POSITION: i8 = 1;
/// Mode of operation: profile velocity.
pub const MODE_PROFILE_VELOCITY: i8 = 3;
/// Mode of operation: homing.
pub const MODE_HOMING: i8 = 6;
/// Mode of operation: cyclic synchronous position.
pub const MODE_CSP: i8 = 8;
/// Mode of operation: cyclic synchronous velocity.
pub const MODE_CSV: i8 = 9;

/// The interpolation period as (value, index) with value·10^index seconds = `period`,
/// choosing the largest index (coarsest unit, from 0.1 s down to 1 µs) that represents it
/// exactly in a u8; `None` if no such pair exists.
pub fn interpolation_period(period: f64) -> Option<(u8, i8)> {
    for index in [-1i8, -2, -3, -4, -5, -6] {
        let value = period / 10f64.powi(i32::from(index));
        let rounded = value.round();
        if (value - rounded).abs() < 1e-6 && (1.0..=255.0).contains(&rounded) {
            return Some((rounded as u8, index));
        }
    }
    None
}
