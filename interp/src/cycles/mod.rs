//! Machining cycles as motion, independent of the language that calls them.
//!
//! A cycle is a number and a set of parameters; [`generate`] turns it into a list of
//! [`Move`]s in the *working-plane frame* of the caller: coordinates `[a, b, t]` where `a`
//! and `b` are the two axes of the working plane (X and Y for tool axis Z) and `t` is the
//! tool axis, in mm, in program coordinates (before datum shift, mirror, rotation and
//! scaling, which the caller applies to the moves afterwards). The caller — the Klartext
//! executor for `CYCL CALL`/`M99`, the ISO executor for `G79` — maps the moves onto axes and
//! emits ops. Generators are pure: no state, no I/O, the same input gives the same moves.

use crate::op::SpindleDir;

mod drill;
mod pattern;
mod pocket;
mod sl;

/// A point in the working-plane frame: `[a, b, tool axis]`, mm.
pub type P3 = [f64; 3];

/// Feed of one cycle move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CycleFeed {
    /// Rapid traverse (FMAX).
    Rapid,
    /// Feed rate, mm/s.
    Rate(f64),
    /// Feed per spindle revolution, mm (rigid tapping: the thread pitch).
    PerRev(f64),
}

/// One step of a cycle's motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Move {
    /// Straight move to `to`.
    Line {
        /// End point.
        to: P3,
        /// Feed.
        feed: CycleFeed,
    },
    /// Circular (helical when `to[2]` differs from the start) move in the working plane
    /// about `centre` (a, b) to `to`; `ccw` is counter-clockwise seen from the positive
    /// tool axis; `turns` whole extra revolutions are added (0 for a plain arc; a start
    /// point equal to the end point with `turns == 0` is one full circle).
    Arc {
        /// Centre in the plane.
        centre: [f64; 2],
        /// End point.
        to: P3,
        /// Direction.
        ccw: bool,
        /// Extra full revolutions.
        turns: u32,
        /// Feed.
        feed: CycleFeed,
    },
    /// Dwell, seconds.
    Dwell(f64),
    /// Spindle direction change at this point (tapping reversal); the speed stays.
    Spindle(SpindleDir),
    /// Rigid tapping geared to the spindle from here (the set-up clearance) towards the
    /// bottom `to` and back: see [`crate::op::OpKind::RigidTap`].
    RigidTap {
        /// Bottom of the thread.
        to: P3,
        /// Pitch, mm per revolution (positive).
        pitch: f64,
        /// Direction of rotation that enters the thread.
        hand: SpindleDir,
        /// Distance from here to the surface, mm: infeeds count from the surface.
        lead_in: f64,
        /// Infeed per stroke for chip breaking, mm (the whole depth at once when ≥ it).
        infeed: f64,
        /// Back-off after each infeed, mm (0: all the way out to the start).
        back: f64,
        /// Spindle speed factor of the retraction.
        retract_factor: f64,
    },
}

/// The depths (mm from the start) the strokes of a rigid tap end at, for a thread from
/// `lead_in` to `depth` below the start: infeeds of `infeed` counted from the surface
/// (`lead_in`), each but the last followed by a back-off of `back` (0: to the start), and
/// the way out to the start last.
pub fn tap_strokes(lead_in: f64, depth: f64, infeed: f64, back: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let thread = depth - lead_in;
    let step = if infeed > 0.0 && infeed < thread {
        infeed
    } else {
        thread.max(0.0)
    };
    let mut d = lead_in.min(depth);
    while d < depth - 1e-9 && step > 0.0 {
        d = (d + step).min(depth);
        out.push(d);
        if d < depth - 1e-9 {
            out.push(if back > 0.0 { (d - back).max(0.0) } else { 0.0 });
        }
        if out.len() > 20_000 {
            break;
        }
    }
    if out.is_empty() {
        out.push(depth);
    }
    out.push(0.0);
    out
}

