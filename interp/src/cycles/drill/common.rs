//! What the drilling cycles share: reading and checking parameters, the geometry of one
//! hole along the tool axis, and a move emitter that knows where the tool is.
//!
//! Parameter conventions (the caller passes values as written in the cycle definition):
//! lengths in mm, feeds in mm/min (converted here to mm/s), dwell times in seconds. A feed
//! parameter written as `FMAX` arrives as `f64::INFINITY` and is accepted only where the
//! manual allows FMAX (retraction and pre-positioning feeds, never a cutting feed). `FAUTO`
//! is resolved by the caller to the feed of the TOOL CALL before it reaches a generator.

use crate::cycles::{CycleError, CycleFeed, Move, P3, ParamKey, ParamSource};
use crate::op::SpindleDir;

/// Largest magnitude the manual allows for a length parameter.
pub(in crate::cycles) const LEN_MAX: f64 = 99_999.999_9;
/// Largest feed the manual allows, mm/min.
pub(in crate::cycles) const FEED_MAX: f64 = 99_999.999;
/// Longest dwell the manual allows, s.
pub(in crate::cycles) const DWELL_MAX: f64 = 3600.0;
/// Upper bound on the number of infeeds of one hole: a guard against parameters that would
/// generate millions of moves (0.0001 mm pecks into a deep hole), not a manual limit.
pub(in crate::cycles) const MAX_INFEEDS: usize = 10_000;
/// Lengths closer than this are the same point (mm).
pub(in crate::cycles) const EPS: f64 = 1e-9;

/// How a parameter is written in messages: `Q201`, `1.2`, `F`.
pub(in crate::cycles) fn key_name(key: ParamKey) -> String {
    match key {
        ParamKey::Q(n) => format!("Q{n}"),
        ParamKey::Old { line, index } => {
            if index == 0 {
                format!("{line}")
            } else {
                format!("{line} (value {})", u32::from(index) + 1)
            }
        }
        ParamKey::OldWord(w) => w.to_string(),
        ParamKey::OldFeed { line } => format!("F of sub-block {line}"),
    }
}

/// The parameters of one cycle definition with the cycle number, for checked reads.
#[derive(Clone, Copy)]
pub(in crate::cycles) struct Params<'a> {
    /// Cycle number, for messages.
    pub cycle: u32,
    src: &'a dyn ParamSource,
}

impl<'a> Params<'a> {
    /// Wraps `src` as the parameters of `cycle`.
    pub fn new(cycle: u32, src: &'a dyn ParamSource) -> Self {
        Params { cycle, src }
    }

    /// The raw value of `key`, unchecked.
    pub fn raw(&self, key: ParamKey) -> Option<f64> {
        self.src.get(key)
    }

    /// An out-of-range error for `key` with value `v`.
    pub fn range_err(&self, key: ParamKey, v: f64, range: &'static str) -> CycleError {
        CycleError::OutOfRange {
            cycle: self.cycle,
            param: key_name(key),
            value: v,
            range,
        }
    }

    /// A geometry error with `msg`.
    pub fn geometry(&self, msg: impl Into<String>) -> CycleError {
        CycleError::Geometry {
            cycle: self.cycle,
            msg: msg.into(),
        }
    }

    fn check(
        &self,
        key: ParamKey,
        v: f64,
        lo: f64,
        hi: f64,
        range: &'static str,
    ) -> Result<f64, CycleError> {
        if v.is_finite() && v >= lo && v <= hi {
            Ok(v)
        } else {
            Err(self.range_err(key, v, range))
        }
    }

    /// A required value of `key` within `[lo, hi]`.
    pub fn req_key(
        &self,
        key: ParamKey,
        what: &'static str,
        lo: f64,
        hi: f64,
        range: &'static str,
    ) -> Result<f64, CycleError> {
        match self.raw(key) {
            None => Err(CycleError::Missing {
                cycle: self.cycle,
                param: key_name(key),
                what,
            }),
            Some(v) => self.check(key, v, lo, hi, range),
        }
    }

    /// A required `Qn` within `[lo, hi]`.
    pub fn req(
        &self,
        q: u32,
        what: &'static str,
        lo: f64,
        hi: f64,
        range: &'static str,
    ) -> Result<f64, CycleError> {
        self.req_key(ParamKey::Q(q), what, lo, hi, range)
    }

