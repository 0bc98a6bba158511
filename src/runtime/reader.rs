//! The program reader: a thread of its own that runs the interpreter, radius compensation
//! and the run's per-op checks (travel, positioning axes), and hands the planner's ops to
//! the servo loop through a bounded queue ([`QUEUE_OPS`] ops, std's array-backed channel:
//! no allocation per message). The interpreter's allocations, its file reads and its
//! frees all happen here, never in the servo loop.
//!
//! Order is kept: an error the reader meets travels down the same queue after the ops
//! before it, so the servo loop finishes the motion of the blocks before the error and
//! then reports it — as a run read in the loop's own thread did.
//!
//! Ops the loop is done with (the events the planner hands back once executed) travel
//! back through a second bounded queue and are freed by the reader, so the servo loop
//! frees no heap memory either; only when that queue is full does the loop drop one
//! itself.

use super::RunError;
use super::stream::OpStream;
use crate::testrun::{check_positioning, check_travel, planner_ops};
use klar_interp::{AxisLetter, Blank, Op, ProbeAnswer, ProbeRequest};
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, RecvError, SyncSender, TryRecvError, sync_channel};

/// Ops the queue from the reader to the servo loop holds.
pub const QUEUE_OPS: usize = 1024;

/// One item from the reader, each with the blocks the interpreter had executed by then.
#[derive(Debug)]
pub enum Feed {
    /// The next op for the planner, and its basis rpm when it is fed per revolution of the
    /// main spindle ([`OpStream::per_rev_basis`]).
    Op(Op, u64, Option<f64>),
    /// The program cannot go on: report this once the motion before it is done.
    Error(RunError, u64),
    /// The program has ended.
    End(u64),
    /// The interpreter waits for the machine to run and measure this probing move (every
    /// op before it came first); the program's BLK FORM for a simulated part. Answer with
    /// [`Reader::answer_probe`].
    Probe(ProbeRequest, Option<Blank>, u64),
}

/// What the reader checks every op against (copies of the run's machine data).
pub struct OpChecks {
    /// Machine axis letters.
    pub letters: Vec<AxisLetter>,
    /// Travel per machine axis.
    pub travel: Vec<[f64; 2]>,
    /// Positioning-only axes: (in-position window, settle timeout).
    pub positioning: Vec<Option<(f64, f64)>>,
    /// The program, for diagnostics.
    pub path: PathBuf,
}

/// The servo loop's end of the reader thread.
pub struct Reader {
    rx: Receiver<Feed>,
    back: SyncSender<Op>,
    answers: SyncSender<ProbeAnswer>,
}

impl Reader {
    /// Starts the reader thread over `ops`.
    pub fn spawn(ops: OpStream, checks: OpChecks) -> std::io::Result<Self> {
        let (tx, rx) = sync_channel(QUEUE_OPS);
        let (back, returned) = sync_channel(QUEUE_OPS);
        let (answers, answered) = sync_channel(1);
        std::thread::Builder::new()
            .name("klar-reader".into())
            .spawn(move || read(ops, &checks, &tx, &returned, &answered))?;
        Ok(Self { rx, back, answers })
    }

    /// The next item: waits for it when `wait`, else `None` when there is none yet (the
    /// reader has not kept up). A reader that ended without saying so (it panicked) reads
    /// as an error.
    pub fn next(&self, wait: bool) -> Option<Feed> {
        let got = if wait {
            self.rx
                .recv()
                .map_err(|RecvError| TryRecvError::Disconnected)
        } else {
            self.rx.try_recv()
        };
        match got {
            Ok(feed) => Some(feed),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => Some(Feed::Error(RunError::ReaderLost, 0)),
        }
    }

    /// The machine's answer to the probing move of a [`Feed::Probe`]: the reader goes on.
    pub fn answer_probe(&self, answer: ProbeAnswer) {
        // an ended reader needs no answer
        let _ = self.answers.try_send(answer);
    }

    /// Hands an op the loop is done with back to be freed by the reader.
    pub fn give_back(&self, op: Op) {
        // A full queue (or an ended reader) hands the op back here: dropped in the loop.
        let _ = self.back.try_send(op);
    }
}

/// The reader thread: reads the program into the queue until it ends, an error, or the
/// servo loop hangs up; frees what comes back meanwhile and after.
fn read(
    mut ops: OpStream,
    checks: &OpChecks,
    tx: &SyncSender<Feed>,
    returned: &Receiver<Op>,
    answered: &Receiver<ProbeAnswer>,
) {
    loop {
        while returned.try_recv().is_ok() {}
        let next = match ops.next() {
            Some(Ok(op)) => check_travel(&op, &checks.letters, &checks.travel, &checks.path)
                .and_then(|()| {
                    check_positioning(&op, &checks.letters, &checks.positioning, &checks.path)
                })
                .map_err(RunError::Program)
                .map(|()| Some(op)),
            Some(Err(e)) => Err(e),
            None => Ok(None),
        };
        let blocks = ops.blocks_executed();
        let basis = ops.per_rev_basis();
        let sent = match next {
            Ok(Some(op)) => planner_ops(op, &checks.letters, &checks.positioning)
                .all(|op| tx.send(Feed::Op(op, blocks, basis)).is_ok()),
            Ok(None) => match ops.probe_request() {
                Some(r) => {
                    let sent = tx.send(Feed::Probe(r, ops.blank(), blocks)).is_ok();
                    // the program goes on once the machine has measured the move
                    match answered.recv() {
                        Ok(a) if sent => {
                            ops.answer_probe(a);
                            true
                        }
                        _ => false,
                    }
                }
                None => {
                    let _ = tx.send(Feed::End(blocks));
                    false
                }
            },
            Err(e) => {
                let _ = tx.send(Feed::Error(e, blocks));
                false
            }
        };
        if !sent {
            break;
        }
    }
    // Free what the loop gives back until it hangs up.
    while returned.recv().is_ok() {}
}
