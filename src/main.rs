//! The `klar` command line: check, run and inspect HEIDENHAIN programs.

use clap::{Parser, Subcommand};
use klar::config::MachineConfig;
use klar::runtime::{RunError, RunOptions};
use klar_interp::{Diagnostic, Pose};
use klar_motion::comp::Compensator;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

mod progress;
mod render;
mod signals;

/// Prints a line to standard output, ignoring a closed pipe (`klar run … | head` must not
/// panic).
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// klar — a CNC control for HEIDENHAIN programs.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    /// Print only errors: no progress bar, no run summary, no "ok".
    #[arg(short, long, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Check a program without moving anything: prints `file:line:col: message` per error.
    /// The full test run on the machine `klar run` would use (soft limits, feeds, spindle,
    /// tools, planner), which `klar run` also does before it starts: the `--machine` file,
    /// else the built-in machine for the program (lathe for `.nc`, mill otherwise).
    Check {
        /// The program file.
        program: PathBuf,
        /// Machine description (TOML); the built-in machine for the program when absent.
        #[arg(long, conflicts_with = "program_only")]
        machine: Option<PathBuf>,
        /// Check the program on its own, without any machine (syntax, parameters, geometry;
        /// PLANE assumes an A/C table, any tool is known): `klar run` may still refuse it.
        #[arg(long)]
        program_only: bool,
        /// Give up after this much planned machine time, s: a program that has not ended by
        /// then (an endless loop with motion) is reported as undecided (exit status 2).
        #[arg(long, value_name = "SECONDS", default_value_t = klar::testrun::MAX_PLANNED_TIME, conflicts_with = "program_only")]
        max_machine_time: f64,
        /// Give up after this many executed blocks with an action (moves, machine
        /// functions): reported as undecided (exit status 2).
        #[arg(long, value_name = "N", default_value_t = klar::testrun::MAX_EXECUTED_BLOCKS, conflicts_with = "program_only")]
        max_blocks: u64,
    },
    /// Run a program on the machine (the built-in simulated mill by default).
    Run {
        /// The program file.
        program: PathBuf,
        /// Machine description (TOML).
        #[arg(long)]
        machine: Option<PathBuf>,
        /// Write a trace CSV (one row per servo cycle).
        #[arg(long)]
        trace: Option<PathBuf>,
        /// Run the servo loop on the wall clock.
        #[arg(long)]
        realtime: bool,
        /// Realtime runs: ask for SCHED_FIFO and locked memory for the servo loop's thread
        /// (says so when refused; the progress bar is left out).
        #[arg(long)]
        fifo: bool,
        /// Inject a fault into the simulated machine: KIND[:AXIS]@SECONDS with KIND one of
        /// drive, comm, noise, stuck, limit, jump (these need an axis), estop, stall,
        /// spindle (e.g. `drive:X@0.5`, `estop@1.2`, `stall@0.3`; durations, offsets and codes
        /// take their defaults: a machine file's [[fault]] table sets them).
        #[arg(long = "fault", value_name = "SPEC")]
        faults: Vec<klar::faults::FaultConfig>,
    },
    /// Draw the toolpath (working plane and isometric view) as SVG or PNG.
    Plot {
        /// Add path speed and per-axis velocity, acceleration and jerk over time from a
        /// simulated run.
        #[arg(long)]
        profile: bool,
        /// The program file.
        program: PathBuf,
        /// Output file, .svg or .png.
        #[arg(short, long)]
        output: PathBuf,
        /// Machine description (TOML): the program is drawn as it runs there (start
        /// position, tool table, rotary axes, M functions); without it, on its own.
        #[arg(long)]
        machine: Option<PathBuf>,
    },
    /// Serve the lab-bench dashboard (program, DRO, toolpath, controls) in a web browser.
    Serve {
        /// Machine description (TOML); the built-in mill when absent.
        #[arg(long)]
        machine: Option<PathBuf>,
        /// Folder of programs the page offers (.h, .i, .nc, also one folder down).
        #[arg(long, default_value = "programs")]
        programs: PathBuf,
        /// Port to listen on (0 picks a free one).
        #[arg(long, default_value_t = 8080)]
        port: u16,
        /// Address to listen on; anything but loopback needs --token.
        #[arg(long, default_value = "127.0.0.1")]
        listen: std::net::IpAddr,
        /// Access token every API call must carry (`?token=` or `Authorization: Bearer`).
        #[arg(long, env = "KLAR_TOKEN")]
        token: Option<String>,
    },
    /// Measure this computer's wake-up latency: a thread sleeps to absolute deadlines one
    /// period apart and counts how late it wakes (as LinuxCNC's latency-test); prints a
    /// histogram and p50 / p99 / p99.99 / max.
    Latency {
        /// How long to measure, s.
        #[arg(long, default_value_t = 10.0)]
        seconds: f64,
        /// Period of the deadlines, s (the servo period to judge).
        #[arg(long, default_value_t = 0.001)]
        period: f64,
        /// Ask for SCHED_FIFO and locked memory (says so when refused).
        #[arg(long)]
        fifo: bool,
    },
    /// Print the canonical op stream, one JSON object per line.
    Ops {
        /// The program file.
        program: PathBuf,
        /// Machine description (TOML), for the start position.
        #[arg(long)]
        machine: Option<PathBuf>,
        /// Print the tool-centre path after radius compensation (RL/RR, APPR/DEP resolved).
        #[arg(long)]
        compensated: bool,
        /// Stop after this many ops (an endless loop), exit status 2; 0 lifts the limit.
        #[arg(long, value_name = "N", default_value_t = klar::testrun::MAX_EXECUTED_BLOCKS)]
        max_ops: u64,
    },
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        // colour codes only for a terminal: a log file or a pipe gets plain text
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    let cli = Cli::parse();
    let quiet = cli.quiet;
    match cli.command {
        Command::Check {
            program,
            machine,
            program_only,
            max_machine_time,
            max_blocks,
        } => {
            let limits = klar::testrun::TestRunLimits {
                machine_time: max_machine_time,
                blocks: max_blocks,
                ..Default::default()
            };
            cmd_check(&program, machine.as_deref(), program_only, &limits, quiet)
        }
        Command::Run {
            program,
            machine,
            trace,
            realtime,
            fifo,
            faults,
        } => cmd_run(
            &program,
            machine.as_deref(),
            trace.as_deref(),
            (realtime, fifo),
            faults,
            quiet,
        ),
        Command::Latency {
            seconds,
            period,
            fifo,
        } => cmd_latency(seconds, period, fifo),
        Command::Ops {
            program,
            machine,
            compensated,
            max_ops,
        } => cmd_ops(&program, machine.as_deref(), compensated, max_ops),
        Command::Serve {
            machine,
            programs,
            port,
            listen,
            token,
        } => cmd_serve(
            machine.as_deref(),
            programs,
            std::net::SocketAddr::new(listen, port),
            token,
        ),
        Command::Plot {
            program,
            output,
            machine,
            profile,
        } => cmd_plot(&program, &output, machine.as_deref(), profile),
    }
}

