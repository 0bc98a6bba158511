//! Building one blend and proving it stays inside the tolerance band.
//!
//! The blend is sampled at [`DEVIATION_SAMPLES`] interior points; each point's distance
//! from the programmed contour near the corner (the parts of the two elements the blend
//! replaces) must stay below [`TOLERANCE_SHARE`] of the tolerance. Distances to a line part
//! are exact; to an arc, helix or spline part they are taken to a fine polyline through it
//! plus the largest sagitta of that polyline, which can only overstate the distance.

use super::Quintic;
use crate::geom::{Metric, PathPoint, Segment};
use klar_interp::Pose;

/// Interior sample points at which a blend's deviation is measured.
pub const DEVIATION_SAMPLES: usize = 32;

/// Share of the tolerance a blend may use at its sample points (the rest covers the curve
/// between samples).
pub const TOLERANCE_SHARE: f64 = 0.9;

/// Chords per curved contour part when measuring distances to it.
const CURVE_CHORDS: usize = 32;

/// A stretch `[from, to]` (path distance) of a programmed element.
#[derive(Debug, Clone, Copy)]
pub struct ContourPart<'a> {
    /// The element.
    pub segment: &'a Segment,
    /// Start of the stretch.
    pub from: f64,
    /// End of the stretch.
    pub to: f64,
}

/// The blend from `start` to `end` (poses with unit tangents and curvature vectors) if it
/// keeps within `tolerance` of `contour`; with its measured largest deviation.
pub fn blend_within(
    start: &PathPoint,
    end: &PathPoint,
    contour: &[ContourPart<'_>],
    tolerance: f64,
) -> Option<(Quintic, f64)> {
    // The tolerance check needs only the curve's shape; the rest is computed once it passes.
    let curve = Quintic::shape(start, end)?;
    let limit = TOLERANCE_SHARE * tolerance;
    let polylines: Vec<Polyline> = contour.iter().map(Polyline::through).collect();
    let mut worst = 0.0f64;
    for k in 1..DEVIATION_SAMPLES {
        let p = curve.pose_at_parameter(k as f64 / DEVIATION_SAMPLES as f64);
        let d = polylines
            .iter()
            .map(|line| line.distance(&p))
            .fold(f64::INFINITY, f64::min);
        // NaN distances count as too far.
        if d.is_nan() || d > limit {
            return None;
        }
        worst = worst.max(d);
    }
    Some((curve.finish()?, worst))
}

/// Distance (over X Y Z U V W) from `p` to a stretch of an element; never less than the
/// true distance.
pub fn distance_to_part(p: &Pose, part: &ContourPart<'_>) -> f64 {
    Polyline::through(part).distance(p)
}

/// A stretch of an element as chords through it, with the largest distance of the stretch
/// from its chords (0 for a line).
struct Polyline {
    points: Vec<Pose>,
    sagitta: f64,
}

impl Polyline {
    fn through(part: &ContourPart<'_>) -> Polyline {
        let (a, b) = (part.from.min(part.to), part.from.max(part.to));
        match part.segment {
            Segment::Line(_) => Polyline {
                points: vec![part.segment.position(a), part.segment.position(b)],
                sagitta: 0.0,
            },
            seg => {
                let bounds = seg.bounds();
                let kappa = Metric::Linear.norm(&bounds.d2);
                let h = (b - a) / CURVE_CHORDS as f64;
                Polyline {
                    points: (0..=CURVE_CHORDS)
                        .map(|k| seg.position(a + h * k as f64))
                        .collect(),
                    sagitta: h * h * kappa / 8.0,
                }
            }
        }
    }

    /// Distance from `p`, never less than the true distance from the stretch.
    fn distance(&self, p: &Pose) -> f64 {
        self.points
            .windows(2)
            .map(|w| distance_to_chord(p, &w[0], &w[1]))
            .fold(f64::INFINITY, f64::min)
            + self.sagitta
    }
}

/// Distance from `p` to the straight chord from `a` to `b` over the linear axes.
fn distance_to_chord(p: &Pose, a: &Pose, b: &Pose) -> f64 {
    let axes = Metric::Linear.axes();
    let (mut ab2, mut ap_ab) = (0.0, 0.0);
    for &i in axes {
        let ab = b.0[i] - a.0[i];
        ab2 += ab * ab;
        ap_ab += (p.0[i] - a.0[i]) * ab;
    }
    let t = if ab2 > 0.0 {
        (ap_ab / ab2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    axes.iter()
        .map(|&i| {
            let q = a.0[i] + t * (b.0[i] - a.0[i]);
            (p.0[i] - q).powi(2)
        })
        .sum::<f64>()
        .sqrt()
}
