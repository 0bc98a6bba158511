//! From planner samples to the commanded machine-axis setpoints, as a run sends them to the
//! backends: the kinematics (with TCPM switched by the planner's events), the velocity and
//! acceleration feed-forward, and the setpoint guard ([`super::guard`]) over every position.
//!
//! The run ([`super::Run`]) and the test run ([`crate::testrun`]) both go through
//! [`CommandPath`], so the test run follows the very trajectory the run will command and
//! refuses, before anything moves, every setpoint the run's guard would stop at.

use super::guard::{GuardAxis, SetpointGuard, Violation};
use crate::config::{AxisKind, BackendConfig, MachineConfig};
use crate::faults::{FaultKind, FaultSpecError};
use crate::testrun::block_diagnostic;
use klar_interp::{AxisLetter, Diagnostic, Op, OpKind, SourceLoc};
use klar_motion::kinematics::Kinematics;
use klar_motion::{Sample, Setpoint};
use std::collections::VecDeque;
use std::path::Path;

/// Planner samples → guarded machine-axis setpoints.
pub(crate) struct CommandPath {
    kin: Box<dyn Kinematics>,
    /// TCPM is on: the velocity and acceleration feed-forward go through the kinematics.
    tcpm: bool,
    letters: Vec<AxisLetter>,
    guard: SetpointGuard,
    /// The positions of the sample being checked (sized once: no allocation per cycle).
    next: Vec<f64>,
    /// Injected `jump` faults not yet struck: (machine time, axis index, offset), by time.
    jumps: VecDeque<(f64, usize, f64)>,
}

impl CommandPath {
    /// The command path of `config`, the machine axes standing at `start` (machine order).
    pub(crate) fn new(config: &MachineConfig, start: &[f64]) -> Self {
        let axes: Vec<GuardAxis> = config
            .axes
            .iter()
            .map(|a| GuardAxis {
                letter: a.letter,
                rotary: a.kind == AxisKind::Rotary,
                travel: a.travel,
                max_velocity: a.max_velocity,
                max_acceleration: a.max_acceleration,
            })
            .collect();
        let n = axes.len();
        Self {
            kin: config.kinematics(),
            tcpm: false,
            letters: config.letters(),
            guard: SetpointGuard::new(axes, config.servo_period, start),
            next: vec![0.0; n],
            jumps: VecDeque::new(),
        }
    }

    /// Schedules the `jump` faults among `config.faults` (simulation: each offsets one
    /// commanded sample of its axis before the guard sees it). A jump of an axis that is not
    /// simulated is refused: real drives never get one.
    pub(crate) fn with_jumps(mut self, config: &MachineConfig) -> Result<Self, FaultSpecError> {
        let mut jumps = Vec::new();
        for f in config.faults.iter().filter(|f| f.kind == FaultKind::Jump) {
            let letter = f.axis.ok_or(FaultSpecError::NeedsAxis(f.kind, f.at))?;
            let axis = config
                .axes
                .iter()
                .position(|a| a.letter == letter && matches!(a.backend, BackendConfig::Sim(_)))
                .ok_or(FaultSpecError::NotSimulated(f.kind, f.at, letter))?;
            jumps.push((f.at, axis, f.jump_offset()));
        }
        jumps.sort_by(|a, b| a.0.total_cmp(&b.0));
        self.jumps = jumps.into();
        Ok(self)
    }

    /// The kinematics, in the TCPM state of the last event.
    pub(crate) fn kinematics(&self) -> &dyn Kinematics {
        self.kin.as_ref()
    }

    /// A non-motion op reaching the servo loop: the TCPM switch changes the kinematics.
    pub(crate) fn event(&mut self, op: &Op) {
        if let OpKind::Tcpm { on, .. } = &op.kind {
            // From here on X Y Z of the samples are the tool tip on the workpiece (on) or the
            // machine's own X Y Z (off).
            self.kin.set_tcpm(*on);
            self.tcpm = *on;
        }
    }

    /// The machine-axis positions of `sample` at machine time `t`, checked by the guard.
    /// Accepted, they are the positions to command; refused, nothing may be sent and the
    /// guard's history stays at the last good setpoint.
    pub(crate) fn positions(&mut self, sample: &Sample, t: f64) -> Result<&[f64], Violation> {
        self.kin.to_machine(&sample.pose, &mut self.next);
        while let Some(&(at, axis, offset)) = self.jumps.front() {
            if at > t {
                break;
            }
            self.jumps.pop_front();
            if let Some(x) = self.next.get_mut(axis) {
                *x += offset;
            }
        }
        self.guard.check(&self.next)?;
        Ok(&self.next)
    }

