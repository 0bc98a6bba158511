//! The touch probe as the interpreter asks it: "move the stylus ball from here toward there;
//! where does it touch the workpiece?". The interpreter stays pure: whoever runs a program
//! answers the question — klar's test run and its simulated machine from a simulated
//! workpiece placed in the machine file. On a machine that measures touch points with its
//! drives the interpreter asks no model: it waits for each probing move to be run and
//! measured (`ProbeRequest`, `ProbeAnswer`; see `tnc::probe_wait`). Touch-probe cycles
//! (`TCH PROBE`) are refused on an interpreter that was given neither.

use crate::tnc::exec::Blank;

/// The data of the touch probe the cycles work with (the TNC keeps them in its touch-probe
/// table): the ball radius, the set-up clearance added to each cycle's own clearance, the
/// longest probing move and the probing and positioning feeds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeData {
    /// Radius of the stylus ball, mm, when the active tool has no radius in the tool table
    /// (the probe called as a tool with one takes that instead).
    pub radius: f64,
    /// Set-up clearance, mm: the probe starts this far (plus the cycle's Q320 and the ball
    /// radius) before the nominal touch point.
    pub set_up: f64,
    /// Longest probing move, mm: a move that finds nothing within it ends the program.
    pub distance: f64,
    /// Probing feed, mm/min.
    pub feed: f64,
    /// Positioning feed between touch points, mm/min; `None`: rapid traverse.
    pub positioning_feed: Option<f64>,
    /// How the axes stop after the trigger (a real probe); `None`: on the trigger point.
    pub stop: Option<ProbeStop>,
}

impl Default for ProbeData {
    fn default() -> Self {
        ProbeData {
            radius: 2.0,
            set_up: 2.0,
            distance: 20.0,
            feed: 100.0,
            positioning_feed: None,
            stop: None,
        }
    }
}

/// How a real touch probe stops. The switch signal reaches the control `trigger_delay` after
/// the stylus touches; only then do the axes brake from the probing feed, as hard as their
/// acceleration and jerk limits allow. The axes therefore come to rest past the touch point
/// by the stop distance, and the stylus deflects by as much; that must stay within the
/// stylus's allowed deflection (its overtravel), which limits the probing feed. The
/// position the cycle uses is the one latched at the trigger, not where the axes stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeStop {
    /// Time from the touch until the axes start braking, s.
    pub trigger_delay: f64,
    /// Allowed stylus deflection, mm; `None`: not checked.
    pub overtravel: Option<f64>,
    /// Largest speed (mm/s), acceleration (mm/s²) and jerk (mm/s³) of X, Y and Z.
    pub axes: [[f64; 3]; 3],
}

impl ProbeStop {
    /// Path speed, acceleration and jerk limits along the unit direction `dir` (X, Y, Z) at
    /// the programmed speed `speed` (mm/s): on a straight line each axis carries its share
    /// `|dir[i]|` of the path's motion, so the path may go as far as the tightest axis allows.
    pub fn path_limits(&self, dir: [f64; 3], speed: f64) -> [f64; 3] {
        let mut out = [speed, f64::INFINITY, f64::INFINITY];
        for (u, lim) in dir.iter().zip(&self.axes) {
            if u.abs() > 1e-12 {
                for (o, l) in out.iter_mut().zip(lim) {
                    *o = o.min(l / u.abs());
                }
            }
        }
        out
    }

    /// Distance a jerk-limited stop from speed `v` at zero acceleration takes with
    /// acceleration limit `a` and jerk limit `j` (the same distance a start from rest to `v`
    /// takes). The deceleration rises and falls with the jerk limit, holding `a` in between
    /// when `v` is large enough to reach it (v ≥ a²/j); the profile is point-symmetric about
    /// its middle, so the distance is the time it takes times v/2.
    pub fn braking_distance(v: f64, a: f64, j: f64) -> f64 {
        if v <= 0.0 {
            return 0.0;
        }
        let time = if !j.is_finite() {
            v / a
        } else if v * j >= a * a {
            v / a + a / j
        } else {
            2.0 * (v / j).sqrt()
        };
        v * time / 2.0
    }

