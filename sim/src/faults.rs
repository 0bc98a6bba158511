//! Fault injection for simulated axes: what can go wrong with a real axis (a drive fault, a
//! lost link, a noisy encoder, a jammed slide, a limit switch, the e-stop chain), scheduled at
//! a machine time and applied by [`crate::axis::SimBackend`] at the start of the cycle that
//! reaches it.
//!
//! Everything here is deterministic: the encoder noise comes from a seeded generator, so a
//! fault run repeats bit for bit.

use klar_motion::AxisFault;

/// Drive fault code used when a schedule asks for a drive fault without a code of its own.
pub const FAULT_INJECTED: u32 = 0xF0F0;

/// One fault that can be injected into a simulated axis.
#[derive(Debug, Clone, PartialEq)]
pub enum InjectedFault {
    /// The drive reports a fault with this code and brakes at its force limit.
    Drive {
        /// Fault code reported.
        code: u32,
    },
    /// The link to the drive is lost: the drive stops on its own (braking at its force
    /// limit) and the control receives no fresh feedback until the link is repaired.
    CommunicationLost,
    /// The encoder reading jumps by a random whole number of counts up to `amplitude` either
    /// way on every control substep.
    EncoderNoise {
        /// Largest deviation in encoder counts.
        amplitude: u32,
    },
    /// The slide jams: it stops dead and no force moves it until repaired.
    Stuck,
    /// The limit switch in the direction of motion trips (positive when standing still).
    LimitSwitch,
    /// The e-stop chain opens: every axis of the backend faults and brakes.
    EStop,
}

impl InjectedFault {
    /// A short name for reports: `drive`, `comm`, `noise`, `stuck`, `limit`, `estop`.
    pub fn name(&self) -> &'static str {
        match self {
            InjectedFault::Drive { .. } => "drive",
            InjectedFault::CommunicationLost => "comm",
            InjectedFault::EncoderNoise { .. } => "noise",
            InjectedFault::Stuck => "stuck",
            InjectedFault::LimitSwitch => "limit",
            InjectedFault::EStop => "estop",
        }
    }

    /// The drive fault a [`InjectedFault::Drive`] raises.
    pub(crate) fn drive_fault(code: u32) -> AxisFault {
        AxisFault::Drive {
            code,
            text: "injected drive fault".into(),
        }
    }
}

/// A fault due at a machine time on one axis (index in the backend's axis order; ignored for
/// the e-stop, which hits every axis).
#[derive(Debug, Clone, PartialEq)]
pub struct ScheduledFault {
    /// Machine time in seconds at which the fault strikes.
    pub at: f64,
    /// Axis index within the backend.
    pub axis: usize,
    /// What happens.
    pub fault: InjectedFault,
}

/// Faults waiting for their time, earliest first.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FaultSchedule {
    pending: Vec<ScheduledFault>,
}

impl FaultSchedule {
    /// A schedule of `faults` in any order; faults with a non-finite time never strike.
    pub fn new(mut faults: Vec<ScheduledFault>) -> Self {
        faults.retain(|f| f.at.is_finite());
        faults.sort_by(|a, b| a.at.total_cmp(&b.at));
        Self { pending: faults }
    }

    /// True when no fault is waiting.
    pub fn is_empty(&self) -> bool {
        self.pending.is_empty()
    }

    /// Removes and returns every fault due at or before machine time `t`.
    pub fn take_due(&mut self, t: f64) -> Vec<ScheduledFault> {
        let n = self.pending.iter().take_while(|f| f.at <= t).count();
        self.pending.drain(..n).collect()
    }
}

/// Deterministic encoder noise: a xorshift64* sequence mapped to whole counts in
/// `[-amplitude, amplitude]`.
#[derive(Debug, Clone, PartialEq)]
pub struct EncoderNoise {
    amplitude: u32,
    state: u64,
}

impl EncoderNoise {
    /// Noise up to `amplitude` counts from a seed (a zero seed is replaced by a fixed one).
    pub fn new(amplitude: u32, seed: u64) -> Self {
        Self {
            amplitude,
            state: if seed == 0 {
                0x9E37_79B9_7F4A_7C15
            } else {
                seed
            },
        }
    }

    /// The next deviation in counts.
    pub fn next_counts(&mut self) -> i64 {
        let mut x = self.state;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.state = x;
        let r = x.wrapping_mul(0x2545_F491_4F6C_DD1D);
        let span = 2 * u64::from(self.amplitude) + 1;
        // `span` is at least 1, and the result is below 2^33: the casts cannot overflow.
        (r % span) as i64 - i64::from(self.amplitude)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn due_faults_come_out_in_time_order_once() {
        let f = |at, axis| ScheduledFault {
            at,
            axis,
            fault: InjectedFault::Stuck,
        };
        let mut s = FaultSchedule::new(vec![f(0.3, 1), f(0.1, 0), f(f64::NAN, 2), f(0.2, 2)]);
        assert!(s.take_due(0.05).is_empty());
        let due: Vec<usize> = s.take_due(0.2).iter().map(|f| f.axis).collect();
        assert_eq!(due, vec![0, 2]);
        assert!(s.take_due(0.25).is_empty());
        assert_eq!(s.take_due(10.0).len(), 1);
        assert!(s.is_empty());
    }

    #[test]
    fn noise_stays_within_its_amplitude_and_reaches_both_ends() {
        let mut n = EncoderNoise::new(3, 42);
        let draws: Vec<i64> = (0..2000).map(|_| n.next_counts()).collect();
        assert!(draws.iter().all(|d| d.abs() <= 3));
        assert!(draws.contains(&3) && draws.contains(&-3));
        let mean = draws.iter().sum::<i64>() as f64 / draws.len() as f64;
        assert!(mean.abs() < 0.3, "mean {mean}");
    }
}
