//! Arc length of a parametric curve P(u), u ∈ [0, 1]: a cumulative table built with 5-point
//! Gauss–Legendre quadrature on equal intervals of u, and its inversion (path distance → u)
//! by a table look-up followed by safeguarded Newton steps. Shared by every curve whose
//! length has no closed form (spline blocks, corner blends).

/// Gauss–Legendre abscissae on [-1, 1] (5 points).
const GL_X: [f64; 5] = [
    -0.906_179_845_938_664,
    -0.538_469_310_105_683_1,
    0.0,
    0.538_469_310_105_683_1,
    0.906_179_845_938_664,
];
/// Gauss–Legendre weights matching [`GL_X`].
const GL_W: [f64; 5] = [
    0.236_926_885_056_189_1,
    0.478_628_670_499_366_5,
    0.568_888_888_888_888_9,
    0.478_628_670_499_366_5,
    0.236_926_885_056_189_1,
];

/// Arc length from u = a to u = b for the parameter speed `speed(u)` = |dP/du| (one panel).
pub fn integrate(a: f64, b: f64, speed: impl Fn(f64) -> f64) -> f64 {
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    GL_X.iter()
        .zip(&GL_W)
        .map(|(x, w)| w * speed(mid + half * x))
        .sum::<f64>()
        * half
}

/// Fills `table[i]` with the arc length from u = 0 to u = i / (table.len() − 1).
pub fn fill_table(table: &mut [f64], speed: impl Fn(f64) -> f64) {
    let Some(intervals) = table.len().checked_sub(1).filter(|&n| n > 0) else {
        return;
    };
    let h = 1.0 / intervals as f64;
    let mut acc = 0.0;
    table[0] = 0.0;
    for i in 0..intervals {
        acc += integrate(i as f64 * h, (i + 1) as f64 * h, &speed);
        table[i + 1] = acc;
    }
}

/// Relative difference between the length from one panel and from two half panels below
/// which two panels are taken as exact (the error of the halves is then far smaller still).
const COARSE_AGREEMENT: f64 = 1e-12;

/// Fills `table` like [`fill_table`], but with two intervals when the quadrature on them
/// already agrees with the one on the whole of [0, 1] to `COARSE_AGREEMENT` (a curve whose
/// parameter speed varies little); returns the number of intervals used (`table[..=n]`).
pub fn fill_table_adaptive(table: &mut [f64], speed: impl Fn(f64) -> f64) -> usize {
    if table.len() > 3 {
        let whole = integrate(0.0, 1.0, &speed);
        let left = integrate(0.0, 0.5, &speed);
        let total = left + integrate(0.5, 1.0, &speed);
        if (whole - total).abs() <= COARSE_AGREEMENT * total {
            table[0] = 0.0;
            table[1] = left;
            table[2] = total;
            return 2;
        }
    }
    fill_table(table, speed);
    table.len().saturating_sub(1)
}

/// The parameter u at path distance `s`, clamped to [0, 1], for a table made by
/// [`fill_table`] with the same `speed`.
pub fn parameter_at(table: &[f64], s: f64, speed: impl Fn(f64) -> f64) -> f64 {
    let (Some(&len), Some(intervals)) = (table.last(), table.len().checked_sub(1)) else {
        return 0.0;
    };
    if s <= 0.0 || intervals == 0 {
        return 0.0;
    }
    if s >= len {
        return 1.0;
    }
    let h = 1.0 / intervals as f64;
    let i = table
        .partition_point(|&c| c <= s)
        .saturating_sub(1)
        .min(intervals - 1);
    let (c0, c1) = (table[i], table[i + 1]);
    let (mut lo, mut hi) = (i as f64 * h, (i + 1) as f64 * h);
    let u0 = lo;
    let target = s - c0;
    let mut u = if c1 > c0 {
        lo + h * target / (c1 - c0)
    } else {
        lo
    };
    for _ in 0..40 {
        let g = integrate(u0, u, &speed) - target;
        if g.abs() <= 1e-13 * len.max(1.0) {
            break;
        }
        if g > 0.0 {
            hi = u;
        } else {
            lo = u;
        }
        let sp = speed(u);
        let next = if sp > 0.0 { u - g / sp } else { f64::NAN };
        u = if next > lo && next < hi {
            next
        } else {
            0.5 * (lo + hi)
        };
    }
    u
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_parabola_has_its_closed_form_length_and_inverts() {
        // P(u) = (u, u²): |P'| = sqrt(1 + 4u²); length over [0, 1] is
        // sqrt(5)/2 + asinh(2)/4 (integral by hand).
        let speed = |u: f64| (1.0 + 4.0 * u * u).sqrt();
        let exact = 5f64.sqrt() / 2.0 + 2f64.asinh() / 4.0;
        let mut table = [0.0; 17];
        fill_table(&mut table, speed);
        assert!((table[16] - exact).abs() < 1e-12, "{}", table[16]);
        // Length to u = 0.3 by the same closed form, then back to u.
        let l = |u: f64| u * (1.0 + 4.0 * u * u).sqrt() / 2.0 + (2.0 * u).asinh() / 4.0;
        let u = parameter_at(&table, l(0.3), speed);
        assert!((u - 0.3).abs() < 1e-12, "{u}");
        assert_eq!(parameter_at(&table, -1.0, speed), 0.0);
        assert_eq!(parameter_at(&table, 10.0, speed), 1.0);
    }

    #[test]
    fn an_adaptive_table_is_coarse_only_where_the_speed_hardly_varies() {
        // Constant speed 5 (P(u) = (3u, 4u)): two intervals, exact to rounding.
        let mut table = [0.0; 17];
        assert_eq!(fill_table_adaptive(&mut table, |_| 5.0), 2);
        assert_eq!(table[0], 0.0);
        assert!((table[1] - 2.5).abs() < 1e-15 && (table[2] - 5.0).abs() < 1e-15);
        // Speed 1 + u/1000 (length 1 + 1/2000 by hand): a polynomial of degree 1, which
        // Gauss–Legendre integrates exactly on any panel.
        let n = fill_table_adaptive(&mut table, |u| 1.0 + u / 1000.0);
        assert_eq!(n, 2);
        assert!((table[2] - 1.0005).abs() < 1e-15);
        // The parabola's speed sqrt(1 + 4u²) varies too much: all 16 intervals, and the
        // closed-form length sqrt(5)/2 + asinh(2)/4.
        let speed = |u: f64| (1.0 + 4.0 * u * u).sqrt();
        assert_eq!(fill_table_adaptive(&mut table, speed), 16);
        let exact = 5f64.sqrt() / 2.0 + 2f64.asinh() / 4.0;
        assert!((table[16] - exact).abs() < 1e-12);
    }
}
