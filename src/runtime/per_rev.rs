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
//! for at most the spindle's at-speed timeout. Once a stop is under way (a spindle fault, the
//! operator's stop) the path brakes on the plan's own time.
//!
//! Moves not fed per revolution run at `k = 1`, and so do the moves of a block that also
//! holds moves not fed per revolution (a cycle's rapids and feeds, whose samples carry the
//! same block): those run at the speed planned from the commanded rpm. Where a move fed per revolution leaves the
//! planner's samples a fraction of a period behind, the fraction is kept (the axes stay that
//! much behind the plan, with no step) until the path comes to rest, where it is dropped.

use super::{Run, RunError};
use klar_interp::SourceLoc;
use klar_motion::Sample;
use std::collections::VecDeque;

/// Blocks remembered ahead of the servo loop: as many as the planner and the reader's queue
/// hold (the ring never grows; should it fill, the oldest entry makes room).
const REMEMBERED: usize = klar_motion::planner::BUFFER_CAPACITY + super::reader::QUEUE_OPS;

/// How far into the ring a sample's block is looked for.
const SEARCH: usize = 64;

/// The servo loop's state of the per-revolution time warp.
pub(super) struct RevWarp {
    /// The blocks of the motion ops the planner has taken, in order: where, and the basis
    /// rpm (magnitude) the planner planned them at when fed per main-spindle revolution.
    blocks: VecDeque<(SourceLoc, Option<f64>)>,
    /// The planner sample before `prev`.
    older: Option<Sample>,
    /// The last planner sample taken.
    prev: Option<Sample>,
    /// Where the last servo cycle stood, in planner periods from `prev` (0: on it; between
    /// -1 and 0: between `older` and `prev`).
    pos: f64,
    /// Machine time the path has waited for a standing spindle, s.
    stalled: f64,
}

impl RevWarp {
    /// No per-revolution move yet.
    pub(super) fn new() -> Self {
        RevWarp {
            blocks: VecDeque::with_capacity(REMEMBERED),
            older: None,
            prev: None,
            pos: 0.0,
            stalled: 0.0,
        }
    }

    /// The planner has taken a motion op of block `loc`, fed per revolution at `basis` rpm
    /// or (`None`) not. A block whose motion ops are not all fed per revolution at one basis
    /// (a cycle's rapids and feeds) runs as planned: its samples cannot be told apart.
    pub(super) fn remember(&mut self, loc: SourceLoc, basis: Option<f64>) {
        let basis = basis.map(f64::abs);
        if let Some(last) = self.blocks.back_mut()
            && last.0 == loc
        {
            if last.1 != basis {
                last.1 = None;
            }
            return;
        }
        if self.blocks.len() == REMEMBERED {
            self.blocks.pop_front();
        }
        self.blocks.push_back((loc, basis));
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
        self.blocks.front().and_then(|(_, b)| *b)
    }
}

/// The sample `f` of the way (0 to 1) from `a` to `b`, which are one planner period `t`
/// apart: quintic Hermite interpolation on their positions, velocities and accelerations, so
/// the path keeps its velocity and acceleration continuous between samples (its jerk stays
/// that of the plan); the speeds are scaled by `k` (planner periods per servo cycle) and
/// the acceleration by `k²`.
fn between(a: &Sample, b: &Sample, f: f64, t: f64, k: f64) -> Sample {
    let (f2, f3) = (f * f, f * f * f);
    let (f4, f5) = (f3 * f, f3 * f2);
    // Weights of p0, t·v0, t²·a0, t²·a1, t·v1, p1, and their derivatives in f.
    let h = [
        1.0 - 10.0 * f3 + 15.0 * f4 - 6.0 * f5,
        f - 6.0 * f3 + 8.0 * f4 - 3.0 * f5,
        0.5 * f2 - 1.5 * f3 + 1.5 * f4 - 0.5 * f5,
        0.5 * f3 - f4 + 0.5 * f5,
        -4.0 * f3 + 7.0 * f4 - 3.0 * f5,
        10.0 * f3 - 15.0 * f4 + 6.0 * f5,
    ];
    let d = [
        -30.0 * f2 + 60.0 * f3 - 30.0 * f4,
        1.0 - 18.0 * f2 + 32.0 * f3 - 15.0 * f4,
        f - 4.5 * f2 + 6.0 * f3 - 2.5 * f4,
        1.5 * f2 - 4.0 * f3 + 2.5 * f4,
        -12.0 * f2 + 28.0 * f3 - 15.0 * f4,
        30.0 * f2 - 60.0 * f3 + 30.0 * f4,
    ];
    let mut s = *b;
    for i in 0..9 {
        let terms = [
            a.pose.0[i],
            a.velocity[i] * t,
            a.acceleration[i] * t * t,
            b.acceleration[i] * t * t,
            b.velocity[i] * t,
            b.pose.0[i],
        ];
        let dot = |w: &[f64; 6]| w.iter().zip(&terms).map(|(w, x)| w * x).sum::<f64>();
        s.pose.0[i] = dot(&h);
        s.velocity[i] = dot(&d) / t * k;
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
        let on_plan = self.warp.pos == 0.0;
        let warped = match self.warp.prev {
            None => false,
            // At rest a fraction behind the plan is dropped.
            Some(prev) if prev.pose == sample.pose => on_plan && basis.is_some(),
            // Fed per revolution, or behind the plan since such a move.
            Some(_) => basis.is_some() || !on_plan,
        };
        if !warped {
            self.warp.older = self.warp.prev;
            self.warp.prev = Some(sample);
            self.warp.pos = 0.0;
            return self.apply_sample(&sample);
        }
        let (Some(prev), older) = (self.warp.prev, self.warp.older) else {
            return Ok(());
        };
        let period = self.config.servo_period;
        loop {
            let k = self.rev_factor(basis);
            let next = self.warp.pos + k;
            if next > 1.0 + 1e-12 {
                self.warp.pos -= 1.0;
                self.warp.older = Some(prev);
                self.warp.prev = Some(sample);
                return Ok(());
            }
            let mut s = if next >= 0.0 {
                between(&prev, &sample, next, period, k)
            } else {
                between(&older.unwrap_or(prev), &prev, 1.0 + next, period, k)
            };
            // Machine time of this cycle (`apply_sample` adds the shift back).
            s.t = self.t + period - self.shift;
            self.apply_sample(&s)?;
            self.warp.pos = next;
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
        }
    }

    /// Planner periods per servo cycle: the measured over the basis speed of a block fed per
    /// revolution (0 to 1), 1 otherwise.
    fn rev_factor(&mut self, basis: Option<f64>) -> f64 {
        // A stop under way (a spindle fault, the operator) brakes on the plan's own time.
        let Some(basis) = basis.filter(|b| *b > 0.0 && self.stopping.is_none()) else {
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
