//! The working plane of the LATERAL_Y / SURFACE_Y sections (YZ plane, G19), with and without
//! a tilted plane (B axis).
//!
//! Section parameters: X reference diameter, C spindle angle (the position on the
//! workpiece), B plane angle (measured from the positive Z axis), I plane reference in X
//! (radius), K plane reference in Z, H automatic shift (0, the default: shift the rotated
//! system back by −I; 1: no shift).
//!
//! Without B the contour lies in the YZ plane at the reference radius X/2; a point (y, z) of
//! the contour is the workpiece point (X/2, y, z) with the spindle at C. With B the manual's
//! three steps are applied to a point p = (x, y, z) of the tilted system, where x is the
//! infeed coordinate (programmed as a diameter, so x = X/2): shift the origin to (I, 0, K),
//! rotate by B about the Y axis through that point, and with H=0 shift the rotated system
//! back by −I along its own X axis. As one formula:
//!
//! ```text
//! workpiece = (I, 0, K) + R_y(B) · (p − h·(I, 0, 0)),   h = 1 for H=0, 0 for H=1
//! R_y(B) = [[cos B, 0, sin B], [0, 1, 0], [−sin B, 0, cos B]]
//! ```
//!
//! R_y is the right-handed rotation about +Y (it turns +Z towards +X), so with H=0 a point at
//! the reference radius on the tilted X axis, (I, 0, 0), lands on the pivot (I, 0, K): the
//! reference diameter keeps meaning "on the plane reference point", which is why the manual
//! recommends H=0. Mirroring does not change the axis the tilt angle B refers to, so B enters
//! unchanged whatever mirror is active.
//!
//! The manual's example writes `SURFACE_Y X118 C0 B130 I59 K0` inside a LATERAL_Y description;
//! both names are accepted for this section and mean the same plane.

/// A LATERAL_Y / SURFACE_Y working plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LateralPlane {
    /// X: reference diameter, mm.
    pub reference_diameter: f64,
    /// C: spindle angle, degrees.
    pub c: f64,
    /// B: plane angle, degrees (`None` without tilted plane).
    pub b: Option<f64>,
    /// I: plane reference in X (radius), mm.
    pub i: f64,
    /// K: plane reference in Z, mm.
    pub k: f64,
    /// H=1: do not shift the rotated system back by −I.
    pub no_back_shift: bool,
}

impl LateralPlane {
    /// The workpiece point (X radius, Y, Z) of a point in the section's system: `x_dia` the
    /// infeed coordinate as a diameter (None: on the reference diameter), `y`, `z` the
    /// contour coordinates.
    pub fn to_workpiece(&self, x_dia: Option<f64>, y: f64, z: f64) -> [f64; 3] {
        let x = x_dia.unwrap_or(self.reference_diameter) / 2.0;
        match self.b {
            None => [x, y, z],
            Some(b) => {
                let (s, c) = b.to_radians().sin_cos();
                let h = if self.no_back_shift { 0.0 } else { 1.0 };
                let px = x - h * self.i;
                [self.i + c * px + s * z, y, self.k - s * px + c * z]
            }
        }
    }
}
