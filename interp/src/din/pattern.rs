//! Hole patterns: circular (G745 on the face, G746 on the lateral surface), the angles of the
//! positions from A, W or Wi, Q and V, as the DIN manual specifies them for G745; and linear
//! (G743, G744), Q positions in a row from a first one.
//!
//! Rules: Q positions (default 1) starting at A (default 0°). V=0 without W: the full circle
//! is divided into Q equal steps; V=0 with W: the longer of the two arcs from A to W is
//! divided, first and last position on A and W; V=0 with Wi: Wi is the step, its sign gives
//! the direction (Wi<0 clockwise); V=1: clockwise, V=2: counter-clockwise, from A to W (or in
//! steps of |Wi|, the sign of Wi ignored). W and Wi together are an error, so is Q<1. Angles
//! are in degrees, counter-clockwise positive seen onto the face (looking in −Z).

use crate::diag::ProgramError;

/// How the end of the pattern is given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PatternEnd {
    /// Neither W nor Wi.
    None,
    /// W: angle of the last position.
    EndAngle(f64),
    /// Wi: angle increment between positions.
    Increment(f64),
}

/// The angular layout of a circular pattern.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CircleLayout {
    /// A: angle of the first position, degrees.
    pub start: f64,
    /// W or Wi.
    pub end: PatternEnd,
    /// Q: number of positions (≥ 1).
    pub count: u32,
    /// V: direction rule 0, 1 (clockwise) or 2 (counter-clockwise).
    pub direction: u8,
}

impl CircleLayout {
    /// The step between positions, degrees (signed: positive counter-clockwise).
    pub fn step(&self) -> Result<f64, ProgramError> {
        if self.count == 0 {
            return Err(ProgramError::OutOfRange(
                "pattern count Q must be at least 1".into(),
            ));
        }
        let n = f64::from(self.count);
        // spans of the two arcs from A to W
        let spans = |w: f64| {
            let ccw = (w - self.start).rem_euclid(360.0);
            let ccw = if ccw == 0.0 { 360.0 } else { ccw };
            (ccw, 360.0 - ccw)
        };
        let divide = |span: f64| {
            if self.count == 1 {
                0.0
            } else if span == 360.0 || span == 0.0 {
                // end on the start: the whole circle, no position twice
                360.0 / n
            } else {
                span / (n - 1.0)
            }
        };
        Ok(match (self.direction, self.end) {
            (0, PatternEnd::None) => 360.0 / n,
            (0, PatternEnd::EndAngle(w)) => {
                let (ccw, cw) = spans(w);
                if ccw >= cw { divide(ccw) } else { -divide(cw) }
            }
            (0, PatternEnd::Increment(wi)) => wi,
            (1, PatternEnd::None) => -360.0 / n,
            (2, PatternEnd::None) => 360.0 / n,
            (1, PatternEnd::EndAngle(w)) => {
                let (_, cw) = spans(w);
                -divide(if cw == 0.0 { 360.0 } else { cw })
            }
            (2, PatternEnd::EndAngle(w)) => divide(spans(w).0),
            (1, PatternEnd::Increment(wi)) => -wi.abs(),
            (2, PatternEnd::Increment(wi)) => wi.abs(),
            (v, _) => {
                return Err(ProgramError::OutOfRange(format!(
                    "pattern direction V{v}: expected 0, 1 or 2"
                )));
            }
        })
    }

    /// The angles of all positions, in machining order.
    pub fn angles(&self) -> Result<Vec<f64>, ProgramError> {
        let step = self.step()?;
        Ok((0..self.count)
            .map(|k| self.start + step * f64::from(k))
            .collect())
    }
}

/// How a linear pattern continues from its first position, per coordinate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LinearStep {
    /// The coordinate of the last position: the span is divided into Q − 1 equal steps.
    To(f64),
    /// The distance between neighbouring positions.
    By(f64),
}

/// The positions of a linear pattern: `count` points from `start`, each coordinate
/// advancing as `steps` says (None: it stays). With one position only the start remains.
pub fn linear_positions(
    start: [f64; 2],
    steps: [Option<LinearStep>; 2],
    count: u32,
) -> Vec<[f64; 2]> {
    let gaps = f64::from(count.saturating_sub(1).max(1));
    let step = |k: usize| match steps.get(k).copied().flatten() {
        None => 0.0,
        Some(LinearStep::By(d)) => d,
        Some(LinearStep::To(end)) => (end - start.get(k).copied().unwrap_or(0.0)) / gaps,
    };
    let (d0, d1) = (step(0), step(1));
    (0..count)
        .map(|k| {
            let k = f64::from(k);
            [start[0] + k * d0, start[1] + k * d1]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout(start: f64, end: PatternEnd, count: u32, direction: u8) -> CircleLayout {
        CircleLayout {
            start,
            end,
            count,
            direction,
        }
    }

    #[test]
    fn longer_arc_is_divided_for_v0_with_w() {
        // A=0, W=90: the ccw arc is 90°, the cw arc 270° → the cw arc, 4 positions: 0, -90, …
        let a = layout(0.0, PatternEnd::EndAngle(90.0), 4, 0)
            .angles()
            .unwrap();
        assert_eq!(a, vec![0.0, -90.0, -180.0, -270.0]);
        // A=0, W=270: the ccw arc is the longer one
        let a = layout(0.0, PatternEnd::EndAngle(270.0), 4, 0)
            .angles()
            .unwrap();
        assert_eq!(a, vec![0.0, 90.0, 180.0, 270.0]);
    }

    #[test]
    fn linear_layouts_divide_the_span_or_step() {
        let p = linear_positions([0.0, 10.0], [Some(LinearStep::To(30.0)), None], 4);
        assert_eq!(
            p,
            vec![[0.0, 10.0], [10.0, 10.0], [20.0, 10.0], [30.0, 10.0]]
        );
        let p = linear_positions(
            [1.0, 2.0],
            [Some(LinearStep::By(-1.5)), Some(LinearStep::By(2.0))],
            3,
        );
        assert_eq!(p, vec![[1.0, 2.0], [-0.5, 4.0], [-2.0, 6.0]]);
        let p = linear_positions([5.0, 5.0], [Some(LinearStep::To(9.0)), None], 1);
        assert_eq!(p, vec![[5.0, 5.0]]);
    }

    #[test]
    fn zero_count_and_bad_direction_fail() {
        assert!(layout(0.0, PatternEnd::None, 0, 0).angles().is_err());
        assert!(layout(0.0, PatternEnd::None, 2, 3).angles().is_err());
    }
}
