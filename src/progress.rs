//! The `klar run` progress bar: percent of the program's machine time (the test run's planned
//! time; percent of its lines only when there is none), program line and machine time, drawn
//! on standard error only when it is a terminal. Machine time, not lines: one cycle call on a
//! single line can take most of a program's time.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use klar::config::MachineConfig;
use klar::runtime::{OperatorStop, Run, RunFailure, RunOptions, RunReport};
use std::io::IsTerminal;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::time::Duration;

/// Wall time between two redraws of the bar.
const REDRAW: Duration = Duration::from_millis(100);

/// Runs `program` to its end like `run_program`, with a progress bar on a terminal unless
/// `quiet`; the run watches `stop` (the signals) when given.
pub fn run_with_progress(
    program: &Path,
    config: &MachineConfig,
    options: RunOptions<'_>,
    quiet: bool,
    stop: Option<OperatorStop>,
) -> Result<RunReport, Box<RunFailure>> {
    let show = !quiet && std::io::stderr().is_terminal();
    let mut run = Run::start(program, config, options)?;
    if let Some(stop) = stop {
        run.watch_operator_stop(stop);
    }
    let lines = if show { count_lines(program) } else { 0 };
    let scale = Scale::new(run.planned_time(), lines);
    let bar = if show {
        let bar = ProgressBar::with_draw_target(Some(scale.len()), ProgressDrawTarget::stderr());
        let style =
            ProgressStyle::with_template("{bar:32.cyan/blue} {percent:>3}%  {msg}  [{elapsed}]")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> ");
        bar.set_style(style);
        bar
    } else {
        ProgressBar::hidden()
    };
    let slot = Slot::default();
    let ended = std::thread::scope(|scope| {
        // The bar is drawn by a thread of its own from the slot the loop fills: the loop
        // neither formats nor writes to the terminal, nor waits for the one that does.
        if show {
            let (bar, slot) = (&bar, &slot);
            let drawn = std::thread::Builder::new()
                .name("klar-progress".into())
                .spawn_scoped(scope, move || draw(bar, slot, scale, lines));
            if let Err(e) = drawn {
                tracing::warn!("no progress bar: {e}");
            }
        }
        let ended = loop {
            let stepped = run.step();
            slot.publish(run.line(), run.time());
            match stepped {
                Ok(true) => {}
                Ok(false) => break None,
                Err(e) => break Some(e),
            }
        };
        slot.done.store(true, Ordering::Release);
        ended
    });
    if show {
        let (t, line) = (run.time(), run.line());
        bar.set_position(if ended.is_none() {
            scale.len()
        } else {
            scale.position(t, line)
        });
        bar.set_message(scale.message(t, line, lines));
        bar.abandon();
    }
    run.finish(ended)
}

/// What the bar counts: milliseconds of the planned machine time, or lines without one.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Scale {
    /// The test run's planned machine time, s.
    Time(f64),
    /// The program's lines.
    Lines(u64),
}

impl Scale {
    fn new(planned: Option<f64>, lines: u64) -> Self {
        match planned {
            Some(t) if t.is_finite() && t > 0.0 => Scale::Time(t),
            _ => Scale::Lines(lines),
        }
    }

    /// The bar's length.
    fn len(self) -> u64 {
        match self {
            Scale::Time(t) => (t * 1000.0).round().max(1.0) as u64,
            Scale::Lines(n) => n,
        }
    }

    /// The bar's position at machine time `t` on program line `line`; below the end until
    /// the run has ended (a run slower than planned, under a feed override, waits at 99 %).
    fn position(self, t: f64, line: u32) -> u64 {
        match self {
            Scale::Time(_) => ((t * 1000.0).max(0.0) as u64).min(self.len().saturating_sub(1)),
            Scale::Lines(_) => u64::from(line),
        }
    }

    fn message(self, t: f64, line: u32, lines: u64) -> String {
        match self {
            Scale::Time(total) => {
                format!("machine time {t:.3} of {total:.3} s  line {line}/{lines}")
            }
            Scale::Lines(_) => format!("line {line}/{lines}  machine time {t:.3} s"),
        }
    }
}

/// Where the servo loop leaves its progress for the thread that draws the bar: atomics,
/// written every cycle and read every redraw, neither side ever waiting for the other (a
/// line and a time from neighbouring cycles may be shown together, which a bar does not
/// mind).
#[derive(Default)]
struct Slot {
    line: AtomicU32,
    /// Machine time, s, as the bits of an f64.
    t: AtomicU64,
    /// The run has ended.
    done: AtomicBool,
}

impl Slot {
    fn publish(&self, line: u32, t: f64) {
        self.line.store(line, Ordering::Relaxed);
        self.t.store(t.to_bits(), Ordering::Relaxed);
    }
}

/// Redraws the bar from the slot every [`REDRAW`] until the run ends.
fn draw(bar: &ProgressBar, slot: &Slot, scale: Scale, lines: u64) {
    while !slot.done.load(Ordering::Acquire) {
        let line = slot.line.load(Ordering::Relaxed);
        let t = f64::from_bits(slot.t.load(Ordering::Relaxed));
        bar.set_position(scale.position(t, line));
        bar.set_message(scale.message(t, line, lines));
        std::thread::sleep(REDRAW);
    }
}

/// Lines of the program file (for the percentage); 0 when it cannot be read.
fn count_lines(program: &Path) -> u64 {
    use std::io::BufRead;
    if klar_interp::not_a_file(program).is_some() {
        return 0;
    }
    let Ok(f) = std::fs::File::open(program) else {
        return 0;
    };
    // counted in the reader's buffer: a line of any length costs no memory
    let mut r = std::io::BufReader::new(f);
    let mut lines = 0u64;
    loop {
        let n = match r.fill_buf() {
            Ok([]) | Err(_) => return lines,
            Ok(buf) => {
                lines += buf.iter().filter(|&&b| b == b'\n').count() as u64;
                buf.len()
            }
        };
        r.consume(n);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bar_counts_machine_time_when_it_is_known() {
        // One long cycle on line 5 of 9 that takes 40 of 50 s: the bar follows the time.
        let s = Scale::new(Some(50.0), 9);
        assert_eq!(s.len(), 50_000);
        assert_eq!(s.position(30.0, 5), 30_000);
        // A run slower than planned does not reach the end before it ends.
        assert_eq!(s.position(60.0, 9), 49_999);
        // Without a planned time (no test run), lines.
        let s = Scale::new(None, 9);
        assert_eq!((s.len(), s.position(30.0, 5)), (9, 5));
        assert_eq!(Scale::new(Some(0.0), 9), Scale::Lines(9));
    }
}
