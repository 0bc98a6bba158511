//! The look-ahead planner and its sampler: ops in, time-stamped samples and events out.
//!
//! Motion ops become path elements ([`crate::geom::Segment`]); corners between elements
//! are blended inside the active path tolerance ([`path`]); a jerk-limited speed generator
//! moves along the blended path one servo period at a time ([`speed`]), looking ahead over
//! the pieces within its braking distance (the window, in `scan.rs`) and meeting their
//! speed limits with zero acceleration or on the way through (`through.rs`). While TCPM is on,
//! [`tcpm`] gives the program axes limits that keep the machine axes within theirs. There
//! is no per-element profile: speed carries across elements, so short elements cost no time
//! of their own.
//!
//! Ops without motion reach the caller as [`Step::Event`]s, in order, before the first
//! sample taken after the path reaches the point where they take effect. These need the
//! machine standing on their point, so the path stops exactly there first (the last sample
//! before the event is on the point): dwell (which also holds for its time), tool change,
//! spindle and C-axis changes, program stops, the program end and explicit exact stops.
//! Coolant, tolerance and radius-compensation ops do not stop or flush the look-ahead.
//! [`OpKind::Tolerance`] sets the tolerance for the corners after it (`None`: the
//! configured default). Radius compensation is the job of the stage before the planner;
//! the planner follows the path it is given.
//!
//! Feed override (0–150 %, [`Planner::set_feed_override`]) and feed hold
//! ([`Planner::hold`], [`Planner::resume`]) act at once with jerk-limited speed changes on
//! the path. A hold stops where its braking ends; when that is a hair short of a stop point
//! the path was braking for anyway, the rest of the way is travelled after the hold (no
//! step onto the point).

mod commit;
mod corner_stop;
use commit::{path_feed, piece_error};
mod cruise;
mod deep;
mod drops;
mod handover;
mod move_hold;
mod outside;
pub mod path;
#[cfg(test)]
mod pool_tests;
#[cfg(test)]
mod reserve_tests;
mod run;
mod scan;
mod search;
pub mod smooth;
pub mod speed;
pub mod splines;
#[cfg(test)]
mod starved_tests;
pub mod tcpm;
#[cfg(test)]
mod test_machine;
mod through;
mod verdicts;

pub use tcpm::{TCPM_DERATE, TableGeometry};

use crate::blend::{BLEND_SLOTS, BlendPool};
use crate::config::{AxisLimits, PlannerConfig};
use crate::error::MotionError;
use crate::geom::{Arc, AxisBounds, GeomError, Line, Poly, Segment, finite_pose, letter};
use crate::limits::Headroom;
use crate::profile::Ramp;
use klar_interp::{AxisLetter, Op, OpKind, Pose, SourceLoc};
use path::{Element, MAX_OVERRIDE, Piece, Shape, Waiting, piece_limits};
use speed::{Motion, Window};
use splines::{SPLINE_SLOTS, SplinePool};
use std::collections::VecDeque;

/// Pieces and events the planner holds at most before it stops asking for input (memory
/// bound; the look-ahead distance is what normally decides).
pub const BUFFER_CAPACITY: usize = 20_000;

/// Pieces the planner makes room for when it is built (the look-ahead of a dense CAM
/// pocket at the bench machine's speeds holds up to about 2 000).
pub const RESERVED_PIECES: usize = 4096;

/// Room kept free in the reserved piece queue for what one op can add (its element and the
/// blends and splits committed with it, and a flush of the waiting elements): the planner
/// takes no more ops once fewer than this are free ([`Planner::needs_input`]).
pub const PIECE_MARGIN: usize = 1024;

/// Limits in the speed window, events, waiting elements and polyline vertices the planner
/// makes room for when it is built (the pocket's window holds up to 64 limits).
pub const RESERVED_LIMITS: usize = 512;

/// Largest gap (mm or degrees) accepted between an op's start and the previous end point.
/// The planner always continues from its own end point, so accepted gaps do not jump.
pub const CONTINUITY_TOLERANCE: f64 = 1e-6;

/// Distance (mm) by which the path may pass an event's point or overshoot a stop point
/// before it counts as more than rounding (an overshoot beyond it is reported).
const STOP_SNAP: f64 = 1e-6;