    /// The setpoints for `sample` at the accepted `positions`, with the velocity and
    /// acceleration feed-forward: under TCPM the kinematics' Jacobian applied to the program
    /// rates (the acceleration without the Jacobian's own rate of change), else the program
    /// axis's own rates.
    pub(crate) fn setpoints(&self, sample: &Sample, positions: &[f64], out: &mut [Setpoint]) {
        let (mut vel, mut acc) = ([0.0; 9], [0.0; 9]);
        if self.tcpm {
            self.kin
                .rates_to_machine(&sample.pose, &sample.velocity, &mut vel);
            self.kin
                .rates_to_machine(&sample.pose, &sample.acceleration, &mut acc);
        }
        for (i, ((sp, &l), &x)) in out.iter_mut().zip(&self.letters).zip(positions).enumerate() {
            let (v, a) = if self.tcpm {
                (vel.get(i).copied(), acc.get(i).copied())
            } else {
                (None, None)
            };
            *sp = Setpoint {
                position: x,
                velocity: v.unwrap_or(sample.velocity[l.index()]),
                acceleration: a.unwrap_or(sample.acceleration[l.index()]),
            };
        }
    }

    /// The backends got the last setpoint again (a cycle holding position).
    pub(crate) fn repeat(&mut self) {
        self.guard.repeat();
    }
}

/// The test run's diagnostic for a setpoint the guard refuses, at its block.
pub(crate) fn refused_in_check(path: &Path, loc: SourceLoc, v: &Violation) -> Diagnostic {
    block_diagnostic(
        path,
        loc,
        format!("setpoint guard: {v} (the run would stop here)"),
    )
}

/// The run's diagnostic for a setpoint the guard refused, at its block.
pub(crate) fn refused_in_run(path: &Path, loc: SourceLoc, v: &Violation) -> Diagnostic {
    block_diagnostic(
        path,
        loc,
        format!("setpoint guard: {v}; not sent: quick stop from the last good setpoint"),
    )
}

#[cfg(test)]
mod tests {
    use super::super::guard::{VELOCITY_MARGIN, Violation};
    use super::super::{Run, RunError, RunOptions};
    use crate::config::MachineConfig;
    use crate::faults::FaultConfig;
    use crate::monitor::{StopCause, StopKind};
    use klar_interp::AxisLetter;
    use std::path::PathBuf;

    #[test]
    fn a_jumping_sample_never_reaches_a_backend_and_the_run_stops_quickly() {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("programs/rectangle.h");
        let mut config = MachineConfig::builtin_mill();
        let mut jump: FaultConfig = "jump:Y@1.1".parse().expect("fault");
        jump.offset = Some(0.5);
        config.faults.push(jump);
        let options = RunOptions {
            realtime: false,
            trace: None,
        };
        let mut run = Run::start(&path, &config, options).unwrap_or_else(|f| panic!("{}", f.error));
        let seen = run.io.record();
        let error = loop {
            match run.step() {
                Ok(true) => {}
                Ok(false) => panic!("the run ended without a stop"),
                Err(e) => break e,
            }
        };
        let RunError::Setpoint {
            diagnostic,
            violation,
        } = &error
        else {
            panic!("{error}");
        };
        let Violation::Velocity { axis, step, .. } = *violation else {
            panic!("{violation:?}");
        };
        assert_eq!(axis, AxisLetter::Y);
        assert!(step > 0.5, "step {step}");
        // Block 5, `L X-10 Y+10 FMAX`, is under way at 1.1 s.
        assert_eq!(
            (diagnostic.line, diagnostic.block),
            (6, Some(5)),
            "{diagnostic}"
        );
        let stop = run.stop_report().expect("stop report").clone();
        assert_eq!(stop.kind, StopKind::Quick);
        assert!(matches!(stop.cause, StopCause::Setpoint(_)), "{stop}");
        // What the backends got: every axis, cycle by cycle, within the guard's step bound,
        // up to rest.
        let seen = seen.lock().expect("record").clone();
        assert!(seen.len() > 100, "{} setpoints recorded", seen.len());
        for (k, a) in config.axes.iter().enumerate() {
            let x: Vec<f64> = seen
                .iter()
                .filter(|(_, i, _)| *i == k)
                .map(|(_, _, sp)| sp.position)
                .collect();
            let bound = VELOCITY_MARGIN * a.max_velocity * config.servo_period;
            let largest = x
                .windows(2)
                .map(|w| (w[1] - w[0]).abs())
                .fold(0.0, f64::max);
            assert!(largest <= bound, "axis {}: a step of {largest}", a.letter);
            // At rest at the end: the last setpoints are still.
            let n = x.len();
            assert!((x[n - 1] - x[n - 2]).abs() < 1e-12, "axis {}", a.letter);
        }
    }
}
