//! The `klar` command line: check, run and inspect HEIDENHAIN programs.

use clap::{Parser, Subcommand};
use klar::config::MachineConfig;
use klar::runtime::{RunError, RunOptions, run_program};
use klar_interp::{Diagnostic, Interpreter, Pose};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// klar — a CNC control for HEIDENHAIN programs.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Check a program without moving anything: prints `file:line:col: message` per error.
    Check {
        /// The program file.
        program: PathBuf,
        /// Machine description (TOML); the built-in mill when absent.
        #[arg(long)]
        machine: Option<PathBuf>,
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
    },
    /// Draw the toolpath (working plane and isometric view) as SVG or PNG.
    Plot {
        /// The program file.
        program: PathBuf,
        /// Output file, .svg or .png.
        #[arg(short, long)]
        output: PathBuf,
        /// Machine description (TOML), for the start position.
        #[arg(long)]
        machine: Option<PathBuf>,
    },
    /// Print the canonical op stream, one JSON object per line.
    Ops {
        /// The program file.
        program: PathBuf,
        /// Machine description (TOML), for the start position.
        #[arg(long)]
        machine: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .init();
    let cli = Cli::parse();
    match cli.command {
        Command::Check { program, machine } => cmd_check(&program, machine.as_deref()),
        Command::Run {
            program,
            machine,
            trace,
            realtime,
        } => cmd_run(&program, machine.as_deref(), trace.as_deref(), realtime),
        Command::Ops { program, machine } => cmd_ops(&program, machine.as_deref()),
        Command::Plot {
            program,
            output,
            machine,
        } => {
            let config = match load_machine(machine.as_deref()) {
                Ok(c) => c,
                Err(code) => return code,
            };
            match klar::plot::plot_program(&program, start_pose(&config), &output) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("{e}");
                    ExitCode::FAILURE
                }
            }
        }
    }
}

fn load_machine(machine: Option<&Path>) -> Result<MachineConfig, ExitCode> {
    match machine {
        None => Ok(MachineConfig::builtin_mill()),
        Some(p) => MachineConfig::load(p).map_err(|e| {
            eprintln!("{e}");
            ExitCode::FAILURE
        }),
    }
}

fn start_pose(config: &MachineConfig) -> Pose {
    let mut p = Pose::ZERO;
    for a in &config.axes {
        p[a.letter] = a.start;
    }
    p
}

fn print_diagnostics(diags: &[Diagnostic]) {
    for d in diags {
        eprintln!("{d}");
    }
}

fn cmd_check(program: &Path, machine: Option<&Path>) -> ExitCode {
    let config = match load_machine(machine) {
        Ok(c) => c,
        Err(code) => return code,
    };
    let diags = klar_interp::check(program, start_pose(&config));
    if diags.is_empty() {
        println!("{}: ok", program.display());
        ExitCode::SUCCESS
    } else {
        print_diagnostics(&diags);
        ExitCode::FAILURE
    }
}

fn cmd_ops(program: &Path, machine: Option<&Path>) -> ExitCode {
    let config = match load_machine(machine) {
        Ok(c) => c,
        Err(code) => return code,
    };
    if let Err(diags) = klar_interp::syntax_check(program) {
        print_diagnostics(&diags);
        return ExitCode::FAILURE;
    }
    let interp = match Interpreter::open(program, start_pose(&config)) {
        Ok(i) => i,
        Err(d) => {
            print_diagnostics(&[d]);
            return ExitCode::FAILURE;
        }
    };
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    for item in interp {
        match item {
            Ok(op) => {
                let line = match serde_json::to_string(&op) {
                    Ok(l) => l,
                    Err(e) => {
                        eprintln!("cannot encode op: {e}");
                        return ExitCode::FAILURE;
                    }
                };
                if writeln!(out, "{line}").is_err() {
                    return ExitCode::FAILURE;
                }
            }
            Err(d) => {
                let _ = out.flush();
                print_diagnostics(&[d]);
                return ExitCode::FAILURE;
            }
        }
    }
    if out.flush().is_err() {
        return ExitCode::FAILURE;
    }
    ExitCode::SUCCESS
}

fn cmd_run(
    program: &Path,
    machine: Option<&Path>,
    trace: Option<&Path>,
    realtime: bool,
) -> ExitCode {
    let config = match load_machine(machine) {
        Ok(c) => c,
        Err(code) => return code,
    };
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
    let options = RunOptions {
        realtime,
        trace: trace_file.as_mut().map(|w| w as &mut dyn Write),
    };
    let result = run_program(program, &config, options);
    let (report, error) = match result {
        Ok(r) => (r, None),
        Err(f) => (f.report, Some(f.error)),
    };
    if let Some(e) = &error {
        match e {
            RunError::Syntax(diags) => print_diagnostics(diags),
            RunError::Program(d) => print_diagnostics(std::slice::from_ref(d)),
            other => eprintln!("{}: {other}", program.display()),
        }
    }
    println!("machine:      {}", config.name);
    println!("machine time: {:.3} s", report.machine_time);
    println!("blocks:       {}", report.blocks);
    println!("servo cycles: {}", report.cycles);
    for (l, fe) in &report.max_following_error {
        let unit = if l.is_rotary() { "deg" } else { "mm" };
        println!("max following error {l}: {fe:.4} {unit}");
    }
    if report.spindle_wait > 0.0 {
        println!("spindle wait: {:.3} s", report.spindle_wait);
    }
    if report.realtime {
        println!("underruns:    {}", report.underruns);
    }
    match error {
        None => ExitCode::SUCCESS,
        Some(e) => {
            eprintln!("stopped: {e}");
            ExitCode::FAILURE
        }
    }
}
