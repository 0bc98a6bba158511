//! The setpoint guard: the last check a commanded setpoint passes before it reaches a backend,
//! independent of the planner that made it.
//!
//! Each servo cycle the run hands every axis a new commanded position. Whatever the
//! interpreter, the planner and the kinematics did, consecutive positions of one axis must
//! stay within what the machine file allows that axis:
//!
//! - the position is a finite number within the axis's `travel` (± [`TRAVEL_EPSILON`]);
//! - the step from the previous position, `|x[n] − x[n−1]|`, is at most
//!   [`VELOCITY_MARGIN`]` · v_max · T + `[`STEP_EPSILON`];
//! - the change of step, `|x[n] − 2·x[n−1] + x[n−2]|` (the acceleration times `T²`), is at
//!   most [`ACCELERATION_MARGIN`]` · a_max · T² + `[`STEP_EPSILON`].
//!
//! # The margins
//!
//! The planner keeps every axis within its limits by construction, so on a legitimate run the
//! finite differences stay at the limits or below them; the margins only absorb what a
//! correct planner may still show in a finite difference:
//!
//! - velocity, 5 %: the planner's speed is exact up to rounding, and the feed override never
//!   lifts an axis over its `max_velocity`; the measured worst case over the example programs
//!   and the corpus is below 1.0 (tests/check_equals_run.rs prints it). 5 % is far below any
//!   real discontinuity (a jump of 0.2 mm at 166 mm/s and 1 ms is already 20 % over) and far
//!   above rounding;
//! - acceleration, 50 %: the second difference is a mean of the acceleration over two
//!   periods, which a correct trajectory keeps within `a_max`, but the planner may put a
//!   standstill onto its stop point in one period at up to 0.1 % of the acceleration and jerk
//!   limits (its snap share), and under TCPM the machine axes' acceleration is the Jacobian
//!   applied to the program axes' plus the Jacobian's own rate of change, which the planner's
//!   derated limits bound only approximately. A jump the guard is meant to catch is orders of
//!   magnitude larger: at 1 ms and 2000 mm/s² the bound is 3 µm of change of step, a 0.1 mm
//!   discontinuity is 33 times that;
//! - [`STEP_EPSILON`] of 1 nm: positions of a metre carry rounding of 1e-13 mm; 1 nm is also
//!   the planner's own snap distance onto a stop point (`STOP_SNAP`), so a snap never trips
//!   the guard however small the limits are.
//!
//! The guard holds no allocation in its check: its history is sized once, when it is made.

use klar_interp::AxisLetter;

/// A step may reach this multiple of `v_max · T`.
pub const VELOCITY_MARGIN: f64 = 1.05;

/// A change of step may reach this multiple of `a_max · T²`.
pub const ACCELERATION_MARGIN: f64 = 1.5;

/// Absolute slack on steps and changes of step, mm or degrees.
pub const STEP_EPSILON: f64 = 1e-6;

/// Absolute slack on the travel, mm or degrees.
pub const TRAVEL_EPSILON: f64 = 1e-6;

/// The limits of one machine axis the guard checks against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GuardAxis {
    /// The axis letter (for the report).
    pub letter: AxisLetter,
    /// True for a rotary axis (degrees), false for a linear one (mm).
    pub rotary: bool,
    /// Soft limits `[min, max]`.
    pub travel: [f64; 2],
    /// Largest velocity, mm/s or °/s.
    pub max_velocity: f64,
    /// Largest acceleration, mm/s² or °/s².
    pub max_acceleration: f64,
}

