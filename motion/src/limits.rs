//! Path limits from per-axis limits: how fast, how hard and how jerky the tool may move
//! along one segment so that every axis stays within its own speed, acceleration and jerk.
//!
//! For an axis position q(s) along the path and path speed v, acceleration a, jerk j:
//!
//! ```text
//! q̇ = q′·v        q̈ = q′·a + q″·v²        q⃛ = q′·j + 3·q″·v·a + q‴·v³
//! ```
//!
//! With c₁, c₂, c₃ the segment's bounds of |q′|, |q″|, |q‴| ([`AxisBounds`]) and path
//! limits V, A, J over the segment, each axis stays within (v, a, j) limits when
//!
//! ```text
//! c₁·V ≤ v_max      c₁·A + c₂·V² ≤ a_max      c₁·J + 3·c₂·V·A + c₃·V³ ≤ j_max
//! ```
//!
//! The peak magnitudes are added, which is conservative where they occur at different
//! places. On the in-plane axes of an arc or helix they do: there `q′ = −W·sin θ + o`,
//! `q″ = −c₂·cos θ`, `q‴ = c₃·sin θ` (W the turning part of c₁, o = c₁ − W a constant end
//! correction), so the terms add in quadrature instead:
//!
//! ```text
//! √((W·A)² + (c₂·v²)²) + o·A ≤ a_max      √((W·J + c₃·V³)² + (3·c₂·V·A)²) + o·J ≤ j_max
//! ```
//!
//! More generally, on any move whose path distance is its length over the linear axes, the
//! unit tangent q′ and the curvature vector q″ (length κ) are orthogonal, so each linear
//! axis's acceleration `q′·A + q″·v²` is at most `√(A² + (κ·v²)²)` (Cauchy–Schwarz with
//! `q′ᵢ² + (q″ᵢ/κ)² ≤ 1`). Blends and splines use whichever of the two forms allows more.
//!
//! The quadrature forms hold at every instant with the speed v of that instant, so the
//! acceleration the path may use depends on its speed: [`Grip`], `√(P² − (K·v²)²)`, all of
//! the limit at rest and less the faster the path goes round the curve. The top speed of a
//! curved piece leaves √(1 − 0.99²) ≈ 14 % of it ([`CURVE_SHARE`]); the speed generator
//! uses the grip of the speed it is at. Where only the sum form applies, the curvature term
//! gets at most half of the acceleration limit at the top speed and the rest is a constant
//! limit. For the jerk, c₃·V³ gets at most half of the jerk limit and 3·c₂·v·A at most a
//! quarter (0.6 in quadrature on arcs); J then takes what is left. The parts of a corner
//! blend keep less free at their top speed ([`Headroom`]). The cross term holds at
//! every instant with that instant's speed too, so it caps the product v·A rather than A at
//! the top speed: the grip allows `A(v) ≤ cross / v`, more acceleration at lower speeds
//! (speeding up out of a curve, braking into one). On a line (c₂ = c₃ = 0) this is exactly
//! the axis limits projected on the direction.

use crate::config::AxisLimits;
use crate::geom::{AxisBounds, ZERO_LENGTH};
use klar_interp::AxisLetter;

/// Share of the acceleration (in quadrature) the curvature term κ·V² may take at the top
/// speed of a curved piece.
pub const CURVE_SHARE: f64 = 0.99;

/// The same for the curvature form (blends, splines: short pieces with a curvature bound
/// rather than an exact curvature, where some acceleration must be left at the top speed
/// for the speed changes between them).
const BLEND_CURVE_SHARE: f64 = 0.8;

/// The curvature form's share on a part of a corner blend ([`Headroom::Lean`]).
const LEAN_CURVE_SHARE: f64 = 0.99;

/// Share of an axis's acceleration limit the curvature term may take where the terms add
/// (no quadrature form applies).
const SUM_CURVE_SHARE: f64 = 0.5;

/// Share of an axis's jerk limit the term c₃·V³ may take at the top speed of a piece (the
/// jerk a curve causes at constant speed as its curvature turns or changes).
const CURVE_JERK_SHARE: f64 = 0.5;

/// The same on a part of a corner blend ([`Headroom::Lean`]): with a quarter of the limit
/// for the cross term 3·c₂·v·A, a tenth is left for the path jerk at the top speed.
const LEAN_CURVE_JERK_SHARE: f64 = 0.65;

