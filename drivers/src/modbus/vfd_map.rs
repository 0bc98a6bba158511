//! VFD register maps: what to write for a speed command and how to read the status, for
//! the generic profile and the Delta family. Pure functions, no I/O.
//!
//! Delta (VFD-E / VFD-M / MS300 communication map, from the Delta user manuals):
//! - 2000H command: bits 0-1 `01` stop, `10` run; bits 4-5 `01` forward, `10` reverse.
//! - 2001H frequency command, 0.01 Hz.
//! - 2002H bit 1: fault reset.
//! - 2100H error code (0: none).
//! - 2101H status: bits 0-1 `00` stopped, `01` decelerating, `10` standby, `11` running;
//!   bits 3-4 `00` forward, `01` reverse→forward, `10` forward→reverse, `11` reverse.
//! - 2103H output frequency, 0.01 Hz.

use super::words::{bit, with_bit};
use super::{GenericVfdRegisters, RegisterTable, VfdPreset, image::RegisterImage};

/// Delta command register.
pub const DELTA_COMMAND: u16 = 0x2000;
/// Delta frequency command register (0.01 Hz).
pub const DELTA_FREQUENCY: u16 = 0x2001;
/// Delta fault-reset register.
pub const DELTA_RESET: u16 = 0x2002;
/// Delta error-code register.
pub const DELTA_ERROR: u16 = 0x2100;
/// Delta status register.
pub const DELTA_STATUS: u16 = 0x2101;
/// Delta output-frequency register (0.01 Hz).
pub const DELTA_OUTPUT_FREQUENCY: u16 = 0x2103;

/// Delta command word: run forward.
pub const DELTA_RUN_FORWARD: u16 = 0b01_0010;
/// Delta command word: run reverse.
pub const DELTA_RUN_REVERSE: u16 = 0b10_0010;
/// Delta command word: stop.
pub const DELTA_STOP: u16 = 0b00_0001;

/// What a VFD reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VfdStatus {
    /// Output running.
    pub running: bool,
    /// Measured speed, rpm, signed (negative: counter-clockwise).
    pub rpm: f64,
    /// Fault code, if the VFD is in fault.
    pub fault_code: Option<u16>,
}

/// A VFD register map ready to use.
#[derive(Debug, Clone, PartialEq)]
pub enum VfdProfile {
    /// The generic map.
    Generic(GenericVfdRegisters),
    /// The Delta family map.
    Delta {
        /// rpm per Hz.
        rpm_per_hz: f64,
    },
}

impl VfdProfile {
    /// The profile a configured preset selects.
    pub fn from_preset(preset: &VfdPreset) -> Self {
        match preset {
            VfdPreset::Generic { registers } => VfdProfile::Generic(registers.clone()),
            VfdPreset::Delta { rpm_per_hz } => VfdProfile::Delta {
                rpm_per_hz: *rpm_per_hz,
            },
        }
    }

    /// Register writes, in order, that command `rpm` (signed; 0 stops). The speed is
    /// written before the run command so the drive never runs at a stale speed.
    pub fn command_writes(&self, rpm: f64) -> Vec<(u16, u16)> {
        let magnitude = if rpm.is_finite() { rpm.abs() } else { 0.0 };
        match self {
            VfdProfile::Generic(r) => {
                let speed = to_register(magnitude * r.units_per_rpm);
                let control = if speed == 0 {
                    0
                } else {
                    with_bit(with_bit(0, r.run_bit, true), r.reverse_bit, rpm < 0.0)
                };
                vec![(r.speed_setpoint, speed), (r.control, control)]
            }
            VfdProfile::Delta { rpm_per_hz } => {
                let centi_hz = to_register(magnitude / rpm_per_hz * 100.0);
                let command = if centi_hz == 0 {
                    DELTA_STOP
                } else if rpm < 0.0 {
                    DELTA_RUN_REVERSE
                } else {
                    DELTA_RUN_FORWARD
                };
                vec![(DELTA_FREQUENCY, centi_hz), (DELTA_COMMAND, command)]
            }
        }
    }

    /// Register writes, in order, that acknowledge a fault.
    pub fn fault_reset_writes(&self) -> Vec<(u16, u16)> {
        match self {
            VfdProfile::Generic(r) => vec![
                (r.control, with_bit(0, r.fault_reset_bit, true)),
                (r.control, 0),
            ],
            VfdProfile::Delta { .. } => vec![(DELTA_RESET, 0b10), (DELTA_RESET, 0)],
        }
    }

