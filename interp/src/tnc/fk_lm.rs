//! Numerical tools of the FK solver: damped least squares (Levenberg–Marquardt) on a residual
//! function, the null space of its Jacobian (which unknowns the equations fix), a small dense
//! linear solver and a deterministic pseudo-random source for start points.

/// Residual norm (mm) below which a point counts as a solution.
pub(crate) const SOLVED: f64 = 1e-8;

/// Central-difference Jacobian (row-major, `m` rows of `x.len()` columns) of `f` at `x`.
pub(crate) fn jacobian(f: &dyn Fn(&[f64], &mut Vec<f64>), x: &[f64], m: usize) -> Vec<f64> {
    let n = x.len();
    let mut jac = vec![0.0; m * n];
    let mut xp = x.to_vec();
    let (mut rp, mut rm) = (Vec::with_capacity(m), Vec::with_capacity(m));
    for k in 0..n {
        let h = 1e-6 * (1.0 + x[k].abs());
        xp[k] = x[k] + h;
        f(&xp, &mut rp);
        xp[k] = x[k] - h;
        f(&xp, &mut rm);
        xp[k] = x[k];
        for i in 0..m.min(rp.len()).min(rm.len()) {
            jac[i * n + k] = (rp[i] - rm[i]) / (2.0 * h);
        }
    }
    jac
}