/// The machine file given, or the built-in machine for `program` (the lathe for lathe DIN
/// programs, the mill otherwise).
fn load_machine_for(program: &Path, machine: Option<&Path>) -> Result<MachineConfig, ExitCode> {
    match machine {
        None => Ok(MachineConfig::builtin_for(program)),
        Some(_) => load_machine(machine),
    }
}

fn load_machine(machine: Option<&Path>) -> Result<MachineConfig, ExitCode> {
    match machine {
        None => Ok(MachineConfig::builtin_mill()),
        Some(p) => {
            let config = MachineConfig::load(p).map_err(|e| {
                eprintln!("{e}");
                ExitCode::FAILURE
            })?;
            for notice in config.notices() {
                eprintln!("warning: {}: {notice}", p.display());
            }
            Ok(config)
        }
    }
}

fn start_pose(config: &MachineConfig) -> Pose {
    config.start_pose()
}

fn print_diagnostics(diags: &[Diagnostic]) {
    render::print(diags);
}

fn cmd_check(
    program: &Path,
    machine: Option<&Path>,
    program_only: bool,
    limits: &klar::testrun::TestRunLimits,
    quiet: bool,
) -> ExitCode {
    let config = match load_machine_for(program, machine) {
        Ok(c) => c,
        Err(code) => return code,
    };
    if !program_only {
        return cmd_test_run(program, &config, limits, quiet);
    }
    // the program checked on its own, on no machine
    let report = match klar::config::open_on(None, program, start_pose(&config)) {
        Ok(it) => it.check_report(),
        Err(d) => klar_interp::CheckReport {
            errors: vec![d],
            ..Default::default()
        },
    };
    for w in &report.warnings {
        eprintln!("{w} (warning)");
    }
    for m in &report.missing {
        eprintln!("{m} (warning: a run stops here)");
    }
    for u in &report.undecided {
        eprintln!("{u} (decided only when the program runs)");
    }
    let diags = report.errors;
    if diags.is_empty() {
        if !quiet {
            say!("{}: ok", program.display());
        }
        ExitCode::SUCCESS
    } else {
        print_diagnostics(&diags);
        ExitCode::FAILURE
    }
}

