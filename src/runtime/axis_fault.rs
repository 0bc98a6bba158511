//! Which axis a fault is reported on, and the error that names it: when one device on a
//! shared link faults, the others stop with it; the report names the device that faulted
//! first-hand, with the cause its backend knows.

use super::{Run, RunError};
use klar_motion::AxisFault;

impl Run<'_, '_> {
    /// The axis whose fault to report: one whose own device faulted (not one stopped only
    /// because another device on its link did), else the first faulted axis. Allocates
    /// nothing unless an axis reports a fault (it runs every servo cycle).
    pub(super) fn faulted_axis(&self) -> Option<usize> {
        let mut first = None;
        for (i, f) in self.io.feedback().iter().enumerate() {
            if f.fault.is_none() {
                continue;
            }
            if self.io.fault_origin(i).is_none_or(|o| o.primary) {
                return Some(i);
            }
            first.get_or_insert(i);
        }
        first
    }

    /// The error for the fault axis `i` reports, with the device and cause its backend
    /// names when the fault's own words do not already say them.
    pub(crate) fn axis_fault(&self, i: usize) -> RunError {
        let fault = self
            .io
            .feedback()
            .get(i)
            .and_then(|f| f.fault.clone())
            .unwrap_or(AxisFault::CommunicationLost);
        let origin = self
            .io
            .fault_origin(i)
            .map(|o| o.detail)
            .filter(|d| !fault.to_string().contains(d.as_str()));
        RunError::Fault {
            axis: self.letters[i],
            fault,
            origin,
            line: self.line,
            block: self.last_loc.and_then(|l| l.block),
        }
    }
}
