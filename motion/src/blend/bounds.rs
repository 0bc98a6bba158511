//! Bounds of a blend's arc-length derivatives |dⁿq/dsⁿ| (n = 1, 2, 3) per axis that hold over
//! the whole curve, not only where it was sampled.
//!
//! For the polynomial curve P(u) with g = |P′|² (over the linear axes), h = P′·P″ and
//! m = |P″|² + P′·P‴, the chain rule for q(s) = P(u(s)) gives, per axis with x = P′ᵢ,
//! y = P″ᵢ, z = P‴ᵢ:
//!
//! ```text
//! q′ = x / g^½      q″ = (y·g − x·h) / g²      q‴ = (z·g² − 3·y·h·g + x·(4h² − m·g)) / g^3.5
//! ```
//!
//! Every numerator and g are polynomials in u. On an interval of u each polynomial's range
//! is enclosed by its Taylor expansion about the interval's midpoint (the constant term
//! plus the largest contributions of the others; the expansion of a product is the product
//! of the expansions of P′, P″, P‴), so the quotients are bounded by the numerators' largest
//! magnitude over the smallest g.
//!
//! Intervals are halved where such a bound exceeds [`BOUND_MARGIN`] times the largest exact
//! value found at the interval ends so far, down to 1/128 of the range; the result per axis
//! is the largest interval bound. Every point of the range lies in an interval whose
//! enclosure holds it, so the result is never below the true maximum, and where the halving
//! succeeds it is at most the margin times the true maximum. Smooth blends need no halving
//! or a few; the finest intervals serve the narrow curvature peak of a blend through a
//! sharp corner.
//!
//! The curvature over the linear axes gets a bound of its own the same way, from
//! κ² = (|P″|²·g − h²) / g³: the per-axis peaks of q″ of a turning curve lie at different
//! places, so the norm of their bounds can overstate the curvature by up to √2. The range
//! may be part of the curve ([`super::Quintic::bounds_between`]): a blend is planned in
//! parts, each with the bounds of its own stretch.

use crate::geom::{AxisBounds, Metric};

/// Factor on exact derivative values within which an interval bound counts as tight.
pub(super) const BOUND_MARGIN: f64 = 1.1;

/// Halvings of [0, 1] at most (intervals of 1/128).
const MAX_DEPTH: u32 = 7;

/// Share of the largest value of the same derivative (over all axes) below which an
/// interval bound of an axis is accepted without halving further.
const FLOOR_SHARE: f64 = 0.01;

/// Relative allowance for rounding in the interval bounds.
const ROUNDING: f64 = 1e-9;

/// Arc-length derivatives [q′, q″, q‴] per axis and the parameter speed at one value of u.
pub(super) struct Exact {
    /// dⁿq/dsⁿ per axis, n = 1, 2, 3.
    pub t: [[f64; 9]; 3],
    /// |P′(u)| over the linear axes.
    pub sigma: f64,
}

/// `out += factor · a · b` for polynomials (coefficients, lowest first).
fn mul_add<const A: usize, const B: usize, const C: usize>(
    a: &[f64; A],
    b: &[f64; B],
    factor: f64,
    out: &mut [f64; C],
) {
    const { assert!(A + B <= C + 1) };
    for i in 0..A {
        let fa = factor * a[i];
        for j in 0..B {
            out[i + j] += fa * b[j];
        }
    }
}

/// The curve's derivative polynomials in u.
struct Derivatives {
    /// Moving axes.
    axes: [usize; 9],
    count: usize,
    /// P′, P″, P‴ per axis.
    x: [[f64; 5]; 9],
    y: [[f64; 4]; 9],
    z: [[f64; 3]; 9],
}

impl Derivatives {
    fn new(c: &[[f64; 6]; 9], moving: &[bool; 9]) -> Derivatives {
        let mut n = Derivatives {
            axes: [0; 9],
            count: 0,
            x: [[0.0; 5]; 9],
            y: [[0.0; 4]; 9],
            z: [[0.0; 3]; 9],
        };
        for (i, ci) in c.iter().enumerate() {
            if !moving[i] {
                continue;
            }
            n.x[i] = [ci[1], 2.0 * ci[2], 3.0 * ci[3], 4.0 * ci[4], 5.0 * ci[5]];
            n.y[i] = [2.0 * ci[2], 6.0 * ci[3], 12.0 * ci[4], 20.0 * ci[5]];
            n.z[i] = [6.0 * ci[3], 24.0 * ci[4], 60.0 * ci[5]];
            n.axes[n.count] = i;
            n.count += 1;
        }
        n
    }

    fn axes(&self) -> &[usize] {
        self.axes.get(..self.count).unwrap_or(&[])
    }

