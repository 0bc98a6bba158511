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
//! [`OpKind::Tolerance`](klar_interp::OpKind::Tolerance) sets the tolerance for the corners
//! after it (`None`: the configured default). Radius compensation is the job of the stage
//! before the planner; the planner follows the path it is given.
//!
//! Feed override (0–150 %, [`Planner::set_feed_override`]) and feed hold
//! ([`Planner::hold`], [`Planner::resume`]) act at once with jerk-limited speed changes on
//! the path. A hold stops where its braking ends; when that is a hair short of a stop point
//! the path was braking for anyway, the rest of the way is travelled after the hold (no
//! step onto the point).

mod commit;
mod corner_share;
mod corner_stop;
mod cruise;
mod deep;
mod drops;
mod generate;
mod handover;
mod input;
mod move_hold;
mod outside;
mod overlap;
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
use crate::geom::{AxisBounds, Segment, letter};
use crate::profile::Ramp;
use klar_interp::{Op, Pose, SourceLoc};
use path::{MAX_OVERRIDE, Piece, Shape, Waiting};
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

/// Events (non-motion ops such as coolant or M functions) between two moves each spare
/// event list has room for; more grow that list once.
const EVENTS_PER_ELEMENT: usize = 8;

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
    /// A standstill at `at`, then the op (if any), then a hold of `dwell` seconds. A stop
    /// with a `corner` is a sharp corner that may be crossed without standing still, as
    /// long as the path stays within its band (see `overlap`).
    Stop {
        at: f64,
        op: Option<Op>,
        dwell: f64,
        corner: Option<overlap::StopCorner>,
    },
}

impl Marker {
    /// The path position it takes effect at.
    fn at(&self) -> f64 {
        match self {
            Marker::Event { at, .. } | Marker::Stop { at, .. } => *at,
        }
    }
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
    /// Empty event lists with room made when the planner is built, handed to waiting
    /// elements and taken back once their events are queued, so that events between moves
    /// do not allocate in the servo loop.
    spare_events: Vec<Vec<Op>>,
    /// Sharp corners crossed without standing still (see `overlap`).
    overlap: overlap::Overlap,
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
            overlap: overlap::Overlap::default(),
            spare_events: Vec::new(),
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
        self.spare_events.reserve(RESERVED_LIMITS);
        for _ in 0..RESERVED_LIMITS {
            self.spare_events
                .push(Vec::with_capacity(EVENTS_PER_ELEMENT));
        }
    }

    /// An empty event list for a new waiting element: a spare one when there is one.
    fn take_event_list(&mut self) -> Vec<Op> {
        self.spare_events.pop().unwrap_or_default()
    }

    /// Takes back the event list of an element whose events are queued (emptied here).
    fn give_back_event_list(&mut self, mut list: Vec<Op>) {
        list.clear();
        if list.capacity() > 0 && self.spare_events.len() < self.spare_events.capacity() {
            self.spare_events.push(list);
        }
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
        (self.cycles - self.overlap.samples_ahead()) as f64 * self.config.period
    }

    /// Servo periods saved so far by crossing sharp corners without standing still (see
    /// `overlap`).
    pub fn corner_periods_saved(&self) -> u64 {
        self.overlap.saved_periods()
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

    /// Current path speed (mm/s, or °/s on rotary-only moves). Positive while samples of
    /// a corner crossed without standing still are still to go out.
    pub fn path_speed(&self) -> f64 {
        if self.overlap.is_empty() {
            self.state.v
        } else {
            self.state.v.max(f64::MIN_POSITIVE)
        }
    }
}
