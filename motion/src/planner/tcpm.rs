//! Limits of the program axes while TCPM is on (M128, FUNCTION TCPM) on a table-table
//! machine, such that every machine axis stays within its own limits.
//!
//! The planner limits the program axes: the tool tip `p` in workpiece coordinates and the
//! rotary axes. The machine's linear axes follow
//! `m = P_t + R_t·((P_c − P_t) + R_c·(p − P_c))` (see `kinematics::table_table`), where `R_t`
//! and `R_c` are the rotations of the tilt and table axes.
//!
//! *At fixed table angles* each machine linear axis is a row of a rotation applied to `ṗ`, so
//! with every program axis within `L` it moves at most `√3·L`: the program's linear axes get
//! `1/√3` of the smallest linear machine limit ([`TCPM_DERATE`]).
//!
//! *While the table turns* the rotation adds motion of its own. With `ω`, `α`, `ζ` the sums
//! of the rotary axes' rates, accelerations and jerks (rad/s, rad/s², rad/s³) and `D` a bound
//! of the tip's distance from the table axis plus the distance between the two pivots, the
//! product rule and the triangle inequality give, for the machine's linear motion,
//!
//! ```text
//! |ṁ| ≤ |ṗ| + ω·D
//! |m̈| ≤ |p̈| + 2ω·|ṗ| + (α + ω²)·D
//! |m⃛| ≤ |p⃛| + 3ω·|p̈| + 3(α + ω²)·|ṗ| + (ζ + 3ω·α + ω³)·D
//! ```
//!
//! (a rotation matrix `R(θ(t))` has `|Ṙx| ≤ ω|x|`, `|R̈x| ≤ (α + ω²)|x|`,
//! `|R⃛x| ≤ (ζ + 3ωα + ω³)|x|`, and the bounds of a product of two rotations add up with the
//! sums of the rates). On a move that turns a rotary axis the program's linear axes get half
//! of the fixed-angle share, so `|ṗ| ≤ V/2`, `|p̈| ≤ A/2`, `|p⃛| ≤ J/2` (V, A, J the smallest
//! linear machine limits), and the rotation is limited so that it uses the other half:
//! `ω·D ≤ V/2`; `2ω·(V/2) + ω²·D ≤ A/4` and `α·D ≤ A/4`; the cross terms of the jerk
//! within `J/4` and `ζ·D ≤ J/4`. The rotary program axes share ω, α and ζ equally.
//!
//! `D` is computed per piece of the path from where its tip positions lie, so a tip near
//! the table axis turns fast and one far from it slowly.
//!
//! *The feed of the compensating moves* (`M128 F…`, the op's `compensation_feed` `F_c`): the
//! turning adds at most `ω·D` to the speed of the linear machine axes (the second term of
//! the first bound), so `ω·D ≤ F_c` keeps the compensating moves within it; the limit is one
//! more cap on `ω` next to `V/2` (a feed above the machine's share changes nothing, as on a
//! control whose machine parameter caps the programmed value).

use crate::config::AxisLimits;
use crate::geom::letter;

/// Share of each linear axis's velocity, acceleration and jerk the program's linear axes get
/// while TCPM is on and the rotary axes stand still (`1/√3`, see the module notes).
pub const TCPM_DERATE: f64 = 0.577_350_269_189_625_8;

/// Where the table's axes are: enough to bound the linear motion a rotation causes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableGeometry {
    /// A point on the table (C) axis, machine coordinates at zero angles (mm).
    pub table_pivot: [f64; 3],
    /// Distance between the table pivot and the tilt pivot (mm).
    pub pivot_gap: f64,
}