    /// The table and addresses to read for [`Self::decode`].
    pub fn status_addresses(&self) -> (RegisterTable, Vec<u16>) {
        match self {
            VfdProfile::Generic(r) => {
                (r.status_table, vec![r.status, r.actual_speed, r.fault_code])
            }
            VfdProfile::Delta { .. } => (
                RegisterTable::Holding,
                vec![DELTA_ERROR, DELTA_STATUS, DELTA_OUTPUT_FREQUENCY],
            ),
        }
    }

    /// Interprets the registers read; `None` when one is missing from the image.
    pub fn decode(&self, image: &RegisterImage) -> Option<VfdStatus> {
        match self {
            VfdProfile::Generic(r) => {
                let status = image.get(r.status)?;
                let speed = f64::from(image.get(r.actual_speed)?) / r.units_per_rpm;
                let fault = bit(status, r.fault_bit);
                let reverse = bit(status, r.reverse_status_bit);
                Some(VfdStatus {
                    running: bit(status, r.running_bit),
                    rpm: if reverse { -speed } else { speed },
                    fault_code: fault.then(|| image.get(r.fault_code).unwrap_or(0)),
                })
            }
            VfdProfile::Delta { rpm_per_hz } => {
                let error = image.get(DELTA_ERROR)?;
                let status = image.get(DELTA_STATUS)?;
                let hz = f64::from(image.get(DELTA_OUTPUT_FREQUENCY)?) / 100.0;
                // Bits 3-4: 01 and 11 mean the shaft still turns in reverse.
                let reverse = bit(status, 3);
                let speed = hz * rpm_per_hz;
                Some(VfdStatus {
                    running: status & 0b11 == 0b11,
                    rpm: if reverse { -speed } else { speed },
                    fault_code: (error != 0).then_some(error),
                })
            }
        }
    }
}

/// Rounds a non-negative value into a register, saturating at 0xFFFF.
fn to_register(value: f64) -> u16 {
    let v = value.round();
    if v.is_nan() || v <= 0.0 {
        0
    } else {
        v.min(f64::from(u16::MAX)) as u16
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delta_commands_follow_the_manual_bit_layout() {
        let p = VfdProfile::Delta { rpm_per_hz: 60.0 };
        // 12000 rpm / 60 = 200 Hz = 20000 x 0.01 Hz; run (bits 0-1 = 10) forward (bits 4-5 = 01).
        assert_eq!(
            p.command_writes(12_000.0),
            vec![(0x2001, 20_000), (0x2000, 0x12)]
        );
        assert_eq!(
            p.command_writes(-600.0),
            vec![(0x2001, 1_000), (0x2000, 0x22)]
        );
        assert_eq!(p.command_writes(0.0), vec![(0x2001, 0), (0x2000, 0x01)]);
    }

    #[test]
    fn delta_status_decodes_direction_and_speed() {
        let p = VfdProfile::Delta { rpm_per_hz: 30.0 };
        // Running (11), reverse (bits 3-4 = 11), 100.00 Hz.
        let img = RegisterImage::from_pairs([(0x2100, 0), (0x2101, 0b1_1011), (0x2103, 10_000)]);
        let s = p.decode(&img);
        assert_eq!(
            s,
            Some(VfdStatus {
                running: true,
                rpm: -3000.0,
                fault_code: None
            })
        );
        let img = RegisterImage::from_pairs([(0x2100, 7), (0x2101, 0), (0x2103, 0)]);
        assert_eq!(p.decode(&img).and_then(|s| s.fault_code), Some(7));
        assert_eq!(p.decode(&RegisterImage::default()), None);
    }

    #[test]
    fn generic_commands_use_configured_bits() {
        let p = VfdProfile::Generic(GenericVfdRegisters::default());
        assert_eq!(p.command_writes(1500.4), vec![(1, 1500), (0, 0b01)]);
        assert_eq!(p.command_writes(-20.0), vec![(1, 20), (0, 0b11)]);
        assert_eq!(p.command_writes(f64::NAN), vec![(1, 0), (0, 0)]);
        assert_eq!(p.fault_reset_writes(), vec![(0, 0b100), (0, 0)]);
    }
}
