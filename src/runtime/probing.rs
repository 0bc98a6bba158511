//! Measured probing in the run (`[probe] latch`): the touch point of a probing move is the
//! position the X, Y and Z drives latched when the probe switched, not where a model of the
//! part says it is.
//!
//! The interpreter hands out the ops before a probing move and waits
//! ([`Feed::Probe`](super::reader::Feed)). The run:
//! 1. lets the planner bring the machine to rest at the end of those ops;
//! 2. arms the touch-probe latch of the X, Y and Z drives and moves the ball centre itself
//!    along the probing move at the probing feed, jerk-limited with the tightest limits of
//!    the axes along it (as the planner's stop does), braking so as to stand at the end of
//!    the probing distance and never beyond it;
//! 3. reads the latches every servo cycle; once every moving axis has latched, it brakes
//!    as hard as those limits allow;
//! 4. at rest, answers the interpreter with the latched position (the axes that do not move
//!    keep their start) and where the axes stand, or with no trigger when the move ran its
//!    whole distance; the planner goes on from where the axes stand.
//!
//! Simulated CiA 402 drives have a probe input switched at a trigger position: before each
//! probing move the run places it where the simulated part (`[workpiece]` moved by its
//! `actual_shift`) meets the ball on the move.

use super::{Run, RunError};
use crate::config::MachineConfig;
use klar_interp::{AxisLetter, Blank, Pose, Probe, ProbeAnswer, ProbeRequest, ProbeStop};
use klar_sim::cia402::ProbeInput;

/// The machine X, Y and Z.
const XYZ: [AxisLetter; 3] = [AxisLetter::X, AxisLetter::Y, AxisLetter::Z];

/// A probing move the run owns.
pub(super) struct Probing {
    request: ProbeRequest,
    blank: Option<Blank>,
    /// `None` while the planner brings the machine to rest.
    moving: Option<Moving>,
}

/// The probing move under way.
struct Moving {
    /// Machine axis index of X, Y, Z.
    axes: [usize; 3],
    /// Unit direction and length of the whole probing move.
    dir: [f64; 3],
    length: f64,
    /// The pose the move starts at (the other axes stay there).
    start: Pose,
    /// Speed, acceleration and jerk limits along the move.
    limits: [f64; 3],
    /// Path position, speed and acceleration.
    s: f64,
    v: f64,
    a: f64,
    /// Once every moving axis has latched: where the ball centre triggered.
    trigger: Option<[f64; 3]>,
    loc: klar_interp::SourceLoc,
}

impl Probing {
    /// A probing move to run once the planner has come to rest.
    pub(super) fn new(request: ProbeRequest, blank: Option<Blank>) -> Self {
        Self {
            request,
            blank,
            moving: None,
        }
    }
}

/// One jerk-limited step of a path state (`s`, `v`, `a`) toward the speed `target` within
/// the acceleration `acc` and jerk `jerk`: the acceleration ramps toward ±`acc` and back so
/// that it reaches zero as the speed reaches the target.
fn ramp(state: (f64, f64, f64), target: f64, acc: f64, jerk: f64, dt: f64) -> (f64, f64, f64) {
    let (s, v, a) = state;
    let dv = target - v;
    // the speed still gained while the acceleration ramps back to zero
    let coast = a * a.abs() / (2.0 * jerk);
    let want = if dv > 0.0 {
        if coast >= dv { 0.0 } else { acc }
    } else if coast <= dv {
        0.0
    } else {
        -acc
    };
    let step = jerk * dt;
    let mut a1 = if want > a {
        (a + step).min(want)
    } else {
        (a - step).max(want)
    };
    let mut v1 = v + 0.5 * (a + a1) * dt;
    if (dv > 0.0 && v1 >= target) || (dv < 0.0 && v1 <= target) || dv == 0.0 {
        v1 = target;
        a1 = 0.0;
    }
    (s + 0.5 * (v + v1) * dt, v1, a1)
}

impl Run<'_, '_> {
    /// True while the run owns a probing move that has started (the planner is bypassed).
    pub(super) fn probe_moving(&self) -> bool {
        self.probing.as_ref().is_some_and(|p| p.moving.is_some())
    }