/// Distance (mm) within which a standstill is on a point by rounding alone: a stop marker
/// takes effect, and the path is finished, only there.
const ROUNDING: f64 = 1e-9;

/// Share of the path's acceleration and jerk limits that putting the state on a stop point
/// in one period may cost at most (its remaining way, speed and acceleration over T², T, 1
/// and over T³, T², T). A state further from the point travels on: a feed hold that comes
/// to rest a hair short of a stop point it was braking for anyway goes the rest of the way
/// when it ends, with no step onto the point (1 µm in one period would be 1000 mm/s³ at
/// 1 ms).
const SNAP_SHARE: f64 = 1e-3;

/// Elements kept back for corner decisions at least.
const ELEMENTS_AHEAD: usize = 3;

/// The commanded state of all program axes at one servo instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time in seconds since the start: exactly `k · period`.
    pub t: f64,
    /// Commanded program position (mm, degrees).
    pub pose: Pose,
    /// Commanded velocity per axis (mm/s, °/s), indexed like the pose.
    pub velocity: [f64; 9],
    /// Commanded acceleration per axis (mm/s², °/s²), indexed like the pose.
    pub acceleration: [f64; 9],
    /// The block being executed.
    pub loc: SourceLoc,
}

/// What the planner hands to the servo loop next.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// One servo cycle's setpoint.
    Sample(Sample),
    /// A non-motion op reaching the servo loop at the time it takes effect.
    Event(Op),
}

/// Something that happens at a path position.
#[derive(Debug, Clone)]
enum Marker {
    /// An op that takes effect when the path gets there.
    Event { at: f64, op: Op },
    /// A standstill at `at`, then the op (if any), then a hold of `dwell` seconds.
    Stop { at: f64, op: Option<Op>, dwell: f64 },
}

/// The planner: takes ops, gives samples at the servo period.
///
/// Call [`Planner::push`] while [`Planner::needs_input`] is true (or [`Planner::finish`] when
/// the ops run out), then [`Planner::next_step`]. It asks for input until the planned path
/// reaches beyond the braking distance from the machine's top speed, and holds at most
/// [`BUFFER_CAPACITY`] pieces and events, so memory stays constant however long the program.
#[derive(Debug, Clone)]
pub struct Planner {
    config: PlannerConfig,
    /// The machine's own limits (`config.limits` is derated from them while TCPM is on).
    base_limits: [Option<crate::config::AxisLimits>; 9],
    /// Tolerance for the corners from now on.
    tolerance: f64,
    /// Look-ahead distance wanted beyond the current position.
    horizon: f64,
    /// Floors of the path acceleration and jerk the look-ahead distance is sized with
    /// (pieces that turn a rotary axis may go below them: `low_ahead`).
    accel_floor: f64,
    jerk_floor: f64,
    /// The lowest limits of the pieces ahead that turn a rotary axis below the floors.
    low_ahead: deep::LowAhead,
    waiting: VecDeque<Waiting>,
    /// The vertices of the polyline of linear lines up to the start of the front waiting
    /// element (the split-point fit looks back on them; a bounded number, see `commit.rs`),
    /// and while an element is committed those of the linear lines waiting after it.
    vertices: Vec<Pose>,
    /// Events before the first waiting element (placed at the planned end).
    pieces: VecDeque<Piece>,
    markers: VecDeque<Marker>,
    /// End of the committed path.
    committed_end: f64,
    /// Which committed speed limits are steps down.
    drops: drops::DropTracker,
    /// End pose of everything pushed so far.
    planned_pose: Pose,
    /// Pose and block where the machine stands when no piece is left.
    rest_pose: Pose,
    rest_loc: SourceLoc,
    state: Motion,
    /// Path position the last computed state reached (events up to here are due).
    reached: f64,
    stash: Option<Sample>,
    hold_until: Option<(f64, SourceLoc)>,
    window: Window,
    /// The speed step's buffers, reused every period.
    scratch: speed::Scratch,
    /// Distance ahead the last scan looked at.
    range: f64,
    factor: f64,
    held: bool,
    cycles: u64,
    finished: bool,
    /// True while TCPM is on.
    tcpm: bool,
    /// The feed (mm/s) of the compensating moves while TCPM is on (`M128 F…`).
    compensation_feed: Option<f64>,
    /// The table axes of a table-table machine, for the limits of turning moves with TCPM.
    table: Option<TableGeometry>,
    /// Where the state may cruise on without the speed generator.
    cruise: cruise::Cruising,
    /// The last window's limits before and after the backward pass.
    settled: scan::SettleMemo,
    /// A feed hold at the end of the next move (see `move_hold`).
    move_hold: move_hold::MoveHold,
    /// Slots for the blend curves of the committed path, made here so that committing a
    /// corner allocates nothing ([`BLEND_SLOTS`]).
    blends: BlendPool,
    /// Slots for the spline elements waiting or ahead, made here so that pushing a spline
    /// block allocates nothing ([`SPLINE_SLOTS`]).
    splines: SplinePool,
    /// The last spline op taken in, kept for the caller to free elsewhere
    /// ([`Planner::take_spent`]).
    spent: Option<Op>,
}