impl TableGeometry {
    /// The table geometry from the pivots of the tilt and the table axis.
    pub fn new(tilt_pivot: [f64; 3], table_pivot: [f64; 3]) -> TableGeometry {
        let gap = (0..3)
            .map(|i| (table_pivot[i] - tilt_pivot[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        TableGeometry {
            table_pivot,
            pivot_gap: gap,
        }
    }

    /// The reach `D` for tip positions within `spread` of the points `ends` (tool tip X Y Z
    /// in workpiece coordinates).
    pub fn reach(&self, ends: &[[f64; 3]], spread: f64) -> f64 {
        let far = ends
            .iter()
            .map(|p| {
                (0..3)
                    .map(|i| (p[i] - self.table_pivot[i]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(0.0, f64::max);
        far + spread + self.pivot_gap
    }
}

/// The smallest velocity, acceleration and jerk over the linear axes.
fn linear_floor(base: &[Option<AxisLimits>; 9]) -> Option<AxisLimits> {
    let mut floor: Option<AxisLimits> = None;
    for (i, l) in base.iter().enumerate() {
        if let Some(l) = l
            && !letter(i).is_rotary()
        {
            floor = Some(match floor {
                None => *l,
                Some(f) => AxisLimits {
                    max_velocity: f.max_velocity.min(l.max_velocity),
                    max_acceleration: f.max_acceleration.min(l.max_acceleration),
                    max_jerk: f.max_jerk.min(l.max_jerk),
                },
            });
        }
    }
    floor
}

/// Every linear program axis gets `share` of the smallest linear machine limits (never more
/// than its own).
fn derate_linear(base: &[Option<AxisLimits>; 9], share: f64) -> [Option<AxisLimits>; 9] {
    let mut out = *base;
    let Some(floor) = linear_floor(base) else {
        return out;
    };
    for (i, l) in out.iter_mut().enumerate() {
        if let Some(l) = l
            && !letter(i).is_rotary()
        {
            l.max_velocity = l.max_velocity.min(floor.max_velocity * share);
            l.max_acceleration = l.max_acceleration.min(floor.max_acceleration * share);
            l.max_jerk = l.max_jerk.min(floor.max_jerk * share);
        }
    }
    out
}

/// The limits for the program axes while TCPM is on and the rotary axes stand still.
pub fn fixed_limits(base: &[Option<AxisLimits>; 9]) -> [Option<AxisLimits>; 9] {
    derate_linear(base, TCPM_DERATE)
}

/// The limits for the program axes on a move that turns a rotary axis while TCPM is on, for
/// tip positions within reach `d` (mm, see [`TableGeometry::reach`]), the turning's share of
/// the linear machine axes' speed kept within `compensation_feed` (mm/s) when there is one.
pub fn turning_limits(
    base: &[Option<AxisLimits>; 9],
    d: f64,
    compensation_feed: Option<f64>,
) -> [Option<AxisLimits>; 9] {
    let mut out = derate_linear(base, 0.5 * TCPM_DERATE);
    let Some(floor) = linear_floor(base) else {
        return out;
    };
    let (v, a, j) = (floor.max_velocity, floor.max_acceleration, floor.max_jerk);
    let d = d.max(1e-3);
    // ω·D ≤ V/2 and ω·V + ω²·D ≤ A/4.
    let mut omega = (0.5 * v / d).min((-v + (v * v + d * a).sqrt()) / (2.0 * d));
    // ω·D ≤ F_c: the compensating moves within the feed M128 F gave them.
    if let Some(fc) = compensation_feed.filter(|f| f.is_finite() && *f > 0.0) {
        omega = omega.min(fc / d);
    }
    let mut alpha = 0.25 * a / d;
    // Never more than the rotary axes can do together anyway.
    let deg = 180.0 / std::f64::consts::PI;
    let (own_w, own_a) = base
        .iter()
        .enumerate()
        .filter(|(i, _)| letter(*i).is_rotary())
        .filter_map(|(_, l)| *l)
        .fold((0.0, 0.0), |(w, al), l| {
            (w + l.max_velocity / deg, al + l.max_acceleration / deg)
        });
    if own_w > 0.0 {
        omega = omega.min(own_w);
        alpha = alpha.min(own_a);
    }
    // Cross terms of the jerk within J/4: shrink ω and α together until they fit.
    let cross =
        |w: f64, al: f64| 1.5 * w * a + 1.5 * (al + w * w) * v + (3.0 * w * al + w * w * w) * d;
    if cross(omega, alpha) > 0.25 * j {
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..50 {
            let mid = 0.5 * (lo + hi);
            if cross(omega * mid, alpha * mid) <= 0.25 * j {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        omega *= lo;
        alpha *= lo;
    }
    let zeta = 0.25 * j / d;
    let rotary = out
        .iter()
        .enumerate()
        .filter(|(i, l)| l.is_some() && letter(*i).is_rotary())
        .count()
        .max(1) as f64;
    for (i, l) in out.iter_mut().enumerate() {
        if let Some(l) = l
            && letter(i).is_rotary()
        {
            l.max_velocity = l.max_velocity.min(omega / rotary * deg);
            l.max_acceleration = l.max_acceleration.min(alpha / rotary * deg);
            l.max_jerk = l.max_jerk.min(zeta / rotary * deg);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(v: f64, a: f64, j: f64) -> AxisLimits {
        AxisLimits {
            max_velocity: v,
            max_acceleration: a,
            max_jerk: j,
        }
    }

    /// X Y Z at 166/2000/50000 (Z 100/1500/40000), A and C at 90 and 180 °/s.
    fn mill5() -> [Option<AxisLimits>; 9] {
        let mut l = [None; 9];
        l[0] = Some(limits(166.0, 2000.0, 50_000.0));
        l[1] = Some(limits(166.0, 2000.0, 50_000.0));
        l[2] = Some(limits(100.0, 1500.0, 40_000.0));
        l[3] = Some(limits(90.0, 720.0, 10_000.0));
        l[5] = Some(limits(180.0, 1440.0, 20_000.0));
        l
    }

    #[test]
    fn fixed_angles_give_the_linear_axes_a_third_of_the_norm() {
        let l = fixed_limits(&mill5());
        for x in l.iter().take(3) {
            let x = x.expect("linear axis");
            assert!((x.max_velocity - 100.0 / 3f64.sqrt()).abs() < 1e-9);
            assert!((x.max_acceleration - 1500.0 / 3f64.sqrt()).abs() < 1e-9);
        }
        // Rotary axes keep their limits at fixed angles.
        assert_eq!(l[5], mill5()[5]);
    }

    #[test]
    fn a_turning_tip_never_drives_a_machine_axis_past_its_limits() {
        // The worst case of the bound: the tip held at distance D from the table axis (the
        // pivots coincide) while C turns at its derated rate, speeding up and down at its
        // derated acceleration: the tip describes a circle of radius D in the machine.
        let base = mill5();
        for d in [1e-3, 10.0, 100.0, 500.0] {
            let l = turning_limits(&base, d, None);
            let rad = std::f64::consts::PI / 180.0;
            let c = l[5].expect("C");
            let a = l[3].expect("A");
            let (w, al, ze) = (
                (c.max_velocity + a.max_velocity) * rad,
                (c.max_acceleration + a.max_acceleration) * rad,
                (c.max_jerk + a.max_jerk) * rad,
            );
            // Closed forms of the circle's motion at rate w, angular acceleration al and
            // jerk ze: speed w·D, acceleration √(al² + w⁴)·D, jerk ≤ (ze + 3·w·al + w³)·D.
            assert!(w * d <= 0.5 * 100.0 + 1e-9, "{d}: {}", w * d);
            assert!((al * al + w.powi(4)).sqrt() * d <= 0.5 * 1500.0 + 1e-9);
            assert!((ze + 3.0 * w * al + w.powi(3)) * d <= 0.5 * 40_000.0 + 1e-9);
            // The rotation of the program's own acceleration and speed (Coriolis-like
            // terms) within the jerk share left for it, even next to the axis.
            let cross =
                3.0 * w * 750.0 + 3.0 * (al + w * w) * 50.0 + (3.0 * w * al + w.powi(3)) * d;
            assert!(cross <= 0.25 * 40_000.0 * (1.0 + 1e-9), "{d}: {cross}");
            // The linear program axes: half the fixed-angle share.
            let x = l[0].expect("X");
            assert!((x.max_velocity - 50.0 / 3f64.sqrt()).abs() < 1e-9);
        }
    }

    #[test]
    fn the_compensation_feed_caps_what_the_turning_adds_to_the_linear_axes() {
        let base = mill5();
        let rad = std::f64::consts::PI / 180.0;
        let d = 150.0;
        let free = turning_limits(&base, d, None);
        // 500 mm/min = 8.33 mm/s: the rotary rates together give ω·D = 8.33 mm/s, shared
        // equally by A and C
        let capped = turning_limits(&base, d, Some(500.0 / 60.0));
        let (a, c) = (capped[3].expect("A"), capped[5].expect("C"));
        let omega = (a.max_velocity + c.max_velocity) * rad;
        assert!((omega * d - 500.0 / 60.0).abs() < 1e-9, "{}", omega * d);
        assert!((c.max_velocity - 0.5 * 500.0 / 60.0 / d / rad).abs() < 1e-9);
        // the programmed tip keeps its share, acceleration and jerk stay as they were
        assert_eq!(capped[0], free[0]);
        assert!(c.max_acceleration <= free[5].expect("C").max_acceleration);
        // a feed above the machine's own share changes nothing
        assert_eq!(turning_limits(&base, d, Some(1e6)), free);
    }

    #[test]
    fn the_reach_adds_the_spread_and_the_pivot_gap() {
        let g = TableGeometry::new([0.0, 0.0, -100.0], [0.0, 0.0, 0.0]);
        assert!((g.pivot_gap - 100.0).abs() < 1e-12);
        let r = g.reach(&[[30.0, 40.0, 0.0], [0.0, 0.0, 10.0]], 2.0);
        assert!((r - (50.0 + 2.0 + 100.0)).abs() < 1e-12);
    }
}