fn cmd_ops(program: &Path, machine: Option<&Path>, compensated: bool, max_ops: u64) -> ExitCode {
    let config = match load_machine_for(program, machine) {
        Ok(c) => c,
        Err(code) => return code,
    };
    if let Err(diags) = klar_interp::syntax_check(program) {
        print_diagnostics(&diags);
        return ExitCode::FAILURE;
    }
    let start = start_pose(&config);
    let mut interp = match config.open_program(program, start) {
        Ok(i) => i,
        Err(d) => {
            print_diagnostics(&[d]);
            return ExitCode::FAILURE;
        }
    };
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let mut comp = compensated.then(|| Compensator::new(start));
    // Ops of a tilted working plane reach the output in workpiece coordinates: turned after
    // the compensation (which runs in the tilted plane) or, without it, by the tilt stage alone.
    interp.set_working_plane_ops(true);
    let mut tilt = klar_motion::tilt::TiltStage::new();
    let mut turned = std::collections::VecDeque::new();
    let mut write = |op: &klar_interp::Op| -> bool {
        match serde_json::to_string(op) {
            Ok(line) => writeln!(out, "{line}").is_ok(),
            Err(e) => {
                eprintln!("cannot encode op: {e}");
                false
            }
        }
    };
    let comp_failed = |e: &dyn std::fmt::Display| {
        eprintln!("{}: {e}", program.display());
        ExitCode::FAILURE
    };
    let mut count = 0u64;
    for item in interp {
        let op = match item {
            Ok(op) => op,
            Err(d) => {
                print_diagnostics(&[d]);
                return ExitCode::FAILURE;
            }
        };
        count += 1;
        if max_ops != 0 && count > max_ops {
            let _ = out.flush();
            eprintln!(
                "{}:{}:{}: undecided: the program did not end within {max_ops} ops; `klar ops` \
                 stops here (an endless loop?); --max-ops 0 lifts the limit",
                program.display(),
                op.loc.line,
                op.loc.col
            );
            return ExitCode::from(2);
        }
        match comp.as_mut() {
            None => {
                tilt.push(op, &mut turned);
                while let Some(o) = turned.pop_front() {
                    if !write(&o) {
                        return ExitCode::FAILURE;
                    }
                }
            }
            Some(c) => {
                if let Err(e) = c.push(op) {
                    return comp_failed(&e);
                }
                while let Some(o) = c.pop() {
                    if !write(&o) {
                        return ExitCode::FAILURE;
                    }
                }
            }
        }
    }
    if let Some(c) = comp.as_mut() {
        if let Err(e) = c.finish() {
            return comp_failed(&e);
        }
        while let Some(o) = c.pop() {
            if !write(&o) {
                return ExitCode::FAILURE;
            }
        }
    }
    if out.flush().is_err() {
        return ExitCode::FAILURE;
    }
    ExitCode::SUCCESS
}

/// `klar check PROGRAM --machine FILE`: the test run.
fn cmd_test_run(
    program: &Path,
    config: &MachineConfig,
    limits: &klar::testrun::TestRunLimits,
    quiet: bool,
) -> ExitCode {
    // A machine with drives that measure their own position is checked from where they
    // stand, as `klar run` would start (no drive is enabled to read it).
    let standing = match klar::machine::standing(config) {
        Some(Ok(at)) => at,
        Some(Err(e)) => {
            eprintln!(
                "warning: could not read where the drives stand ({e}): checked from the \
                 machine file's start"
            );
            Vec::new()
        }
        None => Vec::new(),
    };
    let measured;
    let config = if standing.is_empty() {
        config
    } else {
        measured = config.starting_at(standing.iter().map(|s| s.position));
        &measured
    };
    let report = klar::testrun::test_run_within(program, config, limits);
    print_diagnostics(&report.errors);
    for w in &report.warnings {
        eprintln!("{w} (warning)");
    }
    for u in &report.undecided {
        eprintln!("{}: not checked: {u}", program.display());
    }
    if !report.passed() {
        return ExitCode::FAILURE;
    }
    if let Some(d) = &report.gave_up {
        // neither passed nor refused: the operator decides whether to run it
        eprintln!("{d}");
        return ExitCode::from(2);
    }
    if quiet {
        return ExitCode::SUCCESS;
    }
    say!(
        "{}: ok on {} ({} moves, {:.3} s planned)",
        program.display(),
        config.name,
        report.motion_ops,
        report.planned_time
    );
    let lathe = config.kinematics == klar::config::KinematicsConfig::Lathe;
    for (l, lo, hi) in &report.envelope {
        if lathe && *l == klar_interp::AxisLetter::X {
            // a lathe's X runs in radius; the operator reads it as a diameter
            say!("  X (diameter): {:.4} .. {:.4}", lo * 2.0, hi * 2.0);
        } else {
            say!("  {l}: {lo:.4} .. {hi:.4}");
        }
    }
    if let Ok(preset) = config.active_preset() {
        say!("  preset at start: {preset}");
    }
    for s in &standing {
        say!("  {s}");
    }
    ExitCode::SUCCESS
}

