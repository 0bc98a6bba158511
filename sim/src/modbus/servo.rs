//! A simulated positioning servo drive answering Modbus RTU with a configured
//! [`ServoRegisterMap`]: it runs its own trapezoidal point-to-point profile toward the
//! last target written and feeds it to a [`ServoPlant`], as a real positioning drive does.

use klar_drivers::modbus::words::{bit, i32_to_words, units_to_counts, with_bit, words_to_i32};
use klar_drivers::modbus::{RegisterTable, ServoRegisterMap};
use klar_motion::{AxisFault, AxisState, Setpoint};
use tokio_modbus::prelude::ExceptionCode;

use super::bus::{ModbusDevice, addresses};
use crate::plant::{ServoPlant, SimAxisParams};

/// Internal control period of the simulated drive, seconds.
pub const DRIVE_PERIOD: f64 = 0.001;

/// Longest stretch of time simulated per request (a client that stops polling does not
/// make the next request compute minutes of motion).
const MAX_CATCH_UP: f64 = 2.0;

/// Profile limits of the simulated positioning drive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PositioningLimits {
    /// Maximum profile velocity, units/s.
    pub velocity: f64,
    /// Profile acceleration, units/s².
    pub acceleration: f64,
}

impl Default for PositioningLimits {
    fn default() -> Self {
        Self {
            velocity: 90.0,
            acceleration: 360.0,
        }
    }
}

/// Fault codes the simulated drive reports in its fault-code register.
pub fn fault_code(fault: &AxisFault) -> u16 {
    match fault {
        AxisFault::FollowingError(_) => 0x0101,
        AxisFault::LimitSwitch { positive: true } => 0x0201,
        AxisFault::LimitSwitch { positive: false } => 0x0202,
        AxisFault::Drive { code, .. } => u16::try_from(*code).unwrap_or(0xFFFF),
        AxisFault::EStop => 0x0301,
        AxisFault::CommunicationLost => 0x0401,
        AxisFault::DeviceException { .. } => 0x0402,
    }
}

/// A simulated Modbus positioning drive.
#[derive(Debug, Clone)]
pub struct SimModbusServo {
    map: ServoRegisterMap,
    plant: ServoPlant,
    limits: PositioningLimits,
    target: f64,
    profile_position: f64,
    profile_velocity: f64,
    control: u16,
    target_words: [u16; 2],
    last_now: Option<f64>,
    responds: bool,
}

impl SimModbusServo {
    /// A drive at rest at `position`, disabled.
    pub fn new(
        map: ServoRegisterMap,
        params: SimAxisParams,
        limits: PositioningLimits,
        position: f64,
    ) -> Self {
        let plant = ServoPlant::new(params, position);
        let start = plant.measured_position();
        let counts = units_to_counts(start, map.counts_per_unit);
        Self {
            target_words: i32_to_words(counts, map.word_order),
            map,
            plant,
            limits,
            target: start,
            profile_position: start,
            profile_velocity: 0.0,
            control: 0,
            last_now: None,
            responds: true,
        }
    }

    /// The plant (for inspection).
    pub fn plant(&self) -> &ServoPlant {
        &self.plant
    }

    /// The plant (for fault injection).
    pub fn plant_mut(&mut self) -> &mut ServoPlant {
        &mut self.plant
    }

    /// The last target written by the client, machine units.
    pub fn target(&self) -> f64 {
        self.target
    }

    /// Makes the drive stop (false) or resume (true) answering.
    pub fn set_responding(&mut self, responds: bool) {
        self.responds = responds;
    }

    fn advance(&mut self, now: f64) {
        let Some(last) = self.last_now.replace(now) else {
            return;
        };
        let mut remaining = (now - last).clamp(0.0, MAX_CATCH_UP);
        while remaining > 0.0 {
            let dt = remaining.min(DRIVE_PERIOD);
            remaining -= dt;
            self.drive_step(dt);
        }
    }

    /// One control period: advance the profile toward the target, step the plant.
    fn drive_step(&mut self, dt: f64) {
        let following = matches!(self.plant.state(), AxisState::Enabled);
        if !following {
            // Not following: the profile tracks the axis so enabling never jumps.
            self.profile_position = self.plant.measured_position();
            self.profile_velocity = 0.0;
        } else {
            let (p, v, a) = profile_step(
                self.profile_position,
                self.profile_velocity,
                self.target,
                self.limits,
                dt,
            );
            self.profile_position = p;
            self.profile_velocity = v;
            let sp = Setpoint {
                position: p,
                velocity: v,
                acceleration: a,
            };
            self.plant.step(sp, dt);
            return;
        }
        let hold = Setpoint {
            position: self.profile_position,
            velocity: 0.0,
            acceleration: 0.0,
        };
        self.plant.step(hold, dt);
    }

