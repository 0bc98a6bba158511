//! The geometry of the tilted working plane: rotation matrices for each PLANE form and the
//! rotary-axis angles of a table-table machine that put the tool along the tilted tool axis.
//!
//! A working plane is the rotation `R` whose columns are the tilted X, Y and Z axes written
//! in the untilted workpiece system: a point `p` given in the tilted system lies at `R · p`.
//! The definitions, in the manual's terms:
//! - SPATIAL SPA SPB SPC: turn about the fixed X by SPA, then the fixed Y by SPB, then the
//!   fixed Z by SPC, so `R = Rz(SPC) · Ry(SPB) · Rx(SPA)` (the same as turning about Z, then
//!   about the turned Y, then about the twice-turned X).
//! - EULER EULPR EULNU EULROT: about Z by the precession, about the turned X by the
//!   nutation, about the turned Z by the rotation: `R = Rz(PR) · Rx(NU) · Rz(ROT)`.
//! - PROJECTED PROPR PROMIN ROT (tool axis Z): the tilted plane meets the ZX plane in a line
//!   at PROPR to X and the YZ plane in a line at PROMIN to Y; the signs are those that make a
//!   single angle the same as SPB (PROPR) or SPA (PROMIN) alone. The tilted X axis is the ZX
//!   trace; ROT then turns the plane about its own tool axis.
//! - VECTOR BX BY BZ NX NY NZ: N is the tool axis, B the direction of the tilted X axis
//!   (neither needs to be normalised; B is made square to N).
//! - POINTS P1 P2 P3: P1→P2 is the tilted X axis, the plane passes through all three and its
//!   tool axis follows the right-hand rule P1 → P2 → P3.
//! - RELATIV SPA|SPB|SPC: one more turn about an axis of the plane active so far.
//! - AXIAL: the rotary axes' own angles (see [`axial`]).
//!
//! Machine angles (table-table, primed table axes as in the kinematics of the motion crate):
//! at tilt `t` and table angle `c` the tool axis seen from the workpiece is
//! `Rz(c) · Rtilt(t) · Z`, which is `(sin t·sin c, −sin t·cos c, cos t)` for an A tilt and
//! `(sin t·cos c, sin t·sin c, cos t)` for a B tilt. Every tool axis off ±Z is reached by two
//! angle pairs, `t` and `−t` (with C turned by 180°); SEQ+ picks the positive tilt, SEQ− the
//! negative one.

/// A 3×3 matrix, row-major.
pub(crate) type M3 = [[f64; 3]; 3];

/// A 3-vector.
pub(crate) type V3 = [f64; 3];

/// The identity matrix.
pub(crate) const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Below this, a length or a sine counts as zero.
const EPS: f64 = 1e-9;

/// `a · b`.
pub(crate) fn mul(a: &M3, b: &M3) -> M3 {
    let mut r = [[0.0; 3]; 3];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    r
}

/// `a · v`.
pub(crate) fn apply(a: &M3, v: V3) -> V3 {
    [
        a[0][0] * v[0] + a[0][1] * v[1] + a[0][2] * v[2],
        a[1][0] * v[0] + a[1][1] * v[1] + a[1][2] * v[2],
        a[2][0] * v[0] + a[2][1] * v[1] + a[2][2] * v[2],
    ]
}

/// The transpose (the inverse of a rotation).
pub(crate) fn transpose(a: &M3) -> M3 {
    [
        [a[0][0], a[1][0], a[2][0]],
        [a[0][1], a[1][1], a[2][1]],
        [a[0][2], a[1][2], a[2][2]],
    ]
}

/// True when `a` is the identity within `tol`.
pub(crate) fn is_identity(a: &M3, tol: f64) -> bool {
    a.iter()
        .flatten()
        .zip(IDENTITY.iter().flatten())
        .all(|(x, y)| (x - y).abs() <= tol)
}