    /// Upper bounds of |q′|, |q″|, |q‴| per axis over u ∈ [a, b], and of the curvature over
    /// the linear axes; `None` when |P′|² cannot be shown to stay above `min_speed²` there
    /// (or a value is not finite).
    ///
    /// The derivatives are re-expanded about the interval's midpoint first (u = c + t); the
    /// products are then formed in t and enclosed over |t| ≤ r.
    fn interval(&self, a: f64, b: f64, min_speed: f64) -> Option<([[f64; 9]; 3], f64)> {
        let (c, r) = (0.5 * (a + b), 0.5 * (b - a));
        let mut x = [[0.0; 5]; 9];
        let mut y = [[0.0; 4]; 9];
        let mut z = [[0.0; 3]; 9];
        for &i in self.axes() {
            x[i] = taylor(&self.x[i], c);
            y[i] = taylor(&self.y[i], c);
            z[i] = taylor(&self.z[i], c);
        }
        let (mut g, mut h, mut m, mut yy) = ([0.0; 9], [0.0; 8], [0.0; 7], [0.0; 7]);
        for &i in Metric::Linear.axes() {
            if self.axes().contains(&i) {
                mul_add(&x[i], &x[i], 1.0, &mut g);
                mul_add(&x[i], &y[i], 1.0, &mut h);
                mul_add(&y[i], &y[i], 1.0, &mut yy);
                mul_add(&x[i], &z[i], 1.0, &mut m);
            }
        }
        for (mk, yk) in m.iter_mut().zip(&yy) {
            *mk += yk;
        }
        let (g_lo, _) = enclose(&g, r);
        if !(g_lo > min_speed * min_speed && g_lo.is_finite()) {
            return None;
        }
        // κ² = |q″|² = (|P″|²·g − h²) / g³ over the linear axes.
        let mut k2 = [0.0; 15];
        mul_add(&yy, &g, 1.0, &mut k2);
        mul_add(&h, &h, -1.0, &mut k2);
        let (_, k2_hi) = enclose(&k2, r);
        let kappa = (k2_hi.max(0.0) * (1.0 + ROUNDING) / (g_lo * g_lo * g_lo)).sqrt();
        if !kappa.is_finite() {
            return None;
        }
        // g², 3·h·g and 4h² − m·g.
        let (mut gg, mut hg3, mut w) = ([0.0; 17], [0.0; 16], [0.0; 15]);
        mul_add(&g, &g, 1.0, &mut gg);
        mul_add(&h, &g, 3.0, &mut hg3);
        mul_add(&h, &h, 4.0, &mut w);
        mul_add(&m, &g, -1.0, &mut w);
        let s = g_lo.sqrt();
        let k = 1.0 + ROUNDING;
        let scale = [k / s, k / (g_lo * g_lo), k / (g_lo * g_lo * g_lo * s)];
        let mut u = [[0.0; 9]; 3];
        for &i in self.axes() {
            let mut n2 = [0.0; 12];
            mul_add(&y[i], &g, 1.0, &mut n2);
            mul_add(&x[i], &h, -1.0, &mut n2);
            let mut n3 = [0.0; 19];
            mul_add(&z[i], &gg, 1.0, &mut n3);
            mul_add(&y[i], &hg3, -1.0, &mut n3);
            mul_add(&x[i], &w, 1.0, &mut n3);
            u[0][i] = abs_max(&x[i], r) * scale[0];
            u[1][i] = abs_max(&n2, r) * scale[1];
            u[2][i] = abs_max(&n3, r) * scale[2];
            if !(u[0][i].is_finite() && u[1][i].is_finite() && u[2][i].is_finite()) {
                return None;
            }
        }
        Some((u, kappa))
    }
}

/// The coefficients of p(c + t) in t (repeated synthetic division).
fn taylor<const N: usize>(p: &[f64; N], c: f64) -> [f64; N] {
    let mut a = *p;
    for i in 0..N.saturating_sub(1) {
        for j in (i..N - 1).rev() {
            a[j] += c * a[j + 1];
        }
    }
    a
}

/// Enclosure [lo, hi] of the polynomial with coefficients `a` (in t) over |t| ≤ r.
fn enclose<const N: usize>(a: &[f64; N], r: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (a[0], a[0]);
    let mut rk = 1.0;
    for (k, ak) in a.iter().enumerate().skip(1) {
        rk *= r;
        let v = ak * rk;
        if k % 2 == 0 {
            // tᵏ ≥ 0 for even k: the term has the sign of its coefficient.
            if v > 0.0 {
                hi += v;
            } else {
                lo += v;
            }
        } else {
            hi += v.abs();
            lo -= v.abs();
        }
    }
    (lo, hi)
}

/// Largest |p| over |t| ≤ r (an upper bound) for coefficients `a` in t.
fn abs_max<const N: usize>(a: &[f64; N], r: f64) -> f64 {
    let (lo, hi) = enclose(a, r);
    lo.abs().max(hi.abs())
}

