//! Tapping: 206 TAPPING (floating tap holder), 207 RIGID TAPPING, 209 TAPPING WITH CHIP
//! BREAKING, old cycle 2 TAPPING.

use super::common::{
    HoleSequence, HoleSteps, LEN_MAX, Params, Path, common, infeed_depths, old_common, old_dwell,
    plunged, reversed,
};
use super::peck::old_feed;
use crate::cycles::{CycleContext, CycleError, CycleFeed, Move, ParamKey};
use crate::op::SpindleDir;

/// Refuses tapping with a floating holder when the spindle is not turning: the feed was
/// chosen for the spindle speed and the hand of the thread follows M3/M4.
fn need_spindle(p: &Params<'_>, ctx: &CycleContext) -> Result<(), CycleError> {
    if ctx.spindle == SpindleDir::Off {
        return Err(
            p.geometry("tapping needs the spindle turning (M3 or M4) when the cycle is called")
        );
    }
    Ok(())
}

/// Cycle 206 TAPPING with a floating tap holder.
///
/// Rapid to the set-up clearance; tap at Q206 to the depth Q201 in one move; dwell Q211;
/// reverse the spindle and retract at Q206 to the set-up clearance; there the spindle
/// direction is reversed again; rapid to the 2nd set-up clearance when that is larger.
pub(super) fn tapping(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let seq = plunged(p)?;
    let dwell = p.dwell(211)?;
    let Some(seq) = seq else { return Ok(()) };
    need_spindle(p, ctx)?;
    seq.dwell(dwell).retract(seq.feed).run(
        &mut Path::new(out, ctx.pos),
        &mut Reversal::new(ctx, ctx.spindle),
    );
    Ok(())
}

/// Cycle 207 RIGID TAPPING (no floating holder; the spindle is interpolated with the
/// tool axis).
///
/// Rapid to the set-up clearance; the sign of the pitch Q239 gives the hand of the thread
/// (+ right-hand: the tool enters turning clockwise, M3; − left-hand: M4). From there the
/// tool axis is geared to the spindle ([`Move::RigidTap`]): spindle and tool start
/// together, one pitch per revolution down to the depth Q201, where the spindle stops and
/// reverses with the tool following it, and out the same way to the set-up clearance,
/// with the spindle turning Q403 times faster on the way out. There the spindle returns to
/// the direction it had at the call; rapid to the 2nd set-up clearance when that is
/// larger. Needs a programmed spindle speed.
///
/// Accepted and without effect on the path: Q336 (spindle orientation angle).
pub(super) fn rigid_tapping(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let c = common(p, 201)?;
    let (hand, pitch, factor) = thread(p)?;
    let Some(c) = c else { return Ok(()) };
    need_speed(p, ctx)?;
    geared(&c, ctx, out, hand, pitch, factor, (0.0, 0.0));
    Ok(())
}

/// The geared tap of 207/209 at one hole: rapid to the set-up clearance, the spindle turned
/// to the hand of the thread, the strokes (infeed and back-off of `chips`), the spindle back
/// to the direction of the call, rapid to the 2nd set-up clearance.
fn geared(
    c: &super::common::Common,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
    hand: SpindleDir,
    pitch: f64,
    retract_factor: f64,
    (infeed, back): (f64, f64),
) {
    let mut path = Path::new(out, ctx.pos);
    path.rapid_axis(c.safe);
    if ctx.spindle != hand {
        path.spindle(hand);
    }
    path.push(Move::RigidTap {
        to: [path.pos[0], path.pos[1], c.hole.at(c.hole.depth)],
        pitch,
        hand,
        lead_in: c.clearance,
        infeed,
        back,
        retract_factor,
    });
    if ctx.spindle != hand {
        path.spindle(ctx.spindle);
    }
    path.rapid_axis(c.top);
}

/// The spindle of a tapping cycle: turned to the hand of the thread at the set-up
/// clearance (when it turns the other way at the call), reversed at the bottom to leave the
/// thread, and back to the direction of the call at the set-up clearance.
struct Reversal {
    /// Direction at the call.
    call: SpindleDir,
    /// Direction that enters the thread.
    hand: SpindleDir,
}

impl Reversal {
    /// A thread of `hand` tapped from the spindle state of `ctx`.
    fn new(ctx: &CycleContext, hand: SpindleDir) -> Self {
        Reversal {
            call: ctx.spindle,
            hand,
        }
    }
}

