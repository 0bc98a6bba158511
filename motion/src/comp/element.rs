//! One programmed contour element in the working plane, its offset (tool-centre) curve, the
//! trims that corners cut from that curve, and the ops the trimmed curve becomes.
//!
//! Offset rule: the tool centre runs at the tool radius R from the contour, on the left of
//! the direction of travel for RL and on the right for RR. With the signed offset d (+R for
//! RL, −R for RR) a line moves by d along its left normal; an arc keeps its centre and its
//! radius becomes r − d for a counter-clockwise (DR+) arc and r + d for a clockwise (DR−) one.
//! The axes outside the working plane (the tool axis of a helix, rotary axes) are untouched:
//! an element cut short at an inside corner still reaches its programmed values outside the
//! plane at its (new) end, and transition arcs keep them constant.

use super::error::CompError;
use super::plane::{V2, project, with_point, wrap};
use klar_interp::{CornerRule, Feed, Op, OpKind, Plane, Pose, SourceLoc};

/// In-plane moves shorter than this (mm) count as no movement in the plane.
pub const PLANE_EPS: f64 = 1e-9;

/// The geometry of a programmed element in the working plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// Straight line from `a` to `b`.
    Line {
        /// Start.
        a: V2,
        /// End.
        b: V2,
    },
    /// Arc about `c` with radius `r`, starting at angle `phi0`, turning through `sweep`
    /// radians (positive counter-clockwise).
    Arc {
        /// Centre.
        c: V2,
        /// Radius.
        r: f64,
        /// Start angle, radians.
        phi0: f64,
        /// Signed sweep, radians.
        sweep: f64,
    },
}

/// A programmed motion block with movement in the working plane.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    /// Programmed start pose.
    pub from: Pose,
    /// Programmed end pose.
    pub to: Pose,
    /// Feed of the block.
    pub feed: Feed,
    /// The block.
    pub loc: SourceLoc,
    /// In-plane geometry.
    pub shape: Shape,
}

/// What a motion op is to the compensation stage.
pub enum Motion {
    /// A line or arc with movement in the working plane.
    Contour(Element),
    /// A move with no movement in the working plane (tool axis, rotary axes only).
    OffPlane {
        /// End pose of the move (only its axes outside the plane are used).
        to: Pose,
        /// Feed.
        feed: Feed,
    },
}

fn finite(p: &Pose) -> bool {
    p.0.iter().all(|v| v.is_finite())
}

impl Element {
    /// Classifies a line or arc op; `None` for other ops.
    pub fn classify(op: &Op, plane: Plane) -> Result<Option<Motion>, CompError> {
        let loc = op.loc;
        match &op.kind {
            OpKind::Line { from, to, feed } => {
                if !finite(from) || !finite(to) {
                    return Err(CompError::NonFinite {
                        loc,
                        what: "line end point",
                    });
                }
                let a = project(from, plane);
                let b = project(to, plane);
                if a.dist(b) <= PLANE_EPS {
                    return Ok(Some(Motion::OffPlane {
                        to: *to,
                        feed: *feed,
                    }));
                }
                Ok(Some(Motion::Contour(Element {
                    from: *from,
                    to: *to,
                    feed: *feed,
                    loc,
                    shape: Shape::Line { a, b },
                })))
            }
            OpKind::Arc {
                from,
                to,
                center,
                plane: arc_plane,
                sweep,
                feed,
            } => {
                if !finite(from) || !finite(to) || !center.iter().all(|c| c.is_finite()) {
                    return Err(CompError::NonFinite {
                        loc,
                        what: "arc point or centre",
                    });
                }
                if !sweep.is_finite() {
                    return Err(CompError::NonFinite {
                        loc,
                        what: "arc sweep",
                    });
                }
                if *arc_plane != plane {
                    return Err(CompError::ArcOutsidePlane { loc });
                }
                let c = V2::new(center[0], center[1]);
                let rel = project(from, plane) - c;
                let r = rel.norm();
                let sweep = sweep.to_radians();
                if r * sweep.abs() <= PLANE_EPS {
                    return Ok(Some(Motion::OffPlane {
                        to: *to,
                        feed: *feed,
                    }));
                }
                Ok(Some(Motion::Contour(Element {
                    from: *from,
                    to: *to,
                    feed: *feed,
                    loc,
                    shape: Shape::Arc {
                        c,
                        r,
                        phi0: rel.angle(),
                        sweep,
                    },
                })))
            }
            _ => Ok(None),
        }
    }