impl Planner {
    /// Corners stopped at exactly because every blend slot was held by the path ahead
    /// (none with [`BLEND_SLOTS`] slots unless the look-ahead holds that many blends).
    pub fn blends_refused(&self) -> u64 {
        self.blends.refused()
    }

    /// Corner blends (and runs of dense code blended as one curve) made so far.
    pub fn blends_made(&self) -> u64 {
        self.blends.stored()
    }

    /// A planner for a machine standing at `start`.
    pub fn new(config: PlannerConfig, start: Pose) -> Result<Self, MotionError> {
        config.validate()?;
        if let Some(i) = start.0.iter().position(|v| !v.is_finite()) {
            return Err(crate::config::ConfigError::BadStart(letter(i)).into());
        }
        let axes = config.limits.iter().flatten();
        let top = axes
            .clone()
            .map(|l| l.max_velocity * l.max_velocity)
            .sum::<f64>()
            .sqrt()
            * MAX_OVERRIDE;
        let accel_floor = axes
            .clone()
            .map(|l| l.max_acceleration)
            .fold(f64::INFINITY, f64::min)
            / 2.0;
        let jerk_floor = axes.map(|l| l.max_jerk).fold(f64::INFINITY, f64::min) / 2.0;
        let horizon = 2.0 * Ramp::new(top, 0.0, 0.0, accel_floor, jerk_floor).distance()
            + 4.0 * top * config.period
            + 1.0;
        let period = config.period;
        let mut planner = Planner {
            tolerance: config.tolerance,
            base_limits: config.limits,
            config,
            horizon,
            accel_floor,
            jerk_floor,
            low_ahead: deep::LowAhead::default(),
            waiting: VecDeque::new(),
            vertices: Vec::new(),
            pieces: VecDeque::new(),
            markers: VecDeque::new(),
            committed_end: 0.0,
            drops: drops::DropTracker::default(),
            planned_pose: start,
            rest_pose: start,
            rest_loc: SourceLoc::default(),
            state: Motion::default(),
            reached: 0.0,
            stash: None,
            hold_until: None,
            scratch: speed::Scratch::default(),
            window: Window {
                period,
                ..Window::default()
            },
            range: 0.0,
            factor: 1.0,
            held: false,
            cycles: 0,
            finished: false,
            tcpm: false,
            compensation_feed: None,
            table: None,
            cruise: cruise::Cruising::default(),
            settled: scan::SettleMemo::default(),
            move_hold: move_hold::MoveHold::default(),
            blends: BlendPool::new(BLEND_SLOTS),
            splines: SplinePool::new(SPLINE_SLOTS),
            spent: None,
        };
        planner.reserve();
        Ok(planner)
    }

    /// Reserves the queues' and buffers' room when the planner is built, so that the servo
    /// loop does not grow them: [`RESERVED_PIECES`] pieces and as many markers (the
    /// look-ahead stops short of filling them: [`Planner::needs_input`]), [`RESERVED_LIMITS`]
    /// limits in the window.
    fn reserve(&mut self) {
        self.pieces.reserve(RESERVED_PIECES);
        // A stop or an event at the end of each piece, at most (but for runs of events).
        self.markers.reserve(RESERVED_PIECES);
        self.waiting.reserve(RESERVED_LIMITS);
        self.vertices.reserve(RESERVED_LIMITS);
        self.window.limits.reserve(RESERVED_LIMITS);
        self.scratch.reserve(RESERVED_LIMITS);
        self.settled.reserve(RESERVED_LIMITS);
        self.low_ahead.reserve(RESERVED_LIMITS);
    }