/// Rotation by `deg` degrees about X (right-hand rule).
pub(crate) fn rx(deg: f64) -> M3 {
    let (s, c) = deg.to_radians().sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

/// Rotation by `deg` degrees about Y (right-hand rule).
pub(crate) fn ry(deg: f64) -> M3 {
    let (s, c) = deg.to_radians().sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

/// Rotation by `deg` degrees about Z (right-hand rule).
pub(crate) fn rz(deg: f64) -> M3 {
    let (s, c) = deg.to_radians().sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(v: V3) -> Option<V3> {
    let n = dot(v, v).sqrt();
    (n.is_finite() && n > EPS).then(|| [v[0] / n, v[1] / n, v[2] / n])
}

/// The matrix with columns `x`, `y`, `z`.
fn columns(x: V3, y: V3, z: V3) -> M3 {
    [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]
}

/// PLANE SPATIAL.
pub(crate) fn spatial(spa: f64, spb: f64, spc: f64) -> M3 {
    mul(&rz(spc), &mul(&ry(spb), &rx(spa)))
}

/// PLANE EULER.
pub(crate) fn euler(pr: f64, nu: f64, rot: f64) -> M3 {
    mul(&rz(pr), &mul(&rx(nu), &rz(rot)))
}

/// PLANE PROJECTED (tool axis Z). Fails when the two traces are parallel (|angles| of 90°).
pub(crate) fn projected(propr: f64, promin: f64, rot: f64) -> Result<M3, &'static str> {
    let (sb, cb) = propr.to_radians().sin_cos();
    let (sa, ca) = promin.to_radians().sin_cos();
    let u = [cb, 0.0, -sb];
    let v = [0.0, ca, sa];
    let x = unit(u).ok_or("PLANE PROJECTED: PROPR gives no trace in the ZX plane")?;
    let n = unit(cross(u, v)).ok_or("PLANE PROJECTED: the projection angles define no plane")?;
    let y = cross(n, x);
    Ok(mul(&columns(x, y, n), &rz(rot)))
}

/// PLANE VECTOR: base vector `b` (tilted X), normal vector `n` (tilted Z).
pub(crate) fn vector(b: V3, n: V3) -> Result<M3, &'static str> {
    let z = unit(n).ok_or("PLANE VECTOR: the normal vector NX NY NZ is zero")?;
    let along = dot(b, z);
    let x = unit([
        b[0] - along * z[0],
        b[1] - along * z[1],
        b[2] - along * z[2],
    ])
    .ok_or("PLANE VECTOR: the base vector is zero or parallel to the normal vector")?;
    Ok(columns(x, cross(z, x), z))
}

/// PLANE POINTS.
pub(crate) fn points(p1: V3, p2: V3, p3: V3) -> Result<M3, &'static str> {
    let d = |a: V3, b: V3| [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let x = unit(d(p1, p2)).ok_or("PLANE POINTS: P1 and P2 are the same point")?;
    let z = unit(cross(d(p1, p2), d(p1, p3)))
        .ok_or("PLANE POINTS: the three points lie on one line")?;
    Ok(columns(x, cross(z, x), z))
}

/// The tilt axis of a table-table machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Tilt {
    /// A, about X.
    A,
    /// B, about Y.
    B,
}

impl Tilt {
    /// Rotation by `deg` about the tilt axis.
    pub(crate) fn rot(self, deg: f64) -> M3 {
        match self {
            Tilt::A => rx(deg),
            Tilt::B => ry(deg),
        }
    }
}

/// The working plane the rotary axes make at tilt `t` and table angle `c` (PLANE AXIAL):
/// `Rz(c) · Rtilt(t)`.
pub(crate) fn axial(tilt: Tilt, t: f64, c: f64) -> M3 {
    mul(&rz(c), &tilt.rot(t))
}

/// The tool axis seen from the workpiece at tilt `t` and table angle `c`.
pub(crate) fn tool_axis(tilt: Tilt, t: f64, c: f64) -> V3 {
    let m = axial(tilt, t, c);
    [m[0][2], m[1][2], m[2][2]]
}

/// How the two angle solutions are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Choice {
    /// SEQ+ (`Some(true)`), SEQ− (`Some(false)`), or the solution nearer the present angles.
    pub seq: Option<bool>,
    /// TABLE ROT: when the tool axis is Z already, turn the table by the plane's rotation
    /// about Z instead of keeping the table angle (COORD ROT).
    pub table_rot: bool,
}