/// The derivative bounds over u ∈ `range` of the quintic with monomial coefficients `c`
/// (see the module notes); `exact(u)` gives the exact derivatives at one parameter value.
/// `None` when the parameter speed falls below `min_speed` at an evaluated point or cannot
/// be shown to stay above it on an interval of the finest width (a cusp, or close to one).
///
/// The curvature bound is the smaller of the norm of the per-axis bounds of q″ and a bound
/// of |q″| itself (the per-axis peaks of a turning curve lie at different places, so their
/// norm can overstate the curvature by up to √2).
pub(super) fn derivative_bounds(
    c: &[[f64; 6]; 9],
    moving: &[bool; 9],
    min_speed: f64,
    range: (f64, f64),
    exact: impl Fn(f64) -> Exact,
) -> Option<AxisBounds> {
    let num = Derivatives::new(c, moving);
    let axes = num.axes();
    // Largest exact values found so far, and the largest interval bounds kept.
    let mut found = [[0.0f64; 9]; 3];
    let mut upper = [[0.0f64; 9]; 3];
    let (mut found_kappa, mut upper_kappa) = (0.0f64, 0.0f64);
    let visit = |u: f64, found: &mut [[f64; 9]; 3], found_kappa: &mut f64| -> Option<()> {
        let e = exact(u);
        if e.sigma.is_nan() || e.sigma < min_speed {
            return None;
        }
        for (f, t) in found.iter_mut().zip(&e.t) {
            for &i in axes {
                f[i] = f[i].max(t[i].abs());
            }
        }
        *found_kappa = found_kappa.max(Metric::Linear.norm(&e.t[1]));
        Some(())
    };
    let (lo, hi) = range;
    if !(0.0..=1.0).contains(&lo) || !(lo..=1.0).contains(&hi) {
        return None;
    }
    visit(lo, &mut found, &mut found_kappa)?;
    visit(hi, &mut found, &mut found_kappa)?;
    // Intervals still to bound: (start, end, depth).
    let mut stack = [(0.0, 0.0, 0u32); MAX_DEPTH as usize + 1];
    stack[0] = (lo, hi, 0);
    let mut len = 1;
    while len > 0 {
        len -= 1;
        let (a, b, depth) = stack[len];
        let tight = |u: &[[f64; 9]; 3], kappa: f64| {
            kappa <= BOUND_MARGIN * found_kappa
                && (0..3).all(|n| {
                    let floor = FLOOR_SHARE * axes.iter().map(|&i| found[n][i]).fold(0.0, f64::max);
                    axes.iter()
                        .all(|&i| u[n][i] <= (BOUND_MARGIN * found[n][i]).max(floor))
                })
        };
        let bound = num.interval(a, b, min_speed);
        if let Some((u, kappa)) = &bound {
            if tight(u, *kappa) || depth >= MAX_DEPTH {
                for (up, un) in upper.iter_mut().zip(u) {
                    for &i in axes {
                        up[i] = up[i].max(un[i]);
                    }
                }
                upper_kappa = upper_kappa.max(*kappa);
                continue;
            }
        } else if depth >= MAX_DEPTH {
            return None;
        }
        let mid = 0.5 * (a + b);
        visit(mid, &mut found, &mut found_kappa)?;
        // Depth-first: at most one pending sibling per level.
        if let Some(slots) = stack.get_mut(len..len + 2) {
            slots[0] = (mid, b, depth + 1);
            slots[1] = (a, mid, depth + 1);
            len += 2;
        } else {
            return None;
        }
    }
    let mut b = AxisBounds::default();
    for &i in axes {
        b.d1[i] = found[0][i].max(upper[0][i]);
        b.d2[i] = found[1][i].max(upper[1][i]);
        b.d3[i] = found[2][i].max(upper[2][i]);
        // A unit tangent has no linear component above 1.
        if Metric::Linear.axes().contains(&i) {
            b.d1[i] = b.d1[i].min(1.0);
        }
    }
    // Blends join linear moves only: their path distance is the linear arc length.
    b.curvature = Metric::Linear.norm(&b.d2).min(found_kappa.max(upper_kappa));
    Some(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn taylor_enclosure_contains_the_polynomial_and_is_exact_for_a_monotone_cubic() {
        // p(u) = u³ − u on [0, 2]: values by hand at a grid all inside the enclosure.
        let p = [0.0, -1.0, 0.0, 1.0];
        let (lo, hi) = enclose(&taylor(&p, 1.0), 1.0);
        for k in 0..=200 {
            let u = 2.0 * k as f64 / 200.0;
            let v = u * u * u - u;
            assert!(
                v >= lo - 1e-12 && v <= hi + 1e-12,
                "{u}: {v} not in [{lo}, {hi}]"
            );
        }
        // p(u) = u³ on [1, 3] is increasing: about c = 2 the terms are 8, 12t, 6t², t³ and
        // the enclosure is [8 − 12 − 1, 8 + 12 + 6 + 1] = [−5, 27] (27 = p(3) exactly).
        let (lo, hi) = enclose(&taylor(&[0.0, 0.0, 0.0, 1.0], 2.0), 1.0);
        assert_eq!((lo, hi), (-5.0, 27.0));
    }
}
