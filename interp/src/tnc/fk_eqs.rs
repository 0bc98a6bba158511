//! FK equations: the points, directions and conditions of free contour elements, and their
//! residuals (zero when a condition holds) for given values of the unknowns.

use super::fk_solve::{Done, FkState};
use super::geom::{self, P2};

/// A point of the contour as the equations see it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Pt {
    /// A known point.
    Const(P2),
    /// End point of the element with this serial number.
    End(u64),
    /// Start point of the element.
    Start(u64),
    /// Centre of the arc element.
    Centre(u64),
}

/// A direction of travel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Dir {
    /// Absolute angle, degrees.
    Angle(f64),
    /// The direction at the end of an element, turned by degrees.
    EndOf(u64, f64),
    /// The direction at the start of an element (the end of the one before it).
    Incoming(u64),
}

/// One equation (or two for `Close`) on the unknowns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Con {
    /// `pt[axis] = base[axis] + v` (base 0 when absolute).
    Coord {
        pt: Pt,
        axis: usize,
        base: Option<Pt>,
        v: f64,
    },
    /// Distance from the pole = that of `base` + v.
    PolarR {
        pt: Pt,
        pole: P2,
        base: Option<Pt>,
        v: f64,
    },
    /// Angle about the pole = that of `base` + v (degrees).
    PolarA {
        pt: Pt,
        pole: P2,
        base: Option<Pt>,
        v: f64,
    },
    /// Both polar coordinates of a point (two equations, smooth also at the pole).
    Polar {
        pt: Pt,
        pole: P2,
        rbase: Option<Pt>,
        r: f64,
        abase: Option<Pt>,
        a: f64,
    },
    /// Line element `sid` runs in direction `dir`.
    LineDir { sid: u64, dir: Dir },
    /// Line length, or chord of an arc.
    Len { sid: u64, len: f64 },
    /// The arc's end point lies at this angle (degrees) about its centre.
    EndAngle { sid: u64, a: f64 },
    /// Arc start and end equally far from the centre.
    ArcRound { sid: u64 },
    /// Arc radius.
    Radius { sid: u64, r: f64 },
    /// Arc starts in direction `dir`.
    ArcStartDir { sid: u64, dir: Dir },
    /// Point on the element.
    On { sid: u64, q: P2 },
    /// Point at distance `d` from the element.
    Dist { sid: u64, q: P2, d: f64 },
    /// End of `sid` equals `to`.
    Close { sid: u64, to: Pt },
}

/// Values of the unknowns during a solve.
pub(super) struct Ctx<'a> {
    /// The FK state (pending and solved elements).
    pub st: &'a FkState,
    /// Index of each pending element's first unknown.
    pub off: &'a [usize],
    /// The unknowns.
    pub x: &'a [f64],
}

/// `v` scaled to length 1 (zero stays zero).
pub(super) fn unit(v: P2) -> P2 {
    let n = geom::norm(v);
    if n > 0.0 {
        [v[0] / n, v[1] / n]
    } else {
        [0.0, 0.0]
    }
}

