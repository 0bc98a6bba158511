//! How the dashboard's snapshots leave the machine thread without costing it an allocation
//! or a wait while it steps a run.
//!
//! Each servo cycle the machine thread copies the run's status into a [`Record`] whose
//! buffers were sized before the first cycle, and hands it over through a slot it only ever
//! try-locks: when the publisher is reading the slot, the copy waits for the next cycle and
//! the executed-path points gathered meanwhile stay in the machine thread's record. A
//! publisher thread takes the newest record every [`PUBLISH_PERIOD`], lays it over the last
//! full [`Snapshot`] the machine thread sent (program, messages, probe results: what
//! changes between runs or on rare events) and sends the result to the pages and to the
//! latest-snapshot slot the API reads. Full snapshots and records leave in the order they
//! were made, so a page never sees a run's reading after the snapshot of its end.

use super::{MachineState, Snapshot};
use crate::serve::session::spindle::SpindleStatus;
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use tokio::sync::broadcast;

/// Wall time between two published snapshots while a program runs.
pub const PUBLISH_PERIOD: Duration = Duration::from_millis(40);

/// Executed-path points a record holds until the publisher takes them: at one point every
/// 5 ms of machine time, 1.28 s of path. When the publisher falls further behind, the oldest
/// points give way (the page then draws a straight chord over the gap).
pub const TRAIL_CAPACITY: usize = 256;

/// One servo cycle's reading of a run, in buffers sized before the first cycle: copying one
/// record into another of the same machine allocates nothing.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Record {
    /// Written since the publisher last took it.
    pub fresh: bool,
    /// A feed hold is active or asked for.
    pub held: bool,
    /// Machine time, s.
    pub t: f64,
    /// Program line being executed.
    pub line: u32,
    /// Blocks executed.
    pub blocks: u64,
    /// Commanded position per axis.
    pub commanded: Vec<f64>,
    /// Measured position per axis.
    pub actual: Vec<f64>,
    /// Following error per axis.
    pub following_error: Vec<f64>,
    /// Commanded velocity per axis.
    pub velocity: Vec<f64>,
    /// Commanded acceleration per axis.
    pub acceleration: Vec<f64>,
    /// Path speed, mm/s.
    pub path_speed: f64,
    /// Feed override factor in force.
    pub feed_override: f64,
    /// Single block mode.
    pub single_block: bool,
    /// Measured spindle speed, rpm (signed).
    pub spindle_rpm: Option<f64>,
    /// The spindle, commanded and measured.
    pub spindle: Option<SpindleStatus>,
    /// The tool's measured position in the frame of the program's path.
    pub tool: [f64; 3],
    /// Executed tool positions not yet published, oldest first.
    pub trail: Vec<[f64; 3]>,
}

impl Record {
    /// A record for a machine of `axes` axes, its trail buffer reserved.
    pub fn sized(axes: usize) -> Self {
        Self {
            commanded: vec![0.0; axes],
            actual: vec![0.0; axes],
            following_error: vec![0.0; axes],
            velocity: vec![0.0; axes],
            acceleration: vec![0.0; axes],
            trail: Vec::with_capacity(TRAIL_CAPACITY),
            ..Self::default()
        }
    }

    /// Adds an executed-path point; when the reserved room is full the oldest point gives
    /// way, so this never allocates.
    pub fn push_trail(&mut self, p: [f64; 3]) {
        if self.trail.len() >= TRAIL_CAPACITY {
            self.trail.remove(0);
        }
        if self.trail.len() < self.trail.capacity() {
            self.trail.push(p);
        }
    }

    /// Takes `from`'s reading and moves its trail points over to the end of this record's
    /// (emptying `from`'s); marks this record fresh. Allocates nothing when both records
    /// were sized for the same machine.
    pub fn take_from(&mut self, from: &mut Record) {
        self.held = from.held;
        self.t = from.t;
        self.line = from.line;
        self.blocks = from.blocks;
        copy(&mut self.commanded, &from.commanded);
        copy(&mut self.actual, &from.actual);
        copy(&mut self.following_error, &from.following_error);
        copy(&mut self.velocity, &from.velocity);
        copy(&mut self.acceleration, &from.acceleration);
        self.path_speed = from.path_speed;
        self.feed_override = from.feed_override;
        self.single_block = from.single_block;
        self.spindle_rpm = from.spindle_rpm;
        self.spindle = from.spindle;
        self.tool = from.tool;
        for &p in &from.trail {
            self.push_trail(p);
        }
        from.trail.clear();
        self.fresh = true;
    }

    /// Lays the reading over `snap`, whose other fields (program, messages, probe) stay; a
    /// manual move shows no program line. The trail points are appended.
    pub fn apply(&self, snap: &mut Snapshot) {
        snap.state = if self.held {
            MachineState::Held
        } else {
            MachineState::Running
        };
        snap.t = self.t;
        snap.line = if snap.manual.is_some() { 0 } else { self.line };
        snap.blocks = self.blocks;
        snap.commanded.clone_from(&self.commanded);
        snap.actual.clone_from(&self.actual);
        snap.following_error.clone_from(&self.following_error);
        snap.velocity.clone_from(&self.velocity);
        snap.acceleration.clone_from(&self.acceleration);
        snap.path_speed = self.path_speed;
        snap.feed_override = self.feed_override;
        snap.single_block = self.single_block;
        snap.spindle_rpm = self.spindle_rpm;
        snap.spindle = self.spindle;
        snap.tool = self.tool;
        snap.trail.extend_from_slice(&self.trail);
    }
}