    fn status_word(&self) -> u16 {
        let m = &self.map;
        let state = self.plant.state();
        let mut s = with_bit(
            0,
            m.enabled_bit,
            matches!(state, AxisState::Enabled | AxisState::Homing),
        );
        s = with_bit(s, m.fault_bit, state == AxisState::Faulted);
        if let Some(h) = m.homed_bit {
            s = with_bit(s, h, self.plant.homed());
        }
        s
    }

    fn actual_words(&self) -> [u16; 2] {
        let counts = units_to_counts(self.plant.measured_position(), self.map.counts_per_unit);
        i32_to_words(counts, self.map.word_order)
    }

    fn read_one(&self, table: RegisterTable, address: u16) -> Result<u16, ExceptionCode> {
        let m = &self.map;
        let t = m.target_position;
        if table == RegisterTable::Holding {
            if address == t {
                return Ok(self.target_words[0]);
            }
            if Some(address) == t.checked_add(1) {
                return Ok(self.target_words[1]);
            }
            if address == m.control {
                return Ok(self.control);
            }
        }
        if table != m.status_table {
            return Err(ExceptionCode::IllegalDataAddress);
        }
        let actual = self.actual_words();
        if address == m.actual_position {
            Ok(actual[0])
        } else if Some(address) == m.actual_position.checked_add(1) {
            Ok(actual[1])
        } else if address == m.status {
            Ok(self.status_word())
        } else if Some(address) == m.fault_code {
            Ok(self.plant.fault().map_or(0, fault_code))
        } else {
            Err(ExceptionCode::IllegalDataAddress)
        }
    }

    fn write_control(&mut self, word: u16) {
        let m = self.map.clone();
        let old = self.control;
        self.control = word;
        let rising = |b: u8| bit(word, b) && !bit(old, b);
        if rising(m.fault_reset_bit) {
            let _ = self.plant.reset_fault();
        }
        if bit(word, m.enable_bit)
            && self.plant.state() == AxisState::Disabled
            && rising(m.enable_bit)
        {
            self.profile_position = self.plant.measured_position();
            self.profile_velocity = 0.0;
            let _ = self.plant.enable();
        } else if !bit(word, m.enable_bit) && bit(old, m.enable_bit) {
            self.plant.disable();
        }
        if let Some(h) = m.home_bit
            && rising(h)
        {
            let _ = self.plant.start_homing();
        }
    }
}

/// One step of a trapezoidal profile from (`p`, `v`) toward `target`: returns the new
/// position, velocity and the acceleration used. The braking speed accounts for the
/// travel within the step, so the profile never needs more than the acceleration limit
/// to stop at the target.
pub fn profile_step(
    p: f64,
    v: f64,
    target: f64,
    limits: PositioningLimits,
    dt: f64,
) -> (f64, f64, f64) {
    let a = limits.acceleration;
    let d = target - p;
    if d == 0.0 && v.abs() <= a * dt {
        return (target, 0.0, -v / dt);
    }
    // Work along the direction of the remaining travel.
    let s = if d >= 0.0 { 1.0 } else { -1.0 };
    let (distance, speed) = (d.abs(), v * s);
    // Largest speed after this step from which braking at `a` still stops at the target:
    // v'^2 = 2 a (D - (V + v') dt / 2).
    let room = (distance - speed * dt / 2.0).max(0.0);
    let brake = (-a * dt + (a * a * dt * dt + 8.0 * a * room).sqrt()) / 2.0;
    let want = brake.min(limits.velocity);
    let next = want.clamp(speed - a * dt, speed + a * dt);
    let travelled = (speed + next) / 2.0 * dt;
    let remaining = distance - travelled;
    // Arrive when the rest fits in this step and stopping is within the limit.
    let can_stop = speed <= a * dt * (1.0 + 1e-9);
    if can_stop && (distance <= speed.max(0.0) * dt || remaining <= 1e-12) {
        (target, 0.0, -v / dt)
    } else {
        (p + s * travelled, s * next, s * (next - speed) / dt)
    }
}

impl ModbusDevice for SimModbusServo {
    fn read(
        &mut self,
        table: RegisterTable,
        address: u16,
        count: u16,
        now: f64,
    ) -> Result<Vec<u16>, ExceptionCode> {
        self.advance(now);
        addresses(address, usize::from(count))
            .map(|a| self.read_one(table, a?))
            .collect()
    }

    fn write(&mut self, address: u16, values: &[u16], now: f64) -> Result<(), ExceptionCode> {
        self.advance(now);
        let t = self.map.target_position;
        for (a, v) in addresses(address, values.len()).zip(values) {
            let a = a?;
            if a == t {
                self.target_words[0] = *v;
            } else if Some(a) == t.checked_add(1) {
                self.target_words[1] = *v;
            } else if a == self.map.control {
                self.write_control(*v);
            } else {
                return Err(ExceptionCode::IllegalDataAddress);
            }
        }
        let counts = words_to_i32(self.target_words, self.map.word_order);
        self.target = f64::from(counts) / self.map.counts_per_unit;
        Ok(())
    }

    fn responds(&self) -> bool {
        self.responds
    }
}
