//! Measured probing: on a machine whose probe signal goes to the drives' touch-probe inputs,
//! a touch point is where the drives latched their positions, not where a model of the part
//! says the stylus touches. The interpreter runs ahead of the motion, so it cannot know that
//! point when it reads the cycle; instead it stops at each probing move and waits:
//!
//! 1. the cycle runs up to a probing move that has no measured answer yet; it hands out the
//!    ops before it, leaves a [`ProbeRequest`] (the whole probing distance at the probing
//!    feed) and stops with [`Flow::ProbeWait`];
//! 2. the machine runs those ops to a standstill, then the probing move, which it stops
//!    after the probe triggers (the probing move is no op: the machine owns it), and answers
//!    with the latched trigger position and where the axes came to rest ([`ProbeAnswer`]);
//! 3. the interpreter runs the `TCH PROBE` block again from its start: the probing moves
//!    answered so far take their answers, the ops already handed out are dropped, and the
//!    cycle goes on to its next probing move (step 1) or to its end.
//!
//! Running the block again gives the same ops up to the last answer because the cycle
//! starts from the same state each time: the position, the old-format head block and the
//! probe-axis height are put back as they were when the block first started, and the
//! cycle's parameters come from its definition. A probing move that finds nothing has run
//! its whole probing distance and no further; the cycle then ends with "touch point
//! inaccessible".

use std::collections::VecDeque;

use super::exec::{Flow, Machine};
use super::probe_exec::OldHead;
use crate::op::{Op, Pose};
use crate::probe::{ProbeAnswer, ProbeRequest};

/// The state of measured probing for the `TCH PROBE` block under way.
#[derive(Debug, Default)]
pub(crate) struct Measured {
    /// The answers to the block's probing moves so far, in order.
    answers: Vec<ProbeAnswer>,
    /// How many of `answers` the current run of the block has taken.
    used: usize,
    /// Ops of the block already handed out (dropped when it runs again).
    handed: usize,
    /// The probing move waiting for its answer.
    request: Option<ProbeRequest>,
    /// The machine's state when the block first started.
    saved: Option<Saved>,
}

/// What a `TCH PROBE` block starts from.
#[derive(Debug, Clone, Copy)]
struct Saved {
    pos: Pose,
    old: Option<OldHead>,
    axis_hit: Option<f64>,
}

impl Measured {
    /// The answer to the next probing move of this run of the block, when the machine has
    /// given it.
    pub(super) fn next_answer(&mut self) -> Option<ProbeAnswer> {
        let a = self.answers.get(self.used).copied()?;
        self.used += 1;
        Some(a)
    }

    /// Leaves `request` for the machine to answer.
    pub(super) fn ask(&mut self, request: ProbeRequest) {
        self.request = Some(request);
    }
}

impl Machine {
    /// Switches measured probing on: the touch points come from the machine's answers;
    /// `data` gives the probe's radius, clearance, distance and feeds.
    pub fn set_measured_probing(&mut self, data: crate::probe::ProbeData) {
        self.probe.data = data;
        self.probe.measured = Some(Measured::default());
    }

    /// True when the touch points come from the machine's answers.
    pub fn measured_probing(&self) -> bool {
        self.probe.measured.is_some()
    }

    /// The probing move waiting for its answer.
    pub fn probe_request(&self) -> Option<ProbeRequest> {
        self.probe.measured.as_ref().and_then(|m| m.request)
    }

    /// The machine's answer to [`Machine::probe_request`]. Ignored when no move waits.
    pub fn answer_probe(&mut self, answer: ProbeAnswer) {
        if let Some(m) = self.probe.measured.as_mut()
            && m.request.take().is_some()
        {
            m.answers.push(answer);
        }
    }

    /// Before a `TCH PROBE` block runs: first run, remembers the state; a run again after an
    /// answer, puts it back.
    pub(super) fn probe_block_start(&mut self) {
        let (pos, old, axis_hit) = (self.pos, self.probe.old, self.probe.axis_hit);
        let Some(m) = self.probe.measured.as_mut() else {
            return;
        };
        m.used = 0;
        match m.saved {
            Some(s) => {
                self.pos = s.pos;
                self.probe.old = s.old;
                self.probe.axis_hit = s.axis_hit;
            }
            None => m.saved = Some(Saved { pos, old, axis_hit }),
        }
    }

    /// After a `TCH PROBE` block ran (its ops pushed from `base` on in `out`): drops the
    /// ops handed out before, and tells whether the block waits for a probing move.
    pub(super) fn probe_block_end(&mut self, out: &mut VecDeque<Op>, base: usize) -> bool {
        let Some(m) = self.probe.measured.as_mut() else {
            return false;
        };
        let new = out.len().saturating_sub(base);
        out.drain(base..base + m.handed.min(new));
        if m.request.is_some() {
            m.handed = new;
            true
        } else {
            *m = Measured::default();
            false
        }
    }

    /// The flow after a `TCH PROBE` block whose cycle returned `r`.
    pub(super) fn probe_flow<E>(
        &mut self,
        r: Result<(), E>,
        out: &mut VecDeque<Op>,
        base: usize,
    ) -> Result<Option<Flow>, E> {
        if self.probe_block_end(out, base) {
            return Ok(Some(Flow::ProbeWait));
        }
        r.map(|()| None)
    }
}