    /// Tells the planner where the table axes of a table-table machine are: moves that turn
    /// a rotary axis while TCPM is on then get limits that keep the machine's linear axes
    /// within theirs ([`tcpm`]). Without it such moves get the fixed-angle limits only.
    pub fn set_table_geometry(&mut self, table: TableGeometry) {
        self.table = Some(table);
    }

    /// The per-axis limits for a piece of `shape` from `offset` over `length`, with
    /// derivative `bounds`.
    fn limits_for(
        &self,
        shape: &Shape,
        bounds: &AxisBounds,
        offset: f64,
        length: f64,
    ) -> [Option<AxisLimits>; 9] {
        let Some(table) = self.table.filter(|_| self.tcpm) else {
            return self.config.limits;
        };
        let straight = matches!(shape, Shape::Element(Segment::Line(_)));
        if !deep::turns_rotary(bounds, length) {
            return self.config.limits;
        }
        let tip = |s: f64| {
            let p = shape.point(s).pose;
            [p.0[0], p.0[1], p.0[2]]
        };
        // A point of a curve lies within half its length of one of its ends.
        let spread = if straight { 0.0 } else { 0.5 * length };
        let d = table.reach(&[tip(offset), tip(offset + length)], spread);
        tcpm::turning_limits(&self.base_limits, d, self.compensation_feed)
    }

    /// The configuration in use.
    pub fn config(&self) -> &PlannerConfig {
        &self.config
    }

    /// True while the planner wants more ops (or [`Planner::finish`]) before sampling on:
    /// until the committed path reaches beyond the look-ahead distance, or its reserved
    /// piece queue is full but for [`PIECE_MARGIN`].
    ///
    /// The second is back-pressure: a look-ahead of very many short pieces stops short of
    /// the distance until the machine has passed some of them, rather than grow the queue
    /// (an allocation) in the servo loop. The path stays safe, since its speed profile
    /// always brakes for the end of what is committed: at worst the path slows down ahead
    /// of that end until more fits. The pieces lie on the committed path, which the machine
    /// travels and so frees without more input.
    pub fn needs_input(&self) -> bool {
        !self.finished
            && self.pieces.len() + self.markers.len() + self.waiting.len() < BUFFER_CAPACITY
            && self.pieces.len() + PIECE_MARGIN < RESERVED_PIECES
            && self.committed_end - self.state.s < self.horizon.max(self.range)
    }

    /// Time of the last sample given out, in seconds. (The look-ahead planner decides the
    /// timing as it goes, so this is the program time executed so far.)
    pub fn planned_time(&self) -> f64 {
        self.time()
    }

    /// End point of everything pushed so far.
    pub fn planned_pose(&self) -> Pose {
        self.planned_pose
    }

    /// Time of the last sample given out (0 before the first).
    pub fn time(&self) -> f64 {
        self.cycles as f64 * self.config.period
    }

    /// The look-ahead distance the planner fills before it stops asking for input (mm).
    pub fn horizon(&self) -> f64 {
        self.horizon
    }

    /// Sets the feed override as a factor of the programmed feed, clamped to 0–1.5 (a
    /// value that is not a number leaves it unchanged). Rapid traverse is scaled too, up to
    /// the axes' limits. Returns the factor in force.
    pub fn set_feed_override(&mut self, factor: f64) -> f64 {
        if !factor.is_nan() {
            self.factor = factor.clamp(0.0, MAX_OVERRIDE);
        }
        self.factor
    }

    /// The feed override factor in force.
    pub fn feed_override(&self) -> f64 {
        self.factor
    }

    /// Feed hold: brakes to a standstill on the path (jerk-limited) and stays there.
    pub fn hold(&mut self) {
        self.held = true;
    }

    /// Ends a feed hold (and cancels one asked for after the next move): speeds up again
    /// along the path.
    pub fn resume(&mut self) {
        self.held = false;
        self.move_hold = move_hold::MoveHold::default();
    }

    /// True while a feed hold is requested.
    pub fn is_held(&self) -> bool {
        self.held
    }

