//! The built-in 5-axis mill's geometry, written out independently of the kinematics code:
//! rotations about X and Z, the workpiece point under the tool tip, and a compensated path
//! worked out by hand.

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

/// The tool-centre path, in the tilted system, of the 40 × 20 rectangle (0, 0)–(40, 20) run
/// counter-clockwise from (20, 0) with left compensation and a tool of radius 5 at depth −2:
/// down at (20, 10), on the first element's normal to (20, 5), round the inside offset
/// rectangle (5, 5)–(35, 15) with its corners at the intersections, back to (20, 5), off on
/// the last element's normal to (20, 10) and up.
pub const RECT_RL_CENTRE: [[f64; 3]; 10] = [
    [20.0, 10.0, 5.0],
    [20.0, 10.0, -2.0],
    [20.0, 5.0, -2.0],
    [35.0, 5.0, -2.0],
    [35.0, 15.0, -2.0],
    [5.0, 15.0, -2.0],
    [5.0, 5.0, -2.0],
    [20.0, 5.0, -2.0],
    [20.0, 10.0, -2.0],
    [20.0, 10.0, 5.0],
];