/// Sum of squares.
fn cost(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// `JᵀJ` (n×n) and `Jᵀr` of a row-major `m`×`n` Jacobian.
fn normal(jac: &[f64], r: &[f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let m = r.len();
    let mut a = vec![0.0; n * n];
    let mut g = vec![0.0; n];
    for i in 0..m {
        let row = &jac[i * n..(i + 1) * n];
        for p in 0..n {
            g[p] += row[p] * r[i];
            for q in p..n {
                a[p * n + q] += row[p] * row[q];
            }
        }
    }
    for p in 0..n {
        for q in 0..p {
            a[p * n + q] = a[q * n + p];
        }
    }
    (a, g)
}

/// Minimises `|f(x)|²` from `x0`; returns the point when the residual vanishes there.
pub(crate) fn least_squares(f: &dyn Fn(&[f64], &mut Vec<f64>), x0: Vec<f64>) -> Option<Vec<f64>> {
    let n = x0.len();
    let mut x = x0;
    let mut r = Vec::new();
    f(&x, &mut r);
    let m = r.len();
    let mut c = cost(&r);
    let mut lambda = 1e-3;
    let mut trial = Vec::with_capacity(m);
    for _ in 0..300 {
        if c.sqrt() < SOLVED * 1e-3 {
            break;
        }
        let jac = jacobian(f, &x, m);
        let (a, g) = normal(&jac, &r, n);
        let mut improved = false;
        while lambda < 1e10 {
            let mut damped = a.clone();
            for p in 0..n {
                damped[p * n + p] += lambda * (a[p * n + p] + 1e-6);
            }
            let neg_g: Vec<f64> = g.iter().map(|v| -v).collect();
            let Some(step) = solve_linear(damped, neg_g, n) else {
                lambda *= 10.0;
                continue;
            };
            let xt: Vec<f64> = x.iter().zip(&step).map(|(a, b)| a + b).collect();
            f(&xt, &mut trial);
            let ct = cost(&trial);
            if ct.is_finite() && ct < c {
                x = xt;
                std::mem::swap(&mut r, &mut trial);
                c = ct;
                lambda = (lambda * 0.3).max(1e-12);
                improved = true;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    (c.sqrt() < SOLVED && x.iter().all(|v| v.is_finite())).then_some(x)
}

/// For each unknown, whether the equations fix it at the solution `x`: true when the null
/// space of the Jacobian has no component along that unknown.
pub(crate) fn determined(f: &dyn Fn(&[f64], &mut Vec<f64>), x: &[f64]) -> Vec<bool> {
    let n = x.len();
    let mut r = Vec::new();
    f(x, &mut r);
    let jac = jacobian(f, x, r.len());
    let (a, _) = normal(&jac, &r, n);
    let (vals, vecs) = symmetric_eigen(a, n);
    let top = vals.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    let mut weight = vec![0.0; n];
    for (j, v) in vals.iter().enumerate() {
        if v.abs() < 1e-9 * top {
            for (k, w) in weight.iter_mut().enumerate() {
                let c = vecs[k * n + j];
                *w += c * c;
            }
        }
    }
    weight.iter().map(|w| *w < 1e-6).collect()
}

/// Eigenvalues and eigenvectors (columns of the row-major result) of a symmetric matrix,
/// by cyclic Jacobi rotations.
fn symmetric_eigen(mut a: Vec<f64>, n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut v = vec![0.0; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    for _ in 0..60 {
        let mut off = 0.0;
        for p in 0..n {
            for q in p + 1..n {
                off += a[p * n + q] * a[p * n + q];
            }
        }
        if off < 1e-30 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let akp = a[k * n + p];
                    let akq = a[k * n + q];
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let apk = a[p * n + k];
                    let aqk = a[q * n + k];
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let vkp = v[k * n + p];
                    let vkq = v[k * n + q];
                    v[k * n + p] = c * vkp - s * vkq;
                    v[k * n + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    ((0..n).map(|i| a[i * n + i]).collect(), v)
}

/// Solves `a·x = b` (row-major `n`×`n`) by Gaussian elimination with partial pivoting.
fn solve_linear(mut a: Vec<f64>, mut b: Vec<f64>, n: usize) -> Option<Vec<f64>> {
    for col in 0..n {
        let piv =
            (col..n).max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs()))?;
        if a[piv * n + col].abs() < 1e-300 {
            return None;
        }
        if piv != col {
            for k in 0..n {
                a.swap(piv * n + k, col * n + k);
            }
            b.swap(piv, col);
        }
        for row in col + 1..n {
            let fct = a[row * n + col] / a[col * n + col];
            if fct != 0.0 {
                for k in col..n {
                    a[row * n + k] -= fct * a[col * n + k];
                }
                b[row] -= fct * b[col];
            }
        }
    }
    let mut x = vec![0.0; n];
    for row in (0..n).rev() {
        let mut s = b[row];
        for k in row + 1..n {
            s -= a[row * n + k] * x[k];
        }
        x[row] = s / a[row * n + row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Deterministic pseudo-random numbers in [-1, 1) (64-bit linear congruential generator),
/// so that the same program always finds its solutions in the same way.
pub(crate) struct Lcg(pub u64);

impl Lcg {
    /// The next number.
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_system() {
        // 2x + y = 5, x + 3y = 10 → x = 1, y = 3
        let x = solve_linear(vec![2.0, 1.0, 1.0, 3.0], vec![5.0, 10.0], 2).expect("regular");
        assert!((x[0] - 1.0).abs() < 1e-12 && (x[1] - 3.0).abs() < 1e-12);
        assert!(solve_linear(vec![1.0, 2.0, 2.0, 4.0], vec![1.0, 2.0], 2).is_none());
    }

    #[test]
    fn eigenvalues_of_a_symmetric_matrix() {
        // [[2,1],[1,2]] has eigenvalues 1 and 3
        let (mut vals, _) = symmetric_eigen(vec![2.0, 1.0, 1.0, 2.0], 2);
        vals.sort_by(f64::total_cmp);
        assert!((vals[0] - 1.0).abs() < 1e-12 && (vals[1] - 3.0).abs() < 1e-12);
    }

    #[test]
    fn least_squares_and_null_space() {
        let f = |x: &[f64], out: &mut Vec<f64>| {
            out.clear();
            out.push(x[0] * x[0] - 2.0);
            out.push(x[1] - 3.0);
        };
        let x = least_squares(&f, vec![1.0, 0.0]).expect("solved");
        assert!((x[0] - 2f64.sqrt()).abs() < 1e-9 && (x[1] - 3.0).abs() < 1e-9);
        assert_eq!(determined(&f, &x), vec![true, true]);
        // one equation on x0 only: x1 is free
        let g = |x: &[f64], out: &mut Vec<f64>| {
            out.clear();
            out.push(x[0] - 1.0);
        };
        let x = least_squares(&g, vec![5.0, 7.0]).expect("solved");
        assert_eq!(determined(&g, &x), vec![true, false]);
        // no solution: x0² = -1
        let h = |x: &[f64], out: &mut Vec<f64>| {
            out.clear();
            out.push(x[0] * x[0] + 1.0);
        };
        assert!(least_squares(&h, vec![0.5]).is_none());
    }
}