/// A commanded setpoint the guard refuses, and why.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum Violation {
    /// The position is not a finite number.
    #[error("axis {axis}: the commanded position is not a number ({position})")]
    NotFinite {
        /// The axis.
        axis: AxisLetter,
        /// What was commanded.
        position: f64,
    },
    /// The position is outside the axis's travel.
    #[error(
        "axis {axis}: commanded position {position:.4} {unit} is outside its travel [{min}, {max}]",
        unit = unit(*rotary)
    )]
    Travel {
        /// The axis.
        axis: AxisLetter,
        /// Degrees (true) or mm.
        rotary: bool,
        /// What was commanded.
        position: f64,
        /// Lower soft limit.
        min: f64,
        /// Upper soft limit.
        max: f64,
    },
    /// The step from the previous setpoint is above what the velocity limit allows.
    #[error(
        "axis {axis}: a step of {step:.4} {unit} in one servo cycle, above the limit of \
         {limit:.4} {unit} ({VELOCITY_MARGIN} × {max_velocity} {unit}/s × {period_ms} ms)",
        unit = unit(*rotary),
        period_ms = period * 1e3
    )]
    Velocity {
        /// The axis.
        axis: AxisLetter,
        /// Degrees (true) or mm.
        rotary: bool,
        /// |x[n] − x[n−1]|.
        step: f64,
        /// The largest step allowed.
        limit: f64,
        /// The axis's velocity limit.
        max_velocity: f64,
        /// The servo period, s.
        period: f64,
    },
    /// The change of step is above what the acceleration limit allows.
    #[error(
        "axis {axis}: the step changes by {change:.4} {unit} from one servo cycle to the next \
         ({accel:.0} {unit}/s²), above the limit of {limit:.4} {unit} ({ACCELERATION_MARGIN} × \
         {max_acceleration} {unit}/s² × ({period_ms} ms)²)",
        unit = unit(*rotary),
        accel = change / (period * period),
        period_ms = period * 1e3
    )]
    Acceleration {
        /// The axis.
        axis: AxisLetter,
        /// Degrees (true) or mm.
        rotary: bool,
        /// |x[n] − 2·x[n−1] + x[n−2]|.
        change: f64,
        /// The largest change allowed.
        limit: f64,
        /// The axis's acceleration limit.
        max_acceleration: f64,
        /// The servo period, s.
        period: f64,
    },
}

/// `x ≤ limit`, false when either is NaN: a NaN limit (a broken machine file) refuses.
fn within(x: f64, limit: f64) -> bool {
    x <= limit
}

fn unit(rotary: bool) -> &'static str {
    if rotary { "deg" } else { "mm" }
}

impl Violation {
    /// The axis the setpoint was refused for.
    pub fn axis(&self) -> AxisLetter {
        match self {
            Violation::NotFinite { axis, .. }
            | Violation::Travel { axis, .. }
            | Violation::Velocity { axis, .. }
            | Violation::Acceleration { axis, .. } => *axis,
        }
    }
}

/// The guard over the commanded setpoints of all machine axes, one servo cycle after the
/// other.
#[derive(Debug, Clone)]
pub struct SetpointGuard {
    axes: Vec<GuardAxis>,
    period: f64,
    /// The last accepted position per axis.
    last: Vec<f64>,
    /// The accepted position before it.
    before: Vec<f64>,
}

impl SetpointGuard {
    /// A guard for `axes` at servo period `period` (s), the machine standing at `start` (one
    /// position per axis; missing ones are taken as 0).
    pub fn new(axes: Vec<GuardAxis>, period: f64, start: &[f64]) -> Self {
        let last: Vec<f64> = (0..axes.len())
            .map(|i| start.get(i).copied().unwrap_or(0.0))
            .collect();
        Self {
            axes,
            period,
            before: last.clone(),
            last,
        }
    }

    /// The last accepted position per axis.
    pub fn last(&self) -> &[f64] {
        &self.last
    }

    /// Checks the next setpoint positions (one per axis, in machine order). Accepted, they
    /// become the guard's history; refused, the history stays at the last good setpoint.
    pub fn check(&mut self, positions: &[f64]) -> Result<(), Violation> {
        // Nearly every setpoint passes: one pass over the axes says so; only a refused one
        // needs `find` to name the violation in its order of precedence.
        if !self.passes(positions)
            && let Some(v) = self.find(positions)
        {
            return Err(v);
        }
        for ((b, l), &p) in self.before.iter_mut().zip(&mut self.last).zip(positions) {
            *b = *l;
            *l = p;
        }
        Ok(())
    }

    /// The backend got the last setpoint again (a cycle holding position): the history moves
    /// on by one cycle.
    pub fn repeat(&mut self) {
        self.before.copy_from_slice(&self.last);
    }

