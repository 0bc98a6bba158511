//! Feeding the planner from the program reader, and keeping the errors met on the way.

use super::probing;
use super::reader::Feed;
use super::{Run, RunError};
use klar_interp::OpKind;

impl Run<'_, '_> {
    /// Moves ops from the reader into the planner while it wants more, waiting for them
    /// when `wait`. Returns false when the planner wants more and the reader has none yet.
    pub(super) fn feed_planner(&mut self, wait: bool) -> bool {
        while !self.input_done && self.planner.needs_input() {
            if self.probing.is_some() {
                // nothing comes before the probing move is measured
                return false;
            }
            match self.reader.next(wait) {
                None => return false,
                Some(Feed::Probe(request, blank, blocks)) => {
                    self.blocks = blocks;
                    if let Err(e) = self.planner.end_in_stop() {
                        self.stop_reading(RunError::Motion(e));
                        return true;
                    }
                    self.probing = Some(probing::Probing::new(request, blank));
                    return false;
                }
                Some(Feed::Op(op, blocks, basis)) => {
                    self.blocks = blocks;
                    if matches!(
                        op.kind,
                        OpKind::Line { .. } | OpKind::Arc { .. } | OpKind::Spline { .. }
                    ) {
                        self.warp.remember(op.loc, basis);
                    }
                    if let Err(e) = self.planner.push(op) {
                        self.stop_reading(RunError::Motion(e));
                    }
                    // A spline block's coefficients are freed by the reader, not here.
                    if let Some(spent) = self.planner.take_spent() {
                        self.reader.give_back(spent);
                    }
                }
                Some(Feed::Error(e, blocks)) => {
                    self.blocks = self.blocks.max(blocks);
                    self.stop_reading(e);
                }
                Some(Feed::End(blocks)) => {
                    self.blocks = blocks;
                    self.planner.finish();
                    self.input_done = true;
                }
            }
        }
        true
    }

    /// Keeps an error met during a stop that goes on, for the log when the run finishes
    /// (the first one: what follows from it adds nothing).
    pub(super) fn defer(&mut self, what: &'static str, error: RunError) {
        if self.deferred.is_none() {
            self.deferred = Some((what, error));
        }
    }

    /// An error found while reading ahead: the motion of the blocks before it finishes, then
    /// the run reports it.
    fn stop_reading(&mut self, error: RunError) {
        self.pending_error = Some(error);
        self.planner.finish();
        self.input_done = true;
    }
}
