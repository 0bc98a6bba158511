//! The simulated workpiece a simulated touch probe finds: the program's BLK FORM box (or a
//! box the machine file gives) with bores, rectangular pockets and straight slots cut from its
//! top and round bosses (studs) and straight ridges standing on it (slots, ridges and
//! bolt-hole circles in [`features`]), placed on
//! the machine with an offset and a turn about Z that the program does not know — the
//! set-up error that probing cycles measure.
//!
//! Geometry: in the part's own coordinates `q` (the program coordinates of the preset active
//! when the machine starts) the part is the box minus its bores and pockets; a machine point
//! `m` has `q = Rz(−rotation) · (m − origin − offset)`, where `origin` is that start preset.
//! The stylus ball (radius `r`) touches the part where its centre first comes within `r` of
//! it. The probing move is followed with a distance bound of the part (exact for the box,
//! bores and pockets alone; a lower bound where they meet, which never steps over a surface):
//! the ball advances by the bound until it closes on the surface, and the crossing is then
//! bisected to far below a nanometre.
//!
//! On a machine with a rotary table C the part sits on the table and turns with it about the
//! table axis (machine X, Y `table_centre`): the table turns in the primed sense, so at C = c
//! a machine point `m` lies where `table_centre + Rz(c) · (m − table_centre)` lay at C = 0.

use klar_interp::{Blank, Probe};

mod features;
pub use features::{HoleCircle, Ridge, Slot};

/// A bore cut into the top of the part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bore {
    /// Centre X, Y in part coordinates, mm.
    pub centre: [f64; 2],
    /// Diameter, mm.
    pub diameter: f64,
    /// Depth below the top of the box, mm.
    pub depth: f64,
}

/// A rectangular pocket cut into the top of the part, sides parallel to the part's axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pocket {
    /// Centre X, Y in part coordinates, mm.
    pub centre: [f64; 2],
    /// Side lengths in X and Y, mm.
    pub size: [f64; 2],
    /// Depth below the top of the box, mm.
    pub depth: f64,
}

/// A round boss standing on the top of the part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Boss {
    /// Centre X, Y in part coordinates, mm.
    pub centre: [f64; 2],
    /// Diameter, mm.
    pub diameter: f64,
    /// Height above the top of the box, mm.
    pub height: f64,
}

/// A part on the machine table, answering probing moves.
#[derive(Debug, Clone, PartialEq)]
pub struct SimWorkpiece {
    /// Machine coordinates of the part's origin (the start preset), mm.
    pub origin: [f64; 3],
    /// Where the part really lies off its nominal place, machine X, Y, Z, mm.
    pub offset: [f64; 3],
    /// Its turn about Z (about the part's origin), degrees.
    pub rotation: f64,
    /// The box `[min, max]` in part coordinates; `None`: the program's BLK FORM.
    pub body: Option<[[f64; 3]; 2]>,
    /// Bores.
    pub bores: Vec<Bore>,
    /// Pockets.
    pub pockets: Vec<Pocket>,
    /// Bosses.
    pub bosses: Vec<Boss>,
    /// Straight slots cut from the top.
    pub slots: Vec<Slot>,
    /// Straight ridges standing on the top.
    pub ridges: Vec<Ridge>,
    /// Machine X, Y of the rotary table axis C the part turns with, mm.
    pub table_centre: [f64; 2],
    /// Where the table axis C stands, degrees (0 on a machine without one).
    pub table_angle: f64,
}

