//! What a run hands back: its report, the failure that carries one, the axes' start
//! positions and the status snapshot for displays.

use super::RunError;
use crate::monitor::StopReport;
use klar_interp::AxisLetter;

/// What a finished (or stopped) run measured.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunReport {
    /// Machine time of the program in seconds (simulated, not wall time).
    pub machine_time: f64,
    /// Blocks the interpreter executed.
    pub blocks: u64,
    /// Servo cycles run.
    pub cycles: u64,
    /// Largest |following error| per machine axis.
    pub max_following_error: Vec<(AxisLetter, f64)>,
    /// Cycles whose setpoints missed their slot: in realtime mode a cycle that woke more
    /// than half a servo period after its deadline on the wall clock (or, with an injected
    /// `stall`, more than a period late); an injected `stall` longer than a period in
    /// simulated runs.
    pub underruns: u64,
    /// Wake-up lateness of the servo cycles on the wall clock (realtime runs).
    pub lateness: Option<crate::latency::LatenessSummary>,
    /// The servo loop's own time per cycle, from a wake-up to the next wait (realtime
    /// runs): tells a late wake-up from a cycle whose work ran long.
    pub cycle_work: Option<crate::latency::LatenessSummary>,
    /// Cycles whose work ran past the next cycle's deadline (realtime runs).
    pub work_overruns: u64,
    /// Servo cycles in which the planner wanted ops the program reader had not yet
    /// delivered (realtime runs): the path then brakes for the end of what it has.
    pub starved: u64,
    /// Corner blends the planner made.
    pub blends: u64,
    /// Corners the planner stopped at exactly because every one of its preallocated blend
    /// slots was held by the path ahead (`klar_motion::blend::BLEND_SLOTS`).
    pub blends_refused: u64,
    /// Seconds spent waiting for the spindle to reach speed (on the wall clock in realtime
    /// runs).
    pub spindle_wait: f64,
    /// True when the run used the wall clock.
    pub realtime: bool,
    /// Log records of the servo loop dropped because their queue was full.
    pub log_dropped: u64,
    /// How the run was stopped early by a fault or a request, if it was.
    pub stop: Option<StopReport>,
    /// Set when the spindle's stop at the end of the run could not be confirmed by its
    /// device: a warning that the spindle may still turn.
    pub spindle_warning: Option<String>,
    /// Where each axis stood when the run started.
    pub start: Vec<AxisStart>,
    /// The test run's planned machine time, s, when the test run ran before the start and
    /// went through the whole program: what progress displays count against.
    pub planned_time: Option<f64>,
    /// What the touch-probe cycles measured, in the order they ran.
    pub probe_results: Vec<klar_interp::ProbeResult>,
}

/// Where an axis stood when a run started: read from its drive when the drive measures its
/// own position, else the machine file's `start`.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisStart {
    /// The axis.
    pub axis: AxisLetter,
    /// Its position, mm or degrees.
    pub position: f64,
    /// True when its position is referenced (homed in this power cycle, an absolute
    /// encoder, or a machine file that declares every axis homed with `start_homed`).
    pub referenced: bool,
}

impl std::fmt::Display for AxisStart {
    /// `X stands at 4.9500 mm (referenced)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unit = if self.axis.is_rotary() { "°" } else { "mm" };
        let referenced = if self.referenced {
            "referenced"
        } else {
            "not referenced"
        };
        write!(
            f,
            "{} stands at {:.4} {unit} ({referenced})",
            self.axis, self.position
        )
    }
}

/// A run that ended early: the error plus what was measured until then.
#[derive(Debug)]
pub struct RunFailure {
    /// Why it stopped.
    pub error: RunError,
    /// Figures up to the stop.
    pub report: RunReport,
}

/// A snapshot of a run for displays.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunStatus {
    /// Machine time, s.
    pub t: f64,
    /// Program line of the motion being executed (1-based; 0 before the first).
    pub line: u32,
    /// Commanded position per machine axis.
    pub commanded: Vec<f64>,
    /// Measured position per machine axis.
    pub actual: Vec<f64>,
    /// Following error per machine axis.
    pub following_error: Vec<f64>,
    /// True while a feed hold is active or asked for (from the request on, also while it
    /// waits for the end of a geared pass and its retract).
    pub held: bool,
    /// Feed override factor (1.0 = 100 %).
    pub feed_override: f64,
    /// Path speed, mm/s.
    pub path_speed: f64,
    /// Spindle speed, rpm (signed), when the machine has a spindle.
    pub spindle_rpm: Option<f64>,
    /// Blocks executed so far.
    pub blocks: u64,
}