/// Tilt and table angles (degrees) that put the tool along the tool axis of `r`, starting
/// from the present angles `now` (used to pick a solution when SEQ is absent, and for the
/// table angle when the tool axis is Z and COORD ROT applies).
pub(crate) fn solve(r: &M3, tilt: Tilt, choice: Choice, now: (f64, f64)) -> (f64, f64) {
    let n = [r[0][2], r[1][2], r[2][2]];
    let t = n[2].clamp(-1.0, 1.0).acos().to_degrees();
    if t.to_radians().sin().abs() < EPS {
        // Tool axis ±Z: the table angle is free.
        let c = if choice.table_rot {
            // The plane is a turn about Z by atan2(r10, r00) (for −Z: with the tilt of 180°
            // the same formula holds for the in-plane X axis).
            r[1][0].atan2(r[0][0]).to_degrees()
        } else {
            now.1
        };
        return (if n[2] > 0.0 { 0.0 } else { 180.0 }, c);
    }
    let table = |t: f64| {
        let s = t.to_radians().sin();
        match tilt {
            Tilt::A => (n[0] / s).atan2(-n[1] / s).to_degrees(),
            Tilt::B => (n[1] / s).atan2(n[0] / s).to_degrees(),
        }
    };
    let plus = (t, table(t));
    let minus = (-t, table(-t));
    match choice.seq {
        Some(true) => plus,
        Some(false) => minus,
        None => {
            let cost = |(a, c): (f64, f64)| {
                let dc = (c - now.1).rem_euclid(360.0);
                (a - now.0).abs() + dc.min(360.0 - dc)
            };
            if cost(minus) < cost(plus) {
                minus
            } else {
                plus
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close_m(a: &M3, b: &M3) {
        for (x, y) in a.iter().flatten().zip(b.iter().flatten()) {
            assert!((x - y).abs() < 1e-12, "{a:?} vs {b:?}");
        }
    }

    #[test]
    fn spatial_single_angles_are_the_plain_rotations() {
        // SPA 90: the tilted Z (third column) is Rx(90)·Z = (0, −1, 0).
        let r = spatial(90.0, 0.0, 0.0);
        assert!((r[1][2] + 1.0).abs() < 1e-12 && r[0][2].abs() < 1e-12);
        // SPB 90: tilted Z = (1, 0, 0); SPC 90: tilted X = (0, 1, 0).
        assert!((spatial(0.0, 90.0, 0.0)[0][2] - 1.0).abs() < 1e-12);
        assert!((spatial(0.0, 0.0, 90.0)[1][0] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn projected_single_angles_match_spatial() {
        close_m(
            &projected(30.0, 0.0, 0.0).unwrap(),
            &spatial(0.0, 30.0, 0.0),
        );
        close_m(
            &projected(0.0, 25.0, 0.0).unwrap(),
            &spatial(25.0, 0.0, 0.0),
        );
        close_m(&projected(0.0, 0.0, 40.0).unwrap(), &rz(40.0));
    }

    #[test]
    fn vector_and_points_build_a_right_handed_frame() {
        // Normal along +X, base along +Y: tilted Y = Z × X' = (1,0,0) × (0,1,0) = (0,0,1).
        let r = vector([0.0, 2.0, 0.0], [5.0, 0.0, 0.0]).unwrap();
        close_m(&r, &[[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let p = points([0.0; 3], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]).unwrap();
        close_m(&p, &r);
        assert!(vector([1.0, 0.0, 0.0], [2.0, 0.0, 0.0]).is_err());
        assert!(points([1.0; 3], [2.0; 3], [3.0; 3]).is_err());
    }

    #[test]
    fn a_c_angles_for_spb_30_are_a_30_c_90_or_a_minus_30_c_minus_90() {
        // Tool axis Ry(30)·Z = (1/2, 0, √3/2); (sin a sin c, −sin a cos c) = (1/2, 0).
        let r = spatial(0.0, 30.0, 0.0);
        let plus = solve(
            &r,
            Tilt::A,
            Choice {
                seq: Some(true),
                table_rot: false,
            },
            (0.0, 0.0),
        );
        let minus = solve(
            &r,
            Tilt::A,
            Choice {
                seq: Some(false),
                table_rot: false,
            },
            (0.0, 0.0),
        );
        assert!(
            (plus.0 - 30.0).abs() < 1e-9 && (plus.1 - 90.0).abs() < 1e-9,
            "{plus:?}"
        );
        assert!(
            (minus.0 + 30.0).abs() < 1e-9 && (minus.1 + 90.0).abs() < 1e-9,
            "{minus:?}"
        );
        for (t, c) in [plus, minus] {
            let n = tool_axis(Tilt::A, t, c);
            assert!((n[0] - 0.5).abs() < 1e-12 && n[1].abs() < 1e-12);
        }
    }
}
