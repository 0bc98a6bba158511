//! `klar run`: a program run on a machine, simulated or realtime with the servo loop in a
//! thread of its own.

use crate::{load_machine_for, print_diagnostics, progress, signals};
use klar::config::MachineConfig;
use klar::runtime::{RunError, RunOptions};
use std::io::{BufWriter, Write};
use std::path::Path;
use std::process::ExitCode;

/// `klar run PROGRAM`: runs a program on a machine and prints what the run measured.
pub(crate) fn cmd_run(
    program: &Path,
    machine: Option<&Path>,
    trace: Option<&Path>,
    (realtime, fifo): (bool, bool),
    faults: Vec<klar::faults::FaultConfig>,
    quiet: bool,
) -> ExitCode {
    let mut config = match load_machine_for(program, machine) {
        Ok(c) => c,
        Err(code) => return code,
    };
    config.faults.extend(faults);
    let mut trace_file = match trace {
        None => None,
        Some(p) => match std::fs::File::create(p) {
            Ok(f) => Some(BufWriter::new(f)),
            Err(e) => {
                eprintln!("{}: {e}", p.display());
                return ExitCode::FAILURE;
            }
        },
    };
    // SIGINT and SIGTERM stop the run under control from here on.
    let signals = signals::SignalWatch::install()
        .inspect_err(|e| eprintln!("warning: signals will end the run abruptly: {e}"))
        .ok();
    let stop = signals.as_ref().map(signals::SignalWatch::stop);
    let result = if realtime || config.needs_wall_clock() {
        servo_thread(program, &config, trace_file, fifo, quiet, stop)
    } else {
        let options = RunOptions {
            realtime,
            trace: trace_file.as_mut().map(|w| w as &mut dyn Write),
        };
        progress::run_with_progress(program, &config, options, quiet, stop)
    };
    let (report, error) = match result {
        Ok(r) => (r, None),
        Err(f) => (f.report, Some(f.error)),
    };
    if let Some(e) = &error {
        match e {
            RunError::Syntax(diags) => print_diagnostics(diags),
            RunError::Program(d) | RunError::Setpoint { diagnostic: d, .. } => {
                print_diagnostics(std::slice::from_ref(d))
            }
            other => eprintln!("{}: {other}", program.display()),
        }
    }
    if let Some(stop) = &report.stop {
        eprintln!("{}: {stop}", program.display());
        for a in &stop.axes {
            eprintln!(
                "  axis {}: {:.3} units/s at the fault, stopped in {:.4}, at rest at {:.4}",
                a.axis,
                a.velocity,
                a.stop_distance(),
                a.position_at_rest
            );
        }
    }
    // A run refused before its first servo cycle has nothing to sum up.
    let refused = error.is_some() && report.cycles == 0;
    if !quiet && !refused {
        say!("machine:      {}", config.name);
        for a in &report.start {
            let unit = if a.axis.is_rotary() { "deg" } else { "mm" };
            let referenced = if a.referenced {
                "referenced"
            } else {
                "not referenced"
            };
            say!(
                "start {}:      {:.4} {unit} ({referenced})",
                a.axis,
                a.position
            );
        }
        say!("machine time: {:.3} s", report.machine_time);
        say!("blocks:       {}", report.blocks);
        say!("servo cycles: {}", report.cycles);
        for (l, fe) in &report.max_following_error {
            let unit = if l.is_rotary() { "deg" } else { "mm" };
            say!("max following error {l}: {fe:.4} {unit}");
        }
        if report.blends_refused > 0 {
            say!(
                "blend slots full: {} corners stopped exactly",
                report.blends_refused
            );
        }
        if report.spindle_wait > 0.0 {
            say!("spindle wait: {:.3} s", report.spindle_wait);
        }
        if report.realtime {
            say!("underruns:    {}", report.underruns);
            say!("starved:      {} cycles", report.starved);
            say!("log dropped:  {} records", report.log_dropped);
            if let Some(l) = &report.lateness {
                say!("lateness:     {l}");
            }
            if let Some(w) = &report.cycle_work {
                say!(
                    "cycle work:   {w}; {} ran past the next deadline",
                    report.work_overruns
                );
            }
        }
    }
    let code = match error {
        None => ExitCode::SUCCESS,
        // Reported above; the exit code tells which signal stopped the run.
        Some(RunError::Operator { .. }) => signals
            .as_ref()
            .map_or(ExitCode::FAILURE, signals::SignalWatch::exit_code),
        Some(e) => {
            eprintln!("stopped: {e}");
            ExitCode::FAILURE
        }
    };
    // The last line, whatever else happened: the spindle may still turn.
    match &report.spindle_warning {
        Some(w) => {
            eprintln!("{w}");
            if code == ExitCode::SUCCESS {
                ExitCode::FAILURE
            } else {
                code
            }
        }
        None => code,
    }
}

/// A realtime run: the servo loop in a thread of its own (SCHED_FIFO and locked memory with
/// `fifo`, where allowed), the trace handed through a queue to a writer thread.
fn servo_thread(
    program: &Path,
    config: &MachineConfig,
    trace_file: Option<BufWriter<std::fs::File>>,
    fifo: bool,
    quiet: bool,
    stop: Option<klar::runtime::OperatorStop>,
) -> Result<klar::runtime::RunReport, Box<klar::runtime::RunFailure>> {
    let failed = |what: String| {
        Box::new(klar::runtime::RunFailure {
            error: RunError::Machine(klar::machine::MachineError::Open {
                what: "servo thread".into(),
                message: what,
            }),
            report: klar::runtime::RunReport::default(),
        })
    };
    std::thread::scope(|scope| {
        let (queue, drained) = match trace_file {
            Some(file) => {
                let (writer, rx) = klar::rt::chunk_queue();
                let handle = std::thread::Builder::new()
                    .name("klar-trace".into())
                    .spawn_scoped(scope, move || klar::rt::drain(rx, file))
                    .map_err(|e| failed(e.to_string()))?;
                (Some(writer), Some(handle))
            }
            None => (None, None),
        };
        let servo = std::thread::Builder::new()
            .name("klar-servo".into())
            .spawn_scoped(scope, move || {
                let mut queue = queue;
                if fifo {
                    let status = klar::rt::make_realtime(klar::rt::FIFO_PRIORITY);
                    if status.fifo.is_ok() && status.locked.is_ok() {
                        tracing::info!("servo loop: {status}");
                    } else {
                        eprintln!("warning: servo loop: {status}");
                    }
                }
                let options = RunOptions {
                    realtime: true,
                    trace: queue.as_mut().map(|w| w as &mut dyn Write),
                };
                progress::run_with_progress(program, config, options, quiet || fifo, stop)
            })
            .map_err(|e| failed(e.to_string()))?;
        let result = servo
            .join()
            .unwrap_or_else(|_| Err(failed("the servo thread panicked".into())));
        if let Some(Ok(Err(e))) = drained.map(|h| h.join()) {
            eprintln!("warning: writing the trace: {e}");
        }
        result
    })
}
