//! Feed hold during a pass geared to the spindle.
//!
//! On HEIDENHAIN lathe controls a cycle stop in a thread cycle acts only once the thread
//! cut is over, and the feed override has no say in the cut: stopping the slide while the
//! spindle turns on would ruin the groove, and a tool left standing in it would rub. klar
//! does the same for every pass geared to the spindle. A feed hold asked for during a
//! thread pass (G33, a pass of G31) lets the pass run to its end point, then lets the move
//! after it (the retract out of the groove) run to its end, and holds there. A feed hold
//! during a rigid tap lets the tap finish, the reversal and the stroke back out to the
//! set-up clearance included, and holds where it ends. Resuming goes on with the program;
//! resuming before the hold has taken effect cancels it. A stop asked for during a geared
//! pass (operator or caller) waits the same way before the run ends (`stop`).

use super::Run;

/// A feed hold asked for during a geared pass, waiting for the pass to end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum PassHold {
    /// A thread pass: hold at the end of the move after it (the retract).
    AfterRetract,
    /// A rigid tap, which ends back out of the hole: hold where it ends.
    AtEnd,
}

impl Run<'_, '_> {
    /// True while the servo loop runs a pass geared to the spindle.
    pub(super) fn in_geared_pass(&self) -> bool {
        self.sync.is_some() || self.tap.active()
    }

    /// Remembers a feed hold asked for during a geared pass.
    pub(super) fn defer_hold(&mut self) {
        self.pass_hold = Some(if self.tap.active() {
            PassHold::AtEnd
        } else {
            PassHold::AfterRetract
        });
    }

    /// Once the geared pass is over, hands a deferred feed hold to the planner.
    pub(super) fn apply_pass_hold(&mut self) {
        if self.in_geared_pass() {
            return;
        }
        match self.pass_hold.take() {
            Some(PassHold::AfterRetract) => self.planner.hold_after_move(),
            Some(PassHold::AtEnd) => self.planner.hold(),
            None => {}
        }
    }

    /// True while a feed hold is asked for and not yet in force (deferred to the end of a
    /// geared pass, or to the end of the retract after it).
    pub(super) fn hold_deferred(&self) -> bool {
        self.pass_hold.is_some() || self.planner.hold_pending()
    }
}