/// Signed distance from `p` to the box `[lo, hi]` (negative inside).
fn box_distance(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> f64 {
    let mut outside = 0.0;
    let mut inside = f64::NEG_INFINITY;
    for i in 0..3 {
        let c = (lo[i] + hi[i]) / 2.0;
        let h = (hi[i] - lo[i]) / 2.0;
        let d = (p[i] - c).abs() - h;
        outside += d.max(0.0).powi(2);
        inside = inside.max(d);
    }
    outside.sqrt() + inside.min(0.0)
}

/// Signed distance from `p` to the upright cylinder about `c` of radius `r` between heights
/// `z0` and `z1`.
fn cylinder_distance(p: [f64; 3], c: [f64; 2], r: f64, z0: f64, z1: f64) -> f64 {
    let radial = (p[0] - c[0]).hypot(p[1] - c[1]) - r;
    let axial = (p[2] - (z0 + z1) / 2.0).abs() - (z1 - z0) / 2.0;
    radial.max(axial).min(0.0) + radial.max(0.0).hypot(axial.max(0.0))
}

/// How far above the top the cut-outs reach, so their mouths stay open, mm.
const ABOVE: f64 = 1.0e4;

impl SimWorkpiece {
    /// Part coordinates of machine point `m`.
    pub fn to_part(&self, m: [f64; 3]) -> [f64; 3] {
        // where the point lay before the table turned
        let m = self.untable(m, self.table_angle);
        let d = [
            m[0] - self.origin[0] - self.offset[0],
            m[1] - self.origin[1] - self.offset[1],
            m[2] - self.origin[2] - self.offset[2],
        ];
        let (s, c) = (-self.rotation).to_radians().sin_cos();
        [d[0] * c - d[1] * s, d[0] * s + d[1] * c, d[2]]
    }

    /// Machine coordinates of part point `q`.
    pub fn to_machine(&self, q: [f64; 3]) -> [f64; 3] {
        let (s, c) = self.rotation.to_radians().sin_cos();
        let m = [
            self.origin[0] + self.offset[0] + q[0] * c - q[1] * s,
            self.origin[1] + self.offset[1] + q[0] * s + q[1] * c,
            self.origin[2] + self.offset[2] + q[2],
        ];
        self.untable(m, -self.table_angle)
    }

    /// `m` turned about the table axis by `deg`.
    fn untable(&self, m: [f64; 3], deg: f64) -> [f64; 3] {
        if deg == 0.0 {
            return m;
        }
        let (s, c) = deg.to_radians().sin_cos();
        let d = [m[0] - self.table_centre[0], m[1] - self.table_centre[1]];
        [
            self.table_centre[0] + d[0] * c - d[1] * s,
            self.table_centre[1] + d[0] * s + d[1] * c,
            m[2],
        ]
    }

    /// The box of the part: the machine file's, else the program's BLK FORM.
    fn body(&self, blank: Option<&Blank>) -> Option<[[f64; 3]; 2]> {
        self.body.or_else(|| {
            blank.map(|b| {
                let (lo, hi) = (b.min.0, b.max.0);
                let mut out = [[0.0; 3]; 2];
                for i in 0..3 {
                    out[0][i] = lo[i].min(hi[i]);
                    out[1][i] = lo[i].max(hi[i]);
                }
                out
            })
        })
    }

    /// Distance bound from machine point `m` to the part (negative inside).
    pub fn distance(&self, m: [f64; 3], body: [[f64; 3]; 2]) -> f64 {
        let q = self.to_part(m);
        let top = body[1][2];
        let mut d = box_distance(q, body[0], body[1]);
        for b in &self.bores {
            d = d.max(-cylinder_distance(
                q,
                b.centre,
                b.diameter / 2.0,
                top - b.depth,
                top + ABOVE,
            ));
        }
        for p in &self.pockets {
            let lo = [
                p.centre[0] - p.size[0] / 2.0,
                p.centre[1] - p.size[1] / 2.0,
                top - p.depth,
            ];
            let hi = [
                p.centre[0] + p.size[0] / 2.0,
                p.centre[1] + p.size[1] / 2.0,
                top + ABOVE,
            ];
            d = d.max(-box_distance(q, lo, hi));
        }
        for s in &self.slots {
            let cut =
                features::bar_distance(q, s.from, s.to, s.width / 2.0, top - s.depth, top + ABOVE);
            d = d.max(-cut);
        }
        for b in &self.bosses {
            d = d.min(cylinder_distance(
                q,
                b.centre,
                b.diameter / 2.0,
                top,
                top + b.height,
            ));
        }
        for r in &self.ridges {
            let bar = features::bar_distance(q, r.from, r.to, r.width / 2.0, top, top + r.height);
            d = d.min(bar);
        }
        d
    }
}

/// Smallest step of the probing search, mm (a crossing inside it is bisected).
const MIN_STEP: f64 = 1e-4;

impl Probe for SimWorkpiece {
    fn table_at(&mut self, deg: f64) {
        self.table_angle = deg;
    }

    fn touch(
        &mut self,
        from: [f64; 3],
        to: [f64; 3],
        radius: f64,
        blank: Option<&Blank>,
    ) -> Option<[f64; 3]> {
        let body = self.body(blank)?;
        let len = (0..3)
            .map(|i| (to[i] - from[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        let at = |t: f64| {
            let k = if len > 0.0 { t / len } else { 0.0 };
            [
                from[0] + (to[0] - from[0]) * k,
                from[1] + (to[1] - from[1]) * k,
                from[2] + (to[2] - from[2]) * k,
            ]
        };
        let gap = |t: f64| self.distance(at(t), body) - radius;
        if gap(0.0) <= 0.0 {
            return Some(from);
        }
        let mut t = 0.0;
        while t < len {
            let g = gap(t);
            let next = (t + g.max(MIN_STEP)).min(len);
            if gap(next) <= 0.0 {
                // the surface lies between t (clear) and next (touching): bisect
                let (mut lo, mut hi) = (t, next);
                for _ in 0..80 {
                    let mid = (lo + hi) / 2.0;
                    if gap(mid) > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return Some(at(hi));
            }
            if next >= len {
                break;
            }
            t = next;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn part() -> SimWorkpiece {
        SimWorkpiece {
            origin: [10.0, 20.0, 0.0],
            offset: [3.2, -1.7, 0.0],
            rotation: 1.5,
            body: Some([[-50.0, -40.0, -30.0], [50.0, 40.0, 0.0]]),
            bores: vec![Bore {
                centre: [0.0, 0.0],
                diameter: 30.0,
                depth: 20.0,
            }],
            pockets: Vec::new(),
            bosses: Vec::new(),
            slots: Vec::new(),
            ridges: Vec::new(),
            table_centre: [0.0, 0.0],
            table_angle: 0.0,
        }
    }

    #[test]
    fn a_turned_table_carries_the_part_the_other_way_round() {
        let mut p = part();
        p.table_centre = [10.0, 20.0];
        let before = p.to_machine([30.0, 0.0, -10.0]);
        p.table_at(90.0);
        let after = p.to_machine([30.0, 0.0, -10.0]);
        // C+90 turns the part by −90° about (10, 20): (dx, dy) → (dy, −dx)
        let d = [before[0] - 10.0, before[1] - 20.0];
        assert!((after[0] - (10.0 + d[1])).abs() < 1e-12, "{after:?}");
        assert!((after[1] - (20.0 - d[0])).abs() < 1e-12, "{after:?}");
        assert_eq!(after[2], before[2]);
        let back = p.to_part(after);
        assert!(
            (back[0] - 30.0).abs() < 1e-12 && back[1].abs() < 1e-12,
            "{back:?}"
        );
    }

    #[test]
    fn a_ball_stops_its_radius_before_a_turned_face() {
        let mut p = part();
        // along machine X at the part's centre height, toward the +X face from outside
        let hit = p
            .touch([100.0, 20.0, -10.0], [0.0, 20.0, -10.0], 2.0, None)
            .expect("touches");
        let q = p.to_part(hit);
        assert!((q[0] - 52.0).abs() < 1e-9, "{q:?}");
    }

    #[test]
    fn a_ball_inside_the_bore_touches_its_wall_and_misses_empty_space() {
        let mut p = part();
        let c = p.to_machine([0.0, 0.0, -10.0]);
        let hit = p
            .touch(c, [c[0], c[1] + 30.0, c[2]], 1.5, None)
            .expect("touches the wall");
        let q = p.to_part(hit);
        assert!((q[0].hypot(q[1]) - 13.5).abs() < 1e-9, "{q:?}");
        // far above the part nothing is touched
        assert!(
            p.touch([0.0, 0.0, 50.0], [100.0, 0.0, 50.0], 2.0, None)
                .is_none()
        );
        // starting inside the material answers the start
        let inside = p.to_machine([40.0, 0.0, -10.0]);
        assert_eq!(p.touch(inside, [0.0; 3], 1.0, None), Some(inside));
    }
}
