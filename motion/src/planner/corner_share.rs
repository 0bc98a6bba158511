//! Sharing an axis between the two sides of an overlapped corner.
//!
//! Where the departure from a stop corner starts before the braking into it has ended
//! (see `overlap`), an axis that moves on both sides gets the sum of their accelerations
//! and jerks. At a finishing pass that ends on a slope and lifts in Z, Z brakes with the
//! slope's small share of the pass's jerk while the lift starts Z with all of its own. The
//! side that moves such an axis much more (the lift) then plans with that axis's limits
//! lowered by what the other side may use of them, so the two fit together. The cost is a
//! ramp a few per cent slower on one short element; where the smaller share is more than
//! [`MOST_SHARED`] of a limit, nothing is lowered and the overlap keeps to what the planned
//! motions allow as they are.

use crate::config::AxisLimits;

/// Largest share of an axis's acceleration or jerk limit the side with the smaller use of
/// that axis may take from the other side.
const MOST_SHARED: f64 = 0.1;

/// Factor on the smaller side's estimated use of a shared axis when it is taken off the
/// other side's limits: the estimate is that of a straight line along the corner's
/// tangent, while the braking into a corner of dense code runs on its blends, and the
/// departure from it may be a curve fitted through the chords ahead.
const SHARE_MARGIN: f64 = 1.5;

/// Acceleration and jerk taken off each axis's limits for an element's own pieces.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Derate {
    /// Acceleration taken off, mm/s² (or °/s²), per program axis.
    accel: [f64; 9],
    /// Jerk taken off, mm/s³ (or °/s³), per program axis.
    jerk: [f64; 9],
}

impl Derate {
    /// True when no limit is lowered.
    pub fn is_none(&self) -> bool {
        self.accel.iter().chain(&self.jerk).all(|x| *x == 0.0)
    }

    /// The axis limits with the shares taken off.
    pub fn apply(&self, limits: &[Option<AxisLimits>; 9]) -> [Option<AxisLimits>; 9] {
        let mut out = *limits;
        for (i, l) in out.iter_mut().enumerate() {
            if let Some(l) = l {
                l.max_acceleration -= self.accel[i];
                l.max_jerk -= self.jerk[i];
            }
        }
        out
    }
}

/// Path acceleration and jerk a straight motion along the unit tangent `u` may use within
/// the axis limits.
fn path_limits(u: &[f64; 9], limits: &[Option<AxisLimits>; 9]) -> (f64, f64) {
    let (mut accel, mut jerk) = (f64::INFINITY, f64::INFINITY);
    for (c, l) in u.iter().zip(limits) {
        if let Some(l) = l
            && *c != 0.0
        {
            accel = accel.min(l.max_acceleration / c.abs());
            jerk = jerk.min(l.max_jerk / c.abs());
        }
    }
    (accel, jerk)
}

/// The derates of the element before a stop corner (leaving along `before`, the unit
/// tangent at its end) and of the one after it (starting along `after`), added to
/// `ends` and `starts`.
pub fn share_corner(
    before: &[f64; 9],
    after: &[f64; 9],
    limits: &[Option<AxisLimits>; 9],
    ends: &mut Derate,
    starts: &mut Derate,
) {
    let (a1, j1) = path_limits(before, limits);
    let (a2, j2) = path_limits(after, limits);
    if !(a1.is_finite() && j1.is_finite() && a2.is_finite() && j2.is_finite()) {
        return;
    }
    for (i, l) in limits.iter().enumerate() {
        let Some(l) = l else { continue };
        let (c1, c2) = (before[i].abs(), after[i].abs());
        if c1 == 0.0 || c2 == 0.0 {
            continue;
        }
        // What each side uses of this axis at its path limits.
        let (accel1, jerk1) = (c1 * a1, c1 * j1);
        let (accel2, jerk2) = (c2 * a2, c2 * j2);
        let (small_accel, small_jerk, target) = if jerk1 <= jerk2 {
            (accel1, jerk1, &mut *starts)
        } else {
            (accel2, jerk2, &mut *ends)
        };
        if small_jerk <= MOST_SHARED * l.max_jerk && small_accel <= MOST_SHARED * l.max_acceleration
        {
            target.jerk[i] = target.jerk[i].max(SHARE_MARGIN * small_jerk);
            target.accel[i] = target.accel[i].max(SHARE_MARGIN * small_accel);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_machine::limits as bench;
    use super::*;

    fn unit(x: f64, y: f64, z: f64) -> [f64; 9] {
        let n = (x * x + y * y + z * z).sqrt();
        let mut u = [0.0; 9];
        u[..3].copy_from_slice(&[x / n, y / n, z / n]);
        u
    }

    #[test]
    fn a_lift_after_a_sloped_pass_gives_up_the_pass_share_of_z() {
        // The pass leaves along X with Z falling 0.012 mm per mm; the lift goes up in Z.
        let pass = unit(1.0, 0.0, -0.012);
        let lift = unit(0.0, 0.0, 1.0);
        let (mut ends, mut starts) = (Derate::default(), Derate::default());
        share_corner(&pass, &lift, &bench(), &mut ends, &mut starts);
        assert!(ends.is_none());
        // The pass runs at X's limits: path jerk 1e5/|u_x|, of which Z takes |u_z|.
        let share = SHARE_MARGIN * pass[2].abs() / pass[0].abs();
        let limits = starts.apply(&bench());
        let z = limits[2].expect("Z");
        assert!(
            (z.max_jerk - 1e5 * (1.0 - share)).abs() < 1e-6,
            "{}",
            z.max_jerk
        );
        assert!((z.max_acceleration - 1000.0 * (1.0 - share)).abs() < 1e-9);
        assert_eq!(limits[0], bench()[0]);
        // A lift into a sloped pass is the same corner backwards: the lift gives up again.
        let (mut ends, mut starts) = (Derate::default(), Derate::default());
        share_corner(
            &lift,
            &unit(1.0, 0.0, 0.012),
            &bench(),
            &mut ends,
            &mut starts,
        );
        assert!(starts.is_none());
        assert_eq!(ends.apply(&bench())[2], Some(z));
    }

    #[test]
    fn an_even_share_lowers_nothing() {
        // Two diagonals that share X equally: neither may give up half of X.
        let (mut ends, mut starts) = (Derate::default(), Derate::default());
        let (a, b) = (unit(1.0, 1.0, 0.0), unit(1.0, -1.0, 0.0));
        share_corner(&a, &b, &bench(), &mut ends, &mut starts);
        assert!(ends.is_none() && starts.is_none());
    }
}