    /// The probing speed (mm/s) along `dir` at the probing feed `speed` (mm/s) and how far
    /// past the touch point the axes come to rest (mm): the distance covered during the
    /// trigger delay plus the braking distance.
    pub fn stop_distance(&self, dir: [f64; 3], speed: f64) -> (f64, f64) {
        let [v, a, j] = self.path_limits(dir, speed);
        (v, v * self.trigger_delay + Self::braking_distance(v, a, j))
    }
}

/// A probing move the machine runs and measures itself, on a machine whose probe signal
/// goes to the drives' touch-probe inputs: the ball centre moves from `from` toward `to`
/// (machine X, Y, Z, mm: the whole probing distance) at `feed` (mm/min), the axes stop
/// soon after the probe triggers, and the machine answers with a [`ProbeAnswer`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeRequest {
    /// Where the probing move starts (machine X, Y, Z of the ball centre), mm.
    pub from: [f64; 3],
    /// Where it ends when the probe finds nothing: the probing distance away, mm.
    pub to: [f64; 3],
    /// Probing feed, mm/min.
    pub feed: f64,
    /// The stylus ball's radius the cycle works with, mm (for a simulated part).
    pub radius: f64,
}

/// What the machine measured on a [`ProbeRequest`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeAnswer {
    /// Where the ball centre stood when the probe triggered (the drives' latched
    /// positions, machine X, Y, Z, mm); `None`: no trigger within the probing distance.
    pub trigger: Option<[f64; 3]>,
    /// Where the axes came to rest (machine X, Y, Z, mm).
    pub stop: [f64; 3],
}

/// Answers probing moves. Coordinates are machine coordinates in mm (X, Y, Z) of the centre
/// of the stylus ball, which is the point klar moves when the probe is the active tool.
pub trait Probe: std::fmt::Debug + Send {
    /// Where the ball centre stands when the ball first touches the workpiece while it moves
    /// on the straight line from `from` to `to`; `None` when it touches nothing on the way.
    /// A ball that touches already at `from` answers `from`. `blank` is the program's
    /// BLK FORM (program coordinates as written), for a simulated part shaped after it.
    fn touch(
        &mut self,
        from: [f64; 3],
        to: [f64; 3],
        radius: f64,
        blank: Option<&Blank>,
    ) -> Option<[f64; 3]>;

    /// The rotary table axis C stands at `deg` (machine position, degrees) for the moves that
    /// follow. A table turning in the primed sense carries the part the other way round (a
    /// positive angle turns it clockwise seen from +Z). The default ignores it: a probe on a
    /// machine without a rotary table, or a part that does not sit on one.
    fn table_at(&mut self, _deg: f64) {}
}