fn cmd_run(
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

fn cmd_latency(seconds: f64, period: f64, fifo: bool) -> ExitCode {
    if !(period.is_finite() && period > 0.0 && period <= 1.0) {
        eprintln!("--period must be a number of seconds in (0, 1], got {period}");
        return ExitCode::FAILURE;
    }
    if !(seconds.is_finite() && seconds > 0.0 && seconds <= 86_400.0) {
        eprintln!("--seconds must be a number of seconds in (0, 86400], got {seconds}");
        return ExitCode::FAILURE;
    }
    let measured = std::thread::Builder::new()
        .name("klar-latency".into())
        .spawn(move || {
            let status = fifo.then(|| klar::rt::make_realtime(klar::rt::FIFO_PRIORITY));
            (status, klar::latency::measure(period, seconds))
        })
        .map_err(|e| e.to_string())
        .and_then(|h| {
            h.join()
                .map_err(|_| "the measuring thread failed".to_string())
        });
    let (status, hist) = match measured {
        Ok(m) => m,
        Err(e) => {
            eprintln!("latency: {e}");
            return ExitCode::FAILURE;
        }
    };
    match &status {
        Some(s) if s.fifo.is_ok() => println!("scheduling:   {s}"),
        Some(s) => {
            eprintln!("warning: {s}");
            println!("scheduling:   ordinary (SCHED_FIFO refused)");
        }
        None => println!("scheduling:   ordinary (no --fifo)"),
    }
    println!("period:       {:.3} ms for {seconds} s", period * 1e3);
    println!("wake-up lateness, µs (upper bucket edge) and count:");
    let total = hist.total().max(1) as f64;
    for (us, count) in hist.rows() {
        let bar = "#".repeat(((count as f64 / total) * 50.0).ceil() as usize);
        println!("{us:>9.0} {count:>9} {bar}");
    }
    let s = hist.summary();
    println!("lateness:     {s}");
    let missed = hist.quantile_ns(1.0) as f64 * 1e-9 > period / 2.0;
    if missed {
        println!(
            "at least one wake-up was more than half a period late: a servo loop at this \
             period would count underruns"
        );
    }
    ExitCode::SUCCESS
}

fn cmd_serve(
    machine: Option<&Path>,
    programs: PathBuf,
    listen: std::net::SocketAddr,
    token: Option<String>,
) -> ExitCode {
    let config = match load_machine(machine) {
        Ok(c) => c,
        Err(code) => return code,
    };
    if !programs.is_dir() {
        eprintln!(
            "warning: no programs folder {} (name one with --programs DIR): the page offers \
             no programs",
            programs.display()
        );
    }
    let options = klar::serve::ServeOptions {
        listen,
        token: token.clone(),
        programs,
        machine: config,
    };
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
    {
        Ok(r) => r,
        Err(e) => {
            eprintln!("cannot start the async runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    // SIGINT and SIGTERM stop a running program under control, then the server.
    let signals = match signals::SignalWatch::install() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("cannot install the signal handlers: {e}");
            return ExitCode::FAILURE;
        }
    };
    let served = runtime.block_on(klar::serve::serve_until(options, signals.stop(), |addr| {
        let query = if token.is_some() { "?token=…" } else { "" };
        say!("klar dashboard on http://{addr}/{query}");
        let _ = std::io::stdout().flush();
    }));
    match served {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("serve: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Checks that `path` can be written (before any work goes into what is to be written
/// there), leaving the file system as it was.
fn writable(path: &Path) -> std::io::Result<()> {
    if path.exists() {
        std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map(drop)
    } else {
        std::fs::File::create(path)?;
        std::fs::remove_file(path)
    }
}

fn cmd_plot(program: &Path, output: &Path, machine: Option<&Path>, profile: bool) -> ExitCode {
    if let Err(e) = writable(output) {
        eprintln!("cannot write the plot to {}: {e}", output.display());
        return ExitCode::FAILURE;
    }
    let config = match load_machine_for(program, machine) {
        Ok(c) => c,
        Err(code) => return code,
    };
    let profile = if profile {
        match klar::plot::profile::profile(program, &config) {
            Ok(p) => Some(p),
            Err(klar::plot::PlotError::Program(diags)) => {
                print_diagnostics(&diags);
                return ExitCode::FAILURE;
            }
            Err(e) => {
                eprintln!("{e}");
                return ExitCode::FAILURE;
            }
        }
    } else {
        None
    };
    // drawn as it runs on the machine named; without one, on its own
    let on = machine.is_some().then_some(&config);
    match klar::plot::plot_program_with(program, on, start_pose(&config), output, profile.as_ref())
    {
        Ok(()) => ExitCode::SUCCESS,
        Err(klar::plot::PlotError::Program(diags)) => {
            print_diagnostics(&diags);
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}