    /// An optional `Qn` within `[lo, hi]`, `default` when absent (parameters added to a
    /// cycle in later software versions are absent from older programs).
    pub fn opt(
        &self,
        q: u32,
        default: f64,
        lo: f64,
        hi: f64,
        range: &'static str,
    ) -> Result<f64, CycleError> {
        match self.raw(ParamKey::Q(q)) {
            None => Ok(default),
            Some(v) => self.check(ParamKey::Q(q), v, lo, hi, range),
        }
    }

    /// An optional whole-number `Qn` within `[lo, hi]`.
    pub fn opt_int(
        &self,
        q: u32,
        default: i64,
        lo: i64,
        hi: i64,
        range: &'static str,
    ) -> Result<i64, CycleError> {
        let v = self.opt(q, default as f64, lo as f64, hi as f64, range)?;
        if v.fract() != 0.0 {
            return Err(self.range_err(ParamKey::Q(q), v, range));
        }
        Ok(v as i64)
    }

    /// A required whole-number `Qn` within `[lo, hi]`.
    pub fn req_int(
        &self,
        q: u32,
        what: &'static str,
        lo: i64,
        hi: i64,
        range: &'static str,
    ) -> Result<i64, CycleError> {
        let v = self.req(q, what, lo as f64, hi as f64, range)?;
        if v.fract() != 0.0 {
            return Err(self.range_err(ParamKey::Q(q), v, range));
        }
        Ok(v as i64)
    }

    /// A required cutting feed `Qn` (mm/min in the definition, > 0, FMAX not allowed),
    /// returned in mm/s.
    pub fn cut_feed(&self, q: u32, what: &'static str) -> Result<f64, CycleError> {
        let v = self.req(q, what, 0.0, FEED_MAX, "0 < feed <= 99999.999 mm/min")?;
        if v <= 0.0 {
            return Err(self.range_err(ParamKey::Q(q), v, "0 < feed <= 99999.999 mm/min"));
        }
        Ok(v / 60.0)
    }

    /// The plunging feed Q206 as a cycle feed.
    pub fn plunge_feed(&self) -> Result<CycleFeed, CycleError> {
        Ok(CycleFeed::Rate(
            self.cut_feed(206, "feed rate for plunging")?,
        ))
    }

    /// An optional positioning feed `Qn` that may be FMAX (`+inf`): `None` when absent,
    /// `Some(None)` when 0 (the caller decides what 0 means), `Some(Some(feed))` otherwise.
    pub fn move_feed(&self, q: u32) -> Result<Option<Option<CycleFeed>>, CycleError> {
        const RANGE: &str = "0..=99999.999 mm/min or FMAX";
        match self.raw(ParamKey::Q(q)) {
            None => Ok(None),
            Some(v) if v == f64::INFINITY => Ok(Some(Some(CycleFeed::Rapid))),
            Some(v) => {
                let v = self.check(ParamKey::Q(q), v, 0.0, FEED_MAX, RANGE)?;
                if v == 0.0 {
                    Ok(Some(None))
                } else {
                    Ok(Some(Some(CycleFeed::Rate(v / 60.0))))
                }
            }
        }
    }

    /// A dwell time `Qn`, s, 0 when absent.
    pub fn dwell(&self, q: u32) -> Result<f64, CycleError> {
        self.opt(q, 0.0, 0.0, DWELL_MAX, "0..=3600 s")
    }
}

/// One hole along the tool axis: where the surface is and which way is "into the material".
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::cycles) struct Hole {
    /// Tool-axis coordinate of the workpiece surface.
    pub surface: f64,
    /// −1 when the depth is negative (the usual case: the tool works towards −t), +1 when
    /// the depth is positive (the manual warns that the clearance heights are then
    /// mirrored too: set-up clearance *below* the surface).
    pub dir: f64,
    /// Depth magnitude from the surface, > 0.
    pub depth: f64,
}

impl Hole {
    /// The tool-axis coordinate `d` mm into the material (d ≥ 0) or `-d` above it.
    pub fn at(&self, d: f64) -> f64 {
        self.surface + self.dir * d
    }

    /// The tool-axis coordinate `h` mm in front of the surface (on the clearance side).
    pub fn above(&self, h: f64) -> f64 {
        self.surface - self.dir * h
    }
}