/// How much of each axis's acceleration and jerk a curved piece keeps free at its top
/// speed for changing speed there. Any split keeps every axis within its limits (the
/// acceleration and jerk the piece allows are what the curvature terms leave); it decides
/// only how fast the piece may go against how quickly its speed may change at that speed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Headroom {
    /// A piece the path may run along at its top speed and change speed on: elements,
    /// splines and blends made of one piece (the curves through dense code). The
    /// curvature form takes at most 0.8 of the acceleration at the top speed (0.6 left in
    /// quadrature) and the curve's own jerk c₃·V³ at most half of the jerk.
    Ample,
    /// One of the parts of a corner blend whose curvature varies along it
    /// (`planner::path`): the path slows down towards the corner's tightest part and
    /// speeds up after it, so a part's top speed is a speed the path passes rather than
    /// one it runs at, and the parts before and after it take the speed changes with
    /// their own limits. The curvature form takes 0.99 of the acceleration at the top
    /// speed (as on arcs) and c₃·V³ 0.65 of the jerk.
    Lean,
}

impl Headroom {
    /// Shares of the curvature form and of c₃·V³ at the top speed.
    fn shares(self) -> (f64, f64) {
        match self {
            Headroom::Ample => (BLEND_CURVE_SHARE, CURVE_JERK_SHARE),
            Headroom::Lean => (LEAN_CURVE_SHARE, LEAN_CURVE_JERK_SHARE),
        }
    }
}

/// Share of an axis's jerk limit the term 3·c₂·V·A may take on an arc (0.8 of the limit is
/// left in quadrature for the path jerk and c₃·V³).
const ARC_JERK_SHARE: f64 = 0.6;

/// The path acceleration a piece allows at each path speed:
/// `A(v) = min(flat, cross / v, √(peak² − (bend·v²)²))`. `bend` is 0 and `cross` infinite
/// where the acceleration does not depend on the speed (lines).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grip {
    /// Limit at every speed.
    pub flat: f64,
    /// Limit at rest of the speed-dependent part.
    pub peak: f64,
    /// Curvature factor of the speed-dependent part (1/mm).
    pub bend: f64,
    /// Largest product of speed and acceleration (mm²/s³): on a curve, changing speed at
    /// speed v with acceleration A costs each axis a jerk 3·|q″|·v·A, which may take only its
    /// share of the axis's jerk limit.
    pub cross: f64,
}

impl Grip {
    /// The same acceleration at every speed (no speed-dependent part: its peak is
    /// unbounded, so that [`Grip::min`] with a curved grip keeps that grip's peak).
    pub fn constant(a: f64) -> Grip {
        Grip {
            flat: a,
            peak: f64::INFINITY,
            bend: 0.0,
            cross: f64::INFINITY,
        }
    }

    /// The acceleration at speed `v` (never negative).
    pub fn at(&self, v: f64) -> f64 {
        let flat = if v > 0.0 {
            self.flat.min(self.cross / v)
        } else {
            self.flat
        };
        if self.bend <= 0.0 {
            return flat.min(self.peak);
        }
        let k = self.bend * v * v;
        flat.min((self.peak * self.peak - k * k).max(0.0).sqrt())
    }

    /// The largest acceleration at any speed.
    pub fn most(&self) -> f64 {
        self.flat.min(self.peak)
    }

    /// A grip no larger than either at any speed.
    pub fn min(self, other: Grip) -> Grip {
        Grip {
            flat: self.flat.min(other.flat),
            peak: self.peak.min(other.peak),
            bend: self.bend.max(other.bend),
            cross: self.cross.min(other.cross),
        }
    }

    /// True when `other` allows less than `self` at some speed.
    pub fn undercut_by(&self, other: &Grip) -> bool {
        other.flat < self.flat
            || other.peak < self.peak
            || other.bend > self.bend
            || other.cross < self.cross
    }

    /// The grip scaled by `share` at every speed.
    pub fn scaled(self, share: f64) -> Grip {
        Grip {
            flat: self.flat * share,
            peak: self.peak * share,
            bend: self.bend * share,
            cross: self.cross * share,
        }
    }

    /// The speed at which the speed-dependent part has `share` of its peak left (in
    /// quadrature: `bend·v² = √(1 − share²)·peak`); `None` where it never binds below the
    /// flat limit or does not depend on the speed.
    pub fn knee(&self, share: f64) -> Option<f64> {
        if self.bend <= 0.0 || share * self.peak >= self.flat {
            return None;
        }
        Some(((1.0 - share * share).max(0.0).sqrt() * self.peak / self.bend).sqrt())
    }
}