    /// In-plane start point.
    pub fn start(&self) -> V2 {
        match self.shape {
            Shape::Line { a, .. } => a,
            Shape::Arc { c, r, phi0, .. } => c + V2::polar(phi0) * r,
        }
    }

    /// Unit direction of travel at the start.
    pub fn tangent_start(&self) -> V2 {
        match self.shape {
            Shape::Line { a, b } => (b - a) * (1.0 / a.dist(b)),
            Shape::Arc { phi0, sweep, .. } => V2::polar(phi0).left() * sweep.signum(),
        }
    }

    /// Unit direction of travel at the end.
    pub fn tangent_end(&self) -> V2 {
        match self.shape {
            Shape::Line { .. } => self.tangent_start(),
            Shape::Arc { phi0, sweep, .. } => V2::polar(phi0 + sweep).left() * sweep.signum(),
        }
    }

    /// The tool-centre curve at signed offset `d` (+R left, −R right of travel).
    pub fn offset(&self, d: f64, tool: f64) -> Result<Curve, CompError> {
        match self.shape {
            Shape::Line { a, b } => {
                let len = a.dist(b);
                let u = (b - a) * (1.0 / len);
                let n = u.left() * d;
                Ok(Curve::Line { a: a + n, u, len })
            }
            Shape::Arc { c, r, phi0, sweep } => {
                let ro = r - d * sweep.signum();
                if ro <= PLANE_EPS {
                    return Err(CompError::ArcTooSmall {
                        loc: self.loc,
                        arc: r,
                        tool,
                    });
                }
                Ok(Curve::Arc {
                    c,
                    r: ro,
                    phi0,
                    sweep,
                })
            }
        }
    }
}

/// An offset curve. Trims are measured from its ends inwards: mm for lines, radians of
/// travel for arcs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Curve {
    /// Line from `a` along unit direction `u`, `len` long.
    Line {
        /// Start.
        a: V2,
        /// Unit direction.
        u: V2,
        /// Length.
        len: f64,
    },
    /// Arc about `c` with radius `r` from angle `phi0` through signed `sweep` radians.
    Arc {
        /// Centre.
        c: V2,
        /// Radius (> 0).
        r: f64,
        /// Start angle.
        phi0: f64,
        /// Signed sweep.
        sweep: f64,
    },
}

impl Curve {
    /// Extent in trim units: length for lines, |sweep| for arcs.
    pub fn extent(&self) -> f64 {
        match *self {
            Curve::Line { len, .. } => len,
            Curve::Arc { sweep, .. } => sweep.abs(),
        }
    }

    /// Millimetres of path per trim unit.
    pub fn scale(&self) -> f64 {
        match *self {
            Curve::Line { .. } => 1.0,
            Curve::Arc { r, .. } => r,
        }
    }

    /// The point `trim` from the start, travelling forwards.
    pub fn point_from_start(&self, trim: f64) -> V2 {
        match *self {
            Curve::Line { a, u, .. } => a + u * trim,
            Curve::Arc { c, r, phi0, sweep } => c + V2::polar(phi0 + sweep.signum() * trim) * r,
        }
    }

    /// The point `trim` before the end.
    pub fn point_from_end(&self, trim: f64) -> V2 {
        self.point_from_start(self.extent() - trim)
    }

    /// The trim from the start that reaches `x` (a point on the curve or its extension);
    /// negative when `x` lies before the start.
    pub fn trim_start_to(&self, x: V2) -> f64 {
        match *self {
            Curve::Line { a, u, .. } => (x - a).dot(u),
            Curve::Arc { c, phi0, sweep, .. } => wrap(((x - c).angle() - phi0) * sweep.signum()),
        }
    }

