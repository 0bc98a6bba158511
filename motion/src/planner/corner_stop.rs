//! Blend or exact stop: the rules that replace a corner's blend by an exact stop where the
//! blend would cost more time than stopping, or would crawl.
//!
//! * [`too_slow`]: the blend of a sharp corner whose limits fall below a tenth of its
//!   neighbours';
//! * [`stop_saves_time`]: a corner turning by at least [`SHARP_TURN`] whose blend, crossed
//!   at the speed its curvature allows, loses more time than braking to rest at the corner
//!   and speeding up again;
//! * [`stop_is_faster`]: a corner next to a move that turns a rotary axis, whose turn per
//!   millimetre makes the blend slow.

use super::path::{Element, element_limits, piece_limits};
use crate::blend::Quintic;
use crate::config::AxisLimits;
use crate::geom::{AxisBounds, Metric};
use crate::limits::Headroom;
use crate::profile::Ramp;

/// Smallest turn (radians, 45°) at which a blend is weighed against an exact stop by the
/// time each loses ([`stop_saves_time`]). A gentler corner's blend reaches further into its
/// neighbours for the same band and bends less, so it keeps much more of their speed; such
/// corners are not weighed (nor are blends through dense code, whose split points are
/// estimates).
pub(super) const SHARP_TURN: f64 = std::f64::consts::FRAC_PI_4;

/// One part of a blend as it will be committed: its stretch `[from, to]` along the blend
/// and its programmed feed (`None`: rapid).
#[derive(Debug, Clone, Copy)]
pub(super) struct BlendPart {
    /// Start along the blend.
    pub from: f64,
    /// End along the blend.
    pub to: f64,
    /// Programmed feed over it.
    pub feed: Option<f64>,
}

/// Time a speed change from `from` to `to` (both at zero acceleration, with `accel` and
/// `jerk`) loses against covering the same distance at `cruise`.
fn ramp_loss(from: f64, to: f64, cruise: f64, accel: f64, jerk: f64) -> f64 {
    let ramp = Ramp::new(from, 0.0, to, accel, jerk);
    ramp.duration() - ramp.distance() / cruise
}

/// True when stopping exactly at a sharp corner loses less time than the blend `blend`
/// (committed in `parts` with `headroom`) that replaces `dl` of `cur`'s end and `dr` of
/// `next`'s start.
///
/// Inside a tight band the blend of a sharp corner is short and strongly curved: the jerk
/// its curvature causes, v³·dκ/ds, holds it to a crawl (a 90° corner in a 0.01 mm band on
/// axes with 1e5 mm/s³ allows about 1.3 mm/s), and crossing it takes longer than coming to
/// rest at the corner and speeding up again in the new direction, each a jerk-limited ramp
/// along a straight element. The estimate compares the time each way loses
/// against running at the neighbours' own speeds `vl` (the top speed of `cur`, at most its
/// feed) and `vr`:
/// * through the blend: braking from `vl` to the slowest part's speed `low` (with `cur`'s
///   acceleration and the lower jerk of `cur` and the blend), each part crossed at its own
///   top speed instead of the replaced contour at `vl` and `vr`, and speeding up from `low`
///   to `vr` with `next`'s acceleration and the lower jerk;
/// * stopping: braking from `vl` to rest with `cur`'s limits and speeding up to `vr` with
///   `next`'s.
///
/// Crossing each part at its top speed is the fastest the path could go there, so the
/// blend's loss is if anything understated and a stop is taken only where it clearly pays.
pub(super) fn stop_saves_time<'a>(
    blend: &Quintic,
    parts: impl IntoIterator<Item = &'a BlendPart>,
    headroom: Headroom,
    (cur, next): (&Element, &Element),
    (dl, dr): (f64, f64),
    limits: &[Option<AxisLimits>; 9],
) -> bool {
    let (Some(l), Some(r)) = (element_limits(cur, limits), element_limits(next, limits)) else {
        return false;
    };
    let speed = |top: f64, feed: Option<f64>| feed.map_or(top, |f| top.min(f));
    let (vl, vr) = (speed(l.velocity, cur.feed), speed(r.velocity, next.feed));
    let (mut crossing, mut low, mut jerk) = (0.0, vl.min(vr), f64::INFINITY);
    for part in parts {
        let length = part.to - part.from;
        if length <= 0.0 {
            continue;
        }
        let bounds = blend.bounds_between(part.from, part.to);
        let Ok(b) = piece_limits(&bounds, length, part.feed, limits, headroom) else {
            // A part with no limits: the blend is useless, a stop serves.
            return true;
        };
        let v = speed(b.velocity, part.feed);
        crossing += length / v;
        low = low.min(v);
        jerk = jerk.min(b.jerk);
    }
    let through = ramp_loss(vl, low, vl, l.acceleration, l.jerk.min(jerk)) + crossing
        - (dl / vl + dr / vr)
        + ramp_loss(low, vr, vr, r.acceleration, r.jerk.min(jerk));
    let stop = ramp_loss(vl, 0.0, vl, l.acceleration, l.jerk)
        + ramp_loss(0.0, vr, vr, r.acceleration, r.jerk);
    stop < through
}

