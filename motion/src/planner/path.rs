//! The blended path: programmed elements cut back at their corners and joined by blend
//! curves, as a queue of [`Piece`]s with their speed, acceleration and jerk limits.
//!
//! Elements wait in a queue until the element after the next is known, because the blend
//! at a corner may pass through the middle of a short line (a *split point*, see below),
//! and in dense code until the short lines ahead reach as far as a run and the fit at its
//! end look. Then the front element is cut and committed: its remaining part, then the
//! blend.
//!
//! Corner rules, for two consecutive elements without a stop between them:
//! * already curvature-continuous (same tangent, same curvature vector): no blend;
//! * the same tangent with a jump in curvature (a line running into an arc): no blend
//!   where the step in each axis's acceleration the jump causes at the highest speed either
//!   element allows, v²·|Δq″ᵢ|, stays within [`STEP_SHARE`] of the axis's jerk limit times
//!   the servo period (between two samples that is a jerk far inside the limit: machines
//!   whose jerk is effectively unlimited); otherwise a blend as at any corner;
//! * tolerance 0, rotary-only moves, a turn sharper than 120°, or no blend found: exact
//!   stop at the corner;
//! * a turn of 45° or more outside dense code whose blend, crossed at the speed its
//!   curvature allows, is estimated to lose more time than braking to rest at the corner
//!   and speeding up again: exact stop (`corner_stop.rs`);
//! * next to an element that turns a rotary axis along its linear motion (whose turn per
//!   millimetre can put the blend's limits far below its neighbours'): exact stop where
//!   that is estimated to take less time than slowing into the blend and out of it and the
//!   rotary axes at least double the latter (not between split points: dense code);
//! * otherwise a [`Quintic`] blend whose distance from the programmed contour is checked
//!   against the tolerance ([`blend_within`]); it is made as long as the tolerance allows,
//!   at most half of each element. A blend whose curvature varies along it (through a
//!   corner, or from a line into an arc) is committed as `BLEND_PARTS` pieces, each with
//!   the limits of its own stretch (`Shape::bounds`): the path slows down inside the
//!   blend, where the curvature grows, instead of before it.
//!
//! Split points make dense CAM code smooth. A short line between two gentle corners is
//! consumed completely by the blends at its ends; they meet near its midpoint on a curve
//! fitted to the polyline around it ([`split_point`]: position, tangent and curvature
//! vector), instead of the line's own direction and zero curvature. Once the path runs
//! through split points, a blend does not stop at the next one: it spans a *run* of short
//! lines up to 1 mm (`RUN_LENGTH`, `run.rs`), from one split point to one far ahead, and
//! uses up the lines between ([`Committed::consumed`]). The fitted points carry the
//! rounding noise of the program's coordinates; a blend between points 0.01 mm apart would
//! turn that noise into a large third derivative (the jerk of the curve at constant speed),
//! one over a run barely notices it. A polyline approximating a circle then becomes a curve of almost constant
//! curvature, followed at the programmed feed.

use super::corner_share::{Derate, share_corner};
use super::corner_stop::{
    BlendPart, SHARP_TURN, stop_is_faster, stop_saves_time, too_slow, turns_rotary,
};
use super::overlap::StopCorner;
use super::run;
use super::smooth::{Stencil, split_point};
use crate::blend::{BlendPool, BoundsMemo, ContourPart, Quintic, blend_within};
use crate::config::AxisLimits;
use crate::geom::{AxisBounds, Line, Metric, PathPoint, Segment};
use crate::limits::{Grip, Headroom, LimitError, PieceLimits, path_limits};
use klar_interp::{Op, Pose, SourceLoc};
use std::sync::Arc;

/// Largest feed override, as a factor: path limits are prepared for it.
pub const MAX_OVERRIDE: f64 = 1.5;

/// Largest turning angle (radians) at either end of a line that may become a split point:
/// chords of 0.04 mm round a 0.14 mm radius (the smallest arcs of 2D pocket finishing in
/// CAM output) turn by 0.29 rad each, and their rounding to 1 µm adds up to 0.05 rad.
pub const SPLIT_MAX_ANGLE: f64 = 0.45;

/// Largest turning angle (radians) that is blended; sharper corners (beyond 120°, nearly
/// reversing) stop exactly: a blend there would be slow anyway and its curvature peak too
/// narrow for sampled bounds.
const MAX_BLEND_ANGLE: f64 = 2.1;

