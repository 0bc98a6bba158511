//! Derivative bounds of blends already bounded, kept for blends that come again.
//!
//! CAM programs repeat their geometry: the same contour at several depths, the same loop
//! along a slot. A blend there has the same derivative polynomials as one before it, only
//! moved, and its bounds ([`super::bounds::derivative_bounds`]) depend on nothing else: the
//! coefficients of P′, the smallest accepted parameter speed and the range of u. A bound
//! found once is looked up by exactly those values, bit for bit, so a hit gives the very
//! result the computation would.
//!
//! The table has a fixed number of slots, made with the planner, so that looking up and
//! storing allocate nothing; a new result takes the slot its key hashes to.

use crate::geom::AxisBounds;

/// Slots in a planner's table (about 0.7 KiB each). The long CAM benchmark program finds
/// 86 % of its look-ups here with 4096 slots, 90 % with 8192 (which plans no faster) and
/// fewer with 2048 (which plans slower).
pub const MEMO_SLOTS: usize = 4096;

/// Values per key: P′'s polynomial coefficients (u¹…u⁵) of the nine pose indices, the
/// smallest parameter speed, the two ends of the range of u and the moving axes.
const KEY_LEN: usize = 9 * 5 + 4;

/// The exact inputs of a bound, as bit patterns (so that −0.0 and 0.0, or two NaNs,
/// differ as the computation might).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct MemoKey([u64; KEY_LEN]);

impl MemoKey {
    /// The key of the bounds of the curve with monomial coefficients `c` and moving axes
    /// `moving` over u ∈ `range` with smallest parameter speed `min_speed`. The position
    /// term `c[i][0]` is left out: the derivatives do not depend on it.
    pub(super) fn new(
        c: &[[f64; 6]; 9],
        moving: &[bool; 9],
        min_speed: f64,
        range: (f64, f64),
    ) -> MemoKey {
        let mut k = [0u64; KEY_LEN];
        k[KEY_LEN - 1] = moving
            .iter()
            .enumerate()
            .fold(0, |m, (i, &on)| m | (u64::from(on) << i));
        for (slot, v) in k.iter_mut().zip(
            c.iter()
                .flat_map(|ci| ci[1..].iter())
                .chain([min_speed, range.0, range.1].iter()),
        ) {
            *slot = v.to_bits();
        }
        MemoKey(k)
    }

    /// Slot index among `slots` (a power of two).
    fn slot(&self, slots: usize) -> usize {
        let mut h: u64 = 0;
        for v in self.0 {
            h = (h.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
        }
        // The high bits mix best.
        (h >> 32) as usize & (slots - 1)
    }
}

/// One stored result.
#[derive(Debug, Clone)]
struct Entry {
    key: MemoKey,
    bounds: Option<AxisBounds>,
}

/// A table of derivative bounds by their exact inputs.
#[derive(Debug)]
pub struct BoundsMemo {
    slots: Vec<Option<Entry>>,
    hits: u64,
    misses: u64,
}

impl BoundsMemo {
    /// A table of `capacity` slots (rounded up to a power of two), all made now; 0 keeps
    /// nothing.
    pub fn new(capacity: usize) -> BoundsMemo {
        let n = if capacity == 0 {
            0
        } else {
            capacity.next_power_of_two()
        };
        BoundsMemo {
            slots: vec![None; n],
            hits: 0,
            misses: 0,
        }
    }

    /// The stored result for `key`, or `compute()`'s, which is then stored.
    pub(super) fn get_or_compute(
        &mut self,
        key: &MemoKey,
        compute: impl FnOnce() -> Option<AxisBounds>,
    ) -> Option<AxisBounds> {
        if self.slots.is_empty() {
            return compute();
        }
        let i = key.slot(self.slots.len());
        if let Some(Some(e)) = self.slots.get(i)
            && e.key == *key
        {
            self.hits += 1;
            return e.bounds;
        }
        self.misses += 1;
        let bounds = compute();
        if let Some(slot) = self.slots.get_mut(i) {
            *slot = Some(Entry { key: *key, bounds });
        }
        bounds
    }

    /// Look-ups answered from the table so far.
    pub fn hits(&self) -> u64 {
        self.hits
    }

    /// Look-ups that computed the bounds so far.
    pub fn misses(&self) -> u64 {
        self.misses
    }
}

/// A copy has a table of its own of the same size, empty (results are the same either way).
impl Clone for BoundsMemo {
    fn clone(&self) -> BoundsMemo {
        BoundsMemo::new(self.slots.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blend::Quintic;
    use crate::geom::PathPoint;
    use klar_interp::Pose;

    /// A corner blend in X Y from (−0.7, 0) along +X to the point 0.7 along the direction
    /// `deg`, lifted to height `z`.
    fn corner(deg: f64, z: f64) -> Quintic {
        let th = deg.to_radians();
        let mut a = PathPoint {
            pose: Pose::ZERO,
            d1: [0.0; 9],
            d2: [0.0; 9],
        };
        let mut b = a;
        a.pose.0[..3].copy_from_slice(&[-0.7, 0.0, z]);
        a.d1[0] = 1.0;
        b.pose.0[..3].copy_from_slice(&[0.7 * th.cos(), 0.7 * th.sin(), z]);
        b.d1[..2].copy_from_slice(&[th.cos(), th.sin()]);
        Quintic::hermite(&a, &b).expect("a corner blend")
    }

    #[test]
    fn a_blend_at_another_depth_takes_the_stored_bounds_which_are_the_computed_ones() {
        let mut memo = BoundsMemo::new(64);
        let first = corner(60.0, 0.0);
        let mut shallow = first.clone();
        let mut deep = corner(60.0, -3.0);
        let mut other = corner(45.0, -3.0);
        for q in [&mut shallow, &mut deep, &mut other] {
            q.finish(&mut memo).expect("bounded");
        }
        // The same corner at another depth was looked up, the other corner computed.
        assert_eq!((memo.hits(), memo.misses()), (1, 2));
        // Each equals what the computation alone gives (`hermite` keeps no table).
        assert_eq!(deep.bounds(), corner(60.0, -3.0).bounds());
        assert_eq!(deep.bounds(), first.bounds());
        assert_eq!(other.bounds(), corner(45.0, -3.0).bounds());
        assert_ne!(other.bounds(), first.bounds());
        // A stretch of it, likewise.
        let len = deep.length();
        let part = deep.bounds_between_in(0.25 * len, 0.5 * len, &mut memo);
        let again = first.bounds_between_in(0.25 * len, 0.5 * len, &mut memo);
        assert_eq!(memo.hits(), 2);
        assert_eq!(part, deep.bounds_between(0.25 * len, 0.5 * len));
        assert_eq!(again, part);
    }

    #[test]
    fn a_table_without_slots_always_computes() {
        let mut memo = BoundsMemo::new(0);
        let mut q = corner(30.0, 0.0);
        q.finish(&mut memo).expect("bounded");
        q.finish(&mut memo).expect("bounded");
        assert_eq!((memo.hits(), memo.misses()), (0, 0));
        assert_eq!(q.bounds(), corner(30.0, 0.0).bounds());
    }
}
