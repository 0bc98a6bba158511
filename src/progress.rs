//! The `klar run` progress bar: program line, percent of the program's lines and machine time,
//! drawn on standard error only when it is a terminal.

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
    let lines = if show { count_lines(program) } else { 0 };
    let bar = if show {
        let bar = ProgressBar::with_draw_target(Some(lines), ProgressDrawTarget::stderr());
        let style = ProgressStyle::with_template(
            "{bar:32.cyan/blue} {percent:>3}%  line {pos}/{len}  {msg}  [{elapsed}]",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
        bar.set_style(style);
        bar
    } else {
        ProgressBar::hidden()
    };
    let mut run = Run::start(program, config, options)?;
    if let Some(stop) = stop {
        run.watch_operator_stop(stop);
    }
    let slot = Slot::default();
    let ended = std::thread::scope(|scope| {
        // The bar is drawn by a thread of its own from the slot the loop fills: the loop
        // neither formats nor writes to the terminal, nor waits for the one that does.
        if show {
            let (bar, slot) = (&bar, &slot);
            let drawn = std::thread::Builder::new()
                .name("klar-progress".into())
                .spawn_scoped(scope, move || draw(bar, slot));
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
        bar.set_position(if ended.is_none() {
            lines
        } else {
            u64::from(run.line())
        });
        bar.set_message(format!("machine time {:.3} s", run.time()));
        bar.abandon();
    }
    run.finish(ended)
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
fn draw(bar: &ProgressBar, slot: &Slot) {
    while !slot.done.load(Ordering::Acquire) {
        bar.set_position(u64::from(slot.line.load(Ordering::Relaxed)));
        let t = f64::from_bits(slot.t.load(Ordering::Relaxed));
        bar.set_message(format!("machine time {t:.3} s"));
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