    /// Current path speed (mm/s, or °/s on rotary-only moves).
    pub fn path_speed(&self) -> f64 {
        self.state.v
    }

    /// Adds one op to the end of the path.
    pub fn push(&mut self, op: Op) -> Result<(), MotionError> {
        let loc = op.loc;
        if self.finished {
            return Err(MotionError::AfterFinish { loc });
        }
        if self.pieces.len() + self.markers.len() + self.waiting.len() >= BUFFER_CAPACITY {
            return Err(MotionError::BufferFull { loc });
        }
        let geometry = |e| MotionError::Geometry { loc, source: e };
        let start = self.planned_pose;
        let (segment, feed) = match &op.kind {
            OpKind::Line { from, to, feed } => {
                self.check_start(from, loc)?;
                let feed = path_feed(*feed, loc)?;
                (
                    Line::new(start, *to).map_err(geometry)?.map(Segment::Line),
                    feed,
                )
            }
            OpKind::Arc {
                from,
                to,
                center,
                plane,
                sweep,
                feed,
            } => {
                self.check_start(from, loc)?;
                let feed = path_feed(*feed, loc)?;
                let segment =
                    match Arc::new(start, *to, *center, *plane, *sweep).map_err(geometry)? {
                        Some(arc) => Some(Segment::Arc(arc)),
                        None => Line::new(start, *to).map_err(geometry)?.map(Segment::Line),
                    };
                (segment, feed)
            }
            OpKind::Spline {
                from,
                to,
                axes,
                feed,
            } => {
                self.check_start(from, loc)?;
                let feed = path_feed(*feed, loc)?;
                (
                    Poly::new(start, *to, axes)
                        .map_err(geometry)?
                        .map(|p| Segment::Poly(self.splines.store(p))),
                    feed,
                )
            }
            OpKind::Approach { .. } | OpKind::Depart { .. } => {
                return Err(MotionError::UnresolvedApproach { loc });
            }
            OpKind::Dwell { seconds } => {
                let seconds = *seconds;
                return self.stop_and_hold(op, seconds);
            }
            OpKind::Tolerance { mm } => {
                let mm = match mm {
                    Some(mm) if !(mm.is_finite() && *mm >= 0.0) => {
                        return Err(MotionError::BadTolerance { loc, mm: *mm });
                    }
                    Some(mm) => *mm,
                    None => self.config.tolerance,
                };
                self.tolerance = mm;
                self.add_event(op);
                return Ok(());
            }
            OpKind::SpindleSync { .. } | OpKind::RigidTap { .. } => {
                // The servo loop runs the move itself, geared to the spindle: the path stops
                // exactly at its start, and goes on from its end once the event is done.
                let Some((from, to)) = op.kind.geared_ends() else {
                    return Ok(());
                };
                self.check_start(&from, loc)?;
                if !finite_pose(&to) {
                    return Err(MotionError::Discontinuity {
                        loc,
                        axis: AxisLetter::Z,
                        gap: f64::NAN,
                    });
                }
                self.flush()?;
                self.markers.push_back(Marker::Stop {
                    at: self.committed_end,
                    op: Some(op),
                    dwell: 0.0,
                });
                self.planned_pose = to;
                return Ok(());
            }
            OpKind::Stop { .. }
            | OpKind::End
            | OpKind::ToolChange { .. }
            | OpKind::Spindle { .. }
            | OpKind::CAxis { .. }
            | OpKind::ExactStop => {
                self.flush()?;
                self.markers.push_back(Marker::Stop {
                    at: self.committed_end,
                    op: Some(op),
                    dwell: 0.0,
                });
                return Ok(());
            }
            OpKind::Tcpm {
                on,
                compensation_feed,
                reframe,
            } => {
                // The switch follows an exact stop: the moves after it get the new limits,
                // and start where the machine stands, expressed in the new frame.
                if let Some(p) = reframe {
                    if !finite_pose(p) {
                        return Err(MotionError::Discontinuity {
                            loc: op.loc,
                            axis: AxisLetter::X,
                            gap: f64::NAN,
                        });
                    }
                    self.flush()?;
                    self.planned_pose = *p;
                }
                self.tcpm = *on;
                self.compensation_feed = compensation_feed.filter(|_| *on);
                self.config.limits = if *on {
                    tcpm::fixed_limits(&self.base_limits)
                } else {
                    self.base_limits
                };
                self.add_event(op);
                return Ok(());
            }
            OpKind::MachineFunction {
                stop: true, wait, ..
            } => {
                // A machine function that needs the machine standing: exact stop on its
                // point, the function, then the machine holds for `wait` seconds.
                let wait = *wait;
                return self.stop_and_hold(op, wait);
            }
            // A machine function without stop is an event on the path like coolant; it has
            // no standstill to wait in, so its `wait` is not applied.
            OpKind::Coolant { .. }
            | OpKind::ProbeResult { .. }
            | OpKind::RadiusComp { .. }
            | OpKind::CornerRule { .. }
            | OpKind::WorkingPlane { .. }
            | OpKind::MachineFunction { stop: false, .. } => {
                self.add_event(op);
                return Ok(());
            }
        };
        let Some(segment) = segment else {
            tracing::trace!(line = loc.line, "zero-length move skipped");
            return Ok(());
        };
        if !segment.length().is_finite() {
            return Err(MotionError::Geometry {
                loc,
                source: GeomError::NonFinite("path length"),
            });
        }
        // Refuse absent axes and unusable limits now, at the op that causes them.
        let whole = Shape::Element(segment.clone());
        let bounds = segment.bounds();
        let limits = self.limits_for(&whole, &bounds, 0.0, segment.length());
        piece_limits(&bounds, segment.length(), feed, &limits, Headroom::Ample)
            .map_err(|e| piece_error(e, loc))?;
        self.planned_pose = segment.end();
        self.waiting.push_back(Waiting {
            element: Element {
                segment,
                feed,
                loc,
                tolerance: self.tolerance,
                trim: 0.0,
                split: None,
                // Nothing waits only where the path ends in a stop (or has not started).
                from_rest: self.waiting.is_empty(),
            },
            events: Vec::new(),
        });
        if matches!(op.kind, OpKind::Spline { .. }) {
            // Its coefficients are on the heap: the caller may free them outside the loop.
            self.spent = Some(op);
        }
        while self.waiting.len() >= ELEMENTS_AHEAD && self.front_decidable() {
            self.commit_front(false)?;
        }
        Ok(())
    }

