//! Errors of the radius-compensation stage, each naming the block or blocks involved.

use crate::error::Where;
use klar_interp::SourceLoc;
use std::fmt;

/// The blocks a diagnostic names, written for people: `line 3, column 1 (block 2)` and
/// further blocks joined with "and".
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Blocks(pub Vec<SourceLoc>);

impl fmt::Display for Blocks {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, loc) in self.0.iter().enumerate() {
            if i > 0 {
                write!(f, " and ")?;
            }
            write!(f, "{}", Where(*loc))?;
        }
        Ok(())
    }
}

/// Why the compensation stage refused an op.
///
/// Every variant carries the source location of the block (or blocks) at fault. After an
/// error the [`super::Compensator`] is stopped: it releases no further motion.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CompError {
    /// A coordinate, radius, length or angle is NaN or infinite.
    #[error("{}: {what} is not a finite number", Where(*loc))]
    NonFinite {
        /// The block.
        loc: SourceLoc,
        /// Which value.
        what: &'static str,
    },
    /// The side changed from RL to RR (or back) without R0 or DEP in between.
    #[error("{}: radius compensation cannot switch directly between RL and RR; cancel it with R0 or DEP first", Where(*loc))]
    SideSwitch {
        /// The block.
        loc: SourceLoc,
    },
    /// Compensation was switched on in a circular block; it starts on a straight line.
    #[error("{}: radius compensation must start on a straight line, not on an arc", Where(*loc))]
    StartOnArc {
        /// The block.
        loc: SourceLoc,
    },
    /// An arc in another plane than the working plane while compensation is on.
    #[error("{}: arc outside the working plane while radius compensation is on", Where(*loc))]
    ArcOutsidePlane {
        /// The block.
        loc: SourceLoc,
    },
    /// A spline block while compensation is on (only lines and arcs are compensated).
    #[error("{}: spline blocks cannot be radius-compensated", Where(*loc))]
    SplineCompensated {
        /// The block.
        loc: SourceLoc,
    },
    /// A circular or spline block right after compensation ended starts where the tool is
    /// not: the block after R0 or DEP must be a straight line.
    #[error("{}: after radius compensation ends the tool is off the programmed point; the next move must be a straight line", Where(*loc))]
    CurveAfterCompensation {
        /// The block.
        loc: SourceLoc,
    },
    /// The tool changed while compensation is on.
    #[error("{}: tool change while radius compensation is on; cancel it with R0 or DEP first", Where(*loc))]
    ToolChangeWhileCompensating {
        /// The block.
        loc: SourceLoc,
    },
    /// TCPM switched (M128/M129, FUNCTION TCPM) while compensation is on.
    #[error("{}: TCPM switched while radius compensation is on; cancel it with R0 or DEP first", Where(*loc))]
    TcpmWhileCompensating {
        /// The block.
        loc: SourceLoc,
    },
    /// Compensation was requested with a negative effective tool radius (R + DR < 0).
    #[error("{}: the effective tool radius {radius} mm is negative", Where(*loc))]
    NegativeRadius {
        /// The block.
        loc: SourceLoc,
        /// The radius including DR.
        radius: f64,
    },
    /// A compensated block does not start where the previous one ended.
    #[error("{}: the block starts {gap:.6} mm away from the previous end point", Where(*loc))]
    Discontinuity {
        /// The block.
        loc: SourceLoc,
        /// The gap in the working plane.
        gap: f64,
    },
    /// The offset radius of an arc is zero or negative: the tool is larger than an inside arc.
    #[error("{}: tool radius {tool} mm does not fit inside the arc of radius {arc} mm", Where(*loc))]
    ArcTooSmall {
        /// The block.
        loc: SourceLoc,
        /// Programmed arc radius.
        arc: f64,
        /// Tool radius.
        tool: f64,
    },
    /// At an inside corner the offset paths of two elements never meet.
    #[error("{}: contour violation — the offset paths of these blocks do not intersect (tool radius {tool} mm too large)", Blocks(blocks.clone()))]
    NoIntersection {
        /// The two blocks forming the corner.
        blocks: Vec<SourceLoc>,
        /// Tool radius.
        tool: f64,
    },
    /// A compensated element would run backwards: a gap or step narrower than the tool.
    #[error("{}: contour violation — the tool path of the middle block would run backwards by {overlap:.4} mm (gap narrower than the tool, radius {tool} mm)", Blocks(blocks.clone()))]
    RunsBackwards {
        /// The previous, the offending and the next block.
        blocks: Vec<SourceLoc>,
        /// How far the trimmed element overlaps itself, mm along the path.
        overlap: f64,
        /// Tool radius.
        tool: f64,
    },
    /// The tool path of the first block comes closer than the tool radius to the programmed
    /// contour of the second (found within the look-ahead window); a single block when the
    /// transition arc after an arc of more than half a turn cuts back into that arc.
    #[error("{}: contour violation — the tool path of the first block comes within {distance:.4} mm of the contour of the second (tool radius {tool} mm)", Blocks(blocks.clone()))]
    Gouge {
        /// The block whose tool path intrudes, then the block whose contour it would cut (one
        /// block when both are the same).
        blocks: Vec<SourceLoc>,
        /// Smallest distance found, mm.
        distance: f64,
        /// Tool radius.
        tool: f64,
    },
    /// APPR while compensation is already on.
    #[error("{}: APPR needs radius compensation off (R0) before it", Where(*loc))]
    ApproachWhileCompensating {
        /// The block.
        loc: SourceLoc,
    },
    /// APPR or DEP with a side other than RL or RR, or an unusable parameter.
    #[error("{}: APPR/DEP {what}", Where(*loc))]
    BadApproach {
        /// The block.
        loc: SourceLoc,
        /// What is wrong.
        what: &'static str,
    },
    /// APPR was not followed by a contour element to approach.
    #[error("{}: APPR is not followed by a contour element in the working plane", Where(*loc))]
    ApproachWithoutContour {
        /// The block.
        loc: SourceLoc,
    },
    /// DEP without an active compensated contour to leave.
    #[error("{}: DEP needs a radius-compensated contour element before it", Where(*loc))]
    DepartWithoutContour {
        /// The block.
        loc: SourceLoc,
    },
    /// The start or end point of an LCT construction lies inside its arc's circle.
    #[error("{}: APPR/DEP LCT point lies inside the tangent circle of radius {radius} mm", Where(*loc))]
    LctInsideCircle {
        /// The block.
        loc: SourceLoc,
        /// Radius of the circle.
        radius: f64,
    },
    /// An op was pushed after an error stopped the stage.
    #[error("{}: radius compensation stopped after an earlier error", Where(*loc))]
    Stopped {
        /// The block.
        loc: SourceLoc,
    },
    /// An op was pushed after [`super::Compensator::finish`].
    #[error("{}: op pushed after the end of input", Where(*loc))]
    AfterFinish {
        /// The block.
        loc: SourceLoc,
    },
}