fn cross(a: P2, b: P2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn dot(a: P2, b: P2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// Direction of travel at a point of a circle about `c` turning ccw or cw.
fn arc_dir(c: P2, p: P2, ccw: bool) -> P2 {
    let r = geom::sub(p, c);
    unit(if ccw { [-r[1], r[0]] } else { [r[1], -r[0]] })
}

impl Ctx<'_> {
    fn idx(&self, sid: u64) -> Option<usize> {
        let i = sid.checked_sub(self.st.first())? as usize;
        (i < self.st.pending.len()).then_some(i)
    }

    fn var(&self, i: usize, k: usize) -> P2 {
        let o = self.off.get(i).copied().unwrap_or(0) + k;
        [
            self.x.get(o).copied().unwrap_or(0.0),
            self.x.get(o + 1).copied().unwrap_or(0.0),
        ]
    }

    fn done(&self, sid: u64) -> Option<&Done> {
        self.st.done.iter().find(|d| d.sid == sid)
    }

    /// The coordinates of a point: known, or from the unknowns.
    pub(super) fn pt(&self, p: Pt) -> P2 {
        match p {
            Pt::Const(c) => c,
            Pt::End(s) => match self.idx(s) {
                Some(i) => self.var(i, 0),
                None => self.done(s).map_or([0.0; 2], |d| d.end),
            },
            Pt::Start(s) => {
                if s == self.st.first() {
                    self.st.origin
                } else if self.idx(s).is_some() {
                    self.pt(Pt::End(s - 1))
                } else {
                    self.done(s).map_or([0.0; 2], |d| d.start)
                }
            }
            Pt::Centre(s) => match self.idx(s) {
                Some(i) => self.var(i, 2),
                None => self.done(s).map_or([0.0; 2], |d| d.centre),
            },
        }
    }

    /// Unit direction of travel at the end of element `sid`.
    pub(super) fn end_dir(&self, sid: u64) -> P2 {
        match self.idx(sid).and_then(|i| self.st.pending.get(i)) {
            Some(p) => {
                let e = self.pt(Pt::End(sid));
                if p.line {
                    unit(geom::sub(e, self.pt(Pt::Start(sid))))
                } else {
                    arc_dir(self.pt(Pt::Centre(sid)), e, p.ccw)
                }
            }
            None => self.done(sid).map_or([0.0; 2], |d| d.end_dir),
        }
    }

    /// Unit vector of a direction.
    pub(super) fn dir(&self, d: Dir) -> P2 {
        let turn = |v: P2, deg: f64| {
            let (s, c) = deg.to_radians().sin_cos();
            [v[0] * c - v[1] * s, v[0] * s + v[1] * c]
        };
        match d {
            Dir::Angle(a) => turn([1.0, 0.0], a),
            Dir::EndOf(s, a) => turn(self.end_dir(s), a),
            Dir::Incoming(s) => {
                if s == self.st.first() {
                    self.st.origin_dir.unwrap_or([0.0; 2])
                } else {
                    self.end_dir(s - 1)
                }
            }
        }
    }

    /// Radius of arc `sid`: distance of its start from its centre.
    pub(super) fn radius(&self, sid: u64) -> f64 {
        geom::norm(geom::sub(self.pt(Pt::Start(sid)), self.pt(Pt::Centre(sid))))
    }

    fn is_line(&self, sid: u64) -> bool {
        self.idx(sid)
            .and_then(|i| self.st.pending.get(i))
            .is_some_and(|p| p.line)
    }

    /// Appends the residuals of `c`.
    pub(super) fn residual(&self, c: &Con, out: &mut Vec<f64>) {
        match *c {
            Con::Coord { pt, axis, base, v } => {
                let b = base.map_or(0.0, |b| self.pt(b)[axis]);
                out.push(self.pt(pt)[axis] - b - v);
            }
            Con::PolarR { pt, pole, base, v } => {
                let b = base.map_or(0.0, |b| geom::norm(geom::sub(self.pt(b), pole)));
                out.push(geom::norm(geom::sub(self.pt(pt), pole)) - b - v);
            }
            Con::PolarA { pt, pole, base, v } => {
                let b = base.map_or(0.0, |b| geom::angle(geom::sub(self.pt(b), pole)));
                let u = self.dir(Dir::Angle(b + v));
                out.push(cross(u, geom::sub(self.pt(pt), pole)));
            }
            Con::Polar {
                pt,
                pole,
                rbase,
                r,
                abase,
                a,
            } => {
                let rb = rbase.map_or(0.0, |b| geom::norm(geom::sub(self.pt(b), pole)));
                let ab = abase.map_or(0.0, |b| geom::angle(geom::sub(self.pt(b), pole)));
                let want = geom::polar(pole, rb + r, ab + a);
                let p = self.pt(pt);
                out.push(p[0] - want[0]);
                out.push(p[1] - want[1]);
            }
            Con::LineDir { sid, dir } => {
                let d = self.dir(dir);
                let v = geom::sub(self.pt(Pt::End(sid)), self.pt(Pt::Start(sid)));
                out.push(cross(d, v));
            }
            Con::Len { sid, len } => {
                let v = geom::sub(self.pt(Pt::End(sid)), self.pt(Pt::Start(sid)));
                out.push(geom::norm(v) - len);
            }
            Con::ArcRound { sid } => {
                let c = self.pt(Pt::Centre(sid));
                out.push(geom::norm(geom::sub(self.pt(Pt::End(sid)), c)) - self.radius(sid));
            }
            Con::Radius { sid, r } => out.push(self.radius(sid) - r),
            Con::EndAngle { sid, a } => {
                let rel = geom::sub(self.pt(Pt::End(sid)), self.pt(Pt::Centre(sid)));
                out.push(cross(self.dir(Dir::Angle(a)), rel));
            }
            Con::ArcStartDir { sid, dir } => {
                let d = self.dir(dir);
                let r = geom::sub(self.pt(Pt::Start(sid)), self.pt(Pt::Centre(sid)));
                out.push(dot(d, r));
            }
            Con::On { sid, q } => out.push(self.off_by(sid, q)),
            Con::Dist { sid, q, d } => out.push(self.off_by(sid, q).abs() - d),
            Con::Close { sid, to } => {
                let e = self.pt(Pt::End(sid));
                let t = self.pt(to);
                out.push(e[0] - t[0]);
                out.push(e[1] - t[1]);
            }
        }
    }

    /// Signed distance of `q` from element `sid` (from its line, or its circle).
    fn off_by(&self, sid: u64, q: P2) -> f64 {
        let s = self.pt(Pt::Start(sid));
        if self.is_line(sid) {
            let v = geom::sub(self.pt(Pt::End(sid)), s);
            let n = geom::norm(v).max(1e-12);
            cross(v, geom::sub(q, s)) / n
        } else {
            let c = self.pt(Pt::Centre(sid));
            geom::norm(geom::sub(q, c)) - self.radius(sid)
        }
    }

    /// The inequalities: directions point the right way, no element has length zero.
    pub(super) fn admissible(&self, c: &Con) -> bool {
        match *c {
            Con::PolarA { pt, pole, base, v } => {
                let b = base.map_or(0.0, |b| geom::angle(geom::sub(self.pt(b), pole)));
                let rel = geom::sub(self.pt(pt), pole);
                geom::norm(rel) < 1e-9 || dot(self.dir(Dir::Angle(b + v)), rel) > 0.0
            }
            Con::LineDir { sid, dir } => {
                let v = geom::sub(self.pt(Pt::End(sid)), self.pt(Pt::Start(sid)));
                dot(self.dir(dir), v) > 0.0
            }
            Con::EndAngle { sid, a } => {
                let rel = geom::sub(self.pt(Pt::End(sid)), self.pt(Pt::Centre(sid)));
                dot(self.dir(Dir::Angle(a)), rel) > 0.0
            }
            Con::ArcStartDir { sid, dir } => {
                let ccw = self
                    .idx(sid)
                    .and_then(|i| self.st.pending.get(i))
                    .is_some_and(|p| p.ccw);
                let t = arc_dir(self.pt(Pt::Centre(sid)), self.pt(Pt::Start(sid)), ccw);
                dot(self.dir(dir), t) > 0.0
            }
            _ => true,
        }
    }
}