/// Tangent and curvature differences below which two elements already join smoothly.
const SMOOTH_TANGENT: f64 = 1e-9;
const SMOOTH_CURVATURE: f64 = 1e-7;

/// Share of an axis's jerk limit times the servo period that the acceleration step of a
/// curvature jump may take at a tangent joint left without a blend.
pub const STEP_SHARE: f64 = 0.005;

/// Attempts at shrinking a blend before giving up.
const BLEND_ATTEMPTS: usize = 24;

/// Shortest blend half-length tried (mm).
const MIN_BLEND: f64 = 1e-6;

/// The geometry a piece follows.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // moved into a queue once; boxing would cost a heap trip
pub enum Shape {
    /// (Part of) a programmed element.
    Element(Segment),
    /// A blend curve, in a slot of the planner's [`BlendPool`] that the parts of the blend
    /// share.
    Blend(Arc<Quintic>),
}

impl Shape {
    pub(crate) fn point(&self, s: f64) -> PathPoint {
        match self {
            Shape::Element(g) => g.point(s),
            Shape::Blend(q) => q.point(s),
        }
    }

    pub(super) fn length(&self) -> f64 {
        match self {
            Shape::Element(g) => g.length(),
            Shape::Blend(q) => q.length(),
        }
    }

    /// Derivative bounds over the part from `offset` over `length`: a blend's part has
    /// bounds of its own ([`Quintic::bounds_between_in`], from `memo` where the same part of
    /// a blend with the same derivatives was bounded before), an element's are the whole
    /// element's.
    pub(crate) fn bounds(&self, offset: f64, length: f64, memo: &mut BoundsMemo) -> AxisBounds {
        match self {
            Shape::Element(g) => g.bounds(),
            Shape::Blend(q) => q.bounds_between_in(offset, offset + length, memo),
        }
    }
}

/// Relative length difference within which a piece counts as running to the end of its
/// shape (`offset + length` may round below the shape's length).
const END_ROUNDING: f64 = 1e-12;

/// One piece of the blended path with constant limits.
#[derive(Debug, Clone)]
pub struct Piece {
    /// The geometry.
    pub shape: Shape,
    /// Where on the shape the piece starts (local path distance).
    pub offset: f64,
    /// Length of the piece.
    pub length: f64,
    /// Path distance of its start from the start of the program.
    pub start: f64,
    /// Largest path speed the axes allow (with the feed times [`MAX_OVERRIDE`]).
    pub vmax: f64,
    /// Programmed feed (`None`: rapid).
    pub feed: Option<f64>,
    /// Path acceleration limit by path speed.
    pub grip: Grip,
    /// Path jerk limit.
    pub jerk: f64,
    /// What its limits keep free at its top speed.
    pub headroom: Headroom,
    /// The block it comes from.
    pub loc: SourceLoc,
    /// True when its speed limit at the programmed feed lies a real step below the pieces
    /// before it (see `planner::drops`): a limit the backward pass settles, not a soft one.
    /// Decided once, as the piece is committed, so that it does not depend on the piece the
    /// state is on.
    pub drop: bool,
}

impl Piece {
    /// End of the piece as a path distance.
    pub fn end(&self) -> f64 {
        self.start + self.length
    }

    /// Speed limit under feed override `factor`.
    pub fn speed_limit(&self, factor: f64) -> f64 {
        match self.feed {
            Some(f) => self.vmax.min(f * factor),
            None => self.vmax.min(self.vmax * factor),
        }
    }

    /// Pose and derivatives at path distance `s` (global).
    pub fn point(&self, s: f64) -> PathPoint {
        // At (or past) the end exactly the end: `start + length - start` may round, and so
        // may `offset + length` against the shape's own length, whose end is the programmed
        // end point.
        if s >= self.end() {
            let whole = self.shape.length();
            let to = self.offset + self.length;
            let at = if to >= whole * (1.0 - END_ROUNDING) {
                whole
            } else {
                to
            };
            return self.shape.point(at);
        }
        let local = (s - self.start).clamp(0.0, self.length);
        self.shape.point(self.offset + local)
    }
}

