//! Real-time settings for the thread that runs the servo loop: the SCHED_FIFO scheduling
//! class and locked memory. Both need privileges (root, CAP_SYS_NICE / CAP_IPC_LOCK, or an
//! rtprio / memlock limit); a refusal is reported, and the caller says so and goes on
//! without.
//!
//! Also the way bytes leave the servo loop without a file write in it: [`ChunkWriter`]
//! copies them into fixed-size chunks handed through a bounded queue (std's array-backed
//! channel: no allocation per message, no lock on the way in while there is room) to a
//! thread that writes them out ([`drain`]).

use std::io::{self, Write};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};

/// Bytes per chunk handed from the servo loop to the writer thread.
pub const CHUNK: usize = 8192;
/// Chunks the queue holds (a full queue makes the loop wait: it shows as lateness).
pub const QUEUE_CHUNKS: usize = 512;

/// One chunk of bytes and how many of them are used.
pub type Chunk = ([u8; CHUNK], usize);

/// The servo loop's end of the queue: an [`io::Write`] that fills a chunk in place and
/// hands it over when full or flushed.
pub struct ChunkWriter {
    chunk: Box<Chunk>,
    tx: SyncSender<Chunk>,
    /// Chunks that found the queue full (the loop waited for room).
    pub waited: u64,
}

/// A queue to a writer thread: the servo loop's [`ChunkWriter`] and the receiving end for
/// [`drain`].
pub fn chunk_queue() -> (ChunkWriter, Receiver<Chunk>) {
    let (tx, rx) = sync_channel(QUEUE_CHUNKS);
    let writer = ChunkWriter {
        chunk: Box::new(([0; CHUNK], 0)),
        tx,
        waited: 0,
    };
    (writer, rx)
}

impl ChunkWriter {
    fn hand_over(&mut self) -> io::Result<()> {
        if self.chunk.1 == 0 {
            return Ok(());
        }
        let full = *self.chunk;
        self.chunk.1 = 0;
        match self.tx.try_send(full) {
            Ok(()) => Ok(()),
            Err(TrySendError::Full(c)) => {
                self.waited += 1;
                self.tx.send(c).map_err(|_| closed())
            }
            Err(TrySendError::Disconnected(_)) => Err(closed()),
        }
    }
}

fn closed() -> io::Error {
    io::Error::new(io::ErrorKind::BrokenPipe, "the writer thread has ended")
}

impl Write for ChunkWriter {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.chunk.1 == CHUNK {
            self.hand_over()?;
        }
        let used = self.chunk.1;
        let n = buf.len().min(CHUNK - used);
        if let (Some(dst), Some(src)) = (self.chunk.0.get_mut(used..used + n), buf.get(..n)) {
            dst.copy_from_slice(src);
        }
        self.chunk.1 += n;
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.hand_over()
    }
}

/// The writer thread's loop: writes every chunk to `out` until the [`ChunkWriter`] is
/// dropped, then flushes.
pub fn drain(rx: Receiver<Chunk>, mut out: impl Write) -> io::Result<()> {
    while let Ok((bytes, n)) = rx.recv() {
        out.write_all(bytes.get(..n).unwrap_or(&bytes))?;
    }
    out.flush()
}

/// The SCHED_FIFO priority klar asks for: above ordinary threads and the kernel's threaded
/// interrupt handlers' default of 50, below the top priorities the kernel keeps for itself.
pub const FIFO_PRIORITY: i32 = 80;

/// A real-time setting the system refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RtError {
    /// `sched_setscheduler(SCHED_FIFO)` failed.
    #[error("SCHED_FIFO priority {priority} refused: {message}")]
    Fifo {
        /// The priority asked for.
        priority: i32,
        /// The system's reason.
        message: String,
    },
    /// `mlockall` failed.
    #[error("locking memory refused: {0}")]
    Lock(String),
}

/// What [`make_realtime`] got.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RtStatus {
    /// SCHED_FIFO, or why not.
    pub fifo: Result<i32, RtError>,
    /// Memory locked, or why not.
    pub locked: Result<(), RtError>,
}

impl std::fmt::Display for RtStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.fifo {
            Ok(p) => write!(f, "SCHED_FIFO priority {p}")?,
            Err(e) => write!(f, "no real-time priority ({e})")?,
        }
        match &self.locked {
            Ok(()) => write!(f, ", memory locked"),
            Err(e) => write!(f, ", memory not locked ({e})"),
        }
    }
}

/// Locks present and future pages, unless a memory-lock limit would make later allocations
/// fail (an unprivileged process with a finite RLIMIT_MEMLOCK).
fn lock_memory() -> Result<(), RtError> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: `limit` is a valid, writable rlimit.
    let got = unsafe { libc::getrlimit(libc::RLIMIT_MEMLOCK, &mut limit) } == 0;
    // SAFETY: geteuid has no preconditions.
    let root = unsafe { libc::geteuid() } == 0;
    if got && !root && limit.rlim_cur != libc::RLIM_INFINITY {
        return Err(RtError::Lock(format!(
            "the memory-lock limit is {} kB (ulimit -l unlimited or CAP_IPC_LOCK needed)",
            limit.rlim_cur / 1024
        )));
    }
    // SAFETY: mlockall takes flags only.
    if unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } == 0 {
        Ok(())
    } else {
        Err(RtError::Lock(last_os_error()))
    }
}

fn last_os_error() -> String {
    std::io::Error::last_os_error().to_string()
}

/// Puts the calling thread in SCHED_FIFO at `priority` and locks the process's memory
/// (present and future pages), each as far as the system allows.
pub fn make_realtime(priority: i32) -> RtStatus {
    let param = libc::sched_param {
        sched_priority: priority,
    };
    // SAFETY: `param` is a valid sched_param; pid 0 is the calling thread.
    let fifo = if unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } == 0 {
        Ok(priority)
    } else {
        Err(RtError::Fifo {
            priority,
            message: last_os_error(),
        })
    };
    let locked = lock_memory();
    RtStatus { fifo, locked }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_arrive_whole_and_in_order() {
        let (mut w, rx) = chunk_queue();
        let writer = std::thread::spawn(move || {
            let mut out = Vec::new();
            drain(rx, &mut out).map(|()| out)
        });
        let mut expected = Vec::new();
        for i in 0..5000u32 {
            let line = format!("{i},{}\n", f64::from(i) * 0.001);
            expected.extend_from_slice(line.as_bytes());
            w.write_all(line.as_bytes()).expect("queued");
        }
        w.flush().expect("flushed");
        drop(w);
        let got = writer.join().expect("writer thread").expect("written");
        assert_eq!(got, expected);
    }
}