/// The parameters every 200-series drilling cycle shares: Q200 set-up clearance, the depth
/// (Q201 unless `depth_q` says otherwise), Q203 surface coordinate, Q204 2nd set-up
/// clearance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::cycles) struct Common {
    /// The hole.
    pub hole: Hole,
    /// Q200, ≥ 0.
    pub clearance: f64,
    /// Tool-axis coordinate of the set-up clearance plane.
    pub safe: f64,
    /// Tool-axis coordinate the cycle ends at: the 2nd set-up clearance when Q204 is larger
    /// than Q200 (the manual: Q204 only takes effect then), otherwise the set-up clearance.
    pub top: f64,
}

impl Common {
    /// The clearance heights of `hole` for the set-up clearance `clearance` and the 2nd
    /// set-up clearance `second`.
    pub fn new(hole: Hole, clearance: f64, second: f64) -> Self {
        Common {
            hole,
            clearance,
            safe: hole.above(clearance),
            top: hole.above(clearance.max(second)),
        }
    }
}

/// Reads Q200, the depth `depth_q`, Q203 and Q204. `Ok(None)` when the depth is 0: the
/// manual says the control does not run a cycle programmed with depth 0.
pub(in crate::cycles) fn common(
    p: &Params<'_>,
    depth_q: u32,
) -> Result<Option<Common>, CycleError> {
    let clearance = set_up_clearance(p)?;
    let depth = p.req(
        depth_q,
        "depth",
        -LEN_MAX,
        LEN_MAX,
        "-99999.9999..=99999.9999",
    )?;
    let (surface, second) = surface_and_second(p)?;
    if depth == 0.0 {
        return Ok(None);
    }
    let hole = Hole {
        surface,
        dir: depth.signum(),
        depth: depth.abs(),
    };
    Ok(Some(Common::new(hole, clearance, second)))
}

/// Q200, the set-up clearance, ≥ 0.
pub(in crate::cycles) fn set_up_clearance(p: &Params<'_>) -> Result<f64, CycleError> {
    p.req(200, "set-up clearance", 0.0, LEN_MAX, "0..=99999.9999")
}

/// Q203 (workpiece surface coordinate) and Q204 (2nd set-up clearance, ≥ 0).
pub(in crate::cycles) fn surface_and_second(p: &Params<'_>) -> Result<(f64, f64), CycleError> {
    let surface = p.req(
        203,
        "workpiece surface coordinate",
        -LEN_MAX,
        LEN_MAX,
        "-99999.9999..=99999.9999",
    )?;
    let second = p.req(204, "2nd set-up clearance", 0.0, LEN_MAX, "0..=99999.9999")?;
    Ok((surface, second))
}

/// [`common`] with the depth Q201 and the plunging feed Q206: the hole sequence of a cycle
/// that plunges at Q206, `Ok(None)` when the depth is 0.
pub(in crate::cycles) fn plunged(p: &Params<'_>) -> Result<Option<HoleSequence>, CycleError> {
    let c = common(p, 201)?;
    let feed = p.plunge_feed()?;
    Ok(c.map(|c| HoleSequence::new(&c, feed)))
}

/// Refuses a deepened starting point Q379 (`start`, from the surface) at or below the
/// depth of the hole `c`.
pub(in crate::cycles) fn deepened_start(
    p: &Params<'_>,
    start: f64,
    c: &Common,
) -> Result<(), CycleError> {
    if start >= c.hole.depth {
        return Err(p.geometry(format!(
            "the deepened starting point Q379={start} is not above the depth {}",
            c.hole.depth
        )));
    }
    Ok(())
}

/// Sub-blocks 1 (set-up clearance) and 2 (total hole depth) of the old cycles 1 and 2,
/// which start at the current tool position `start` (tool axis): that is the set-up
/// clearance, and the cycle ends there too. The sign of the depth gives the direction; the
/// clearance is taken by magnitude (programs in the field mix `ABST+1` with `TIEFE-21`).
/// `Ok(None)` when the depth is 0.
pub(in crate::cycles) fn old_common(
    p: &Params<'_>,
    start: f64,
) -> Result<Option<Common>, CycleError> {
    const ANY: &str = "-99999.9999..=99999.9999";
    let clearance = p
        .req_key(old_key(1), "set-up clearance", -LEN_MAX, LEN_MAX, ANY)?
        .abs();
    let depth = p.req_key(old_key(2), "total hole depth", -LEN_MAX, LEN_MAX, ANY)?;
    if depth == 0.0 {
        return Ok(None);
    }
    let hole = Hole {
        surface: start + depth.signum() * clearance,
        dir: depth.signum(),
        depth: depth.abs(),
    };
    Ok(Some(Common {
        hole,
        clearance,
        safe: start,
        top: start,
    }))
}

