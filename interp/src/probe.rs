//! The touch probe as the interpreter asks it: "move the stylus ball from here toward there;
//! where does it touch the workpiece?". The interpreter stays pure: whoever runs a program
//! answers the question — klar's test run and its simulated machine from a simulated
//! workpiece placed in the machine file. Touch-probe cycles (`TCH PROBE`) are refused on an
//! interpreter that was given no probe.

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
}

impl Default for ProbeData {
    fn default() -> Self {
        ProbeData {
            radius: 2.0,
            set_up: 2.0,
            distance: 20.0,
            feed: 100.0,
            positioning_feed: None,
        }
    }
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
