//! The dashboard's machine thread does not allocate while it steps a run: it copies each
//! cycle's status into a record made before the first cycle, and a publisher thread builds
//! the page's snapshots from it. A counting global allocator counts the allocations,
//! reallocations and frees the machine thread makes between its first and last servo cycle
//! of a served run on the simulated mill, while the snapshots still show the run moving.

use klar::config::MachineConfig;
use klar::serve::session::{Command, MachineLoop, MachineState, SteppingHooks, idle_snapshot};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use tokio::sync::broadcast;

mod common;
#[path = "common/counting.rs"]
mod counting;

/// Allocations and frees the machine thread counted while it stepped, as of its last
/// stepping hook.
static ALLOCS: AtomicU64 = AtomicU64::new(0);
static FREES: AtomicU64 = AtomicU64::new(0);

fn begin() {
    counting::begin();
}

fn end() {
    counting::end();
    let (allocs, frees) = counting::counts();
    ALLOCS.store(allocs, Ordering::Relaxed);
    FREES.store(frees, Ordering::Relaxed);
}

/// Lines, an arc and the spindle turning: every field of the snapshot changes. About two
/// seconds on the wall clock.
const PROGRAM: &str = "\
0 BEGIN PGM SERVED MM
1 BLK FORM 0.1 Z X-50 Y-50 Z-20
2 BLK FORM 0.2 X+50 Y+50 Z+0
3 TOOL CALL 1 Z S2000
4 L Z+5 R0 FMAX M3
5 L X+10 Y+0 F1500
6 CC X+0 Y+0
7 C X-10 Y+0 DR+
8 L X-10 Y-10 F1500
9 L Z+5 FMAX M5
10 END PGM SERVED MM
";

#[test]
fn the_machine_thread_does_not_allocate_while_it_steps_a_served_run() {
    let path = common::temp_program("served.h", PROGRAM);
    let config = MachineConfig::builtin_mill();
    let (tx, rx) = std::sync::mpsc::channel();
    let (snapshots, mut pages) = broadcast::channel(4096);
    let latest = Arc::new(Mutex::new(idle_snapshot(&config)));
    let slot = latest.clone();
    let machine = std::thread::spawn(move || {
        MachineLoop::new(config, rx, snapshots, slot)
            .expect("the publisher starts")
            .with_stepping_hooks(SteppingHooks { begin, end })
            .run();
    });
    tx.send(Command::Load {
        name: "served.h".into(),
        path,
    })
    .expect("machine thread");
    tx.send(Command::Start(None)).expect("machine thread");
    let (mut moving, mut trail, mut last_t, mut turning) = (0u32, 0usize, 0.0f64, false);
    let mut seq = 0u64;
    let last = loop {
        let s = match pages.blocking_recv() {
            Ok(s) => s,
            Err(broadcast::error::RecvError::Lagged(_)) => continue,
            Err(e) => panic!("snapshots ended: {e}"),
        };
        assert!(s.seq > seq, "snapshot numbers increase");
        seq = s.seq;
        if matches!(s.state, MachineState::Running) && s.t > 0.0 {
            assert!(s.t >= last_t, "machine time runs forward");
            last_t = s.t;
            moving += 1;
            trail += s.trail.len();
            turning |= s.spindle_rpm.is_some_and(|r| r > 0.0);
        }
        if matches!(
            s.state,
            MachineState::Finished | MachineState::Error | MachineState::Fault
        ) {
            break s;
        }
    };
    drop(tx);
    machine.join().expect("machine thread");
    assert_eq!(last.state, MachineState::Finished, "{:?}", last.message);
    // The run was seen moving, its trail and its spindle, and it ended where the program
    // ends (X-10 Y-10 Z+5).
    assert!(moving >= 5 && trail > 50 && turning, "{moving} {trail}");
    for (got, want) in last.commanded.iter().zip([-10.0, -10.0, 5.0]) {
        assert!((got - want).abs() < 1e-6, "{:?}", last.commanded);
    }
    let (allocs, frees) = (
        ALLOCS.load(Ordering::Relaxed),
        FREES.load(Ordering::Relaxed),
    );
    assert_eq!(
        (allocs, frees),
        (0, 0),
        "allocations and frees in the machine thread while it stepped"
    );
}