/// Which parameter of a cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ParamKey {
    /// A Q-numbered parameter of a current cycle (`Q200=2`).
    Q(u32),
    /// The `index`-th value (0-based) on sub-block `line` of an old-format cycle
    /// (`CYCL DEF 1.2 TIEFE -20` is `Old { line: 2, index: 0 }`). Words whose letter is a
    /// known address keep their letter in [`ParamKey::OldWord`] instead.
    Old {
        /// Sub-block number (the `n` of `1.n`).
        line: u8,
        /// Position among the plain values of that sub-block.
        index: u8,
    },
    /// An address word of an old-format cycle: `F` (feed, in the program's F unit per
    /// minute, already converted to mm/s by the caller) or `DR` (+1 or −1).
    OldWord(&'static str),
    /// The `F` word of sub-block `line` of an old-format cycle, mm/s (cycles with a plunging
    /// and a milling feed on different sub-blocks; [`ParamKey::OldWord`]`("F")` is the first).
    OldFeed {
        /// Sub-block number.
        line: u8,
    },
}

/// The parameters of one cycle definition.
///
/// Values are passed as written (lengths mm, feeds mm/min, dwell times s). Words in place
/// of a number: `FMAX` (allowed by the manual for retraction and pre-positioning feeds such
/// as Q208 and Q253) is passed as `f64::INFINITY`; `FAUTO` is resolved by the caller to
/// the feed of the TOOL CALL in mm/min; `PREDEF` to the global default, or `None`. A
/// generator treats `None` for a parameter that later software versions added (Q395,
/// Q379, …) as that parameter's neutral value and reports [`CycleError::Missing`] for the
/// essential ones.
pub trait ParamSource {
    /// The value of `key`, or `None` when the definition did not give it.
    fn get(&self, key: ParamKey) -> Option<f64>;
}

impl<F: Fn(ParamKey) -> Option<f64>> ParamSource for F {
    fn get(&self, key: ParamKey) -> Option<f64> {
        self(key)
    }
}

/// What a cycle needs to know about the machine at the call.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CycleContext {
    /// Tool position when the cycle is called, `[a, b, t]` (the cycle works at `a, b`).
    pub pos: P3,
    /// Active tool radius (table radius + deltas), mm.
    pub tool_radius: f64,
    /// Programmed spindle speed, rpm (0 when none).
    pub spindle_rpm: f64,
    /// Spindle direction when the cycle is called.
    pub spindle: SpindleDir,
    /// Modal feed, mm/s, when one was programmed.
    pub feed: Option<f64>,
    /// Cycle 21: radius of the rough-out tool named in its Q13 (table radius + DR), which
    /// the caller looks up in its tool table; `None` otherwise.
    pub rough_out_radius: Option<f64>,
}

/// Why a cycle cannot be generated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CycleError {
    /// No generator for that number.
    #[error("cycle {0} is not supported")]
    Unknown(u32),
    /// A required parameter is missing.
    #[error("cycle {cycle}: parameter {param} ({what}) is missing")]
    Missing {
        /// Cycle number.
        cycle: u32,
        /// The parameter as written (`Q201`, `1.2`).
        param: String,
        /// What it means.
        what: &'static str,
    },
    /// A parameter lies outside the range the manual allows.
    #[error("cycle {cycle}: {param} = {value} is out of range ({range})")]
    OutOfRange {
        /// Cycle number.
        cycle: u32,
        /// The parameter as written.
        param: String,
        /// Its value.
        value: f64,
        /// The allowed range in words.
        range: &'static str,
    },
    /// The active tool's radius does not fit the cycle (zero, negative, or too large).
    #[error("cycle {cycle}: tool radius {radius} is not usable")]
    ToolRadius {
        /// Cycle number.
        cycle: u32,
        /// The radius of the active tool, mm.
        radius: f64,
    },
    /// The parameters are consistent on their own but describe impossible geometry (tool
    /// wider than the pocket, zero depth, …).
    #[error("cycle {cycle}: {msg}")]
    Geometry {
        /// Cycle number.
        cycle: u32,
        /// What is wrong.
        msg: String,
    },
}

