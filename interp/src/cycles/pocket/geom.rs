//! Plane geometry shared by the pocket and stud cycles: rounded rectangles, their rings,
//! frames and depth steps.

use super::super::{CycleError, CycleFeed, Move, P3};

/// Tolerance for lengths, mm.
pub(in crate::cycles) const EPS: f64 = 1e-9;

/// A rectangle centred on the origin of its frame with half side lengths `ha` (along the
/// frame's first axis) and `hb`, and corners rounded with radius `rc` (`rc <= min(ha, hb)`).
/// A circle is `ha = hb = rc`; a slot is `rc = hb`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::cycles) struct RoundedRect {
    /// Half length along the first axis.
    pub ha: f64,
    /// Half length along the second axis.
    pub hb: f64,
    /// Corner radius.
    pub rc: f64,
}

impl RoundedRect {
    /// The shape offset by `d` (outwards when positive). Offsetting inwards keeps a corner
    /// round while its radius is larger than the offset and makes it sharp after that;
    /// half lengths never go below zero.
    pub fn offset(self, d: f64) -> Self {
        let ha = (self.ha + d).max(0.0);
        let hb = (self.hb + d).max(0.0);
        let rc = (self.rc + d).max(0.0).min(ha).min(hb);
        Self { ha, hb, rc }
    }

    /// The smaller half length.
    pub fn half_min(self) -> f64 {
        self.ha.min(self.hb)
    }

    /// The closed ring along the shape, starting and ending at `(ha, 0)`, as segments in
    /// the shape's frame; counter-clockwise when `ccw`. Zero-length lines are left out, so
    /// a shape with `hb = 0` becomes a stroke there and back, and a point gives nothing.
    pub fn ring(self, ccw: bool) -> Vec<Seg> {
        let Self { ha, hb, rc } = self;
        let (ea, eb) = (ha - rc, hb - rc);
        // Counter-clockwise, as (end point, arc centre).
        let pts: [([f64; 2], Option<[f64; 2]>); 9] = [
            ([ha, eb], None),
            ([ea, hb], Some([ea, eb])),
            ([-ea, hb], None),
            ([-ha, eb], Some([-ea, eb])),
            ([-ha, -eb], None),
            ([-ea, -hb], Some([-ea, -eb])),
            ([ea, -hb], None),
            ([ha, -eb], Some([ea, -eb])),
            ([ha, 0.0], None),
        ];
        let mut segs = Vec::with_capacity(9);
        let mut from = [ha, 0.0];
        for (to, centre) in pts {
            let keep = match centre {
                Some(_) => rc > 1e-6,
                None => dist2(from, to) > EPS,
            };
            if keep {
                segs.push(Seg {
                    from,
                    to,
                    centre,
                    ccw: true,
                });
            }
            from = to;
        }
        if ccw {
            segs
        } else {
            segs.iter()
                .rev()
                .map(|s| Seg {
                    from: s.to,
                    to: s.from,
                    centre: s.centre,
                    ccw: false,
                })
                .collect()
        }
    }
}

/// One segment of a path in a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::cycles) struct Seg {
    /// Start point.
    pub from: [f64; 2],
    /// End point.
    pub to: [f64; 2],
    /// Arc centre, `None` for a line.
    pub centre: Option<[f64; 2]>,
    /// Arc direction.
    pub ccw: bool,
}

/// Distance between two plane points.
pub(in crate::cycles) fn dist2(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// A plane frame: origin and rotation of the shape's axes against the working plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::cycles) struct Frame {
    /// Origin in the working plane.
    pub origin: [f64; 2],
    cos: f64,
    sin: f64,
}

impl Frame {
    /// A frame at `origin` turned by `deg` degrees counter-clockwise.
    pub fn new(origin: [f64; 2], deg: f64) -> Self {
        let r = deg.to_radians();
        Self {
            origin,
            cos: r.cos(),
            sin: r.sin(),
        }
    }

    /// A frame point in working-plane coordinates.
    pub fn map(&self, p: [f64; 2]) -> [f64; 2] {
        [
            self.origin[0] + self.cos * p[0] - self.sin * p[1],
            self.origin[1] + self.sin * p[0] + self.cos * p[1],
        ]
    }

    /// A frame point at tool-axis height `t`.
    pub fn at(&self, p: [f64; 2], t: f64) -> P3 {
        let q = self.map(p);
        [q[0], q[1], t]
    }
}

