//! The wall-clock schedule of a realtime run: every servo cycle of every phase (the run,
//! stops, settling, the fault reset) waits for its absolute deadline, one servo period after
//! the one before, and its lateness goes into a histogram.
//!
//! A cycle that wakes more than half a period late has missed its slot: it counts as an
//! underrun and the schedule is moved on to it, so the cycles after it keep one period
//! apart instead of catching up in a burst (a burst of SYNCs would shorten the period the
//! drives interpolate over, and a wait counted in cycles would end early on the wall).

use crate::latency::{LatencyHistogram, now_ns, sleep_until};

/// The deadlines of a realtime run.
pub(super) struct Pacer {
    /// Monotonic time of machine time 0, ns.
    origin: i64,
    /// Half the servo period, ns: the lateness that makes a missed slot.
    half_period: i64,
    /// Lateness of every wake-up.
    pub(super) histogram: LatencyHistogram,
}

impl Pacer {
    /// A schedule starting now, for a servo period of `period` seconds.
    pub(super) fn new(period: f64) -> Self {
        Self {
            origin: now_ns(),
            half_period: (period * 0.5e9).round() as i64,
            histogram: LatencyHistogram::new(),
        }
    }

    /// Sleeps until the deadline of machine time `t`; returns how late the wake-up came
    /// (seconds) and whether the slot was missed (the schedule then moves on).
    pub(super) fn wait(&mut self, t: f64) -> (f64, bool) {
        let due = self.origin + (t * 1e9).round() as i64;
        sleep_until(due);
        let late = (now_ns() - due).max(0);
        self.histogram.record(late);
        let missed = late > self.half_period;
        if missed {
            self.origin += late;
        }
        (late as f64 * 1e-9, missed)
    }

    /// Moves every later deadline by `seconds` (a stall the run waited out).
    pub(super) fn delay(&mut self, seconds: f64) {
        self.origin += (seconds * 1e9).round() as i64;
    }
}