/// Copies `from` into `to` in place when the lengths agree (the case between records of
/// one machine); otherwise makes `to` a copy.
fn copy(to: &mut Vec<f64>, from: &[f64]) {
    if to.len() == from.len() {
        to.copy_from_slice(from);
    } else {
        to.clear();
        to.extend_from_slice(from);
    }
}

/// The slot between the machine thread (try-locks it) and the publisher.
pub type Slot = Arc<Mutex<Record>>;

/// The machine thread's end of the publisher: full snapshots go over a channel, readings
/// through the slot. Dropping it publishes what was sent and ends the publisher thread.
pub struct Publisher {
    full: Option<Sender<Snapshot>>,
    slot: Slot,
    thread: Option<JoinHandle<()>>,
}

impl Publisher {
    /// Starts the publisher thread, which sends to `pages` and keeps `latest` current.
    pub fn start(
        pages: broadcast::Sender<Snapshot>,
        latest: Arc<Mutex<Snapshot>>,
    ) -> std::io::Result<Self> {
        let (full, rx) = std::sync::mpsc::channel();
        let slot: Slot = Arc::new(Mutex::new(Record::default()));
        let taken = slot.clone();
        let thread = std::thread::Builder::new()
            .name("klar-publish".into())
            .spawn(move || publish_loop(&rx, &taken, &pages, &latest))?;
        Ok(Self {
            full: Some(full),
            slot,
            thread: Some(thread),
        })
    }

    /// Sends a full snapshot (made outside the servo cycles).
    pub fn send(&self, snap: Snapshot) {
        if let Some(f) = &self.full {
            // A publisher that ended (it panicked) leaves nobody to tell.
            let _ = f.send(snap);
        }
    }

    /// The slot the machine thread hands its readings through.
    pub fn slot(&self) -> Slot {
        self.slot.clone()
    }

    /// Takes back a reading the publisher has not taken yet (waiting for the slot; for the
    /// moments between servo cycles): its trail points are appended to `snap`'s, and the
    /// slot is left sized for `axes` axes and not fresh.
    pub fn take_back(&self, snap: &mut Snapshot, axes: usize) {
        if let Ok(mut r) = self.slot.lock() {
            if r.fresh {
                snap.trail.extend_from_slice(&r.trail);
            }
            *r = Record::sized(axes);
        }
    }
}

impl Drop for Publisher {
    fn drop(&mut self) {
        self.full = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The publisher thread: publishes each full snapshot as it comes and the newest reading
/// every [`PUBLISH_PERIOD`], numbering them; ends when the machine thread's end is dropped.
fn publish_loop(
    full: &Receiver<Snapshot>,
    slot: &Slot,
    pages: &broadcast::Sender<Snapshot>,
    latest: &Mutex<Snapshot>,
) {
    let mut base: Option<Snapshot> = None;
    let mut reading = Record::sized(0);
    let mut seq = 0u64;
    let mut next = Instant::now() + PUBLISH_PERIOD;
    loop {
        let wait = next.saturating_duration_since(Instant::now());
        match full.recv_timeout(wait) {
            Ok(snap) => {
                let b = base.insert(snap);
                send(b, &mut seq, pages, latest);
            }
            Err(RecvTimeoutError::Timeout) => {
                next = Instant::now() + PUBLISH_PERIOD;
                let taken = match slot.lock() {
                    Ok(mut r) if r.fresh => {
                        reading.take_from(&mut r);
                        r.fresh = false;
                        true
                    }
                    _ => false,
                };
                if taken && let Some(b) = base.as_mut() {
                    reading.apply(b);
                    reading.trail.clear();
                    send(b, &mut seq, pages, latest);
                }
            }
            Err(RecvTimeoutError::Disconnected) => return,
        }
    }
}

/// Numbers `snap`, sends it to the pages and the latest-snapshot slot, and empties its
/// trail (those points are published).
fn send(
    snap: &mut Snapshot,
    seq: &mut u64,
    pages: &broadcast::Sender<Snapshot>,
    latest: &Mutex<Snapshot>,
) {
    *seq += 1;
    snap.seq = *seq;
    if let Ok(mut l) = latest.lock() {
        l.clone_from(snap);
    }
    // No page open is not an error: nobody is watching.
    let _ = pages.send(snap.clone());
    snap.trail.clear();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_trail_drops_its_oldest_points() {
        let mut r = Record::sized(3);
        for k in 0..TRAIL_CAPACITY + 10 {
            r.push_trail([k as f64, 0.0, 0.0]);
        }
        assert_eq!(r.trail.len(), TRAIL_CAPACITY);
        assert_eq!(r.trail[0][0], 10.0);
        assert_eq!(r.trail[TRAIL_CAPACITY - 1][0], (TRAIL_CAPACITY + 9) as f64);
    }

    #[test]
    fn taking_a_reading_moves_its_trail_and_keeps_the_older_points() {
        let mut slot = Record::sized(2);
        let mut mine = Record::sized(2);
        mine.t = 1.5;
        mine.commanded = vec![1.0, 2.0];
        mine.push_trail([1.0, 0.0, 0.0]);
        slot.take_from(&mut mine);
        mine.t = 2.0;
        mine.push_trail([2.0, 0.0, 0.0]);
        slot.take_from(&mut mine);
        assert!(slot.fresh && mine.trail.is_empty());
        assert_eq!(slot.t, 2.0);
        assert_eq!(slot.commanded, [1.0, 2.0]);
        assert_eq!(slot.trail, [[1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]);
    }
}