    /// The last spline op [`Planner::push`] took in and no longer needs (its coefficients
    /// live on the heap), for the caller to free on another thread than the servo loop's.
    /// Left here, it is freed when the next spline op takes its place.
    pub fn take_spent(&mut self) -> Option<Op> {
        self.spent.take()
    }

    /// An op that needs the machine standing on its point: exact stop, the op, then a hold
    /// of `seconds` (finite and ≥ 0).
    fn stop_and_hold(&mut self, op: Op, seconds: f64) -> Result<(), MotionError> {
        if !(seconds.is_finite() && seconds >= 0.0) {
            return Err(MotionError::BadDwell {
                loc: op.loc,
                seconds,
            });
        }
        self.flush()?;
        self.markers.push_back(Marker::Stop {
            at: self.committed_end,
            op: Some(op),
            dwell: seconds,
        });
        Ok(())
    }

    /// A non-motion op that needs no stop: after the last waiting element, or at the end
    /// of the committed path.
    fn add_event(&mut self, op: Op) {
        match self.waiting.back_mut() {
            Some(w) => w.events.push(op),
            None => self.markers.push_back(Marker::Event {
                at: self.committed_end,
                op,
            }),
        }
    }

    /// Declares the end of input: the planner drains what it holds.
    pub fn finish(&mut self) {
        if !self.finished {
            // Elements were checked when pushed; committing them cannot fail on limits.
            if let Err(e) = self.flush() {
                tracing::warn!(error = %e, "dropping the rest of the path");
                self.waiting.clear();
            }
            self.finished = true;
        }
    }

    fn at_rest(&self) -> bool {
        self.state.v <= 1e-9 && self.state.a.abs() <= 1e-3
    }

    /// The next sample or event; `None` once finished and drained (or, before
    /// [`Planner::finish`], when it needs input first).
    pub fn next_step(&mut self) -> Option<Step> {
        self.step(false)
    }

