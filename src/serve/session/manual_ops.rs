//! The manual operations the machine thread carries out between program runs: a jog or an
//! MDI block (a generated one-block program through the same test run and run as any
//! program) and homing (the backends' own sequences, in machine time).

use super::{HOMING_TIMEOUT, MachineLoop, MachineState, Reply};
use crate::machine::MachineIo;
use crate::serve::manual::{self, ManualOp, Refusal};

impl MachineLoop {
    /// Carries out a manual operation: refused with the reason, or accepted and run.
    pub(super) fn manual(&mut self, op: ManualOp, reply: Reply) {
        if let Some(r) = self.refusal() {
            let _ = reply.send(Err(r));
            return;
        }
        let described = describe(&op);
        let program = match manual::program_for(&op, &self.config, &self.standing) {
            Ok(p) => p,
            Err(r) => {
                let _ = reply.send(Err(r));
                return;
            }
        };
        let Some((name, text)) = program else {
            let axis = match &op {
                ManualOp::Home { axis } => axis.clone(),
                _ => None,
            };
            self.home(axis.as_deref(), reply, described);
            return;
        };
        let path = match manual::write_program(&self.scratch, name, &text) {
            Ok(p) => p,
            Err(r) => {
                let _ = reply.send(Err(r));
                return;
            }
        };
        // The same test run a program gets, from where the axes stand: refused before
        // anything moves, with the diagnostics.
        let checked = crate::testrun::test_run(&path, &self.run_config());
        if !checked.passed() {
            let why = checked
                .errors
                .iter()
                // The generated program's line numbers mean nothing to the operator.
                .map(|d| d.message.clone())
                .collect::<Vec<_>>()
                .join("\n");
            let _ = reply.send(Err(Refusal::Check(why)));
            return;
        }
        let _ = reply.send(Ok(()));
        tracing::info!(operation = %described, "manual operation");
        self.snap.manual = Some(described);
        self.run_program(&path);
        // A manual move that ended normally leaves the machine idle, ready for the next.
        if matches!(
            self.snap.state,
            MachineState::Finished | MachineState::Stopped
        ) {
            self.snap.state = MachineState::Idle;
            self.publish();
        }
    }

    /// Homes one axis or all with the backends' own sequences.
    pub(super) fn home(&mut self, axis: Option<&str>, reply: Reply, described: String) {
        if self.config.needs_wall_clock() {
            let _ = reply.send(Err(Refusal::Unsupported(
                "homing drives on a bus or serial line from the dashboard is not supported yet"
                    .into(),
            )));
            return;
        }
        let order = match manual::homing_order(&self.config, axis) {
            Ok(o) => o,
            Err(r) => {
                let _ = reply.send(Err(r));
                return;
            }
        };
        let config = self.run_config();
        let mut io = match MachineIo::open(&config) {
            Ok(io) => io,
            Err(e) => {
                let _ = reply.send(Err(Refusal::Unsupported(e.to_string())));
                return;
            }
        };
        let _ = reply.send(Ok(()));
        self.snap.manual = Some(described);
        self.snap.state = MachineState::Running;
        self.publish();
        let letters = config.letters();
        let homed = crate::state::home_axes(
            &mut io,
            &letters,
            &order,
            0.0,
            config.servo_period,
            HOMING_TIMEOUT,
        );
        let at: Vec<f64> = io.feedback().iter().map(|f| f.position).collect();
        let referenced: Vec<bool> = io.feedback().iter().map(|f| f.homed).collect();
        if let Err(e) = io.disable() {
            tracing::warn!("disabling after homing: {e}");
        }
        self.standing.clone_from(&at);
        self.snap.tool = super::readings::tool_of(&config, &at);
        self.snap.commanded.clone_from(&at);
        self.snap.actual = at;
        for &i in &order {
            if let (Some(h), Some(&r)) = (self.homed.get_mut(i), referenced.get(i)) {
                *h = r;
            }
        }
        for (r, (&now, &before)) in self
            .snap
            .referenced
            .iter_mut()
            .zip(referenced.iter().zip(&self.homed))
        {
            *r = now || before || self.config.start_homed;
        }
        match homed {
            Ok(_) => {
                self.snap.state = MachineState::Idle;
                self.snap.message = None;
            }
            Err(e) => {
                self.snap.state = MachineState::Fault;
                self.snap.message = Some(format!("homing: {e}"));
            }
        }
        self.publish();
    }
}

/// An operation in words for the page and the log.
fn describe(op: &ManualOp) -> String {
    match op {
        ManualOp::Jog { axis, distance, .. } => format!("jog {axis} {distance:+.3}"),
        ManualOp::JogContinuous {
            axis, direction, ..
        } => format!("jog {axis} {}", if *direction > 0.0 { "+" } else { "-" }),
        ManualOp::Home { axis: Some(a) } => format!("home {a}"),
        ManualOp::Home { axis: None } => "home all".into(),
        ManualOp::Mdi { block } => format!("MDI {}", block.trim()),
    }
}
