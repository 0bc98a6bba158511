//! Feed per revolution that follows the measured spindle speed (lathe G95, Klartext FU and
//! M136).
//!
//! The planner plans a move fed per revolution at the speed the program commands, `F · n /
//! 60` mm/s with `n` the programmed (or, under constant surface speed, the computed) rpm:
//! its basis. The servo loop then runs the planner's time at the rate the spindle really
//! turns: every cycle the path advances by `k` planner periods, `k = n_measured / n_basis`,
//! interpolating between the planner's samples. So the path speed is `F · n_measured / 60`
//! every cycle, and the feed per revolution stays `F` when the spindle slows under the cut.
//! Feed override and feed hold act on the planner and so still act, on top of this.
//!
//! `k` is at most 1: a spindle measured faster than commanded does not drive the axes
//! faster than planned (the planner keeps them within their limits at the basis speed).
//! A spindle that stands while a move fed per revolution waits for it holds the path there,
//! for at most the spindle's at-speed timeout.
//!
//! Moves not fed per revolution run at `k = 1`. Where a move fed per revolution leaves the
//! planner's samples a fraction of a period behind, the fraction is kept (the axes stay that
//! much behind the plan, with no step) until the path comes to rest, where it is dropped.

use super::{Run, RunError};
use klar_interp::SourceLoc;
use klar_motion::Sample;
use std::collections::VecDeque;

/// Per-revolution moves remembered ahead of the servo loop (the ring never grows: the
/// oldest entry, long passed, makes room).
const REMEMBERED: usize = 4096;

/// How far into the ring a sample's block is looked for.
const SEARCH: usize = 64;

/// The servo loop's state of the per-revolution time warp.
pub(super) struct RevWarp {
    /// Blocks fed per main-spindle revolution the planner has taken: where, and the basis
    /// rpm (magnitude) the planner planned them at.
    blocks: VecDeque<(SourceLoc, f64)>,
    /// The last planner sample reached.
    prev: Option<Sample>,
    /// Where the next servo cycle stands between `prev` and the next planner sample, in
    /// planner periods (1: on it).
    ahead: f64,
    /// Machine time the path has waited for a standing spindle, s.
    stalled: f64,
}

impl RevWarp {
    /// No per-revolution move yet.
    pub(super) fn new() -> Self {
        RevWarp {
            blocks: VecDeque::with_capacity(REMEMBERED),
            prev: None,
            ahead: 1.0,
            stalled: 0.0,
        }
    }

    /// The planner has taken an op of block `loc` fed per revolution at `basis` rpm.
    pub(super) fn remember(&mut self, loc: SourceLoc, basis: f64) {
        if self.blocks.len() == REMEMBERED {
            self.blocks.pop_front();
        }
        self.blocks.push_back((loc, basis.abs()));
    }

    /// The basis rpm of the block of `loc` when it is fed per revolution; blocks passed
    /// before it are forgotten.
    fn basis(&mut self, loc: SourceLoc) -> Option<f64> {
        let i = self
            .blocks
            .iter()
            .take(SEARCH)
            .position(|(l, _)| *l == loc)?;
        for _ in 0..i {
            self.blocks.pop_front();
        }
        self.blocks.front().map(|(_, b)| *b)
    }
}

/// The interpolated sample `f` of the way from `a` to `b`, its speeds scaled by `k`.
fn between(a: &Sample, b: &Sample, f: f64, k: f64) -> Sample {
    let mut s = *b;
    for i in 0..9 {
        s.pose.0[i] = a.pose.0[i] + (b.pose.0[i] - a.pose.0[i]) * f;
        s.velocity[i] = (a.velocity[i] + (b.velocity[i] - a.velocity[i]) * f) * k;
        s.acceleration[i] =
            (a.acceleration[i] + (b.acceleration[i] - a.acceleration[i]) * f) * k * k;
    }
    s
}

impl Run<'_, '_> {
    /// Runs the servo cycles that planner sample `sample` covers (none, one or more): at
    /// the spindle's measured rate for blocks fed per revolution, else one.
    pub(super) fn warped_sample(&mut self, sample: Sample) -> Result<(), RunError> {
        let basis = self.warp.basis(sample.loc);
        let Some(prev) = self.warp.prev else {
            self.warp.prev = Some(sample);
            self.warp.ahead = 1.0;
            return self.apply_sample(&sample);
        };
        if basis.is_none() && (self.warp.ahead - 1.0).abs() < 1e-12 {
            // Not fed per revolution, on the plan: as planned.
            self.warp.prev = Some(sample);
            return self.apply_sample(&sample);
        }
        if basis.is_none() && prev.pose == sample.pose {
            // At rest: the fraction behind the plan is dropped.
            self.warp.ahead = 1.0;
            self.warp.prev = Some(sample);
            return self.apply_sample(&sample);
        }
        let period = self.config.servo_period;
        let mut k = self.rev_factor(basis);
        while self.warp.ahead <= 1.0 + 1e-12 {
            let mut s = between(&prev, &sample, self.warp.ahead.min(1.0), k);
            // Machine time of this cycle (`apply_sample` adds the shift back).
            s.t = self.t + period - self.shift;
            self.apply_sample(&s)?;
            if k <= 0.0 {
                self.warp.stalled += period;
                let timeout = self.io.spindle_mut().map_or(0.0, |s| s.at_speed_timeout);
                if self.warp.stalled > timeout {
                    return Err(RunError::Spindle {
                        message: format!(
                            "a move fed per revolution waited {timeout} s for the spindle to \
                             turn"
                        ),
                        line: sample.loc.line,
                    });
                }
            } else {
                self.warp.stalled = 0.0;
            }
            k = self.rev_factor(basis);
            self.warp.ahead += k;
        }
        self.warp.ahead -= 1.0;
        self.warp.prev = Some(sample);
        Ok(())
    }

    /// Planner periods per servo cycle: the measured over the basis speed of a block fed per
    /// revolution (0 to 1), 1 otherwise.
    fn rev_factor(&mut self, basis: Option<f64>) -> f64 {
        let Some(basis) = basis.filter(|b| *b > 0.0) else {
            return 1.0;
        };
        let Some(s) = self.io.spindle_mut() else {
            return 1.0;
        };
        let k = s.feedback().rpm.abs() / basis;
        if k.is_finite() {
            k.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}