/// A programmed element waiting for its corners to be decided.
#[derive(Debug, Clone)]
pub struct Element {
    /// The geometry.
    pub segment: Segment,
    /// Programmed feed (`None`: rapid).
    pub feed: Option<f64>,
    /// The block.
    pub loc: SourceLoc,
    /// Path tolerance active for this element.
    pub tolerance: f64,
    /// Length already used by the blend before it.
    pub trim: f64,
    /// The split point at `trim` (where the blend before ended), when it is one.
    pub split: Option<PathPoint>,
    /// True when the path stands still at its start (the first element after a stop).
    pub from_rest: bool,
    /// Axis limits its own pieces give up to a neighbour across an overlapped stop corner
    /// (see `corner_share`).
    pub derate: Derate,
}

/// An element waiting for its corners, with the events that follow it.
#[derive(Debug, Clone)]
pub struct Waiting {
    /// The element.
    pub element: Element,
    /// Non-motion ops after it.
    pub events: Vec<Op>,
}

/// The polyline vertices around the corner being decided: `all[first]` is the start of the
/// element after the one being committed, `all[first + j]` the start of the `j`-th waiting
/// element after it while those are linear lines; before `first` lie the vertices of the
/// linear lines already committed.
#[derive(Debug, Clone, Copy)]
pub struct Vertices<'a> {
    /// The vertices in path order.
    pub all: &'a [Pose],
    /// Index of the next element's start.
    pub first: usize,
}

impl<'a> Vertices<'a> {
    /// The stencil of the `j`-th element after the one being committed.
    pub(super) fn around(&self, j: usize) -> Stencil<'a> {
        let i = (self.first + j).min(self.all.len());
        let (behind, ahead) = self.all.split_at((i + 1).min(self.all.len()));
        Stencil { behind, ahead }
    }
}

impl Element {
    /// True for a line measured over the linear axes (the polyline of dense code, whose
    /// vertices the split-point fit takes).
    pub fn is_linear_line(&self) -> bool {
        matches!(self.segment, Segment::Line(_)) && self.segment.metric() == Metric::Linear
    }
}

/// A new piece, before its limits are known.
#[derive(Debug)]
pub struct NewPiece {
    /// The geometry.
    pub shape: Shape,
    /// Where on the shape it starts.
    pub offset: f64,
    /// Its length.
    pub length: f64,
    /// Programmed feed (`None`: rapid).
    pub feed: Option<f64>,
    /// The block it comes from.
    pub loc: SourceLoc,
    /// What its limits keep free at its top speed.
    pub headroom: Headroom,
}

/// Pieces kept inline in [`NewPieces`]: the element's own part and every part of the blend
/// after it, the most committing one element makes.
const INLINE_PIECES: usize = BLEND_PARTS + 2;

/// The pieces committing one element produces: the element's own part and the parts of the
/// blend after it, kept inline (no allocation per element); any further piece goes to
/// `more`.
#[derive(Debug, Default)]
pub struct NewPieces {
    slots: [Option<NewPiece>; INLINE_PIECES],
    more: Vec<NewPiece>,
}

impl NewPieces {
    pub(super) fn push(&mut self, piece: NewPiece) {
        match self.slots.iter_mut().find(|s| s.is_none()) {
            Some(slot) => *slot = Some(piece),
            None => self.more.push(piece),
        }
    }
}

impl IntoIterator for NewPieces {
    type Item = NewPiece;
    type IntoIter = std::iter::Chain<
        std::iter::Flatten<std::array::IntoIter<Option<NewPiece>, INLINE_PIECES>>,
        std::vec::IntoIter<NewPiece>,
    >;

    /// The pieces in path order.
    fn into_iter(self) -> Self::IntoIter {
        self.slots.into_iter().flatten().chain(self.more)
    }
}

/// What committing one element produced.
#[derive(Debug, Default)]
pub struct Committed {
    /// New pieces in path order.
    pub pieces: NewPieces,
    /// True when the path must stop where it ended before these pieces.
    pub stop_first: bool,
    /// True when the path must stop after all new pieces.
    pub stop_at_end: bool,
    /// The corner at the stop at the end, where it may be crossed without standing still:
    /// a corner between two elements on linear axes (neither turning a rotary axis) whose
    /// blend was refused, within a positive tolerance (see `overlap`).
    pub stop_corner: Option<StopCorner>,
    /// Waiting elements the new pieces used up completely (a run of dense code blended as
    /// one curve): their events follow the new pieces.
    pub consumed: usize,
}

