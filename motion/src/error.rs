//! Errors of the motion planner, each naming the block that caused it.

use crate::config::ConfigError;
use crate::geom::GeomError;
use klar_interp::{AxisLetter, SourceLoc};
use std::fmt;

/// A source location written for people: `line L, column C (block N)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Where(pub SourceLoc);

impl fmt::Display for Where {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}, column {}", self.0.line, self.0.col)?;
        if let Some(b) = self.0.block {
            write!(f, " (block {b})")?;
        }
        Ok(())
    }
}

/// Why the planner refused a configuration or an op.
///
/// Every variant caused by an op carries that op's [`SourceLoc`]; only [`MotionError::Config`]
/// has none, since no op is involved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MotionError {
    /// The planner configuration is unusable.
    #[error("planner configuration: {0}")]
    Config(#[from] ConfigError),
    /// The op's geometry cannot be followed.
    #[error("{}: {source}", Where(*loc))]
    Geometry {
        /// The block.
        loc: SourceLoc,
        /// What is wrong with it.
        source: GeomError,
    },
    /// The op moves an axis the machine does not have.
    #[error("{}: axis {axis} is not on this machine", Where(*loc))]
    AbsentAxis {
        /// The block.
        loc: SourceLoc,
        /// The axis.
        axis: AxisLetter,
    },
    /// Feed per revolution needs a spindle the planner does not follow yet.
    #[error("{}: feed per revolution needs a spindle speed, which the planner does not follow yet", Where(*loc))]
    NeedsSpindle {
        /// The block.
        loc: SourceLoc,
    },
    /// The feed is not a positive finite number.
    #[error("{}: feed {feed} mm/s is not a positive finite number", Where(*loc))]
    BadFeed {
        /// The block.
        loc: SourceLoc,
        /// The feed given.
        feed: f64,
    },
    /// A dwell time is negative or not finite.
    #[error("{}: dwell time {seconds} s is not a finite number >= 0", Where(*loc))]
    BadDwell {
        /// The block.
        loc: SourceLoc,
        /// The time given.
        seconds: f64,
    },
    /// A path tolerance is negative or not finite.
    #[error("{}: path tolerance {mm} mm is not a finite number >= 0", Where(*loc))]
    BadTolerance {
        /// The block.
        loc: SourceLoc,
        /// The tolerance given.
        mm: f64,
    },
    /// The op does not start where the previous motion ended.
    #[error("{}: move starts {gap} away from the previous end point in axis {axis}", Where(*loc))]
    Discontinuity {
        /// The block.
        loc: SourceLoc,
        /// The axis with the gap.
        axis: AxisLetter,
        /// The gap (mm or degrees; NaN for a value that is not a number).
        gap: f64,
    },
    /// No usable speed limits exist for the move.
    #[error("{}: no speed limit can be derived for this move", Where(*loc))]
    Unplannable {
        /// The block.
        loc: SourceLoc,
    },
    /// An APPR/DEP op reached the planner: it must be resolved into lines and arcs by the
    /// radius-compensation stage first.
    #[error("{}: APPR/DEP needs the radius-compensation stage", Where(*loc))]
    UnresolvedApproach {
        /// The block.
        loc: SourceLoc,
    },
    /// More ops were pushed than the planner holds; push only while it needs input.
    #[error("{}: the planner's buffer is full (push only while it needs input)", Where(*loc))]
    BufferFull {
        /// The block.
        loc: SourceLoc,
    },
    /// An op was pushed after [`crate::Planner::finish`].
    #[error("{}: op pushed after the end of input", Where(*loc))]
    AfterFinish {
        /// The block.
        loc: SourceLoc,
    },
}
