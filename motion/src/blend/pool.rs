//! Blend curves kept in slots made when the planner is built, so that committing a corner
//! allocates nothing in the servo thread.
//!
//! Every slot is an [`Arc`] made up front. A new blend is written into a slot that nothing
//! else holds (only the pool's own reference is left once the pieces that followed the
//! curve have been passed), and the pieces of that blend share the slot by cloning the
//! reference, which allocates nothing either. When every slot is held by pieces still
//! ahead, no blend can be made: the caller stops exactly at that corner instead, and the
//! pool counts it ([`BlendPool::refused`]).

use super::{BoundsMemo, MEMO_SLOTS, Quintic};
use std::sync::Arc;

/// Blend curves a planner keeps slots for: blends of the committed path still ahead of
/// the machine. The look-ahead of the densest bench program (a CAM pocket of 0.01–0.1 mm
/// chords) holds about 700 at once; each slot takes about 1 KiB.
pub const BLEND_SLOTS: usize = 4096;

/// Preallocated slots for blend curves.
#[derive(Debug)]
pub struct BlendPool {
    slots: Vec<Arc<Quintic>>,
    /// Where the search for a free slot starts (the slot after the last one taken).
    next: usize,
    /// Corners that found every slot taken.
    refused: u64,
    /// Blends stored so far.
    stored: u64,
    /// Derivative bounds of the blends made so far, for blends that come again.
    memo: BoundsMemo,
}

impl BlendPool {
    /// A pool of `capacity` slots, all made now, with a table of [`MEMO_SLOTS`] derivative
    /// bounds.
    pub fn new(capacity: usize) -> BlendPool {
        BlendPool {
            slots: (0..capacity)
                .map(|_| Arc::new(Quintic::default()))
                .collect(),
            next: 0,
            refused: 0,
            stored: 0,
            memo: BoundsMemo::new(MEMO_SLOTS),
        }
    }

    /// The table of derivative bounds the blends of this pool are made with.
    pub fn memo(&mut self) -> &mut BoundsMemo {
        &mut self.memo
    }

    /// Number of slots.
    pub fn capacity(&self) -> usize {
        self.slots.len()
    }

    /// Index of a slot that nothing but the pool holds, searching from the one after the
    /// last taken.
    fn free_slot(&self) -> Option<usize> {
        let n = self.slots.len();
        (0..n).map(|k| (self.next + k) % n).find(|&i| {
            Arc::strong_count(&self.slots[i]) == 1 && Arc::weak_count(&self.slots[i]) == 0
        })
    }

    /// True when a blend can be stored (counts nothing).
    pub fn has_free(&self) -> bool {
        self.free_slot().is_some()
    }

    /// True when a blend can be stored; when not, counts the corner as refused.
    pub fn can_store(&mut self) -> bool {
        let free = self.free_slot().is_some();
        if !free {
            self.refused += 1;
        }
        free
    }

    /// Writes `curve` into a free slot and returns a reference to it; `None` when every
    /// slot is held (call [`BlendPool::can_store`] first to count the corner).
    pub fn store(&mut self, curve: Quintic) -> Option<Arc<Quintic>> {
        let i = self.free_slot()?;
        let n = self.slots.len();
        let slot = self.slots.get_mut(i)?;
        *Arc::get_mut(slot)? = curve;
        let out = Arc::clone(slot);
        self.next = (i + 1) % n;
        self.stored += 1;
        Some(out)
    }

    /// Slots held by pieces now (looks at every slot: for diagnostics, not the loop).
    pub fn held(&self) -> usize {
        self.slots
            .iter()
            .filter(|s| Arc::strong_count(s) > 1)
            .count()
    }

    /// Blends stored so far.
    pub fn stored(&self) -> u64 {
        self.stored
    }

    /// Corners that were stopped at exactly because every slot was held.
    pub fn refused(&self) -> u64 {
        self.refused
    }
}

/// A copy has slots of its own (made now), so that neither pool writes into a curve the
/// other's pieces still follow; it starts with the original's counts.
impl Clone for BlendPool {
    fn clone(&self) -> BlendPool {
        BlendPool {
            refused: self.refused,
            stored: self.stored,
            ..BlendPool::new(self.capacity())
        }
    }
}
