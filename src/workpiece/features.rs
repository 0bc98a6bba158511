//! Straight features of the simulated part: slots cut from its top and ridges standing on it,
//! each a rectangle along a centre line from `from` to `to` (any direction in the part's XY
//! plane, square ends), and bolt-hole circles, which become bores.
//!
//! A slot or ridge is a box in its own frame (along the centre line, across it, up): the
//! signed distance to it is exact, so the probing search of [`super::SimWorkpiece`] keeps its
//! bound. A slot that runs past the part's box is open at that end.

use super::Bore;

/// A straight slot cut into the top of the part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slot {
    /// Start of the centre line, part X/Y, mm.
    pub from: [f64; 2],
    /// End of the centre line, part X/Y, mm.
    pub to: [f64; 2],
    /// Width across the centre line, mm.
    pub width: f64,
    /// Depth below the top of the box, mm.
    pub depth: f64,
}

/// A straight ridge (a rectangular bar) standing on the top of the part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ridge {
    /// Start of the centre line, part X/Y, mm.
    pub from: [f64; 2],
    /// End of the centre line, part X/Y, mm.
    pub to: [f64; 2],
    /// Width across the centre line, mm.
    pub width: f64,
    /// Height above the top of the box, mm.
    pub height: f64,
}

/// Bores on a circle: `count` holes evenly spread from `start` degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoleCircle {
    /// Centre of the circle, part X/Y, mm.
    pub centre: [f64; 2],
    /// Diameter of the circle through the hole centres, mm.
    pub diameter: f64,
    /// Number of holes.
    pub count: u32,
    /// Polar angle of the first hole, degrees.
    pub start: f64,
    /// Diameter of each hole, mm.
    pub hole_diameter: f64,
    /// Depth of each hole below the top, mm.
    pub depth: f64,
}

impl HoleCircle {
    /// The holes as bores.
    pub fn bores(&self) -> Vec<Bore> {
        let step = 360.0 / f64::from(self.count.max(1));
        (0..self.count)
            .map(|k| {
                let (s, c) = (self.start + step * f64::from(k)).to_radians().sin_cos();
                Bore {
                    centre: [
                        self.centre[0] + self.diameter / 2.0 * c,
                        self.centre[1] + self.diameter / 2.0 * s,
                    ],
                    diameter: self.hole_diameter,
                    depth: self.depth,
                }
            })
            .collect()
    }
}

/// Signed distance from part point `q` to the box along the line `from`–`to` of half width
/// `half` between heights `z0` and `z1` (negative inside).
pub(super) fn bar_distance(
    q: [f64; 3],
    from: [f64; 2],
    to: [f64; 2],
    half: f64,
    z0: f64,
    z1: f64,
) -> f64 {
    let d = [to[0] - from[0], to[1] - from[1]];
    let len = d[0].hypot(d[1]);
    let (u, n) = if len > 0.0 {
        ([d[0] / len, d[1] / len], [-d[1] / len, d[0] / len])
    } else {
        ([1.0, 0.0], [0.0, 1.0])
    };
    let r = [q[0] - from[0], q[1] - from[1]];
    let along = r[0] * u[0] + r[1] * u[1];
    let across = r[0] * n[0] + r[1] * n[1];
    let ex = [
        (along - len / 2.0).abs() - len / 2.0,
        across.abs() - half,
        (q[2] - (z0 + z1) / 2.0).abs() - (z1 - z0) / 2.0,
    ];
    let outside = ex.iter().map(|e| e.max(0.0).powi(2)).sum::<f64>().sqrt();
    let inside = ex[0].max(ex[1]).max(ex[2]).min(0.0);
    outside + inside
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slanted_bar_measures_across_its_centre_line() {
        // a bar from (0,0) to (10,10), half width 1, z 0..2: a point 3 off the line
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let p = [5.0 - 3.0 * s, 5.0 + 3.0 * s, 1.0];
        let d = bar_distance(p, [0.0, 0.0], [10.0, 10.0], 1.0, 0.0, 2.0);
        assert!((d - 2.0).abs() < 1e-12, "{d}");
        // inside: the nearest face is the top, 1 away
        let d = bar_distance([5.0, 5.0, 1.5], [0.0, 0.0], [10.0, 10.0], 1.0, 0.0, 2.0);
        assert!((d + 0.5).abs() < 1e-12, "{d}");
    }

    #[test]
    fn a_hole_circle_spreads_its_bores_evenly() {
        let c = HoleCircle {
            centre: [1.0, 2.0],
            diameter: 40.0,
            count: 3,
            start: 90.0,
            hole_diameter: 8.0,
            depth: 5.0,
        };
        let b = c.bores();
        assert_eq!(b.len(), 3);
        assert!((b[0].centre[0] - 1.0).abs() < 1e-12 && (b[0].centre[1] - 22.0).abs() < 1e-12);
        let r = (b[1].centre[0] - 1.0).hypot(b[1].centre[1] - 2.0);
        assert!((r - 20.0).abs() < 1e-12);
    }
}