/// Why a touch-probe cycle stops the program.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProbeError {
    /// No probe was given to the interpreter.
    #[error(
        "TCH PROBE {0} needs a touch probe: this machine has none (a simulated probe and workpiece come from [probe] and [workpiece] in the machine file)"
    )]
    NoProbe(u32),
    /// The probing move found nothing within the probing distance.
    #[error(
        "touch point inaccessible: TCH PROBE {cycle}, touch point {point}, found no workpiece within the probing distance of {distance} mm"
    )]
    NotReached {
        /// Cycle number.
        cycle: u32,
        /// Touch point of the cycle, from 1.
        point: u32,
        /// The probing distance, mm.
        distance: f64,
    },
    /// The stylus touched the workpiece before its probing move started.
    #[error(
        "stylus already in contact: TCH PROBE {cycle}, touch point {point}, starts inside the workpiece (more clearance needed)"
    )]
    AlreadyInContact {
        /// Cycle number.
        cycle: u32,
        /// Touch point of the cycle, from 1.
        point: u32,
    },
    /// The stylus met the workpiece on a positioning move.
    #[error(
        "touch probe collision: TCH PROBE {cycle}, on the way to touch point {point}, the stylus meets the workpiece outside a probing move"
    )]
    Collision {
        /// Cycle number.
        cycle: u32,
        /// Touch point of the cycle the probe was moving to, from 1.
        point: u32,
    },
    /// The axes would stop further past the touch point than the stylus may deflect.
    #[error(
        "stylus deflection exceeds overtravel: TCH PROBE {cycle}, touch point {point}, the axes stop {stop:.4} mm past the touch point at the probing feed of {feed} mm/min, the stylus allows {allowed} mm (probing feed too high)"
    )]
    Overtravel {
        /// Cycle number.
        cycle: u32,
        /// Touch point of the cycle, from 1.
        point: u32,
        /// The stop distance, mm.
        stop: f64,
        /// The allowed stylus deflection, mm.
        allowed: f64,
        /// The probing feed, mm/min.
        feed: f64,
    },
    /// The probe touches before it reaches its probing feed.
    #[error(
        "too little clearance: TCH PROBE {cycle}, touch point {point}, the stylus touches {moved:.4} mm into its probing move but needs {run_up:.4} mm to reach the probing feed (more set-up clearance needed)"
    )]
    ShortRunUp {
        /// Cycle number.
        cycle: u32,
        /// Touch point of the cycle, from 1.
        point: u32,
        /// How far the probe moved before it touched, mm.
        moved: f64,
        /// How far it needs to reach the probing feed, mm.
        run_up: f64,
    },
    /// The probing move is under way on the machine: the cycle goes on once the machine
    /// has answered ([`ProbeAnswer`]). Never reported as an error.
    #[error("TCH PROBE {0}: waiting for the probing move to be measured")]
    Pending(u32),
    /// A cycle number klar does not run.
    #[error("touch-probe cycle {0} not supported yet")]
    Unknown(u32),
    /// A parameter the cycle cannot do without.
    #[error("TCH PROBE {cycle} needs Q{q}")]
    Missing {
        /// Cycle number.
        cycle: u32,
        /// The parameter.
        q: u32,
    },
    /// A parameter outside its range, or a form the cycle does not take.
    #[error("TCH PROBE {cycle}: {what}")]
    Bad {
        /// Cycle number.
        cycle: u32,
        /// What is wrong.
        what: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brakes from `v` by integrating the jerk phases step by step: jerk −j until the
    /// deceleration reaches `a` (or until half the speed is gone), hold it, then +j back to
    /// zero; returns the distance covered until the speed is zero.
    fn integrate_stop(v: f64, a: f64, j: f64) -> f64 {
        let dt = 1e-7;
        let (mut s, mut speed, mut acc) = (0.0, v, 0.0f64);
        // deceleration needed to stop from `speed` while ramping `acc` down at j: acc²/(2j)
        while speed > 0.0 {
            let ramp_down_loss = acc * acc / (2.0 * j);
            let jerk = if speed <= ramp_down_loss {
                j
            } else if -acc < a {
                -j
            } else {
                0.0
            };
            let next_acc = (acc + jerk * dt).max(-a).min(0.0);
            let next_speed = speed + 0.5 * (acc + next_acc) * dt;
            s += 0.5 * (speed + next_speed.max(0.0)) * dt;
            speed = next_speed;
            acc = next_acc;
        }
        s
    }

    #[test]
    fn braking_distance_matches_a_step_by_step_stop() {
        // below a²/j (the deceleration never reaches a) and above it
        for (v, a, j) in [
            (5.0, 2000.0, 50000.0),
            (90.0, 1500.0, 40000.0),
            (100.0, 2000.0, 50000.0),
        ] {
            let closed = ProbeStop::braking_distance(v, a, j);
            let steps = integrate_stop(v, a, j);
            assert!(
                (closed - steps).abs() < 1e-5 * closed.max(1e-3),
                "v {v}: closed form {closed}, integrated {steps}"
            );
        }
        assert_eq!(ProbeStop::braking_distance(0.0, 1.0, 1.0), 0.0);
    }

    #[test]
    fn the_tightest_axis_sets_the_limits_along_a_direction() {
        let stop = ProbeStop {
            trigger_delay: 0.01,
            overtravel: None,
            axes: [
                [100.0, 1000.0, 10000.0],
                [100.0, 2000.0, 40000.0],
                [50.0, 500.0, 5000.0],
            ],
        };
        let h = std::f64::consts::FRAC_1_SQRT_2;
        // along X+Y at 45°: X's limits over cos 45°
        let l = stop.path_limits([h, h, 0.0], 10.0);
        assert!((l[1] - 1000.0 / h).abs() < 1e-9 && (l[2] - 10000.0 / h).abs() < 1e-9);
        // a feed above Z's speed limit is cut to it
        let (v, s) = stop.stop_distance([0.0, 0.0, -1.0], 80.0);
        assert_eq!(v, 50.0);
        let want = 0.01 * 50.0 + 25.0 * (50.0 / 500.0 + 500.0 / 5000.0);
        assert!((s - want).abs() < 1e-12, "{s} against {want}");
    }
}