/// The optional dwell time of an old-format cycle on sub-block `line`, s (0 when absent).
pub(in crate::cycles) fn old_dwell(p: &Params<'_>, line: u8) -> Result<f64, CycleError> {
    match p.raw(old_key(line)) {
        Some(_) => p.req_key(old_key(line), "dwell time", 0.0, DWELL_MAX, "0..=3600 s"),
        None => Ok(0.0),
    }
}

/// The plain value of sub-block `line` of an old-format cycle.
pub(in crate::cycles) fn old_key(line: u8) -> ParamKey {
    ParamKey::Old { line, index: 0 }
}

/// Rejects Q395 = 1 (depth measured to the cylindrical part of the tool): that needs the
/// point angle of the tool, which the cycle context does not carry.
pub(in crate::cycles) fn depth_reference_tip(p: &Params<'_>) -> Result<(), CycleError> {
    let r = p.opt_int(395, 0, 0, 1, "0 (tool tip) or 1 (cylindrical part)")?;
    if r == 1 {
        return Err(p.geometry("Q395=1 (depth to the cylindrical part) needs the tool's point angle, which is not known"));
    }
    Ok(())
}

/// The depths (measured from the surface, growing) at which successive infeeds stop,
/// starting at `start` (already reached: the surface, or a deepened starting point) and
/// ending exactly at `total`. The first infeed is `first`; each later one is `decrement`
/// smaller but never smaller than `min` (when `min` is 0 and the decrement would make the
/// infeed vanish, the last positive infeed is kept). An infeed of at least the remaining
/// depth goes to depth in one move, as the manual says.
pub(in crate::cycles) fn infeed_depths(
    p: &Params<'_>,
    start: f64,
    total: f64,
    first: f64,
    decrement: f64,
    min: f64,
) -> Result<Vec<f64>, CycleError> {
    let mut out = Vec::new();
    let mut reached = start;
    let mut step = first;
    while reached < total - EPS {
        if out.len() >= MAX_INFEEDS {
            return Err(p.geometry(format!(
                "more than {MAX_INFEEDS} infeeds for one hole; increase the plunging depth"
            )));
        }
        let next = (reached + step).min(total);
        out.push(next);
        reached = next;
        let smaller = step - decrement;
        step = if smaller < min {
            if min > 0.0 { min } else { step }
        } else if smaller <= 0.0 {
            step
        } else {
            smaller
        };
    }
    Ok(out)
}

/// The opposite spindle direction (tapping reversal); `Off` stays `Off`.
pub(in crate::cycles) fn reversed(d: SpindleDir) -> SpindleDir {
    match d {
        SpindleDir::Cw => SpindleDir::Ccw,
        SpindleDir::Ccw => SpindleDir::Cw,
        SpindleDir::Off => SpindleDir::Off,
    }
}

/// The direction the spindle cuts in when a cycle switches it on: as at the call (`d`),
/// M3 when it was stopped.
pub(in crate::cycles) fn cutting(d: SpindleDir) -> SpindleDir {
    if d == SpindleDir::Off {
        SpindleDir::Cw
    } else {
        d
    }
}

/// Appends moves to the output and remembers where the tool is; straight moves of zero
/// length and dwells of zero time are dropped.
pub(in crate::cycles) struct Path<'a> {
    out: &'a mut Vec<Move>,
    /// Current tool position `[a, b, t]`.
    pub pos: P3,
}

impl<'a> Path<'a> {
    /// Starts at `pos`.
    pub fn new(out: &'a mut Vec<Move>, pos: P3) -> Self {
        Path { out, pos }
    }

    /// Straight move to `to`.
    pub fn line(&mut self, to: P3, feed: CycleFeed) {
        let d =
            (to[0] - self.pos[0]).abs() + (to[1] - self.pos[1]).abs() + (to[2] - self.pos[2]).abs();
        if d > EPS {
            self.out.push(Move::Line { to, feed });
            self.pos = to;
        }
    }

    /// Straight move along the tool axis to `t`.
    pub fn axis(&mut self, t: f64, feed: CycleFeed) {
        self.line([self.pos[0], self.pos[1], t], feed);
    }

    /// Any other move, where the tool stands after it does not change.
    pub fn push(&mut self, m: Move) {
        self.out.push(m);
    }

