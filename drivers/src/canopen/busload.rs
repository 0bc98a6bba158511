//! Bus-load estimate for cyclic traffic: the worst-case bits of the frames sent every
//! servo period (SYNC plus each drive's PDOs) against the bitrate.

use crate::can::frame::worst_case_bits;

/// The largest bus load klar accepts for cyclic traffic, leaving room for SDO, EMCY and
/// heartbeat traffic and for retransmissions.
pub const MAX_LOAD: f64 = 0.8;

/// The cyclic traffic of one servo period.
#[derive(Debug, Clone, PartialEq)]
pub struct CyclicTraffic {
    /// Data lengths (bytes) of every standard-identifier frame sent each period,
    /// including SYNC (0 bytes).
    pub frame_lengths: Vec<usize>,
}

impl CyclicTraffic {
    /// Worst-case bits per period, with stuff bits and interframe space.
    pub fn bits_per_period(&self) -> u64 {
        self.frame_lengths
            .iter()
            .map(|&n| u64::from(worst_case_bits(false, n)))
            .sum()
    }

    /// Bus load (0..) at `bitrate` bit/s with a period of `period` seconds.
    pub fn load(&self, bitrate: u32, period: f64) -> f64 {
        if bitrate == 0 || period <= 0.0 {
            return f64::INFINITY;
        }
        self.bits_per_period() as f64 / (f64::from(bitrate) * period)
    }

    /// The shortest period (seconds, rounded up to a multiple of 0.25 ms) at which the
    /// load stays at or below [`MAX_LOAD`].
    pub fn shortest_period(&self, bitrate: u32) -> f64 {
        let exact = self.bits_per_period() as f64 / (f64::from(bitrate.max(1)) * MAX_LOAD);
        (exact / 0.000_25).ceil() * 0.000_25
    }
}

/// The load check refused the configuration.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "CAN bus load {load_percent:.1} % at {bitrate} bit/s with a {period_ms} ms servo period \
     exceeds {max_percent:.0} %; a servo period of {fitting_ms} ms or longer would fit"
)]
pub struct BusLoadError {
    /// The computed load in percent.
    pub load_percent: f64,
    /// The bitrate.
    pub bitrate: u32,
    /// The servo period asked for, ms.
    pub period_ms: f64,
    /// The limit in percent.
    pub max_percent: f64,
    /// The shortest period that fits, ms.
    pub fitting_ms: f64,
}

/// Checks the cyclic load; returns it (0..1) or an error naming a period that fits.
pub fn check(traffic: &CyclicTraffic, bitrate: u32, period: f64) -> Result<f64, BusLoadError> {
    let load = traffic.load(bitrate, period);
    if load <= MAX_LOAD {
        return Ok(load);
    }
    Err(BusLoadError {
        load_percent: load * 100.0,
        bitrate,
        period_ms: period * 1000.0,
        max_percent: MAX_LOAD * 100.0,
        fitting_ms: traffic.shortest_period(bitrate) * 1000.0,
    })
}