/// Path limits of one piece.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PieceLimits {
    /// Largest path speed.
    pub velocity: f64,
    /// Largest path acceleration at low speed, with the speed–acceleration product of the
    /// grip taken at the top speed (a measure to compare pieces by; the speed generator uses
    /// `grip`).
    pub acceleration: f64,
    /// Largest path jerk.
    pub jerk: f64,
    /// Path acceleration by speed.
    pub grip: Grip,
}

/// A moving axis: its limits, the bounds c₁, c₂, c₃, the turning part W of c₁ (arcs) and
/// the curvature bound κ that applies to it (linear axes of a linear move, else 0).
#[derive(Debug, Clone, Copy)]
struct Moving {
    l: AxisLimits,
    c1: f64,
    c2: f64,
    c3: f64,
    wave: f64,
    kappa: f64,
}

impl Moving {
    /// The quadrature forms of this axis as grips (peak, bend): the arc form with the end
    /// correction folded in (`√((W·A)² + X²) + o·A ≤ a_max` holds for `A = √(ã² − X²)/c₁`
    /// with `ã = a_max·W/c₁`: o·A ≤ o·a_max/c₁ and W ≤ c₁), and the curvature form.
    fn curves(&self, blend_share: f64) -> [Option<(f64, f64, f64)>; 2] {
        let a = self.l.max_acceleration;
        let wave = (self.wave > 0.0 && self.c1 > 0.0).then(|| {
            (
                a * self.wave / self.c1 / self.c1,
                self.c2 / self.c1,
                CURVE_SHARE,
            )
        });
        let kappa = (self.kappa > 0.0).then_some((a, self.kappa, blend_share));
        [wave, kappa]
    }
}

/// Why no path limits exist for a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LimitError {
    /// The segment moves an axis the machine does not have.
    AbsentAxis(AxisLetter),
}

