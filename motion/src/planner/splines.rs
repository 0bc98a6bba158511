//! Spline elements kept in slots made when the planner is built, so that pushing a spline
//! block allocates nothing in the servo thread.
//!
//! The same scheme as the blend curves' pool: every slot is an [`Arc`] made up front; a
//! new spline is written into a slot that only the pool still holds, and the waiting
//! element and the pieces cut from it share the slot by cloning the reference. When every
//! slot is held by splines still ahead, the spline gets an `Arc` of its own (an
//! allocation, counted: [`SplinePool::overflowed`]); the path is the same either way.

use crate::geom::Poly;
use std::sync::Arc;

/// Spline elements a planner keeps slots for: those waiting or committed and still ahead
/// of the machine. Each slot takes about 1.1 KiB.
pub const SPLINE_SLOTS: usize = 1024;

/// Preallocated slots for spline elements.
#[derive(Debug)]
pub struct SplinePool {
    slots: Vec<Arc<Poly>>,
    /// Where the search for a free slot starts (the slot after the last one taken).
    next: usize,
    /// Splines that found every slot held.
    overflowed: u64,
}

impl SplinePool {
    /// A pool of `capacity` slots, all made now.
    pub fn new(capacity: usize) -> SplinePool {
        SplinePool {
            slots: (0..capacity)
                .map(|_| Arc::new(Poly::placeholder()))
                .collect(),
            next: 0,
            overflowed: 0,
        }
    }

    /// Writes `poly` into a slot nothing else holds and returns a shared reference to it;
    /// when every slot is held, a reference of its own (allocated, counted).
    pub fn store(&mut self, poly: Poly) -> Arc<Poly> {
        let n = self.slots.len();
        for k in 0..n {
            let i = (self.next + k) % n;
            if let Some(slot) = self.slots.get_mut(i)
                && let Some(free) = Arc::get_mut(slot)
            {
                *free = poly;
                self.next = (i + 1) % n;
                return Arc::clone(slot);
            }
        }
        self.overflowed += 1;
        Arc::new(poly)
    }

    /// Splines that found every slot held and were given an allocation of their own.
    pub fn overflowed(&self) -> u64 {
        self.overflowed
    }
}

/// A copy has slots of its own (made now), so that neither pool writes into a spline the
/// other's pieces still follow.
impl Clone for SplinePool {
    fn clone(&self) -> SplinePool {
        SplinePool {
            overflowed: self.overflowed,
            ..SplinePool::new(self.slots.len())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use klar_interp::Pose;
    use klar_interp::op::SplineAxis;

    fn spline(x: f64) -> Poly {
        let from = Pose::default();
        let mut to = Pose::default();
        to.0[0] = x;
        // t runs from 1 to 0: the start is the end plus K3 + K2 + K1.
        let axes = [SplineAxis {
            axis: klar_interp::AxisLetter::X,
            k: [0.0, 0.0, -x],
        }];
        match Poly::new(from, to, &axes) {
            Ok(Some(p)) => p,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_slot_is_reused_once_nothing_follows_its_spline() {
        let mut pool = SplinePool::new(2);
        let a = pool.store(spline(1.0));
        let b = pool.store(spline(2.0));
        assert!(!Arc::ptr_eq(&a, &b));
        assert_eq!((a.length(), b.length()), (1.0, 2.0));
        // Both held: the third gets its own allocation.
        let c = pool.store(spline(3.0));
        assert_eq!(pool.overflowed(), 1);
        assert_eq!(c.length(), 3.0);
        // Once `a` is let go its slot takes the next spline.
        let a_ptr = Arc::as_ptr(&a);
        drop(a);
        let d = pool.store(spline(4.0));
        assert_eq!(Arc::as_ptr(&d), a_ptr);
        assert_eq!((d.length(), b.length()), (4.0, 2.0));
        assert_eq!(pool.overflowed(), 1);
    }
}