impl CompError {
    /// The (first) block the error names.
    pub fn loc(&self) -> Option<SourceLoc> {
        match self {
            CompError::NonFinite { loc, .. }
            | CompError::SideSwitch { loc, .. }
            | CompError::StartOnArc { loc, .. }
            | CompError::ArcOutsidePlane { loc, .. }
            | CompError::SplineCompensated { loc, .. }
            | CompError::CurveAfterCompensation { loc, .. }
            | CompError::ToolChangeWhileCompensating { loc, .. }
            | CompError::TcpmWhileCompensating { loc, .. }
            | CompError::NegativeRadius { loc, .. }
            | CompError::Discontinuity { loc, .. }
            | CompError::ArcTooSmall { loc, .. }
            | CompError::ApproachWhileCompensating { loc, .. }
            | CompError::BadApproach { loc, .. }
            | CompError::ApproachWithoutContour { loc, .. }
            | CompError::DepartWithoutContour { loc, .. }
            | CompError::LctInsideCircle { loc, .. }
            | CompError::Stopped { loc, .. }
            | CompError::AfterFinish { loc, .. } => Some(*loc),
            CompError::NoIntersection { blocks, .. }
            | CompError::RunsBackwards { blocks, .. }
            | CompError::Gouge { blocks, .. } => blocks.first().copied(),
        }
    }
}