    /// The next sample or event when the caller has no input to give though the planner
    /// wants some (its source has fallen behind): the path goes on with what is committed.
    /// That is safe because the speed profile always brakes for the end of the committed
    /// path (it counts as a stop, see `next_stop`): a starved path slows down and comes to
    /// rest there, and holds until input arrives. `None` once finished and drained.
    pub fn next_step_starved(&mut self) -> Option<Step> {
        self.step(true)
    }

    fn step(&mut self, starved: bool) -> Option<Step> {
        self.place_move_hold();
        loop {
            match self.markers.front() {
                Some(Marker::Event { at, .. }) if *at <= self.reached + STOP_SNAP => {
                    if let Some(Marker::Event { op, .. }) = self.markers.pop_front() {
                        if let OpKind::Tcpm {
                            reframe: Some(p), ..
                        } = &op.kind
                        {
                            self.reframe(*p);
                        }
                        return Some(Step::Event(op));
                    }
                }
                Some(Marker::Stop { at, .. })
                    if self.stash.is_none()
                        && self.at_rest()
                        && (*at - self.state.s).abs() <= ROUNDING =>
                {
                    let at = *at;
                    self.state = Motion {
                        s: at,
                        v: 0.0,
                        a: 0.0,
                    };
                    self.reached = at;
                    self.reached_stop(at);
                    if let Some(Marker::Stop { op, dwell, .. }) = self.markers.pop_front() {
                        if dwell > 0.0 {
                            let loc = op.as_ref().map_or(self.rest_loc, |o| o.loc);
                            // Holds at the same point add up (two dwells, a dwell and
                            // a machine function's wait).
                            let from = self
                                .hold_until
                                .map_or(self.time(), |(end, _)| end.max(self.time()));
                            self.hold_until = Some((from + dwell, loc));
                        }
                        if let Some(op) = op {
                            if let Some((_, to)) = op.kind.geared_ends() {
                                // The servo loop moves the axes to `to` during the event.
                                self.reframe(to);
                            }
                            return Some(Step::Event(op));
                        }
                    }
                    continue;
                }
                _ => {}
            }
            if let Some(sample) = self.stash.take() {
                return Some(Step::Sample(sample));
            }
            let t = (self.cycles + 1) as f64 * self.config.period;
            if let Some((end, loc)) = self.hold_until {
                if t <= end + 1e-9 {
                    self.cycles += 1;
                    let pose = self.pose_here();
                    return Some(Step::Sample(Sample {
                        t,
                        pose,
                        velocity: [0.0; 9],
                        acceleration: [0.0; 9],
                        loc,
                    }));
                }
                self.hold_until = None;
            }
            if !self.finished && !starved && self.needs_input() {
                return None;
            }
            if self.finished
                && self.markers.is_empty()
                && self.at_rest()
                && self.state.s >= self.committed_end - ROUNDING
            {
                return None;
            }
            let sample = self.advance(t);
            self.cycles += 1;
            if matches!(self.markers.front(), Some(Marker::Event { at, .. }) if *at <= self.reached + STOP_SNAP)
            {
                self.stash = Some(sample);
                continue;
            }
            return Some(Step::Sample(sample));
        }
    }

    /// The frame changed under the machine standing at the end of the path so far (a TCPM
    /// switch): the pieces behind it are done, and the pose it stands at is `p` from now on,
    /// so every sample after the switch event is in the new frame.
    fn reframe(&mut self, p: Pose) {
        while self
            .pieces
            .front()
            .is_some_and(|piece| piece.end() <= self.reached + STOP_SNAP)
        {
            if let Some(piece) = self.pieces.pop_front() {
                self.rest_loc = piece.loc;
            }
        }
        self.rest_pose = p;
        if let Some(sample) = self.stash.as_mut() {
            sample.pose = p;
        }
    }

    /// Where the machine stands: on the current piece, or at rest after the last one.
    fn pose_here(&self) -> Pose {
        match self.pieces.front() {
            Some(p) => p.point(self.state.s).pose,
            None => self.rest_pose,
        }
    }

