//! The `klar run` progress bar: program line, percent of the program's lines and machine time,
//! drawn on standard error only when it is a terminal.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use klar::config::MachineConfig;
use klar::runtime::{OperatorStop, Run, RunFailure, RunOptions, RunReport};
use std::io::IsTerminal;
use std::path::Path;
use std::time::{Duration, Instant};

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
    let mut last = Instant::now();
    let mut steps = 0u32;
    let ended = loop {
        match run.step() {
            Ok(true) => {}
            Ok(false) => break None,
            Err(e) => break Some(e),
        }
        steps = steps.wrapping_add(1);
        if show && steps.is_multiple_of(64) && last.elapsed() >= REDRAW {
            last = Instant::now();
            let s = run.status();
            bar.set_position(u64::from(s.line));
            bar.set_message(format!("machine time {:.3} s", s.t));
        }
    };
    if show {
        let s = run.status();
        bar.set_position(if ended.is_none() {
            lines
        } else {
            u64::from(s.line)
        });
        bar.set_message(format!("machine time {:.3} s", s.t));
        bar.abandon();
    }
    run.finish(ended)
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