    /// The planner has brought the machine to rest before the probing move: starts it.
    pub(super) fn start_probe_move(&mut self) -> Result<(), RunError> {
        let Some(p) = self.probing.as_mut() else {
            return Ok(());
        };
        let r = p.request;
        let d: [f64; 3] = [0, 1, 2].map(|i| r.to[i] - r.from[i]);
        let length = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        let dir = d.map(|v| v / length.max(f64::MIN_POSITIVE));
        let axes = XYZ.map(|l| self.letters.iter().position(|&m| m == l));
        let [Some(x), Some(y), Some(z)] = axes else {
            return Err(RunError::Probe(
                "measured probing needs axes X, Y and Z".into(),
            ));
        };
        let axes = [x, y, z];
        let mut start = self.planner.planned_pose();
        for (i, l) in XYZ.iter().enumerate() {
            start[*l] = r.from[i];
        }
        let limits = stop_model(self.config).path_limits(dir, r.feed / 60.0);
        // where the simulated part meets the ball on this move
        let hit = self
            .config
            .actual_workpiece()
            .and_then(|mut w| w.touch(r.from, r.to, r.radius, p.blank.as_ref()));
        for (i, &axis) in axes.iter().enumerate() {
            let input = hit.filter(|_| dir[i].abs() > 1e-12).map(|h| ProbeInput {
                at: h[i],
                above: dir[i] > 0.0,
            });
            self.io.set_sim_probe_input(axis, input);
            if !self.io.arm_touch_probe(axis)? && dir[i].abs() > 1e-12 {
                return Err(RunError::Probe(format!(
                    "measured probing: axis {} has no touch-probe latch",
                    XYZ[i]
                )));
            }
        }
        let loc = self.last_loc.unwrap_or_default();
        if let Some(p) = self.probing.as_mut() {
            p.moving = Some(Moving {
                axes,
                dir,
                length,
                start,
                limits,
                s: 0.0,
                v: 0.0,
                a: 0.0,
                trigger: None,
                loc,
            });
        }
        Ok(())
    }

    /// One servo cycle of the probing move; at rest, the answer to the interpreter.
    pub(super) fn probe_step(&mut self) -> Result<(), RunError> {
        let Some(mut m) = self.probing.as_mut().and_then(|p| p.moving.take()) else {
            return Ok(());
        };
        let dt = self.config.servo_period;
        let [vmax, acc, jerk] = m.limits;
        let left = m.length - m.s;
        // brake for a trigger, and in time to stand at the end of the probing distance
        let target = if m.trigger.is_some()
            || left <= ProbeStop::braking_distance(m.v, acc, jerk) + m.v * dt
        {
            0.0
        } else {
            vmax
        };
        let (s, v, a) = ramp((m.s, m.v, m.a), target, acc, jerk, dt);
        (m.s, m.v, m.a) = (s.min(m.length), v, a);
        let mut pose = m.start;
        let mut velocity = [0.0; 9];
        for (i, l) in XYZ.iter().enumerate() {
            pose[*l] = m.start[*l] + m.dir[i] * m.s;
            velocity[l.index()] = m.dir[i] * m.v;
        }
        self.geared_cycle(pose, velocity, m.loc)?;
        if m.trigger.is_none() {
            m.trigger = self.read_latches(&m)?;
        }
        let at_rest = m.v <= 0.0 && (m.trigger.is_some() || m.s >= m.length);
        if !at_rest {
            if let Some(p) = self.probing.as_mut() {
                p.moving = Some(m);
            }
            return Ok(());
        }
        for &axis in &m.axes {
            self.io.disarm_touch_probe(axis)?;
            self.io.set_sim_probe_input(axis, None);
        }
        self.probing = None;
        if !self.planner.moved_to(pose) {
            return Err(RunError::Probe(
                "measured probing: the planner was not at rest".into(),
            ));
        }
        self.reader.answer_probe(ProbeAnswer {
            trigger: m.trigger,
            stop: XYZ.map(|l| pose[l]),
        });
        Ok(())
    }

    /// The trigger position once every axis that moves has latched.
    fn read_latches(&mut self, m: &Moving) -> Result<Option<[f64; 3]>, RunError> {
        let mut at = [0.0; 3];
        for (i, &axis) in m.axes.iter().enumerate() {
            let from = m.start[XYZ[i]];
            if m.dir[i].abs() <= 1e-12 {
                at[i] = from;
                continue;
            }
            match self.io.touch_probe_position(axis)? {
                Some(p) => at[i] = p,
                None => return Ok(None),
            }
        }
        Ok(Some(at))
    }
}

/// The limits of X, Y and Z the probing move is planned with.
fn stop_model(config: &MachineConfig) -> ProbeStop {
    let limits = |l: AxisLetter| {
        config
            .axes
            .iter()
            .find(|a| a.letter == l)
            .map_or([f64::INFINITY; 3], |a| {
                [a.max_velocity, a.max_acceleration, a.max_jerk]
            })
    };
    ProbeStop {
        trigger_delay: 0.0,
        overtravel: None,
        axes: XYZ.map(limits),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ramp_reaches_its_speed_and_stops_in_the_closed_form_distance() {
        let (v, a, j, dt) = (5.0, 2000.0, 50_000.0, 1e-5);
        let mut st = (0.0, 0.0, 0.0);
        while st.1 < v {
            st = ramp(st, v, a, j, dt);
        }
        let run_up = st.0;
        let from = st.0;
        while st.1 > 0.0 {
            st = ramp(st, 0.0, a, j, dt);
        }
        let closed = ProbeStop::braking_distance(v, a, j);
        assert!((run_up - closed).abs() < 1e-4, "{run_up} against {closed}");
        assert!(
            (st.0 - from - closed).abs() < 1e-4,
            "{} against {closed}",
            st.0 - from
        );
        assert!(st.2.abs() < 1e-9 && st.1 == 0.0);
    }
}