    /// The speed the period's action heads for: the current piece's limit (zero in a feed
    /// hold), or the next piece's where that is faster, the state may get there still
    /// speeding up (within the distance easing the largest acceleration of the current
    /// piece covers, plus two periods' travel) and the path does not stop in between. The
    /// checks keep the speed within the current piece's limit until its end (see
    /// `through::leaves_below`).
    fn go_target(&self) -> f64 {
        let k = self.current_index();
        let Some(p) = self.pieces.get(k).filter(|_| !self.held) else {
            return 0.0;
        };
        let here = p.speed_limit(self.factor);
        let Some(q) = self.pieces.get(k + 1) else {
            return here;
        };
        let (v, accel) = (self.state.v, p.grip.most());
        let ease = accel / p.jerk;
        let reach = (v + accel * ease) * ease + 2.0 * v * self.config.period;
        if accel.is_finite() && p.end() - self.state.s <= reach && self.next_stop() > p.end() {
            here.max(q.speed_limit(self.factor))
        } else {
            here
        }
    }

    /// Moves the path state on by one period and samples it at time `t`.
    fn advance(&mut self, t: f64) -> Sample {
        let next = match self.cruise_step() {
            Some(next) => next,
            None => self.generate(),
        };
        self.state = next;
        self.reached = next.s;
        self.sample_at(t, next)
    }

    /// The next state from the speed generator.
    fn generate(&mut self) -> Motion {
        self.scan();
        let target = self.go_target();
        let before = self.state;
        let mut next = speed::advance_with(
            &self.state,
            target,
            &self.window,
            self.config.period,
            &mut self.scratch,
        );
        if let Some(split) = self.hand_over(&before, &next, target) {
            next = split;
        }
        // Never past the end of the committed path or the next stop.
        let stop = self.next_stop();
        if next.s > stop {
            if next.s - stop > STOP_SNAP {
                tracing::warn!(over = next.s - stop, "path state clamped at a stop point");
            }
            next = Motion {
                s: stop,
                v: 0.0,
                a: 0.0,
            };
        }
        if next.v < 0.0 {
            next.v = 0.0;
        }
        // On the stop point when getting there in one step costs a negligible acceleration
        // and jerk.
        let period = self.config.period;
        let step_accel = (stop - next.s) / (period * period) + next.v / period + next.a.abs();
        let negligible = next.s <= stop
            && step_accel / period <= SNAP_SHARE * self.window.jerk
            && step_accel <= SNAP_SHARE * self.window.grip.most();
        if negligible {
            next = Motion {
                s: stop,
                v: 0.0,
                a: 0.0,
            };
        }
        self.find_cruise(&before, &next, target);
        next
    }

    /// Moves past the pieces behind `next` and samples it at time `t`.
    fn sample_at(&mut self, t: f64, next: Motion) -> Sample {
        while self.pieces.len() > 1 && self.pieces.front().is_some_and(|p| p.end() < next.s) {
            if let Some(p) = self.pieces.pop_front() {
                self.rest_pose = p.point(p.end()).pose;
                self.rest_loc = p.loc;
            }
        }
        match self.pieces.front() {
            Some(p) => {
                let point = p.point(next.s);
                let mut velocity = [0.0; 9];
                let mut acceleration = [0.0; 9];
                for i in 0..9 {
                    velocity[i] = point.d1[i] * next.v;
                    acceleration[i] = point.d1[i] * next.a + point.d2[i] * next.v * next.v;
                }
                Sample {
                    t,
                    pose: point.pose,
                    velocity,
                    acceleration,
                    loc: p.loc,
                }
            }
            None => Sample {
                t,
                pose: self.rest_pose,
                velocity: [0.0; 9],
                acceleration: [0.0; 9],
                loc: self.rest_loc,
            },
        }
    }

    /// Refuses an op that does not start at the previous end point.
    fn check_start(&self, from: &Pose, loc: SourceLoc) -> Result<(), MotionError> {
        if !finite_pose(from) {
            let i = from.0.iter().position(|v| !v.is_finite()).unwrap_or(0);
            return Err(MotionError::Discontinuity {
                loc,
                axis: letter(i),
                gap: f64::NAN,
            });
        }
        for (i, (a, b)) in from.0.iter().zip(&self.planned_pose.0).enumerate() {
            let gap = (a - b).abs();
            if gap > CONTINUITY_TOLERANCE {
                return Err(MotionError::Discontinuity {
                    loc,
                    axis: letter(i),
                    gap,
                });
            }
        }
        Ok(())
    }
}
