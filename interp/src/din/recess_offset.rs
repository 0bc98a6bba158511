//! The offset width `B` of recess turning G869.
//!
//! What the CNC PILOT / MANUALplus DIN manuals say of it, in our words (the G869 parameter
//! list and the recess-turning unit that calls G869 describe it alike):
//!
//! - From the second plunge on, a turning pass that is followed by a plunge stops short of
//!   the end of its stretch by the offset, and the tool plunges there. This happens on one
//!   side only: the side where the first shortened pass ends, which with passes back and
//!   forth (U0) is the side of the first plunge, the NS end. Each further pass that turns
//!   into a plunge on that side stops short by `B` more: the j-th by j·B.
//! - The offsets add up to at most 80 % of the effective cutting width (the cutting width
//!   less twice the cutting radius); the control cuts the programmed offset down to that.
//!   klar's recess-turning tool has square corners (G869 takes its width `SB` and no
//!   radius), so the limit is 0.8·SB.
//! - When the roughing is done, what the shortened passes left at that side goes in a
//!   single cut.
//!
//! How klar runs that single cut: the material left lies under the tool's width at the NS
//! end of each level whose pass neither began nor ended there. The tool comes down at rapid
//! to the safety distance above the last level that was cut fully at that end, then plunges
//! at the recessing feed; where the NS end of the next level lies further in (a sloping
//! wall), it first plunges to the level above and moves there along that level at the
//! turning feed, so it never leaves the stretch of a level it stands on. After the deepest
//! level with material left it lifts at rapid to the safety distance above the area. The
//! largest offset is less than the tool's width, so one plunge clears every step.
//!
//! Passes that run one way (U1) never turn into a plunge (the tool lifts after each), so
//! the manual's rule has nothing to act on there: G869 refuses `B` with U1.

use super::grooving::SAFETY;

/// The share of the cutting width the offsets may add up to.
pub const LIMIT: f64 = 0.8;

/// The offsets of the shortened passes, one after another.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Offsets {
    /// B.
    step: f64,
    /// The most the offsets add up to.
    most: f64,
    /// How many passes were shortened so far.
    count: u32,
}

impl Offsets {
    /// Offsets of `step` for a tool `width` wide.
    pub(crate) fn new(step: f64, width: f64) -> Self {
        Self {
            step,
            most: LIMIT * width,
            count: 0,
        }
    }

    /// Whether passes are shortened at all.
    pub(crate) fn active(&self) -> bool {
        self.step > 0.0
    }

    /// The offset of the next shortened pass: j·B for the j-th, at most the limit.
    pub(crate) fn next(&mut self) -> f64 {
        self.count += 1;
        (self.step * f64::from(self.count)).min(self.most)
    }
}

/// A move of the clean-up cut.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Step {
    /// At rapid.
    Rapid,
    /// Plunging, at the recessing feed.
    Plunge,
    /// Along a level, at the turning feed.
    Turn,
}

/// The single cut after the roughing, in the cycle's plane (u along the contour, v the
/// depth): `levels` the depth of each level, `ns` the NS end of its stretch, `left` whether
/// its pass left material at that end, `above` the safety height above the area. Empty
/// when nothing was left.
pub(crate) fn clean_up(
    levels: &[f64],
    ns: &[f64],
    left: &[bool],
    above: f64,
) -> Vec<(Step, [f64; 2])> {
    let (Some(first), Some(last)) = (left.iter().position(|l| *l), left.iter().rposition(|l| *l))
    else {
        return Vec::new();
    };
    let (Some(&z0), Some(&bottom)) = (ns.get(first), levels.get(last)) else {
        return Vec::new();
    };
    // the level above the first one with material left was cut fully at this end
    let done = first
        .checked_sub(1)
        .and_then(|k| levels.get(k))
        .map_or(above, |v| (v + SAFETY).min(above));
    let mut out = vec![(Step::Rapid, [z0, above])];
    if done < above {
        out.push((Step::Rapid, [z0, done]));
    }
    let mut z = z0;
    for k in first + 1..=last {
        let (Some(&to), Some(&upper)) = (ns.get(k), levels.get(k - 1)) else {
            break;
        };
        if (to - z).abs() > 1e-12 {
            out.push((Step::Plunge, [z, upper]));
            out.push((Step::Turn, [to, upper]));
            z = to;
        }
    }
    out.push((Step::Plunge, [z, bottom]));
    out.push((Step::Rapid, [z, above]));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_grow_by_b_up_to_four_fifths_of_the_width() {
        // B1.5 with a 4 mm tool: 1.5, 3, then 3.2 (0.8 · 4) for ever
        let mut o = Offsets::new(1.5, 4.0);
        let got: Vec<f64> = (0..4).map(|_| o.next()).collect();
        assert_eq!(got, vec![1.5, 3.0, 3.2, 3.2]);
        assert!(!Offsets::new(0.0, 4.0).active());
    }

    #[test]
    fn clean_up_plunges_once_at_a_straight_wall_and_steps_along_a_sloped_one() {
        // nothing left: no cut
        assert!(clean_up(&[3.0, 2.0], &[0.0, 0.0], &[false, false], 5.0).is_empty());
        // levels 1 and 2 left at the same NS end: down at rapid to 1 above level 0, one
        // plunge to level 2, up again
        let c = clean_up(
            &[4.0, 3.0, 2.0, 1.0],
            &[0.0; 4],
            &[false, true, true, false],
            6.0,
        );
        assert_eq!(
            c,
            vec![
                (Step::Rapid, [0.0, 6.0]),
                (Step::Rapid, [0.0, 5.0]),
                (Step::Plunge, [0.0, 2.0]),
                (Step::Rapid, [0.0, 6.0]),
            ]
        );
        // the NS end moves in at level 2: plunge to level 1, along it, on down
        let c = clean_up(
            &[4.0, 3.0, 2.0],
            &[0.0, 0.0, 0.5],
            &[false, true, true],
            4.5,
        );
        assert_eq!(
            c,
            vec![
                (Step::Rapid, [0.0, 4.5]),
                (Step::Plunge, [0.0, 3.0]),
                (Step::Turn, [0.5, 3.0]),
                (Step::Plunge, [0.5, 2.0]),
                (Step::Rapid, [0.5, 4.5]),
            ]
        );
    }
}
