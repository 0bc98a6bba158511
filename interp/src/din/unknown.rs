//! Unknown coordinates (`X?`, `Z?`) of straight FINISHED PART elements, solved from the
//! line's angle and its neighbour.
//!
//! A straight element `G1` may carry the angle `A` of its direction: degrees measured from
//! the +Z axis towards +X (counter-clockwise with Z to the right and X up; A180 runs towards
//! the chuck, A90 straight up), in true geometry (X as a radius). A coordinate written `?`,
//! or left out when A is given, is unknown:
//! - one unknown: the line from the element's start in the direction A meets the given
//!   coordinate (`G1 X? Z-20 A150`), which fails when the line runs parallel to that axis;
//! - both unknown (`G1 X? Z? A150`): the end is the intersection of this line with the next
//!   element, which must be a line given by its end point X, Z and its angle A; parallel
//!   lines have no intersection.
//!
//! Other unknowns (in arcs, or without an angle) are reported as not solvable.

use super::block::{DinValue, DinWord};
use crate::diag::ProgramError;

/// Unit direction (dz, dx) of angle `a` degrees.
pub fn direction(a: f64) -> [f64; 2] {
    let (s, c) = a.to_radians().sin_cos();
    [c, s]
}

/// The point where the line from `start` (z, x) in direction `a` reaches the given Z or X.
pub fn along_to(start: [f64; 2], a: f64, z: Option<f64>, x: Option<f64>) -> Option<[f64; 2]> {
    let d = direction(a);
    match (z, x) {
        (Some(z), None) if d[0].abs() > 1e-12 => {
            let t = (z - start[0]) / d[0];
            Some([z, start[1] + t * d[1]])
        }
        (None, Some(x)) if d[1].abs() > 1e-12 => {
            let t = (x - start[1]) / d[1];
            Some([start[0] + t * d[0], x])
        }
        _ => None,
    }
}

/// The intersection of the line through `p1` in direction `a1` with the line through `p2`
/// in direction `a2` (points (z, x), angles in degrees); None for parallel lines.
pub fn intersect(p1: [f64; 2], a1: f64, p2: [f64; 2], a2: f64) -> Option<[f64; 2]> {
    let (d1, d2) = (direction(a1), direction(a2));
    let cross = d1[0] * d2[1] - d1[1] * d2[0];
    if cross.abs() < 1e-12 {
        return None;
    }
    let w = [p2[0] - p1[0], p2[1] - p1[1]];
    let t = (w[0] * d2[1] - w[1] * d2[0]) / cross;
    Some([p1[0] + t * d1[0], p1[1] + t * d1[1]])
}

/// What a straight element says about its end point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LineSpec {
    /// Z given (absolute).
    pub z: Option<f64>,
    /// X given (absolute, radius).
    pub x: Option<f64>,
    /// Zi given.
    pub zi: Option<f64>,
    /// Xi given (radius).
    pub xi: Option<f64>,
    /// The angle A.
    pub angle: Option<f64>,
    /// Z unknown (written `Z?`, or left out with A).
    pub z_unknown: bool,
    /// X unknown.
    pub x_unknown: bool,
    /// The byte position of the first unknown word (or of A).
    pub pos: Option<usize>,
}

/// Reads X/Z/A of a `G1` group's words.
pub(crate) fn line_spec(words: &[DinWord]) -> Result<LineSpec, (usize, ProgramError)> {
    let mut spec = LineSpec {
        z: None,
        x: None,
        zi: None,
        xi: None,
        angle: None,
        z_unknown: false,
        x_unknown: false,
        pos: None,
    };
    for w in words {
        let value = match &w.value {
            DinValue::Num(v) => Some(*v),
            DinValue::Unknown => None,
            _ => continue,
        };
        match (w.addr.as_str(), value) {
            ("Z", Some(v)) => spec.z = Some(v),
            ("X", Some(v)) => spec.x = Some(v / 2.0),
            ("Z", None) => {
                spec.z_unknown = true;
                spec.pos.get_or_insert(w.pos);
            }
            ("X", None) => {
                spec.x_unknown = true;
                spec.pos.get_or_insert(w.pos);
            }
            ("Zi", Some(v)) => spec.zi = Some(v),
            ("Xi", Some(v)) => spec.xi = Some(v / 2.0),
            ("A", Some(v)) => {
                spec.angle = Some(v);
                spec.pos.get_or_insert(w.pos);
            }
            (a, None) => {
                return Err((
                    w.pos,
                    ProgramError::NotSupported(format!("{a}? (only X? and Z? are solved)")),
                ));
            }
            _ => {}
        }
    }
    if spec.angle.is_some() {
        spec.z_unknown |= spec.z.is_none() && spec.zi.is_none();
        spec.x_unknown |= spec.x.is_none() && spec.xi.is_none();
    }
    Ok(spec)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_meet_where_worked_out_by_hand() {
        // from (0, 10) at 45°: reaches z = 5 at x = 15
        let p = along_to([0.0, 10.0], 45.0, Some(5.0), None).unwrap();
        assert!((p[0] - 5.0).abs() < 1e-12 && (p[1] - 15.0).abs() < 1e-12);
        // a line at 90° never reaches another Z
        assert!(along_to([0.0, 10.0], 90.0, Some(5.0), None).is_none());
        // x = 10 + t (45° up from (0, 10)) meets the line through (-20, 20) at 180°
        // (x = 20): t = 10 → (10, 20)
        let p = intersect([0.0, 10.0], 45.0, [-20.0, 20.0], 180.0).unwrap();
        assert!((p[0] - 10.0).abs() < 1e-12 && (p[1] - 20.0).abs() < 1e-12);
        assert!(intersect([0.0, 0.0], 30.0, [5.0, 5.0], 210.0).is_none());
    }
}