/// Path limits of a segment of `length` with derivative `bounds`, at the programmed path
/// speed `feed` (`None` for rapid traverse: as fast as the axes allow), keeping `headroom`
/// at the top speed.
pub fn path_limits(
    bounds: &AxisBounds,
    length: f64,
    limits: &[Option<AxisLimits>; 9],
    feed: Option<f64>,
    headroom: Headroom,
) -> Result<PieceLimits, LimitError> {
    let (blend_share, curve_jerk_share) = headroom.shares();
    let mut moving: [Option<Moving>; 9] = [None; 9];
    for (i, axis) in AxisLetter::ALL.into_iter().enumerate() {
        let (c1, c2, c3) = (bounds.d1[i], bounds.d2[i], bounds.d3[i]);
        // An axis moves when its excursion along the segment is measurable.
        if c1 * length <= ZERO_LENGTH && c2 * length * length <= ZERO_LENGTH {
            continue;
        }
        match limits[i] {
            Some(l) => {
                moving[i] = Some(Moving {
                    l,
                    c1,
                    c2,
                    c3,
                    wave: bounds.wave[i].min(c1),
                    kappa: if axis.is_rotary() {
                        0.0
                    } else {
                        bounds.curvature
                    },
                })
            }
            None => return Err(LimitError::AbsentAxis(axis)),
        }
    }
    let axes = || moving.iter().flatten();

    let mut v = feed.unwrap_or(f64::INFINITY);
    for m in axes() {
        let l = m.l;
        if m.c1 > 0.0 {
            v = v.min(l.max_velocity / m.c1);
        }
        if m.c2 > 0.0 {
            let mut top = (SUM_CURVE_SHARE * l.max_acceleration / m.c2).sqrt();
            for (peak, bend, share) in m.curves(blend_share).into_iter().flatten() {
                top = top.max((share * peak / bend).sqrt());
            }
            v = v.min(top);
        }
        if m.c3 > 0.0 {
            v = v.min((curve_jerk_share * l.max_jerk / m.c3).cbrt());
        }
    }
    let mut grip = Grip::constant(f64::INFINITY);
    for m in axes() {
        let (l, c1, c2, w) = (m.l, m.c1, m.c2, m.wave);
        // The sum form at the top speed, a constant limit.
        let curve = c2 * v * v;
        let sum = if c1 > 0.0 {
            (l.max_acceleration - curve) / c1
        } else if curve <= l.max_acceleration {
            f64::INFINITY
        } else {
            0.0
        };
        // The quadrature form that allows most at the top speed, if it beats the sum.
        let best = m
            .curves(blend_share)
            .into_iter()
            .flatten()
            .map(|(peak, bend, _)| {
                let k = bend * v * v;
                ((peak * peak - k * k).max(0.0).sqrt(), peak, bend)
            })
            .max_by(|x, y| x.0.total_cmp(&y.0))
            .filter(|q| q.0 >= sum);
        let mut axis = match best {
            Some((_, peak, bend)) => Grip {
                flat: f64::INFINITY,
                peak,
                bend,
                cross: f64::INFINITY,
            },
            None => Grip::constant(sum),
        };
        if c2 > 0.0 && v > 0.0 {
            let share = if w > 0.0 {
                ARC_JERK_SHARE / 3.0
            } else {
                1.0 / 12.0
            };
            axis.cross = axis.cross.min(share * l.max_jerk / c2);
        }
        grip = grip.min(axis);
    }
    // The cross term 3·c₂·u·A(u) is at most 3·c₂ times the smaller of the top speed times
    // the largest acceleration and the grip's speed-acceleration product.
    let a = grip.most();
    let va = (v * a).min(grip.cross);
    let mut j = f64::INFINITY;
    for m in axes() {
        let (l, c1, c2, c3, w) = (m.l, m.c1, m.c2, m.c3, m.wave);
        if c1 <= 0.0 {
            continue;
        }
        let cross = 3.0 * c2 * va;
        if w > 0.0 {
            // The same construction as for the acceleration.
            let jm = l.max_jerk * (1.0 - (c1 - w) / c1);
            j = j.min(((jm * jm - cross * cross).max(0.0).sqrt() - c3 * v.powi(3)) / c1);
        } else {
            j = j.min((l.max_jerk - cross - c3 * v.powi(3)) / c1);
        }
    }
    Ok(PieceLimits {
        velocity: v,
        acceleration: if v > 0.0 { a.min(grip.cross / v) } else { a },
        jerk: j,
        grip,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Arc, Segment};
    use klar_interp::{Plane, Pose};

    fn xyz(v: f64, a: f64, j: f64) -> [Option<AxisLimits>; 9] {
        let l = AxisLimits {
            max_velocity: v,
            max_acceleration: a,
            max_jerk: j,
        };
        [
            Some(l),
            Some(l),
            Some(l),
            None,
            None,
            None,
            None,
            None,
            None,
        ]
    }

    /// Limits of a full circle r = 5 in XY (centre at X+5) on axes of 500 mm/s, 1000 mm/s²
    /// and jerk `jerk`.
    fn circle_r5_limits(jerk: f64) -> PieceLimits {
        let from = Pose::xyz(0.0, 0.0, 0.0);
        let arc = Arc::new(from, from, [5.0, 0.0], Plane::XY, 360.0)
            .ok()
            .flatten()
            .map(Segment::Arc);
        let Some(arc) = arc else {
            panic!("a full circle is an arc")
        };
        let l = path_limits(
            &arc.bounds(),
            arc.length(),
            &xyz(500.0, 1000.0, jerk),
            None,
            Headroom::Ample,
        );
        let Ok(l) = l else { panic!("limits") };
        l
    }

    #[test]
    fn a_full_circle_leaves_the_acceleration_the_curvature_does_not_take() {
        // Circle r = 5 in XY: per axis √(A² + (v²/r)²) ≤ a, so A(v) = √(a² − (v²/r)²).
        let l = circle_r5_limits(1e9);
        for v in [0.0f64, 20.0, 50.0, 65.0] {
            let want = (1000.0f64.powi(2) - (v * v / 5.0).powi(2)).sqrt();
            assert!((l.grip.at(v) - want).abs() <= 1e-6 * want, "{v}");
        }
        // The top speed leaves √(1 − 0.99²) of the limit.
        let top = (CURVE_SHARE * 1000.0 * 5.0f64).sqrt();
        assert!((l.velocity - top).abs() < 1e-9, "{}", l.velocity);
    }

    #[test]
    fn a_circle_allows_more_acceleration_the_slower_the_path_goes_round_it() {
        // Circle r = 5, jerk 2e4: changing speed at v with A costs each axis up to
        // 3·v·A/r of jerk (in quadrature on an arc), held to 0.6 of the limit, so
        // v·A ≤ 0.6·2e4·5/3 at every speed, not only at the top one.
        let l = circle_r5_limits(2e4);
        let product = ARC_JERK_SHARE * 2e4 * 5.0 / 3.0;
        let mut last = f64::INFINITY;
        for v in [5.0f64, 10.0, 20.0, 30.0, l.velocity] {
            let a = l.grip.at(v);
            let quadrature = (1000.0f64.powi(2) - (v * v / 5.0).powi(2)).sqrt();
            assert!(v * a <= product * (1.0 + 1e-12), "{v}: {a}");
            assert!(a <= last && a <= quadrature + 1e-9, "{v}: {a}");
            // Where neither the product nor the curvature binds, all of it.
            assert!(
                (a - (product / v).min(quadrature)).abs() <= 1e-9 * a,
                "{v}: {a}"
            );
            last = a;
        }
        // At the top speed less than half of what a third of it allows.
        assert!(l.grip.at(l.velocity) < 0.5 * l.grip.at(l.velocity / 3.0));
    }

    #[test]
    fn grips_combine_below_both_and_knees_sit_where_the_share_is_left() {
        let g = Grip {
            flat: 900.0,
            peak: 1000.0,
            bend: 0.1,
            cross: f64::INFINITY,
        };
        assert_eq!(g.at(0.0), 900.0);
        assert_eq!(g.at(200.0), 0.0);
        // Half of the peak left where (0.1·v²)² = 1000² · (1 − 0.25).
        let Some(u) = g.knee(0.5) else {
            panic!("the knee lies below the flat limit")
        };
        assert!((g.at(u) - 500.0).abs() < 1e-9);
        assert_eq!(g.knee(0.95), None);
        let h = Grip::constant(700.0);
        let m = g.min(h);
        for v in [0.0, 30.0, 60.0, 90.0, 99.0] {
            assert!(m.at(v) <= g.at(v).min(h.at(v)) + 1e-12);
        }
        assert!(g.undercut_by(&m) && h.undercut_by(&m) && !m.undercut_by(&g));
    }

    #[test]
    fn a_constant_grip_combined_with_a_curved_one_is_the_lower_at_every_speed() {
        // The curved grip keeps its peak and its speed-acceleration product in the
        // combination: the result is exactly the lower of the two at each speed, not a
        // curve below both.
        let curved = Grip {
            flat: f64::INFINITY,
            peak: 1000.0,
            bend: 1.0,
            cross: 20_000.0,
        };
        let flat = Grip::constant(460.0);
        for m in [curved.min(flat), flat.min(curved)] {
            for v in [0.0, 10.0, 20.0, 28.0, 30.0, 31.0] {
                let want = curved.at(v).min(flat.at(v));
                assert!(
                    (m.at(v) - want).abs() < 1e-9,
                    "{v}: {} against {want}",
                    m.at(v)
                );
            }
        }
    }

    #[test]
    fn a_corner_blend_part_goes_faster_and_keeps_every_axis_within_its_limits() {
        // The bounds of the third of four parts of the blend from a line into a 1 mm arc
        // (the bench square's corner, tolerance 0.01 mm): X along the line, Y turning in.
        let mut b = AxisBounds {
            d1: [0.0; 9],
            d2: [0.0; 9],
            d3: [0.0; 9],
            wave: [0.0; 9],
            curvature: 0.996,
        };
        (b.d1[0], b.d1[1]) = (1.0, 0.317);
        (b.d2[0], b.d2[1]) = (0.315, 0.947);
        (b.d3[0], b.d3[1]) = (1.338, 1.652);
        let (a_max, j_max) = (1000.0, 1e5);
        let axes = xyz(100.0, a_max, j_max);
        let limits = |h| match path_limits(&b, 0.35, &axes, None, h) {
            Ok(l) => l,
            Err(e) => panic!("{e:?}"),
        };
        let (ample, lean) = (limits(Headroom::Ample), limits(Headroom::Lean));
        // Ample: the curvature form takes 0.8 of the acceleration at the top speed.
        let top = (0.8 * a_max / 0.996f64).sqrt();
        assert!((ample.velocity - top).abs() < 1e-9, "{}", ample.velocity);
        assert!(lean.velocity > 1.05 * ample.velocity, "{}", lean.velocity);
        for l in [ample, lean] {
            // At every speed up to the top one, with the grip of that speed and the path
            // jerk: each axis's acceleration within the sum or the curvature form, its
            // jerk within the sum of the magnitudes of its three terms.
            for k in 0..=20 {
                let v = l.velocity * f64::from(k) / 20.0;
                let a = l.grip.at(v);
                for i in 0..2 {
                    let sum = b.d1[i] * a + b.d2[i] * v * v;
                    let quadrature = a.hypot(b.curvature * v * v);
                    assert!(sum.min(quadrature) <= a_max * (1.0 + 1e-12), "{v}: {a}");
                    let jerk = b.d1[i] * l.jerk + 3.0 * b.d2[i] * v * a + b.d3[i] * v.powi(3);
                    assert!(jerk <= j_max * (1.0 + 1e-12), "{v}: {a} {}", l.jerk);
                }
            }
            assert!(l.jerk > 0.0 && l.grip.at(l.velocity) > 0.0);
        }
    }
}