/// Appends moves to a list, working in one frame; straight moves that would not move the
/// tool are left out, and arcs whose ends nearly meet become straight moves.
pub(in crate::cycles) struct Path<'a> {
    /// The moves.
    pub out: &'a mut Vec<Move>,
    /// The frame the points are given in.
    pub frame: Frame,
    /// Where the tool is after the moves so far (working plane).
    pub cur: P3,
}

impl<'a> Path<'a> {
    /// A path in `frame` that starts with the tool at `cur`.
    pub fn new(out: &'a mut Vec<Move>, frame: Frame, cur: P3) -> Self {
        Self { out, frame, cur }
    }

    /// Straight move to frame point `p` at height `t`.
    pub fn line(&mut self, p: [f64; 2], t: f64, feed: CycleFeed) {
        let to = self.frame.at(p, t);
        self.line_abs(to, feed);
    }

    /// Straight move to a working-plane point.
    pub fn line_abs(&mut self, to: P3, feed: CycleFeed) {
        let d = (to[0] - self.cur[0])
            .hypot(to[1] - self.cur[1])
            .hypot(to[2] - self.cur[2]);
        if d > EPS {
            self.out.push(Move::Line { to, feed });
            self.cur = to;
        }
    }

    /// Arc about frame point `centre` to `p` at height `t` (helical when `t` differs from
    /// the start height); `turns` whole extra revolutions.
    pub fn arc(
        &mut self,
        centre: [f64; 2],
        p: [f64; 2],
        t: f64,
        ccw: bool,
        turns: u32,
        feed: CycleFeed,
    ) {
        let to = self.frame.at(p, t);
        let centre = self.frame.map(centre);
        // An arc whose ends nearly meet would read as a full circle: a short straight
        // move stands for it.
        let gap = (to[0] - self.cur[0]).hypot(to[1] - self.cur[1]);
        if turns == 0 && gap > 0.0 && gap < 1e-6 {
            self.line_abs(to, feed);
            return;
        }
        self.out.push(Move::Arc {
            centre,
            to,
            ccw,
            turns,
            feed,
        });
        self.cur = to;
    }

    /// The segments `segs` at height `t`.
    pub fn segs(&mut self, segs: &[Seg], t: f64, feed: CycleFeed) {
        for s in segs {
            match s.centre {
                Some(c) => self.arc(c, s.to, t, s.ccw, 0, feed),
                None => self.line(s.to, t, feed),
            }
        }
    }

    /// Full ring along `shape` at height `t`, entered with a straight move to its start.
    pub fn ring(&mut self, shape: RoundedRect, ccw: bool, t: f64, feed: CycleFeed) {
        self.line([shape.ha, 0.0], t, feed);
        self.segs(&shape.ring(ccw), t, feed);
    }
}

/// Most moves one cycle call may produce.
pub(in crate::cycles) const MAX_MOVES: f64 = 2_000_000.0;

/// Refuses a cycle whose parameters would need about `moves` moves (tiny infeeds or
/// stepovers on a large part).
pub(in crate::cycles) fn check_size(cycle: u32, moves: f64) -> Result<(), CycleError> {
    if moves > MAX_MOVES {
        return Err(CycleError::Geometry {
            cycle,
            msg: format!(
                "the parameters would need about {moves:.0} moves (at most {MAX_MOVES:.0})"
            ),
        });
    }
    Ok(())
}

/// Tool-axis heights of successive cuts from `top` down to `bottom` (`bottom < top`) with
/// at most `step` per cut: full steps first, the remainder last. A step that is zero,
/// negative or not smaller than the whole depth gives one cut at `bottom`.
pub(in crate::cycles) fn steps_down(top: f64, bottom: f64, step: f64) -> Vec<f64> {
    let total = top - bottom;
    if step.is_nan() || step <= 0.0 || step >= total - EPS {
        return vec![bottom];
    }
    let mut v = Vec::new();
    let mut k = 1.0;
    while top - k * step > bottom + 1e-6 && v.len() < 2_100_000 {
        v.push(top - k * step);
        k += 1.0;
    }
    v.push(bottom);
    v
}

/// Tool-axis heights from `top` down to `bottom` in equal cuts of at most `step`.
pub(in crate::cycles) fn steps_even(top: f64, bottom: f64, step: f64) -> Vec<f64> {
    let total = top - bottom;
    if step.is_nan() || step <= 0.0 || step >= total - EPS {
        return vec![bottom];
    }
    let n = (total / step - 1e-9).ceil().clamp(1.0, 2_100_000.0);
    // n is a small positive whole number.
    let count = n as usize;
    (1..=count).map(|k| top - total * k as f64 / n).collect()
}
