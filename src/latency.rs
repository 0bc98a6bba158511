//! Wake-up lateness on the wall clock: the monotonic clock, sleeps to absolute deadlines,
//! a fixed-size histogram of how late each wake-up came, and the `klar latency` measurement
//! (the machine's own wake-up latency, without a program or a bus), and [`Pacer`], the
//! schedule both the servo loop of a realtime run and `klar latency` keep.
//!
//! The histogram has one bucket per microsecond up to [`FINE_LIMIT_US`], then one per
//! [`COARSE_STEP_US`] up to [`COARSE_LIMIT_US`], and one overflow bucket; the largest value
//! is kept exactly. Recording never allocates, so it can run in the servo loop.

use std::fmt;

/// Upper end of the 1 µs buckets, µs.
pub const FINE_LIMIT_US: u64 = 2_000;
/// Width of the buckets above [`FINE_LIMIT_US`], µs.
pub const COARSE_STEP_US: u64 = 100;
/// Upper end of the coarse buckets, µs (later wake-ups share the overflow bucket).
pub const COARSE_LIMIT_US: u64 = 200_000;
const FINE: usize = FINE_LIMIT_US as usize;
const COARSE: usize = ((COARSE_LIMIT_US - FINE_LIMIT_US) / COARSE_STEP_US) as usize;
const BUCKETS: usize = FINE + COARSE + 1;

/// Nanoseconds on the monotonic clock (the clock [`sleep_until`] sleeps on).
pub fn now_ns() -> i64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; CLOCK_MONOTONIC always exists on Linux.
    unsafe {
        libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts);
    }
    ts.tv_sec * 1_000_000_000 + ts.tv_nsec
}

/// Sleeps until the monotonic clock reads `deadline_ns` (an absolute deadline: a wake-up
/// that comes late does not shift the deadlines after it). Returns at once when the deadline
/// has passed.
pub fn sleep_until(deadline_ns: i64) {
    let ts = libc::timespec {
        tv_sec: (deadline_ns / 1_000_000_000) as libc::time_t,
        tv_nsec: (deadline_ns % 1_000_000_000) as libc::c_long,
    };
    loop {
        // SAFETY: `ts` is a valid timespec; the remaining-time pointer may be null with
        // TIMER_ABSTIME.
        let rc = unsafe {
            libc::clock_nanosleep(
                libc::CLOCK_MONOTONIC,
                libc::TIMER_ABSTIME,
                &ts,
                std::ptr::null_mut(),
            )
        };
        // Interrupted by a signal: sleep on to the same deadline.
        if rc != libc::EINTR {
            return;
        }
    }
}

/// Counts of wake-up lateness, without allocation per sample.
#[derive(Clone)]
pub struct LatencyHistogram {
    counts: Box<[u64; BUCKETS]>,
    total: u64,
    max_ns: u64,
}

impl Default for LatencyHistogram {
    fn default() -> Self {
        Self::new()
    }
}

impl fmt::Debug for LatencyHistogram {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("LatencyHistogram")
            .field("total", &self.total)
            .field("max_ns", &self.max_ns)
            .finish()
    }
}

impl LatencyHistogram {
    /// An empty histogram (its buckets are allocated here, once).
    pub fn new() -> Self {
        Self {
            counts: Box::new([0; BUCKETS]),
            total: 0,
            max_ns: 0,
        }
    }

    fn bucket(late_ns: u64) -> usize {
        let us = late_ns / 1_000;
        if us < FINE_LIMIT_US {
            us as usize
        } else if us < COARSE_LIMIT_US {
            FINE + ((us - FINE_LIMIT_US) / COARSE_STEP_US) as usize
        } else {
            BUCKETS - 1
        }
    }

    /// The upper edge of bucket `i`, ns.
    fn upper_ns(&self, i: usize) -> u64 {
        let us = if i < FINE {
            i as u64 + 1
        } else if i < BUCKETS - 1 {
            FINE_LIMIT_US + (i - FINE) as u64 * COARSE_STEP_US + COARSE_STEP_US
        } else {
            return self.max_ns;
        };
        (us * 1_000).min(self.max_ns)
    }

    /// Counts one wake-up that came `late_ns` nanoseconds after its deadline (negative:
    /// early, counted as on time).
    pub fn record(&mut self, late_ns: i64) {
        let late = late_ns.max(0) as u64;
        if let Some(c) = self.counts.get_mut(Self::bucket(late)) {
            *c += 1;
        }
        self.total += 1;
        self.max_ns = self.max_ns.max(late);
    }

    /// Wake-ups counted.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// The largest lateness, ns.
    pub fn max_ns(&self) -> u64 {
        self.max_ns
    }

