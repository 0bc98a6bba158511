//! Working-plane arithmetic: 2-D points and directions, and moving between a [`Pose`] and
//! its two in-plane coordinates.

use klar_interp::{Plane, Pose};
use std::ops::{Add, Mul, Neg, Sub};

/// A point or direction in the working plane: (first axis, second axis) of [`Plane::axes`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct V2 {
    /// First in-plane coordinate.
    pub x: f64,
    /// Second in-plane coordinate.
    pub y: f64,
}

impl V2 {
    /// A vector from its coordinates.
    pub const fn new(x: f64, y: f64) -> V2 {
        V2 { x, y }
    }

    /// The unit vector at `angle` radians from the first axis (counter-clockwise).
    pub fn polar(angle: f64) -> V2 {
        let (s, c) = angle.sin_cos();
        V2::new(c, s)
    }

    /// Scalar product.
    pub fn dot(self, o: V2) -> f64 {
        self.x * o.x + self.y * o.y
    }

    /// z component of the cross product: positive when `o` lies counter-clockwise of `self`.
    pub fn cross(self, o: V2) -> f64 {
        self.x * o.y - self.y * o.x
    }

    /// Euclidean length.
    pub fn norm(self) -> f64 {
        self.x.hypot(self.y)
    }

    /// The vector turned 90° counter-clockwise (the left normal of a direction).
    pub fn left(self) -> V2 {
        V2::new(-self.y, self.x)
    }

    /// The vector turned by `angle` radians counter-clockwise.
    pub fn rotated(self, angle: f64) -> V2 {
        let (s, c) = angle.sin_cos();
        V2::new(c * self.x - s * self.y, s * self.x + c * self.y)
    }

    /// Angle of the vector from the first axis, radians in (−π, π].
    pub fn angle(self) -> f64 {
        self.y.atan2(self.x)
    }

    /// Distance to another point.
    pub fn dist(self, o: V2) -> f64 {
        (self - o).norm()
    }
}

impl Add for V2 {
    type Output = V2;
    fn add(self, o: V2) -> V2 {
        V2::new(self.x + o.x, self.y + o.y)
    }
}

impl Sub for V2 {
    type Output = V2;
    fn sub(self, o: V2) -> V2 {
        V2::new(self.x - o.x, self.y - o.y)
    }
}

impl Mul<f64> for V2 {
    type Output = V2;
    fn mul(self, k: f64) -> V2 {
        V2::new(self.x * k, self.y * k)
    }
}

impl Neg for V2 {
    type Output = V2;
    fn neg(self) -> V2 {
        V2::new(-self.x, -self.y)
    }
}

/// The in-plane coordinates of a pose.
pub fn project(pose: &Pose, plane: Plane) -> V2 {
    let (a, b, _) = plane.axes();
    V2::new(pose[a], pose[b])
}

/// A copy of `pose` with its in-plane coordinates replaced by `p`.
pub fn with_point(pose: &Pose, plane: Plane, p: V2) -> Pose {
    let (a, b, _) = plane.axes();
    let mut out = *pose;
    out[a] = p.x;
    out[b] = p.y;
    out
}

/// Wraps an angle into (−π, π].
pub fn wrap(angle: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let mut a = angle.rem_euclid(TAU);
    if a > PI {
        a -= TAU;
    }
    a
}