    /// The trim from the end that reaches `x`; negative when `x` lies beyond the end.
    pub fn trim_end_to(&self, x: V2) -> f64 {
        match *self {
            Curve::Line { a, u, len } => (a + u * len - x).dot(u),
            Curve::Arc { c, phi0, sweep, .. } => {
                wrap((phi0 + sweep - (x - c).angle()) * sweep.signum())
            }
        }
    }

    /// Intersections of the two curves taken whole (infinite lines, full circles).
    pub fn intersect(&self, other: &Curve) -> Vec<V2> {
        match (*self, *other) {
            (Curve::Line { a: p, u, .. }, Curve::Line { a: q, u: v, .. }) => {
                let den = u.cross(v);
                if den.abs() < 1e-12 {
                    return Vec::new();
                }
                let s = (q - p).cross(v) / den;
                vec![p + u * s]
            }
            (Curve::Line { a, u, .. }, Curve::Arc { c, r, .. })
            | (Curve::Arc { c, r, .. }, Curve::Line { a, u, .. }) => line_circle(a, u, c, r),
            (Curve::Arc { c: c1, r: r1, .. }, Curve::Arc { c: c2, r: r2, .. }) => {
                circle_circle(c1, r1, c2, r2)
            }
        }
    }
}

/// Intersections of the line through `a` with unit direction `u` and the circle (c, r).
fn line_circle(a: V2, u: V2, c: V2, r: f64) -> Vec<V2> {
    let f = a - c;
    let b = f.dot(u);
    let disc = b * b - (f.dot(f) - r * r);
    if disc < 0.0 {
        // A line grazing the circle within rounding still touches it.
        if disc > -1e-12 * r * r {
            return vec![a - u * b];
        }
        return Vec::new();
    }
    let s = disc.sqrt();
    vec![a + u * (-b - s), a + u * (-b + s)]
}

/// Intersections of two circles.
fn circle_circle(c1: V2, r1: f64, c2: V2, r2: f64) -> Vec<V2> {
    let dv = c2 - c1;
    let d = dv.norm();
    if d < 1e-12 {
        return Vec::new();
    }
    let a = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d);
    let h2 = r1 * r1 - a * a;
    let e = dv * (1.0 / d);
    let m = c1 + e * a;
    if h2 < 0.0 {
        if h2 > -1e-12 * r1 * r1 {
            return vec![m];
        }
        return Vec::new();
    }
    let h = h2.sqrt();
    vec![m + e.left() * h, m - e.left() * h]
}

/// Something that happens between two contour elements.
#[derive(Debug, Clone, PartialEq)]
pub enum Trail {
    /// A non-motion op, passed through.
    Pass(Op),
    /// A move without movement in the working plane: made at the current tool position.
    OffPlane {
        /// Target of the axes outside the plane.
        to: Pose,
        /// Feed.
        feed: Feed,
        /// The block.
        loc: SourceLoc,
    },
}

impl Trail {
    /// Appends this item's op to `out` with the tool at `pos`; returns the new tool pose.
    pub fn emit(&self, pos: Pose, plane: Plane, out: &mut Vec<Op>) -> Pose {
        match self {
            Trail::Pass(op) => {
                out.push(op.clone());
                pos
            }
            Trail::OffPlane { to, feed, loc } => {
                let target = with_point(to, plane, project(&pos, plane));
                out.push(line(pos, target, *feed, *loc));
                target
            }
        }
    }
}

/// The transition arc rolled around an outside corner, centred on the programmed corner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CornerArc {
    /// The programmed corner point.
    pub center: V2,
    /// End of the arc: the offset start of the next element.
    pub to: V2,
    /// Signed sweep, radians.
    pub sweep: f64,
}