impl HoleSteps for Reversal {
    fn at_clearance(&mut self, path: &mut Path<'_>) {
        if self.call != self.hand {
            path.spindle(self.hand);
        }
    }

    fn at_bottom(&mut self, path: &mut Path<'_>) {
        path.spindle(reversed(self.hand));
    }

    fn before_top(&mut self, path: &mut Path<'_>) {
        if self.call != reversed(self.hand) {
            path.spindle(self.call);
        }
    }
}

/// Reads the pitch Q239 of a rigid tapping cycle; returns the spindle direction for
/// entering the thread (the hand), the pitch magnitude and the retraction speed factor
/// Q403.
fn thread(p: &Params<'_>) -> Result<(SpindleDir, f64, f64), CycleError> {
    const PITCH: &str = "-99.9999..=99.9999, not 0";
    let pitch = p.req(239, "thread pitch", -99.9999, 99.9999, PITCH)?;
    if pitch == 0.0 {
        return Err(p.range_err(ParamKey::Q(239), pitch, PITCH));
    }
    p.opt(336, 0.0, 0.0, 360.0, "0..=360")?;
    let factor = p.opt(403, 1.0, 0.0001, 10.0, "0.0001..=10")?;
    let hand = if pitch > 0.0 {
        SpindleDir::Cw
    } else {
        SpindleDir::Ccw
    };
    Ok((hand, pitch.abs(), factor))
}

/// Refuses rigid tapping without a spindle speed: the feed is one pitch per revolution.
fn need_speed(p: &Params<'_>, ctx: &CycleContext) -> Result<(), CycleError> {
    if ctx.spindle_rpm.is_nan() || ctx.spindle_rpm <= 0.0 {
        return Err(p.geometry("rigid tapping needs a spindle speed (S) when the cycle is called"));
    }
    Ok(())
}

/// Cycle 209 TAPPING WITH CHIP BREAKING (rigid, like 207).
///
/// Rapid to the set-up clearance; geared to the spindle at one pitch Q239 per revolution
/// (the sign gives the hand as in 207), tap by the infeed depth for chip breaking Q257
/// (0: the whole depth at once); the spindle reverses and the tool backs off by Q256, or,
/// with Q256 = 0, all the way to the set-up clearance for chip removal; the spindle
/// reverses again and taps the next infeed. At the depth Q201 the spindle reverses and the
/// tool retracts to the set-up clearance; every retraction turns Q403 times faster. Then
/// the spindle direction of the call is restored and the tool rapids to the 2nd set-up
/// clearance when that is larger.
pub(super) fn tapping_chip_breaking(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    const LEN: &str = "0..=99999.9999";
    let c = common(p, 201)?;
    let infeed = p.opt(257, 0.0, 0.0, LEN_MAX, LEN)?;
    let back = p.opt(256, 0.0, 0.0, LEN_MAX, LEN)?;
    let (hand, pitch, factor) = thread(p)?;
    let Some(c) = c else { return Ok(()) };
    need_speed(p, ctx)?;
    // The number of infeeds is bounded like every other infeed loop.
    let step = if infeed > 0.0 { infeed } else { c.hole.depth };
    infeed_depths(p, 0.0, c.hole.depth, step, 0.0, 0.0)?;
    geared(&c, ctx, out, hand, pitch, factor, (infeed, back));
    Ok(())
}

/// Old cycle 2 TAPPING with a floating tap holder (`2.1` set-up clearance, `2.2` depth,
/// `2.3` dwell, `2.4 F` feed = pitch × speed).
///
/// From the current position (the set-up clearance above the surface) tap at F to the
/// depth in one move; dwell, reverse the spindle and retract at F to the starting position;
/// there the spindle direction is reversed again.
pub(super) fn old_tapping(
    p: &Params<'_>,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    let c = old_common(p, ctx.pos[2])?;
    let dwell = old_dwell(p, 3)?;
    let feed = CycleFeed::Rate(old_feed(p, ctx, 4)?);
    let Some(c) = c else { return Ok(()) };
    need_spindle(p, ctx)?;
    HoleSequence::new(&c, feed).dwell(dwell).retract(feed).run(
        &mut Path::new(out, ctx.pos),
        &mut Reversal::new(ctx, ctx.spindle),
    );
    Ok(())
}
