//! The `klar` command line: check, run and inspect HEIDENHAIN programs.

use clap::{Parser, Subcommand};
use klar::config::MachineConfig;
use klar_interp::{Diagnostic, Pose};
use std::io::Write;
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

mod cli;

use cli::check::{cmd_check, cmd_ops};
use cli::run::cmd_run;

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
