//! Why a run did not complete ([`RunError`]) and the words its messages are made of.

use klar_interp::{AxisLetter, Diagnostic};
use klar_motion::{AxisFault, BackendError, MotionError};

use crate::machine::MachineError;

/// Why a run did not complete.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The program reader thread ended without a word (it panicked): the run stops on
    /// the path where the ops read so far end.
    #[error("the program reader stopped unexpectedly")]
    ReaderLost,
    /// Errors found before motion (syntax, or anything the test run refuses): nothing moved.
    #[error("the program has {} error(s); nothing moved{}", .0.len(), first_of(.0))]
    Syntax(Vec<Diagnostic>),
    /// Axes without a reference on a machine that needs homing: nothing moved.
    #[error("axes not homed: {}; home them first (nothing moved)", letters_list(.0))]
    NotHomed(Vec<AxisLetter>),
    /// A run-time program error: motion stopped at the end of the previous block.
    #[error("{0}")]
    Program(Diagnostic),
    /// The planner refused an op.
    #[error("{0}")]
    Motion(#[from] MotionError),
    /// An axis faulted (or the control's following-error monitor tripped on it): the
    /// axes were brought to rest with a quick stop.
    #[error("axis {axis}: {fault}{} (at {})", origin_text(.origin), where_text(*line, *block))]
    Fault {
        /// The axis.
        axis: AxisLetter,
        /// What it reported.
        fault: AxisFault,
        /// The device and cause behind the fault when the backend names more than the fault
        /// says (e.g. `node 1: heartbeat lost (silent for 0.512 s)`).
        origin: Option<String>,
        /// Program line being executed.
        line: u32,
        /// Block number being executed, if the block has one.
        block: Option<u64>,
    },
    /// At the program's end an axis did not come within its in-position window of the end
    /// point in time: the drives were switched off where they stood.
    #[error(
        "axis {axis}: not in position at the program end: {distance:.4} from the end point after {timeout} s (window {window})"
    )]
    NotInPosition {
        /// The axis.
        axis: AxisLetter,
        /// Commanded minus measured position when the time ran out.
        distance: f64,
        /// The in-position window.
        window: f64,
        /// The time allowed, s.
        timeout: f64,
    },
    /// The setpoints reached the axes too late (setpoint underrun): the run stopped on the
    /// path.
    #[error("setpoint underrun: a setpoint came {:.1} ms late, the limit is {:.1} ms (at {})", .late * 1e3, .limit * 1e3, where_text(*line, *block))]
    Underrun {
        /// How late, s.
        late: f64,
        /// The machine's limit, s.
        limit: f64,
        /// Program line being executed.
        line: u32,
        /// Block number being executed, if the block has one.
        block: Option<u64>,
    },
    /// The spindle faulted or did not reach speed.
    #[error("spindle: {message} (at line {line})")]
    Spindle {
        /// What happened.
        message: String,
        /// Program line being executed.
        line: u32,
    },
    /// The setpoint guard refused a commanded setpoint (a step beyond the axis's velocity or
    /// acceleration limit, or outside its travel): it was not sent, the axes were brought to
    /// rest with a quick stop from the last good setpoint.
    #[error("{diagnostic}")]
    Setpoint {
        /// Where (`file:line:col`, block) and what.
        diagnostic: Diagnostic,
        /// The refused step.
        violation: super::guard::Violation,
    },
    /// The run was stopped on request (after a feed hold brought it to rest).
    #[error("stopped on request (at line {line})")]
    Stopped {
        /// Program line being executed.
        line: u32,
    },
    /// The operator stopped the run from outside (SIGINT or SIGTERM to `klar run`, see
    /// [`OperatorStop`](super::OperatorStop)): the axes were brought to rest on the path (or,
    /// on a second request, with a quick stop) and the drives switched off.
    #[error("stopped by the operator {}", operator_where(*line, *block))]
    Operator {
        /// Program line being executed when the request came.
        line: u32,
        /// Block number being executed, if the block has one.
        block: Option<u64>,
    },
    /// The machine's backends could not be opened.
    #[error("{0}")]
    Machine(#[from] MachineError),
    /// The backend failed.
    #[error("backend: {0}")]
    Backend(#[from] BackendError),
    /// Writing the trace failed.
    #[error("trace: {0}")]
    Trace(#[from] std::io::Error),
    /// A probing move the run measures could not be run.
    #[error("touch probe: {0}")]
    Probe(String),
}

/// `; the first: <diagnostic>` when there is one.
fn first_of(diags: &[Diagnostic]) -> String {
    diags
        .first()
        .map(|d| format!("; the first: {d}"))
        .unwrap_or_default()
}

/// `A, B, C` for a list of letters.
fn letters_list(letters: &[AxisLetter]) -> String {
    letters
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// ` (origin)` when there is one.
fn origin_text(origin: &Option<String>) -> String {
    origin
        .as_ref()
        .map(|o| format!(" ({o})"))
        .unwrap_or_default()
}

/// `block N (line L)` or `line L`.
fn where_text(line: u32, block: Option<u64>) -> String {
    match block {
        Some(b) => format!("block {b}, line {line}"),
        None => format!("line {line}"),
    }
}

/// `at block N (line L)`, `at line L`, or `before the first block` (line 0: nothing ran yet).
fn operator_where(line: u32, block: Option<u64>) -> String {
    match (block, line) {
        (Some(b), _) => format!("at block {b} (line {line})"),
        (None, 0) => "before the first block".to_string(),
        (None, _) => format!("at line {line}"),
    }
}
