//! Real-time settings for the thread that runs the servo loop: the SCHED_FIFO scheduling
//! class and locked memory. Both need privileges (root, CAP_SYS_NICE / CAP_IPC_LOCK, or an
//! rtprio / memlock limit); a refusal is reported, and the caller says so and goes on
//! without.

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
    // SAFETY: mlockall takes flags only.
    let locked = if unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } == 0 {
        Ok(())
    } else {
        Err(RtError::Lock(last_os_error()))
    };
    RtStatus { fifo, locked }
}