    /// The lateness (ns, the upper edge of its bucket, never above the maximum) that the
    /// fraction `q` (0..=1) of the wake-ups did not exceed; 0 with no samples.
    pub fn quantile_ns(&self, q: f64) -> u64 {
        if self.total == 0 {
            return 0;
        }
        let rank = ((q.clamp(0.0, 1.0) * self.total as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (i, &c) in self.counts.iter().enumerate() {
            seen += c;
            if seen >= rank {
                return self.upper_ns(i);
            }
        }
        self.max_ns
    }

    /// The summary figures.
    pub fn summary(&self) -> LatenessSummary {
        LatenessSummary {
            cycles: self.total,
            p50: self.quantile_ns(0.5) as f64 * 1e-9,
            p99: self.quantile_ns(0.99) as f64 * 1e-9,
            p9999: self.quantile_ns(0.9999) as f64 * 1e-9,
            max: self.max_ns as f64 * 1e-9,
        }
    }

    /// Rows for a printed histogram: (upper edge µs, count) of the non-empty buckets.
    pub fn rows(&self) -> impl Iterator<Item = (f64, u64)> + '_ {
        self.counts
            .iter()
            .enumerate()
            .filter(|(_, c)| **c > 0)
            .map(|(i, &c)| (self.upper_ns(i) as f64 / 1e3, c))
    }
}

/// Percentiles of wake-up lateness over a run, seconds.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LatenessSummary {
    /// Wake-ups measured.
    pub cycles: u64,
    /// Median.
    pub p50: f64,
    /// 99th percentile.
    pub p99: f64,
    /// 99.99th percentile.
    pub p9999: f64,
    /// Largest.
    pub max: f64,
}

impl fmt::Display for LatenessSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "p50 {:.1} µs, p99 {:.1} µs, p99.99 {:.1} µs, max {:.1} µs ({} wake-ups)",
            self.p50 * 1e6,
            self.p99 * 1e6,
            self.p9999 * 1e6,
            self.max * 1e6,
            self.cycles
        )
    }
}

/// The wall-clock schedule of a realtime run and of `klar latency`: every cycle waits for
/// its absolute deadline, one servo period after the one before, and its lateness goes into
/// the histogram. A cycle that wakes more than half a period late has missed its slot: it
/// counts as an underrun and the schedule is moved on to it, so the cycles after it keep one
/// period apart instead of catching up in a burst (a burst of SYNCs would shorten the period
/// the drives interpolate over, and a wait counted in cycles would end early on the wall).
pub struct Pacer {
    /// Monotonic time of machine time 0, ns.
    origin: i64,
    /// Half the servo period, ns: the lateness that makes a missed slot.
    half_period: i64,
    /// Lateness of every wake-up.
    pub histogram: LatencyHistogram,
    /// The loop's own time per cycle: from a wake-up to the next call to wait.
    pub work: LatencyHistogram,
    /// Cycles whose work ran past the next deadline (their lateness is the work's, not
    /// the wake-up's).
    pub overruns: u64,
    /// Monotonic time of the last wake-up, ns.
    woke: Option<i64>,
}

impl Pacer {
    /// A schedule starting now, for a servo period of `period` seconds.
    pub fn new(period: f64) -> Self {
        Self {
            origin: now_ns(),
            half_period: (period * 0.5e9).round() as i64,
            histogram: LatencyHistogram::new(),
            work: LatencyHistogram::new(),
            overruns: 0,
            woke: None,
        }
    }

    /// Sleeps until the deadline of machine time `t`; returns how late the wake-up came
    /// (seconds) and whether the slot was missed (the schedule then moves on).
    pub fn wait(&mut self, t: f64) -> (f64, bool) {
        let due = self.origin + (t * 1e9).round() as i64;
        let called = now_ns();
        if let Some(w) = self.woke {
            self.work.record(called - w);
        }
        if called > due {
            self.overruns += 1;
        }
        sleep_until(due);
        let woke = now_ns();
        self.woke = Some(woke);
        let late = (woke - due).max(0);
        self.histogram.record(late);
        let missed = late > self.half_period;
        if missed {
            self.origin += late;
        }
        (late as f64 * 1e-9, missed)
    }

    /// Moves every later deadline by `seconds` (a stall the run waited out).
    pub fn delay(&mut self, seconds: f64) {
        self.origin += (seconds * 1e9).round() as i64;
    }
}

/// Measures the wake-up lateness of a loop sleeping to absolute deadlines `period_s`
/// apart for `seconds`, on the servo loop's own schedule ([`Pacer`]).
pub fn measure(period_s: f64, seconds: f64) -> LatencyHistogram {
    let cycles = (seconds / period_s).ceil().max(1.0) as u64;
    let mut pacer = Pacer::new(period_s);
    for k in 1..=cycles {
        pacer.wait(k as f64 * period_s);
    }
    pacer.histogram
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_follow_the_samples() {
        let mut h = LatencyHistogram::new();
        // 1..=1000 µs, one each: the median lies at 500 µs, p99 at 990 µs.
        for us in 1..=1000i64 {
            h.record(us * 1_000);
        }
        assert_eq!(h.total(), 1000);
        assert_eq!(h.quantile_ns(0.5), 501_000);
        assert_eq!(h.quantile_ns(0.99), 991_000);
        assert_eq!(h.quantile_ns(1.0), 1_000_000);
        assert_eq!(h.max_ns(), 1_000_000);
    }

    #[test]
    fn coarse_and_overflow_buckets_keep_the_maximum() {
        let mut h = LatencyHistogram::new();
        h.record(-5);
        h.record(3_456_000);
        h.record(900_000_000);
        assert_eq!(h.quantile_ns(0.0), 1_000);
        // 3456 µs falls in the 3400..3500 µs bucket.
        assert_eq!(h.quantile_ns(0.6), 3_500_000);
        assert_eq!(h.quantile_ns(1.0), 900_000_000);
        assert_eq!(h.summary().max, 0.9);
    }
}
