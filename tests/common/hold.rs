//! A run with one feed hold: asked for once the run's status meets a condition, resumed
//! after the commanded position has stood still for a number of cycles, read back from the
//! trace.

use klar::config::MachineConfig;
use klar::runtime::{Run, RunOptions, RunStatus};
use klar::trace::Trace;
use std::path::Path;

/// What happened around the hold.
pub struct Held {
    /// The whole run's trace.
    pub trace: Trace,
    /// The status when the hold was asked for.
    pub asked_at: RunStatus,
    /// Machine time the hold was asked for, s.
    pub asked: f64,
    /// Machine time of the resume, s.
    pub resumed: f64,
}

/// Runs `file` on `machine`, asks for a feed hold the first time `when` says so, resumes
/// once the commanded position has stood still for `rest_rows` cycles, and runs to the end.
/// From the request to the resume the status must show the hold.
pub fn run_with_hold(
    file: &Path,
    machine: &MachineConfig,
    rest_rows: usize,
    when: impl Fn(&RunStatus) -> bool,
) -> Held {
    let mut buf = Vec::new();
    let mut asked: Option<RunStatus> = None;
    let mut resumed = None;
    {
        let mut run = Run::start(
            file,
            machine,
            RunOptions {
                realtime: false,
                trace: Some(&mut buf),
            },
        )
        .unwrap_or_else(|f| panic!("{}", f.error));
        let mut last: Vec<f64> = Vec::new();
        let mut still = 0;
        loop {
            let status = run.status();
            if asked.is_some() && resumed.is_none() {
                assert!(
                    status.held,
                    "the hold shows from the request on: {status:?}"
                );
                still = if status.commanded == last {
                    still + 1
                } else {
                    0
                };
                last.clone_from(&status.commanded);
                if still == rest_rows {
                    run.resume();
                    resumed = Some(status.t);
                }
            }
            if asked.is_none() && when(&status) {
                run.hold();
                asked = Some(status);
            }
            match run.step() {
                Ok(true) => {}
                Ok(false) => break,
                Err(e) => panic!("run failed: {e}"),
            }
        }
        run.finish(None).unwrap_or_else(|f| panic!("{}", f.error));
    }
    let trace = Trace::parse(&String::from_utf8(buf).expect("UTF-8")).expect("trace parses");
    let asked_at = asked.expect("the hold point was reached");
    Held {
        trace,
        asked: asked_at.t,
        asked_at,
        resumed: resumed.expect("the axes came to rest and the run resumed"),
    }
}