    /// Rapid along the tool axis to `t`.
    pub fn rapid_axis(&mut self, t: f64) {
        self.axis(t, CycleFeed::Rapid);
    }

    /// Straight move in the working plane to `(a, b)` at the current tool-axis height.
    pub fn plane(&mut self, a: f64, b: f64, feed: CycleFeed) {
        self.line([a, b, self.pos[2]], feed);
    }

    /// Circular or helical move of less than a full turn about `centre` to `to`.
    pub fn arc(&mut self, centre: [f64; 2], to: P3, ccw: bool, feed: CycleFeed) {
        self.out.push(Move::Arc {
            centre,
            to,
            ccw,
            turns: 0,
            feed,
        });
        self.pos = to;
    }

    /// Dwell of `s` seconds (nothing when 0).
    pub fn dwell(&mut self, s: f64) {
        if s > 0.0 {
            self.out.push(Move::Dwell(s));
        }
    }

    /// Spindle direction change.
    pub fn spindle(&mut self, d: SpindleDir) {
        self.out.push(Move::Spindle(d));
    }
}

/// What a cycle adds at the fixed points of [`HoleSequence`]: spindle reversals for tapping,
/// the oriented stop and disengaging move for boring. Every step does nothing by default.
pub(in crate::cycles) trait HoleSteps {
    /// At the set-up clearance, after the rapid approach and before the first infeed.
    fn at_clearance(&mut self, _path: &mut Path<'_>) {}
    /// At the bottom, after the dwell and before the retraction.
    fn at_bottom(&mut self, _path: &mut Path<'_>) {}
    /// After the retraction to the set-up clearance (at the bottom when the sequence has no
    /// separate retraction), before the rapid move to the 2nd set-up clearance.
    fn before_top(&mut self, _path: &mut Path<'_>) {}
}

/// No additional steps.
impl HoleSteps for () {}

/// The sequence every drilling cycle runs at one hole: rapid along the tool axis to the
/// set-up clearance, feed to the bottom, dwell there, retract to the set-up clearance and
/// rapid to the 2nd set-up clearance. Cycles with several infeeds run [`Self::enter`] and
/// [`Self::finish`] around their own infeeds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::cycles) struct HoleSequence {
    /// The hole and its clearance heights.
    pub c: Common,
    /// Feed to the bottom.
    pub feed: CycleFeed,
    /// Dwell at the bottom, s.
    pub dwell: f64,
    /// Feed of the retraction from the bottom to the set-up clearance; `None`: no separate
    /// retraction, the tool rapids from the bottom straight to the end height.
    pub retract: Option<CycleFeed>,
}

impl HoleSequence {
    /// The hole of `c` drilled at `feed`, without dwell, rapid out.
    pub fn new(c: &Common, feed: CycleFeed) -> Self {
        HoleSequence {
            c: *c,
            feed,
            dwell: 0.0,
            retract: None,
        }
    }

    /// Tool-axis coordinate of the bottom of the hole.
    pub fn bottom(&self) -> f64 {
        self.c.hole.at(self.c.hole.depth)
    }

    /// With a dwell of `s` seconds at the bottom.
    pub fn dwell(self, s: f64) -> Self {
        HoleSequence { dwell: s, ..self }
    }

    /// With a retraction at `feed` to the set-up clearance.
    pub fn retract(self, feed: CycleFeed) -> Self {
        HoleSequence {
            retract: Some(feed),
            ..self
        }
    }

    /// Rapid to the set-up clearance, then the cycle's step there.
    pub fn enter(&self, path: &mut Path<'_>, steps: &mut impl HoleSteps) {
        path.rapid_axis(self.c.safe);
        steps.at_clearance(path);
    }

    /// From the bottom: dwell, the cycle's step there, retract to the set-up clearance,
    /// the cycle's step before leaving, rapid to the end height.
    pub fn finish(&self, path: &mut Path<'_>, steps: &mut impl HoleSteps) {
        path.dwell(self.dwell);
        steps.at_bottom(path);
        if let Some(feed) = self.retract {
            path.axis(self.c.safe, feed);
        }
        steps.before_top(path);
        path.rapid_axis(self.c.top);
    }

    /// The whole sequence with one infeed to the bottom.
    pub fn run(&self, path: &mut Path<'_>, steps: &mut impl HoleSteps) {
        self.enter(path, steps);
        path.axis(self.bottom(), self.feed);
        self.finish(path, steps);
    }
}