/// Why a piece cannot be planned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PieceError {
    /// An axis that moves is not on the machine.
    Absent(klar_interp::AxisLetter),
    /// No positive finite limits.
    Unplannable,
}

/// Path limits of a piece of `length` with derivative `bounds` (`Shape::bounds`), at
/// feed `feed`, keeping `headroom` at its top speed.
pub fn piece_limits(
    bounds: &AxisBounds,
    length: f64,
    feed: Option<f64>,
    limits: &[Option<AxisLimits>; 9],
    headroom: Headroom,
) -> Result<PieceLimits, PieceError> {
    let l = path_limits(
        bounds,
        length,
        limits,
        feed.map(|f| f * MAX_OVERRIDE),
        headroom,
    )
    .map_err(|e| match e {
        LimitError::AbsentAxis(a) => PieceError::Absent(a),
    })?;
    let usable = |x: f64| x.is_finite() && x > 0.0;
    if usable(l.velocity) && usable(l.acceleration) && usable(l.jerk) {
        Ok(l)
    } else {
        Err(PieceError::Unplannable)
    }
}

/// Path limits of a whole element (`None` where none can be derived).
pub(super) fn element_limits(e: &Element, limits: &[Option<AxisLimits>; 9]) -> Option<PieceLimits> {
    let (bounds, length) = (e.segment.bounds(), e.segment.length());
    piece_limits(&bounds, length, e.feed, limits, Headroom::Ample).ok()
}

pub(super) fn angle(a: &[f64; 9], b: &[f64; 9]) -> f64 {
    let m = Metric::Linear;
    let c = m.dot(a, b) / (m.norm(a) * m.norm(b)).max(f64::MIN_POSITIVE);
    c.clamp(-1.0, 1.0).acos()
}

/// True when the curvature jump between `cur` and `next` at a tangent joint (their
/// curvature vectors `d2`) steps each axis's acceleration by at most [`STEP_SHARE`] of its
/// jerk limit times `period`, at the highest speed either element allows there.
fn jump_fits(
    cur: &Element,
    next: &Element,
    d2: (&[f64; 9], &[f64; 9]),
    limits: &[Option<AxisLimits>; 9],
    period: f64,
) -> bool {
    let top = |e: &Element| element_limits(e, limits).map(|l| l.velocity);
    let (Some(a), Some(b)) = (top(cur), top(next)) else {
        return false;
    };
    let v = a.min(b);
    (0..9).all(|i| {
        let step = (d2.0[i] - d2.1[i]).abs() * v * v;
        step == 0.0 || limits[i].is_some_and(|l| step <= STEP_SHARE * l.max_jerk * period)
    })
}