    /// True when `positions` pass every check of [`SetpointGuard::find`] (the same
    /// comparisons, NaN refusing; a missing position is no check, as there).
    fn passes(&self, positions: &[f64]) -> bool {
        let t = self.period;
        self.axes
            .iter()
            .zip(positions)
            .zip(self.last.iter().zip(&self.before))
            .all(|((a, &p), (&l, &b))| {
                let [min, max] = a.travel;
                let step = VELOCITY_MARGIN * a.max_velocity * t + STEP_EPSILON;
                let change = ACCELERATION_MARGIN * a.max_acceleration * t * t + STEP_EPSILON;
                p.is_finite()
                    && within(min - TRAVEL_EPSILON, p)
                    && within(p, max + TRAVEL_EPSILON)
                    && within((p - l).abs(), step)
                    && within((p - 2.0 * l + b).abs(), change)
            })
    }

    /// The first problem of `positions`: a non-finite position first, then travel, then the
    /// worst step relative to its limit, then the worst change of step.
    fn find(&self, positions: &[f64]) -> Option<Violation> {
        let axes = || self.axes.iter().zip(positions);
        for (a, &p) in axes() {
            if !p.is_finite() {
                return Some(Violation::NotFinite {
                    axis: a.letter,
                    position: p,
                });
            }
        }
        for (a, &p) in axes() {
            let [min, max] = a.travel;
            if !(within(min - TRAVEL_EPSILON, p) && within(p, max + TRAVEL_EPSILON)) {
                return Some(Violation::Travel {
                    axis: a.letter,
                    rotary: a.rotary,
                    position: p,
                    min,
                    max,
                });
            }
        }
        let t = self.period;
        let keep = |worst: &mut Option<(f64, Violation)>, ratio: f64, v: Violation| {
            if worst.as_ref().is_none_or(|(r, _)| ratio > *r) {
                *worst = Some((ratio, v));
            }
        };
        let mut worst: Option<(f64, Violation)> = None;
        for ((a, &p), &l) in axes().zip(&self.last) {
            let step = (p - l).abs();
            let limit = VELOCITY_MARGIN * a.max_velocity * t + STEP_EPSILON;
            if !within(step, limit) {
                let v = Violation::Velocity {
                    axis: a.letter,
                    rotary: a.rotary,
                    step,
                    limit,
                    max_velocity: a.max_velocity,
                    period: t,
                };
                keep(&mut worst, step / limit, v);
            }
        }
        if worst.is_some() {
            return worst.map(|(_, v)| v);
        }
        for (((a, &p), &l), &b) in axes().zip(&self.last).zip(&self.before) {
            let change = (p - 2.0 * l + b).abs();
            let limit = ACCELERATION_MARGIN * a.max_acceleration * t * t + STEP_EPSILON;
            if !within(change, limit) {
                let v = Violation::Acceleration {
                    axis: a.letter,
                    rotary: a.rotary,
                    change,
                    limit,
                    max_acceleration: a.max_acceleration,
                    period: t,
                };
                keep(&mut worst, change / limit, v);
            }
        }
        worst.map(|(_, v)| v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: f64 = 0.001;

    fn guard() -> SetpointGuard {
        let axes = vec![
            GuardAxis {
                letter: AxisLetter::X,
                rotary: false,
                travel: [-100.0, 100.0],
                max_velocity: 100.0,
                max_acceleration: 1000.0,
            },
            GuardAxis {
                letter: AxisLetter::C,
                rotary: true,
                travel: [-360.0, 360.0],
                max_velocity: 180.0,
                max_acceleration: 1440.0,
            },
        ];
        SetpointGuard::new(axes, T, &[0.0, 0.0])
    }

    /// Feeds X positions of a profile accelerating at `a` from rest; returns the first refusal.
    fn accelerate(g: &mut SetpointGuard, a: f64, cycles: u32) -> Option<Violation> {
        for k in 1..=cycles {
            let t = f64::from(k) * T;
            if let Err(v) = g.check(&[0.5 * a * t * t, 0.0]) {
                return Some(v);
            }
        }
        None
    }

    #[test]
    fn a_trajectory_at_the_limits_passes() {
        let mut g = guard();
        // a_max up to v_max (0.1 s), then cruise at v_max for 0.1 s.
        assert_eq!(accelerate(&mut g, 1000.0, 100), None);
        let x0 = g.last()[0];
        for k in 1..=100 {
            let x = x0 + 100.0 * f64::from(k) * T;
            assert_eq!(g.check(&[x, 0.0]), Ok(()), "cycle {k}");
        }
    }

    #[test]
    fn velocity_is_refused_just_above_the_margin() {
        let mut g = guard();
        // From rest a step is also a change of step: the velocity check speaks first.
        let limit = VELOCITY_MARGIN * 100.0 * T + STEP_EPSILON;
        let Err(Violation::Velocity { axis, step, .. }) = g.check(&[limit * 1.001, 0.0]) else {
            panic!("not refused for velocity");
        };
        assert_eq!(axis, AxisLetter::X);
        assert!((step - limit * 1.001).abs() < 1e-15);
        // Nothing was accepted: the history is still the start.
        assert_eq!(g.last(), &[0.0, 0.0]);
    }

    #[test]
    fn acceleration_is_refused_above_its_margin_and_passes_below() {
        assert_eq!(accelerate(&mut guard(), 1000.0 * 1.49, 50), None);
        let v = accelerate(&mut guard(), 1000.0 * 1.6, 50).expect("refused");
        let Violation::Acceleration { change, limit, .. } = v else {
            panic!("{v:?}");
        };
        assert!(change > limit, "{change} {limit}");
        let text = v.to_string();
        assert!(
            text.contains("axis X") && text.contains("1600 mm/s²"),
            "{text}"
        );
    }

    #[test]
    fn a_jump_in_cruise_is_refused_and_the_history_keeps_the_last_good_setpoint() {
        let mut g = guard();
        // C already turning at 90 °/s (0.09° per cycle).
        g.before = vec![0.0, -0.09];
        for k in 1..=20 {
            assert_eq!(g.check(&[0.0, 0.09 * f64::from(k)]), Ok(()), "cycle {k}");
        }
        let good = g.last().to_vec();
        let v = g.check(&[0.0, good[1] + 0.09 + 5.0]).expect_err("jump");
        assert_eq!(v.axis(), AxisLetter::C);
        assert!(v.to_string().contains("5.0900 deg"), "{v}");
        assert_eq!(g.last(), good.as_slice());
        // The path goes on from the last good setpoint.
        assert_eq!(g.check(&[0.0, good[1] + 0.09]), Ok(()));
    }

    #[test]
    fn travel_and_non_finite_positions_are_refused_first() {
        let mut g = guard();
        assert!(matches!(
            g.check(&[f64::NAN, 0.0]),
            Err(Violation::NotFinite { .. })
        ));
        let v = g.check(&[0.0, 360.5]).expect_err("outside");
        assert!(
            matches!(
                v,
                Violation::Travel {
                    axis: AxisLetter::C,
                    ..
                }
            ),
            "{v:?}"
        );
        // On the limit (and within its rounding slack) is within the travel.
        let mut g = SetpointGuard::new(g.axes.clone(), T, &[100.0, 0.0]);
        assert_eq!(g.check(&[100.0 + 1e-9, 0.0]), Ok(()));
        // A limit that is not a number refuses every step.
        g.axes[0].max_velocity = f64::NAN;
        assert!(matches!(
            g.check(&[100.0, 0.0]),
            Err(Violation::Velocity { .. })
        ));
    }

    #[test]
    fn the_one_pass_check_agrees_with_the_named_violations() {
        let mut g = guard();
        g.before = vec![0.02, -0.05];
        g.last = vec![0.05, 0.0];
        // Steps around each limit of X and C (travel, step, change of step), and NaN.
        let xs = [
            0.05,
            0.05 + 0.104,
            0.05 + 0.106,
            0.08 + 0.0014,
            0.08 + 0.0016,
            100.0,
            100.1,
            -100.1,
            f64::NAN,
        ];
        let cs = [0.0, 0.05, 0.1, 0.19, 0.2, 360.0, f64::INFINITY];
        let mut refused = 0;
        for &x in &xs {
            for &c in &cs {
                let p = [x, c];
                assert_eq!(g.passes(&p), g.find(&p).is_none(), "{p:?}");
                refused += usize::from(!g.passes(&p));
            }
        }
        // Both outcomes occur: the comparison is not vacuous.
        assert!(refused > 0 && refused < xs.len() * cs.len(), "{refused}");
    }

    #[test]
    fn a_hold_moves_the_history_on() {
        let mut g = guard();
        g.before = vec![-0.05, 0.0];
        // Moving at 50 mm/s: a repeated setpoint is a stop in one cycle, which the next step
        // shows as a change of step of 0.05 mm.
        g.repeat();
        let v = g.check(&[0.05, 0.0]).expect_err("restart after a hold");
        assert!(matches!(v, Violation::Acceleration { .. }), "{v:?}");
    }
}