/// Share of its neighbours' speed or acceleration limit below which the blend of a sharp
/// corner (turning more than [`SPLIT_MAX_ANGLE`](super::path::SPLIT_MAX_ANGLE)) is not worth
/// it: the path stops exactly at the corner instead.
const SLOW_BLEND: f64 = 0.1;

/// True when a blend's limits fall so far below those of the elements it joins that an
/// exact stop serves better (a blend through a sharp corner in a tight band).
pub(super) fn too_slow(
    blend: &Quintic,
    length: f64,
    feed: Option<f64>,
    cur: &Element,
    next: &Element,
    limits: &[Option<AxisLimits>; 9],
) -> bool {
    let Ok(b) = piece_limits(&blend.bounds(), length, feed, limits, Headroom::Ample) else {
        return true;
    };
    let (Some(l), Some(r)) = (element_limits(cur, limits), element_limits(next, limits)) else {
        return true;
    };
    b.velocity < SLOW_BLEND * l.velocity.min(r.velocity)
        || b.acceleration < SLOW_BLEND * l.acceleration.min(r.acceleration)
}

/// True when the element turns a rotary axis along its linear motion.
pub(super) fn turns_rotary(e: &Element) -> bool {
    e.segment.metric() == Metric::Linear && Metric::Rotary.norm(&e.segment.bounds().d1) > 0.0
}

/// Share by which the rotary axes must at least slow down the way through a blend (its
/// estimated time against that of the same blend with the linear axes' limits alone)
/// before an exact stop may replace it.
const ROTARY_COST: f64 = 2.0;

/// True when stopping at the corner takes less time than slowing down into the blend and
/// speeding up out of it, and the rotary axes are what makes the blend slow (a corner next
/// to a move that turns a rotary axis, whose turn per millimetre can put the blend's limits
/// far below its neighbours').
///
/// The estimate: from the speed on `cur` (its top speed, at most the programmed feed) down
/// to the blend's top speed (with `headroom`, as it will be committed) and on to the speed
/// on `next`: braking with the acceleration of `cur` and the lower of the two jerks (the
/// look-ahead brakes into a piece with its jerk), speeding up with the acceleration of
/// `next` and again the lower jerk; against braking `cur` to rest and speeding `next` up
/// from rest with their own limits. It is rough for corners that slow the path down to
/// nearly nothing anyway (those [`too_slow`] settles): the blend must also take at least
/// [`ROTARY_COST`] times as long as it would if only the linear axes limited it.
pub(super) fn stop_is_faster(
    blend: &Quintic,
    length: f64,
    feed: Option<f64>,
    headroom: Headroom,
    (cur, next): (&Element, &Element),
    limits: &[Option<AxisLimits>; 9],
) -> bool {
    let time = |from: f64, to: f64, accel: f64, jerk: f64| {
        Ramp::new(from, 0.0, to, accel, jerk).duration()
    };
    // (through the blend, stopping) with the bounds as `keep` leaves them.
    let estimate = |keep: fn(AxisBounds) -> AxisBounds| -> Option<(f64, f64)> {
        let get = |b: AxisBounds, len: f64, feed: Option<f64>, h: Headroom| {
            piece_limits(&keep(b), len, feed, limits, h).ok()
        };
        let b = get(blend.bounds(), length, feed, headroom)?;
        let (lc, ln) = (cur.segment.length(), next.segment.length());
        let l = get(cur.segment.bounds(), lc, cur.feed, Headroom::Ample)?;
        let r = get(next.segment.bounds(), ln, next.feed, Headroom::Ample)?;
        let speed = |top: f64, e: &Element| e.feed.map_or(top, |f| top.min(f));
        let (vl, vr) = (speed(l.velocity, cur), speed(r.velocity, next));
        let low = b.velocity.min(vl).min(vr);
        let through = time(vl, low, l.acceleration, l.jerk.min(b.jerk))
            + time(low, vr, r.acceleration, r.jerk.min(b.jerk));
        let stop = time(vl, 0.0, l.acceleration, l.jerk) + time(0.0, vr, r.acceleration, r.jerk);
        Some((through, stop))
    };
    let Some((through, stop)) = estimate(|b| b) else {
        return true;
    };
    let Some((linear, _)) = estimate(without_rotary) else {
        return true;
    };
    through > stop && through > ROTARY_COST * linear
}

/// The bounds with those of the rotary axes left out.
fn without_rotary(mut b: AxisBounds) -> AxisBounds {
    for &i in Metric::Rotary.axes() {
        (b.d1[i], b.d2[i], b.d3[i], b.wave[i]) = (0.0, 0.0, 0.0, 0.0);
    }
    b
}