/// True when `number` is a call-active cycle that [`generate`] knows.
pub fn is_call_active(number: u32) -> bool {
    drill::knows(number) || pocket::knows(number) || sl::knows(number)
}

/// Appends the motion of cycle `number` with parameters `p`, called at `ctx`, to `out`.
/// On error `out` is left as it was.
pub fn generate(
    number: u32,
    p: &dyn ParamSource,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let mark = out.len();
    let r = if drill::knows(number) {
        drill::generate(number, p, ctx, out)
    } else if pocket::knows(number) {
        pocket::generate(number, p, ctx, out)
    } else {
        Err(CycleError::Unknown(number))
    };
    if r.is_err() {
        out.truncate(mark);
    }
    r
}

/// True when `number` is a DEF-active pattern cycle (220, 221) that calls the last defined
/// machining cycle at each of its positions as soon as it is defined.
pub fn is_pattern(number: u32) -> bool {
    pattern::knows(number)
}

/// Runs pattern cycle `pattern` (220, 221) with parameters `pp`: at each of its positions
/// the machining cycle `machining` with parameters `mp` is generated, with the traverse
/// between positions the pattern's parameters prescribe. Moves are appended to `out`; on
/// error `out` is left as it was.
pub fn generate_pattern(
    pattern: u32,
    pp: &dyn ParamSource,
    machining: u32,
    mp: &dyn ParamSource,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let mark = out.len();
    let r = pattern::generate(pattern, pp, machining, mp, ctx, out);
    if r.is_err() {
        out.truncate(mark);
    }
    r
}

/// Runs the machining cycle `machining` at each of `points` (`PATTERN DEF` + `CYCL CALL
/// PAT`; the tool-axis coordinate of a point is the workpiece surface there), with the
/// traverse between points the manual prescribes. Moves are appended to `out`; on error
/// `out` is left as it was.
pub fn generate_at_points(
    points: &[P3],
    machining: u32,
    mp: &dyn ParamSource,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let mark = out.len();
    let r = pattern::at_points(points, machining, mp, ctx, out);
    if r.is_err() {
        out.truncate(mark);
    }
    r
}

/// One element of a closed contour in the working plane, for the SL cycles (14, 20–24):
/// the contour starts at the end of the previous element (the first element's start is
/// [`Contour::start`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContourSeg {
    /// Straight to `to`.
    Line {
        /// End point (a, b).
        to: [f64; 2],
    },
    /// Arc about `centre` to `to`.
    Arc {
        /// End point (a, b).
        to: [f64; 2],
        /// Centre (a, b).
        centre: [f64; 2],
        /// Counter-clockwise seen from the positive tool axis.
        ccw: bool,
    },
}

/// A closed contour described by one contour subprogram of cycle 14, with the radius
/// compensation it was programmed with (the SL cycles tell pockets from islands by it).
#[derive(Debug, Clone, PartialEq)]
pub struct Contour {
    /// First point (a, b).
    pub start: [f64; 2],
    /// Elements in programmed order.
    pub segs: Vec<ContourSeg>,
    /// Compensation programmed in the subprogram: `Some(true)` RL, `Some(false)` RR,
    /// `None` R0.
    pub left: Option<bool>,
}

/// Runs an SL cycle (`cycle` = 21 pilot drilling, 22 rough-out, 23 floor finishing,
/// 24 side finishing) on the contours of the last cycle 14 with the parameters of the last
/// cycle 20 (`p20`) and of this cycle (`p`). Moves are appended to `out`; on error `out` is
/// left as it was.
pub fn generate_sl(
    cycle: u32,
    contours: &[Contour],
    p20: &dyn ParamSource,
    p: &dyn ParamSource,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let mark = out.len();
    let r = sl::generate(cycle, contours, p20, p, ctx, out);
    if r.is_err() {
        out.truncate(mark);
    }
    r
}