/// A contour element waiting for its neighbours, with what follows it.
#[derive(Debug, Clone, PartialEq)]
pub struct Pending {
    /// The programmed element.
    pub elem: Element,
    /// Its tool-centre curve.
    pub curve: Curve,
    /// Trim at the start (set by the join with the previous element).
    pub trim0: f64,
    /// Trim at the end (set by the join with the next element).
    pub trim1: f64,
    /// The block before, if joined to one (for diagnostics).
    pub prev: Option<SourceLoc>,
    /// True for the block that switches compensation on: a straight move from the tool
    /// position to the offset start of the next element.
    pub lead_in: bool,
    /// End point of a lead-in move, once the next element is known.
    pub lead_end: Option<V2>,
    /// Transition arc after this element.
    pub corner: Option<CornerArc>,
    /// Ops and off-plane moves after this element.
    pub trail: Vec<Trail>,
    /// The corner rule of this element's block (M97/M98) for the corner at its end.
    pub end_rule: Option<CornerRule>,
    /// M98: a straight move after this element to the untrimmed offset start of the next.
    pub bridge: Option<V2>,
    /// M98 neighbours (the next block after this element, or the block before it) whose
    /// programmed contour this element's path may come closer to than the tool radius:
    /// the corner between them is open.
    pub open_to: Vec<SourceLoc>,
}

impl Pending {
    /// A new pending element with its offset curve.
    pub fn new(elem: Element, d: f64, tool: f64, lead_in: bool) -> Result<Pending, CompError> {
        let curve = elem.offset(d, tool)?;
        Ok(Pending {
            elem,
            curve,
            trim0: 0.0,
            trim1: 0.0,
            prev: None,
            lead_in,
            lead_end: None,
            corner: None,
            trail: Vec::new(),
            end_rule: None,
            bridge: None,
            open_to: Vec::new(),
        })
    }

    /// The tool-centre end point of this element after trimming.
    pub fn end_point(&self) -> V2 {
        if self.lead_in {
            return self
                .lead_end
                .unwrap_or_else(|| self.curve.point_from_end(0.0));
        }
        self.curve.point_from_end(self.trim1)
    }

    /// Appends the ops of this element (the trimmed curve, the trailing ops, the corner
    /// arc) to `out`, starting at the tool pose `pos`; returns the tool pose at the end.
    pub fn emit(&self, mut pos: Pose, plane: Plane, out: &mut Vec<Op>) -> Pose {
        let loc = self.elem.loc;
        let feed = self.elem.feed;
        let mut end = with_point(&self.elem.to, plane, self.end_point());
        match self.curve {
            Curve::Arc { c, phi0, sweep, .. } if !self.lead_in => {
                let dir = sweep.signum();
                let remaining = (sweep.abs() - self.trim0 - self.trim1).max(0.0);
                if remaining * self.curve.scale() > PLANE_EPS {
                    let start_angle = phi0 + dir * self.trim0;
                    let p = c + V2::polar(start_angle + dir * remaining) * self.curve.scale();
                    end = with_point(&self.elem.to, plane, p);
                    out.push(Op {
                        kind: OpKind::Arc {
                            from: pos,
                            to: end,
                            center: [c.x, c.y],
                            plane,
                            sweep: (dir * remaining).to_degrees(),
                            feed,
                        },
                        loc,
                    });
                    pos = end;
                } else if pos != end {
                    out.push(line(pos, end, feed, loc));
                    pos = end;
                }
            }
            _ => {
                if pos != end {
                    out.push(line(pos, end, feed, loc));
                    pos = end;
                }
            }
        }
        for t in &self.trail {
            pos = t.emit(pos, plane, out);
        }
        if let Some(b) = self.bridge {
            let target = with_point(&pos, plane, b);
            out.push(line(pos, target, feed, loc));
            pos = target;
        }
        if let Some(corner) = self.corner {
            let target = with_point(&pos, plane, corner.to);
            out.push(Op {
                kind: OpKind::Arc {
                    from: pos,
                    to: target,
                    center: [corner.center.x, corner.center.y],
                    plane,
                    sweep: corner.sweep.to_degrees(),
                    feed,
                },
                loc,
            });
            pos = target;
        }
        pos
    }
}

/// A line op.
pub fn line(from: Pose, to: Pose, feed: Feed, loc: SourceLoc) -> Op {
    Op {
        kind: OpKind::Line { from, to, feed },
        loc,
    }
}
