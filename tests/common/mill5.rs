//! The built-in 5-axis mill's geometry, written out independently of the kinematics code:
//! rotations about X and Z and the workpiece point under the tool tip.

/// Rotation of `v` by `deg` degrees about X, written out (right-hand rule).
pub fn rx(deg: f64, v: [f64; 3]) -> [f64; 3] {
    let (s, c) = deg.to_radians().sin_cos();
    [v[0], c * v[1] - s * v[2], s * v[1] + c * v[2]]
}

/// Rotation of `v` by `deg` degrees about Z, written out (right-hand rule).
pub fn rz(deg: f64, v: [f64; 3]) -> [f64; 3] {
    let (s, c) = deg.to_radians().sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]
}

/// The workpiece point under machine X Y Z `m` at A `a`, C `c` on the built-in 5-axis mill
/// (tilt line at z = −100 parallel to X, table axis through the origin): undo the tilt, then
/// the table.
pub fn tip_of(m: [f64; 3], a: f64, c: f64) -> [f64; 3] {
    let lifted = rx(a, [m[0], m[1], m[2] + 100.0]);
    rz(c, [lifted[0], lifted[1], lifted[2] - 100.0])
}
