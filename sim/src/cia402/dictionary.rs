//! The object dictionary a simulated CiA 402 drive starts with (and returns to on NMT
//! reset): identity, heartbeat, four receive and four transmit PDOs (PDO 1 valid with
//! controlword / statusword, the others invalid), and the CiA 402 objects the simulation
//! implements.

use klar_drivers::canopen::pdo::COB_INVALID;
use klar_drivers::cia402::objects::*;

use super::od::{Access, ObjectDictionary};

/// The dictionary of node `node` whose position scaling is `counts_per_unit` counts per
/// unit (it sets the default velocity window, 60 units/s, and velocity threshold).
pub(crate) fn drive_dictionary(node: u8, counts_per_unit: f64) -> ObjectDictionary {
    let n = u32::from(node);
    let mut od = ObjectDictionary::new();
    let rw = Access::ReadWrite;
    let ro = Access::ReadOnly;
    od.add(0x1000, 0, &0x0002_0192u32.to_le_bytes(), ro, false);
    od.add(0x1001, 0, &[0], ro, true);
    od.add(0x1006, 0, &0u32.to_le_bytes(), rw, false);
    od.add_bytes(0x1008, 0, b"klar simulated CiA 402 drive", ro);
    od.add(PRODUCER_HEARTBEAT, 0, &0u16.to_le_bytes(), rw, false);
    for p in 0..4u16 {
        let rx_cob = (0x200 + 0x100 * u32::from(p) + n) | if p == 0 { 0 } else { COB_INVALID };
        let tx_cob = (0x180 + 0x100 * u32::from(p) + n) | if p == 0 { 0 } else { COB_INVALID };
        for (comm, map, cob) in [
            (0x1400 + p, 0x1600 + p, rx_cob),
            (0x1800 + p, 0x1A00 + p, tx_cob),
        ] {
            od.add(comm, 0, &[2], ro, false);
            od.add(comm, 1, &cob.to_le_bytes(), rw, false);
            od.add(comm, 2, &[0xFF], rw, false);
            od.add(map, 0, &[0], rw, false);
            for s in 1..=8 {
                od.add(map, s, &0u32.to_le_bytes(), rw, false);
            }
        }
    }
    // Default mapping of PDO 1: controlword / statusword only.
    od.set(0x1600, 1, 0x6040_0010);
    od.set(0x1600, 0, 1);
    od.set(0x1A00, 1, 0x6041_0010);
    od.set(0x1A00, 0, 1);
    od.add(ERROR_CODE, 0, &0u16.to_le_bytes(), ro, true);
    od.add(CONTROLWORD, 0, &0u16.to_le_bytes(), rw, true);
    od.add(STATUSWORD, 0, &0u16.to_le_bytes(), ro, true);
    od.add(QUICK_STOP_OPTION, 0, &2i16.to_le_bytes(), rw, false);
    od.add(MODES_OF_OPERATION, 0, &[0], rw, true);
    od.add(MODES_DISPLAY, 0, &[0], ro, true);
    od.add(POSITION_ACTUAL, 0, &0i32.to_le_bytes(), ro, true);
    od.add(
        FOLLOWING_ERROR_WINDOW,
        0,
        &u32::MAX.to_le_bytes(),
        rw,
        false,
    );
    od.add(VELOCITY_ACTUAL, 0, &0i32.to_le_bytes(), ro, true);
    od.add(TARGET_POSITION, 0, &0i32.to_le_bytes(), rw, true);
    od.add(HOME_OFFSET, 0, &0i32.to_le_bytes(), rw, false);
    od.add(PROFILE_VELOCITY, 0, &0u32.to_le_bytes(), rw, false);
    od.add(PROFILE_ACCELERATION, 0, &0u32.to_le_bytes(), rw, false);
    od.add(PROFILE_DECELERATION, 0, &0u32.to_le_bytes(), rw, false);
    od.add(QUICK_STOP_DECELERATION, 0, &0u32.to_le_bytes(), rw, false);
    od.add(HOMING_METHOD, 0, &[35], rw, false);
    od.add(HOMING_SPEEDS, 0, &[2], ro, false);
    od.add(HOMING_SPEEDS, 1, &0u32.to_le_bytes(), rw, false);
    od.add(HOMING_SPEEDS, 2, &0u32.to_le_bytes(), rw, false);
    od.add(HOMING_ACCELERATION, 0, &0u32.to_le_bytes(), rw, false);
    od.add(INTERPOLATION_PERIOD, 0, &[2], ro, false);
    od.add(INTERPOLATION_PERIOD, 1, &[1], rw, false);
    od.add(INTERPOLATION_PERIOD, 2, &[(-3i8) as u8], rw, false);
    od.add(FOLLOWING_ERROR_ACTUAL, 0, &0i32.to_le_bytes(), ro, true);
    od.add(TARGET_VELOCITY, 0, &0i32.to_le_bytes(), rw, true);
    od.add(TOUCH_PROBE_FUNCTION, 0, &0u16.to_le_bytes(), rw, true);
    od.add(TOUCH_PROBE_STATUS, 0, &0u16.to_le_bytes(), ro, true);
    od.add(TOUCH_PROBE_1_POSITIVE, 0, &0i32.to_le_bytes(), ro, true);
    od.add(TOUCH_PROBE_1_NEGATIVE, 0, &0i32.to_le_bytes(), ro, true);
    // Velocity window: 60 units/s (10 rpm on a rotary axis).
    let window = (60.0 * counts_per_unit).round() as u32;
    od.add(VELOCITY_WINDOW, 0, &window.to_le_bytes(), rw, false);
    od.add(VELOCITY_WINDOW_TIME, 0, &0u16.to_le_bytes(), rw, false);
    od.add(
        VELOCITY_THRESHOLD,
        0,
        &(window.min(u32::from(u16::MAX)) as u16).to_le_bytes(),
        rw,
        false,
    );
    od
}