fn diff_norm(a: &[f64; 9], b: &[f64; 9]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// Commits the part of `cur` up to its next corner, and the blend at that corner.
///
/// `rest` are the elements waiting after it (none: `cur` is the last before a stop); the one
/// after the next decides whether the next becomes a split point, and a run of dense code
/// may be blended over several of them ([`Committed::consumed`]). Updates the trim of the
/// element the new pieces end on. `vertices` are the polyline's vertices around the corner;
/// `last` is true when the path stops at the end of `rest` (a run may end there).
pub fn commit(
    cur: &mut Element,
    rest: &mut [Waiting],
    last: bool,
    vertices: &Vertices<'_>,
    limits: &[Option<AxisLimits>; 9],
    period: f64,
    pool: &mut BlendPool,
) -> Committed {
    let mut out = Committed::default();
    if (cur.split.is_some() || cur.from_rest)
        && let Some(done) = run::try_run(cur, rest, last, vertices, pool)
    {
        return done;
    }
    let (next, further) = match rest.split_first_mut() {
        Some((n, f)) => (Some(&mut n.element), f),
        None => (None, &mut [][..]),
    };
    let after = further.first().map(|w| &w.element);
    let stencil = vertices.around(0);
    let stencil = &stencil;
    let Some(next) = next else {
        detach_split(cur);
        push_part(&mut out, cur, cur.trim, cur.segment.length());
        out.stop_at_end = true;
        return out;
    };
    let len = cur.segment.length();
    let end = cur.segment.point(len);
    let start = next.segment.point(0.0);
    let tangent = cur.segment.metric() == next.segment.metric()
        && diff_norm(&end.d1, &start.d1) <= SMOOTH_TANGENT;
    let smooth = tangent
        && (diff_norm(&end.d2, &start.d2) <= SMOOTH_CURVATURE
            || jump_fits(cur, next, (&end.d2, &start.d2), limits, period));
    if smooth && cur.split.is_none() {
        push_part(&mut out, cur, cur.trim, len);
        return out;
    }
    let tol = cur.tolerance.min(next.tolerance);
    // A corner that finds every blend slot held stops exactly (counted by the pool).
    let blendable = tol > 0.0
        && cur.segment.metric() == Metric::Linear
        && next.segment.metric() == Metric::Linear
        && pool.can_store();
    if blendable {
        if let Some(done) = try_corner(cur, next, after, tol, stencil, limits, pool) {
            return done;
        }
        if cur.split.is_some() {
            // The blend before ends at a split point whose curvature no blend here can take
            // over: stop there, then treat the rest of the line as a plain element.
            detach_split(cur);
            if let Some(mut done) = try_corner(cur, next, None, tol, stencil, limits, pool) {
                done.stop_first = true;
                return done;
            }
            out.stop_first = true;
        }
    }
    detach_split(cur);
    push_part(&mut out, cur, cur.trim, cur.segment.length());
    out.stop_at_end = true;
    if tol > 0.0
        && cur.segment.metric() == Metric::Linear
        && next.segment.metric() == Metric::Linear
        && !turns_rotary(cur)
        && !turns_rotary(next)
    {
        let straight = |e: &Element, d1: &[f64; 9], length: f64| {
            matches!(e.segment, Segment::Line(_)).then_some((*d1, length))
        };
        out.stop_corner = Some(StopCorner {
            band: tol,
            before: straight(cur, &end.d1, len - cur.trim),
            after: straight(next, &start.d1, next.segment.length()),
        });
        share_corner(
            &end.d1,
            &start.d1,
            limits,
            &mut cur.derate,
            &mut next.derate,
        );
    }
    next.trim = 0.0;
    next.split = None;
    next.from_rest = true;
    out
}

/// Makes the rest of a line that starts at a split point a plain element again: the line
/// from the split point (which may lie a little off the programmed line, see
/// [`split_point`]) to the line's end, so that the path runs on without a step.
fn detach_split(cur: &mut Element) {
    if let Some(p) = cur.split.take()
        && let Ok(Some(line)) = Line::new(p.pose, cur.segment.end())
    {
        cur.segment = Segment::Line(line);
        cur.trim = 0.0;
    }
}

/// The element's own part from `from` to `to`, if it has length.
fn push_part(out: &mut Committed, e: &Element, from: f64, to: f64) {
    if to - from > 1e-12 {
        out.pieces.push(NewPiece {
            shape: Shape::Element(e.segment.clone()),
            offset: from,
            length: to - from,
            feed: e.feed,
            loc: e.loc,
            headroom: Headroom::Ample,
        });
    }
}

/// The split point to give `mid` at its midpoint when it can become one between `prev`
/// and `next` ([`split_point`]); `tp` and `tm` are the unit tangents at the end of `prev`
/// and the start of `mid`, `turn` the angle between them.
fn split_for(
    prev: &Element,
    mid: &Element,
    next: &Element,
    tol: f64,
    stencil: &Stencil<'_>,
    (tm, turn): (&[f64; 9], f64),
) -> Option<PathPoint> {
    let Segment::Line(line) = &mid.segment else {
        return None;
    };
    if mid.segment.metric() != Metric::Linear
        || next.segment.metric() != Metric::Linear
        || prev.segment.metric() != Metric::Linear
    {
        return None;
    }
    let lm = mid.segment.length();
    let tn = next.segment.point(0.0).d1;
    let worst = turn.max(angle(tm, &tn));
    if !gentle(lm, worst, tol) || tol.min(next.tolerance) <= 0.0 {
        return None;
    }
    split_point(line, stencil, tol, SPLIT_MAX_ANGLE)
}

/// Parts a blend whose curvature varies along it is committed in, each with the limits
/// of its own part: where the curvature is low the path need not slow down yet.
const BLEND_PARTS: usize = 4;

/// Shortest part of a blend planned in parts (mm): shorter ones would pass within a servo
/// period or two and only multiply the limits ahead.
const MIN_PART: f64 = 0.1;

/// Share of a blend's curvature bound below which the curvature at one of its ends counts
/// as varying along it.
const EVEN_CURVATURE: f64 = 0.7;

/// True when the curvature of the blend `q` from `a` to `b` varies along it (a corner or a
/// line running into an arc, not a stretch of a polyline's circle).
fn varies(q: &Quintic, a: &PathPoint, b: &PathPoint) -> bool {
    let m = Metric::Linear;
    m.norm(&a.d2).min(m.norm(&b.d2)) < EVEN_CURVATURE * q.bounds().curvature
}

/// Tries to blend the corner between `cur` and `next`; on success returns the pieces (the
/// blend curve stored in `pool`) and sets `next`'s trim (and split point).
fn try_corner(
    cur: &Element,
    next: &mut Element,
    after: Option<&Element>,
    tol: f64,
    stencil: &Stencil<'_>,
    limits: &[Option<AxisLimits>; 9],
    pool: &mut BlendPool,
) -> Option<Committed> {
    let len = cur.segment.length();
    let nlen = next.segment.length();
    let t_end = cur.segment.point(len);
    let t_start = next.segment.point(0.0);
    let theta = angle(&t_end.d1, &t_start.d1);
    if theta > MAX_BLEND_ANGLE {
        return None;
    }
    let mut right_split =
        after.and_then(|a| split_for(cur, next, a, tol, stencil, (&t_start.d1, theta)));
    let left_fixed = cur.split;
    let cap_left = (len - cur.trim).min(0.5 * len).max(0.0);
    let cap_right = 0.5 * nlen;
    // First guess from the corner angle (or the curvature jump of a tangent joint).
    let guess = if theta > 1e-3 {
        4.0 * tol / (0.5 * theta).sin()
    } else {
        let jump = diff_norm(&t_end.d2, &t_start.d2).max(1e-12);
        (48.0 * tol / jump).sqrt()
    };
    let mut d = guess.min(cap_left.max(cap_right));
    for _ in 0..BLEND_ATTEMPTS {
        let dl = match left_fixed {
            Some(_) => len - cur.trim,
            None => d.min(cap_left),
        };
        let dr = match right_split {
            Some(_) => cap_right,
            None => d.min(cap_right),
        };
        if dl < MIN_BLEND && left_fixed.is_none() || dr < MIN_BLEND {
            return None;
        }
        let a = left_fixed.unwrap_or_else(|| cur.segment.point(len - dl));
        let b = right_split.unwrap_or_else(|| next.segment.point(dr));
        let contour = [
            ContourPart {
                segment: &cur.segment,
                from: len - dl,
                to: len,
            },
            ContourPart {
                segment: &next.segment,
                from: 0.0,
                to: dr,
            },
        ];
        if let Some((curve, _)) = blend_within(&a, &b, &contour, tol, pool.memo()) {
            let length = curve.length();
            let feed = min_feed(cur.feed, next.feed);
            if theta > SPLIT_MAX_ANGLE && too_slow(&curve, length, feed, cur, next, limits) {
                return None;
            }
            // Blends through split points (dense code) keep one piece each: their
            // curvature there is an estimate, and its noise would only multiply the limits.
            // Nor are they weighed against a stop: the path runs from blend to blend at
            // about their speed, not at the top speed of the short lines between.
            let dense = left_fixed.is_some() || right_split.is_some();
            let parts = if !dense && varies(&curve, &a, &b) {
                ((length / MIN_PART) as usize).clamp(1, BLEND_PARTS)
            } else {
                1
            };
            let headroom = if parts > 1 {
                Headroom::Lean
            } else {
                Headroom::Ample
            };
            if !dense
                && (turns_rotary(cur) || turns_rotary(next))
                && stop_is_faster(&curve, length, feed, headroom, (cur, next), limits)
            {
                return None;
            }
            // A blend's parts: at most `BLEND_PARTS`, one of them cut at the joint.
            let mut cut = [None; BLEND_PARTS + 1];
            let split_feed = cur.feed != next.feed;
            for (slot, (from, to, before)) in cut
                .iter_mut()
                .zip(blend_parts(length, parts, dl, dr, split_feed))
            {
                let (feed, loc) = match before {
                    Some(true) => (cur.feed, cur.loc),
                    Some(false) => (next.feed, next.loc),
                    None => (feed, next.loc),
                };
                *slot = Some((BlendPart { from, to, feed }, loc));
            }
            let weighed = cut.iter().flatten().map(|(part, _)| part);
            if !dense
                && theta >= SHARP_TURN
                && stop_saves_time(&curve, weighed, headroom, (cur, next), (dl, dr), limits)
            {
                return None;
            }
            // The caller made sure a slot is free; were none, the corner would stop.
            let shape = Shape::Blend(pool.store(curve)?);
            let mut out = Committed::default();
            push_part(&mut out, cur, cur.trim, len - dl);
            for (part, loc) in cut.into_iter().flatten() {
                out.pieces.push(NewPiece {
                    shape: shape.clone(),
                    offset: part.from,
                    length: part.to - part.from,
                    feed: part.feed,
                    loc,
                    headroom,
                });
            }
            next.trim = dr;
            next.split = right_split;
            return Some(out);
        }
        if right_split.is_some() {
            right_split = None;
        } else if left_fixed.is_some() && dr <= MIN_BLEND {
            return None;
        } else {
            d = d.min(cap_left.max(cap_right)) * 0.6;
        }
    }
    None
}

/// Shortest stretch (mm) of a blend on either side of the joint it replaces that gets a
/// piece of its own when the feeds on the two sides differ (a shorter one is part of its
/// neighbour and takes the lower feed).
const MIN_FEED_PART: f64 = 1e-6;

/// The parts a blend of `length` is committed in: `parts` equal parts, cut once more at the
/// programmed joint where the feeds on its two sides differ (`split_feed`). The joint lies
/// `dl` into the blend's reach of `dl + dr` over the contour; it is placed at the same share
/// of the blend's length. Each part comes with `Some(true)` when it lies before the joint
/// (the feed of the element before holds there), `Some(false)` after it, `None` when the
/// blend is not cut by feed (the lower feed holds).
///
/// A blend reaches as far into its neighbours as the tolerance allows; at a nearly straight
/// joint that is up to half of each. Planned at the lower feed as a whole, a blend between
/// a fast and a slow block would stretch the slow feed over half of the fast one; cut at
/// the joint, each block's feed holds over its own stretch, and the speed changes there.
fn blend_parts(
    length: f64,
    parts: usize,
    dl: f64,
    dr: f64,
    split_feed: bool,
) -> impl Iterator<Item = (f64, f64, Option<bool>)> {
    let step = length / parts as f64;
    let joint = (split_feed && dl + dr > 0.0)
        .then(|| length * dl / (dl + dr))
        .filter(|j| *j > MIN_FEED_PART && *j < length - MIN_FEED_PART);
    (0..parts).flat_map(move |k| {
        let from = step * k as f64;
        let to = if k + 1 == parts { length } else { from + step };
        let cut = joint.filter(|j| *j > from + MIN_FEED_PART && *j < to - MIN_FEED_PART);
        let side = |a: f64| joint.map(|j| a < j);
        let (first, second) = match cut {
            Some(j) => ((from, j, side(from)), Some((j, to, side(j)))),
            None => ((from, to, side(0.5 * (from + to))), None),
        };
        std::iter::once(first).chain(second)
    })
}

/// True when a line of length `len` whose ends turn by at most `turn` (radians) may lie
/// inside a blend through split points in tolerance `tol`: a gentle turn, and `len·turn`
/// within four times the tolerance. On a curve through the polyline's vertices the line
/// turns by about `len/r`, and the curve passes its midpoint at the sagitta
/// `len²/8r ≈ len·turn/8` from it: at most half the tolerance, as much as the fitted split
/// point may lie off the line (`smooth::SHIFT`). Adaptive clearing round a 4 mm radius in
/// 0.3 mm chords (`len·turn` = 2.25 tolerances of 0.01 mm) is such code; planned corner by
/// corner, each chord would be a blend from zero curvature to twice the circle's and back.
/// Every blend through split points is still checked against the tolerance band.
pub(super) fn gentle(len: f64, turn: f64, tol: f64) -> bool {
    turn <= SPLIT_MAX_ANGLE && len * turn <= 4.0 * tol
}

/// The lower of two feeds (`None`: rapid, the higher of any).
pub(super) fn min_feed(x: Option<f64>, y: Option<f64>) -> Option<f64> {
    match (x, y) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, y) => x.or(y),
    }
}
