//! The runtime: wires interpreter → planner → kinematics → backends for one program run,
//! streams the trace, watches the feedback and reports.
//!
//! Error handling follows the program contract: the test run ([`crate::testrun`]) refuses a
//! program with any error it can find before any axis moves (a syntax error always does); an
//! error that shows only when a block is reached (geometry, a computed value, travel) lets the
//! motion of the previous blocks finish — a controlled stop at the end of the previous block —
//! and then reports the diagnostic.
//!
//! Monitors run every servo cycle ([`crate::monitor`]): a fault an axis reports (drive fault,
//! limit switch, e-stop, lost link, its own following-error window), the control's own
//! following-error limit per axis and a failing backend end the run with a quick stop — the
//! faulted axes brake in their drives, every other axis stops on its own jerk-limited ramp,
//! since the path cannot be kept when one axis no longer follows. A spindle fault leaves the
//! axes able to follow, so it ends the run with a feed hold on the path. Either way the run
//! reports the cause, the block and the axis ([`StopReport`]); after
//! [`Run::reset_faults`] the control's position is read back from the drives.
//!
//! An operator's stop from outside the run ([`OperatorStop`]: SIGINT or SIGTERM to the `klar`
//! binary) is looked at once per servo cycle: a feed hold on the path, and on a second request
//! the quick stop.
//!
//! Spindle commands reach the spindle backend when their block is reached; after a command to
//! turn, the run holds position until the spindle reports at-speed, for at most the machine's
//! `at_speed_timeout`.

mod axis_fault;
pub(crate) mod command;
mod display;
mod error;
mod events;
pub mod guard;
mod log;
mod operator;
mod pass_hold;
mod per_rev;
mod probing;
mod reader;
mod settle;
mod spindle;
mod stop;
pub mod stream;
pub(crate) mod sync;
pub(crate) mod tap;

use crate::config::MachineConfig;
use crate::latency::Pacer;
use crate::machine::{MachineError, MachineIo};
use crate::monitor::{StopCause, StopReport};
use crate::testrun::positioning_axes;
use crate::trace::{SpindleRow, TraceWriter};
use command::CommandPath;
pub use error::RunError;
use klar_interp::{AxisLetter, OpKind, SourceLoc};
use klar_motion::{AxisFault, Planner, Sample, Step};
use log::{LogQueue, LogRecord};
pub use operator::{OperatorStop, StopLevel};
use reader::{Feed, OpChecks, Reader};
use std::collections::VecDeque;
use std::io::Write;
use std::path::Path;
use std::time::Duration;
use stop::PendingStop;
use stream::OpStream;

/// How to run.
pub struct RunOptions<'a> {
    /// Run the servo loop on the wall clock instead of as fast as possible.
    pub realtime: bool,
    /// Where to write the trace CSV, if anywhere.
    pub trace: Option<&'a mut dyn Write>,
}

/// What a finished (or stopped) run measured.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunReport {
    /// Machine time of the program in seconds (simulated, not wall time).
    pub machine_time: f64,
    /// Blocks the interpreter executed.
    pub blocks: u64,
    /// Servo cycles run.
    pub cycles: u64,
    /// Largest |following error| per machine axis.
    pub max_following_error: Vec<(AxisLetter, f64)>,
    /// Cycles whose setpoints missed their slot: in realtime mode a cycle that woke more
    /// than half a servo period after its deadline on the wall clock (or, with an injected
    /// `stall`, more than a period late); an injected `stall` longer than a period in
    /// simulated runs.
    pub underruns: u64,
    /// Wake-up lateness of the servo cycles on the wall clock (realtime runs).
    pub lateness: Option<crate::latency::LatenessSummary>,
    /// The servo loop's own time per cycle, from a wake-up to the next wait (realtime
    /// runs): tells a late wake-up from a cycle whose work ran long.
    pub cycle_work: Option<crate::latency::LatenessSummary>,
    /// Cycles whose work ran past the next cycle's deadline (realtime runs).
    pub work_overruns: u64,
    /// Servo cycles in which the planner wanted ops the program reader had not yet
    /// delivered (realtime runs): the path then brakes for the end of what it has.
    pub starved: u64,
    /// Corner blends the planner made.
    pub blends: u64,
    /// Corners the planner stopped at exactly because every one of its preallocated blend
    /// slots was held by the path ahead (`klar_motion::blend::BLEND_SLOTS`).
    pub blends_refused: u64,
    /// Seconds spent waiting for the spindle to reach speed (on the wall clock in realtime
    /// runs).
    pub spindle_wait: f64,
    /// True when the run used the wall clock.
    pub realtime: bool,
    /// Log records of the servo loop dropped because their queue was full.
    pub log_dropped: u64,
    /// How the run was stopped early by a fault or a request, if it was.
    pub stop: Option<StopReport>,
    /// Set when the spindle's stop at the end of the run could not be confirmed by its
    /// device: a warning that the spindle may still turn.
    pub spindle_warning: Option<String>,
    /// Where each axis stood when the run started.
    pub start: Vec<AxisStart>,
    /// The test run's planned machine time, s, when the test run ran before the start and
    /// went through the whole program: what progress displays count against.
    pub planned_time: Option<f64>,
    /// What the touch-probe cycles measured, in the order they ran.
    pub probe_results: Vec<klar_interp::ProbeResult>,
}

/// Where an axis stood when a run started: read from its drive when the drive measures its
/// own position, else the machine file's `start`.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisStart {
    /// The axis.
    pub axis: AxisLetter,
    /// Its position, mm or degrees.
    pub position: f64,
    /// True when its position is referenced (homed in this power cycle, an absolute
    /// encoder, or a machine file that declares every axis homed with `start_homed`).
    pub referenced: bool,
}

impl std::fmt::Display for AxisStart {
    /// `X stands at 4.9500 mm (referenced)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unit = if self.axis.is_rotary() { "°" } else { "mm" };
        let referenced = if self.referenced {
            "referenced"
        } else {
            "not referenced"
        };
        write!(
            f,
            "{} stands at {:.4} {unit} ({referenced})",
            self.axis, self.position
        )
    }
}

/// A run that ended early: the error plus what was measured until then.
#[derive(Debug)]
pub struct RunFailure {
    /// Why it stopped.
    pub error: RunError,
    /// Figures up to the stop.
    pub report: RunReport,
}

/// One program run on a machine, advanced step by step ([`Run::step`]) so that a front end
/// can hold, resume, override and stop it between servo cycles; [`run_program`] drives it to
/// the end.
pub struct Run<'a, 'w> {
    path: &'a Path,
    config: &'a MachineConfig,
    letters: Vec<AxisLetter>,
    /// Samples → kinematics → guarded setpoints (shared with the test run).
    command: CommandPath,
    io: MachineIo,
    /// The program reader thread's queue of ops.
    reader: Reader,
    /// Blocks the interpreter had executed when it read the last op taken.
    blocks: u64,
    planner: Planner,
    /// The interpreter has nothing more to give (end, or an error).
    input_done: bool,
    /// An error found while reading ahead, reported once the motion before it is done.
    pending_error: Option<RunError>,
    stop_requested: bool,
    trace: Option<TraceWriter<&'w mut dyn Write>>,
    report: RunReport,
    /// The wall-clock deadlines of a realtime run.
    pacer: Pacer,
    /// Lateness of the last wake-up on the wall clock, s, and whether it missed its slot.
    wall_late: (f64, bool),
    /// Machine time of the last cycle.
    t: f64,
    /// Machine time minus planner time: grows while the run waits (spindle).
    shift: f64,
    /// Program line of the last sample (for reports).
    line: u32,
    commanded: Vec<f64>,
    actual: Vec<f64>,
    /// Per machine axis: the command the measured position answers (the one sent a
    /// feedback lag earlier), for the following-error check.
    reference: Vec<f64>,
    /// The commands sent with the last cycle.
    last_sent: Vec<f64>,
    /// Per machine axis: cycles its feedback lags behind its setpoints.
    lags: Vec<u32>,
    warned_no_spindle: bool,
    /// Per machine axis: (in-position window, settle timeout) for positioning-only axes.
    positioning: Vec<Option<(f64, f64)>>,
    /// Per machine axis: (in-position window, timeout) waited for at the program's end.
    end_windows: Vec<Option<(f64, f64)>>,
    /// Source of the last sample sent.
    last_loc: Option<SourceLoc>,
    /// Constant surface speed in m/min and its speed limit in rpm (G26; infinite without)
    /// while G96 is active.
    surface_speed: Option<(f64, f64)>,
    /// Per machine axis: (max acceleration, max jerk) for quick stops.
    stop_limits: Vec<(f64, f64)>,
    /// Per machine axis: the control's following-error limit.
    fe_limits: Vec<Option<f64>>,
    /// A stop on the path under way: its cause, axis and figures at the fault.
    stopping: Option<PendingStop>,
    /// The report of the stop that ended the run.
    stop_report: Option<StopReport>,
    /// Injected servo-loop stalls not yet struck: (machine time, seconds), by time.
    stalls: VecDeque<(f64, f64)>,
    /// Wall-clock lateness counts against the limit (some axis is not simulated, or the
    /// machine sets the limit explicitly).
    enforce_wall_lateness: bool,
    /// The operator's stop request the run watches, if any.
    operator: Option<OperatorStop>,
    /// What the loop reports, on its way to the log thread.
    log: LogQueue,
    /// An error met during a stop after which the stop went on: logged when the run
    /// finishes, outside the loop (what it was doing, the error).
    deferred: Option<(&'static str, RunError)>,
    /// The operator's stop level the run has acted on.
    operator_seen: StopLevel,
    /// A pass geared to the spindle under way (a thread pass).
    sync: Option<sync::SyncPass>,
    /// A rigid tap geared to the spindle (idle between taps).
    tap: tap::TapPass,
    /// A feed hold asked for during a geared pass, for its end.
    pass_hold: Option<pass_hold::PassHold>,
    /// Feed per revolution following the measured spindle speed.
    warp: per_rev::RevWarp,
    /// A probing move the run measures itself (`[probe] latch`), while one is due.
    probing: Option<probing::Probing>,
}

impl Run<'_, '_> {
    /// One servo cycle at machine time `t` with the setpoints already in `io`.
    fn servo_cycle(&mut self, t: f64) -> Result<(), RunError> {
        self.wait_until(t);
        let (wall, injected) = self.lateness(t);
        let late = wall + injected;
        if self.wall_late.1 || late > self.config.servo_period {
            self.report.underruns += 1;
        }
        // Simulated plants run on machine time and do not mind a late wall clock: on an
        // all-simulated machine only injected stalls (or an explicit limit) stop the run.
        let counted = if self.enforce_wall_lateness {
            late
        } else {
            injected
        };
        let limit = self.config.setpoint_lateness_limit();
        if counted > limit && self.stopping.is_none() {
            self.log.send(LogRecord::Underrun {
                line: self.line,
                late: counted,
            });
            let block = self.last_loc.and_then(|l| l.block);
            self.begin_path_stop(
                StopCause::Underrun {
                    late: counted,
                    limit,
                },
                None,
                RunError::Underrun {
                    late: counted,
                    limit,
                    line: self.line,
                    block,
                },
            );
        }
        self.io.cycle(t)?;
        self.record_cycle(t)?;
        if let Some(i) = self.faulted_axis() {
            return Err(self.axis_fault(i));
        }
        for i in 0..self.letters.len() {
            if let Some(limit) = self.fe_limits[i] {
                let e = self.reference[i] - self.actual[i];
                if e.abs() > limit || e.is_nan() {
                    return Err(RunError::Fault {
                        axis: self.letters[i],
                        fault: AxisFault::FollowingError(e),
                        origin: None,
                        line: self.line,
                        block: self.last_loc.and_then(|l| l.block),
                    });
                }
            }
        }
        if self.stopping.is_none()
            && let Some(s) = self.io.spindle_mut()
            && let Some(fault) = s.feedback().fault.clone()
        {
            let message = s.describe_fault(&fault);
            self.log.send(LogRecord::SpindleFault { line: self.line });
            self.begin_path_stop(
                StopCause::Spindle(message.clone()),
                None,
                RunError::Spindle {
                    message,
                    line: self.line,
                },
            );
        }
        self.check_operator()
    }

    /// In realtime mode, sleeps until the deadline of the cycle due at machine time `t`
    /// (see [`Pacer`]).
    fn wait_until(&mut self, t: f64) {
        if self.report.realtime {
            self.wall_late = self.pacer.wait(t);
        }
    }

    /// How late the setpoints of the cycle due at machine time `t` reach the axes, s: the
    /// wall-clock delay in realtime mode, and any injected stall that strikes now (which a
    /// realtime run also really waits out).
    fn lateness(&mut self, t: f64) -> (f64, f64) {
        let wall = if self.report.realtime {
            self.wall_late.0
        } else {
            0.0
        };
        let mut late = 0.0;
        while let Some(&(at, seconds)) = self.stalls.front() {
            if at > t {
                break;
            }
            self.stalls.pop_front();
            if self.report.realtime {
                std::thread::sleep(Duration::from_secs_f64(seconds));
                self.pacer.delay(seconds);
            }
            late += seconds;
        }
        (wall, late)
    }

    /// Bookkeeping after a cycle: time, measured positions, figures, trace row.
    fn record_cycle(&mut self, t: f64) -> Result<(), RunError> {
        self.t = t;
        self.report.cycles += 1;
        self.report.machine_time = t;
        for i in 0..self.commanded.len() {
            let lagging = self.lags.get(i).is_some_and(|&l| l > 0);
            self.reference[i] = if lagging {
                self.last_sent[i]
            } else {
                self.commanded[i]
            };
            self.last_sent[i] = self.commanded[i];
        }
        for (i, f) in self.io.feedback().iter().enumerate() {
            self.actual[i] = f.position;
            let fe = f.following_error.abs();
            if fe > self.report.max_following_error[i].1 {
                self.report.max_following_error[i].1 = fe;
            }
        }
        if let Some(tr) = self.trace.as_mut() {
            let spindle = self
                .io
                .spindle_mut()
                .map(|s| SpindleRow {
                    rpm: s.commanded(),
                    angle: s.feedback().position,
                })
                .unwrap_or_default();
            tr.row(t, &self.commanded, &self.actual, spindle)?;
        }
        Ok(())
    }

    /// Sends one planner sample to the axes. Before the first sample of a new block, every
    /// positioning axis must have reached its last commanded position.
    fn apply_sample(&mut self, sample: &Sample) -> Result<(), RunError> {
        if self.last_loc != Some(sample.loc) {
            self.settle_all()?;
            self.last_loc = Some(sample.loc);
        }
        self.line = sample.loc.line;
        // The last line of defence: a setpoint the guard refuses never reaches a backend.
        let t = sample.t + self.shift;
        let positions =
            self.command
                .positions(sample, t)
                .map_err(|violation| RunError::Setpoint {
                    diagnostic: command::refused_in_run(self.path, sample.loc, &violation),
                    violation,
                })?;
        for (c, &x) in self.commanded.iter_mut().zip(positions) {
            *c = x;
        }
        self.command
            .setpoints(sample, &self.commanded, self.io.setpoints_mut());
        // Constant surface speed follows the radius of this cycle's setpoint.
        self.follow_surface_speed()?;
        self.servo_cycle(t)
    }

    /// One cycle holding the last commanded position; planner time stands still.
    fn hold_cycle(&mut self) -> Result<(), RunError> {
        self.io.hold();
        self.command.repeat();
        let period = self.config.servo_period;
        self.shift += period;
        self.servo_cycle(self.t + period)
    }
}

/// Runs a program on a machine to its end.
pub fn run_program(
    path: &Path,
    config: &MachineConfig,
    options: RunOptions<'_>,
) -> Result<RunReport, Box<RunFailure>> {
    let mut run = Run::start(path, config, options)?;
    loop {
        match run.step() {
            Ok(true) => {}
            Ok(false) => return run.finish(None),
            Err(e) => return run.finish(Some(e)),
        }
    }
}

/// A snapshot of a run for displays.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunStatus {
    /// Machine time, s.
    pub t: f64,
    /// Program line of the motion being executed (1-based; 0 before the first).
    pub line: u32,
    /// Commanded position per machine axis.
    pub commanded: Vec<f64>,
    /// Measured position per machine axis.
    pub actual: Vec<f64>,
    /// Following error per machine axis.
    pub following_error: Vec<f64>,
    /// True while a feed hold is active or asked for (from the request on, also while it
    /// waits for the end of a geared pass and its retract).
    pub held: bool,
    /// Feed override factor (1.0 = 100 %).
    pub feed_override: f64,
    /// Path speed, mm/s.
    pub path_speed: f64,
    /// Spindle speed, rpm (signed), when the machine has a spindle.
    pub spindle_rpm: Option<f64>,
    /// Blocks executed so far.
    pub blocks: u64,
}

impl<'a, 'w> Run<'a, 'w> {
    /// Checks the program's syntax (nothing moves on a syntax error), opens the machine's
    /// backends and enables them.
    pub fn start(
        path: &'a Path,
        config: &'a MachineConfig,
        options: RunOptions<'w>,
    ) -> Result<Self, Box<RunFailure>> {
        let letters = config.letters();
        let mut report = RunReport {
            max_following_error: letters.iter().map(|&l| (l, 0.0)).collect(),
            realtime: options.realtime || config.needs_wall_clock(),
            ..RunReport::default()
        };
        let fail = |error: RunError, report: &RunReport| {
            Box::new(RunFailure {
                error,
                report: report.clone(),
            })
        };
        if let Err(diags) = klar_interp::syntax_check(path) {
            return Err(fail(RunError::Syntax(diags), &report));
        }
        let mut io = MachineIo::open(config).map_err(|e| fail(e.into(), &report))?;
        // Drives that measure their own position stand where they stand, not at the machine
        // file's `start`: the test run and the run start from there.
        let at: Vec<f64> = io.feedback().iter().map(|f| f.position).collect();
        if config.check_before_run {
            let measured = config.starting_at(at.iter().copied());
            let checked = crate::testrun::test_run(path, &measured);
            for w in checked.warnings.iter().chain(&checked.gave_up) {
                tracing::warn!("{w}");
            }
            if !checked.passed() {
                return Err(fail(RunError::Syntax(checked.errors), &report));
            }
            if checked.gave_up.is_none() {
                report.planned_time = Some(checked.planned_time);
            }
        }
        report.start = io.standing(config);
        for (s, a) in report.start.iter().zip(&config.axes) {
            tracing::info!("axis {s}; machine file start {:.4}", a.start);
        }
        if let Some(sim) = io.sim_axes() {
            sim.schedule(&config.faults).map_err(|e| {
                let e = MachineError::Open {
                    what: "fault injection".into(),
                    message: e.to_string(),
                };
                fail(e.into(), &report)
            })?;
        }
        let command = CommandPath::new(config, &at)
            .with_jumps(config)
            .map_err(|e| {
                let (what, message) = ("fault injection".into(), e.to_string());
                fail(MachineError::Open { what, message }.into(), &report)
            })?;
        let start = command.kinematics().to_program(&at);
        let mut interp = config
            .open_program(path, start)
            .map_err(|d| fail(RunError::Program(d), &report))?;
        if config.probe.as_ref().is_some_and(|p| p.latch) {
            // touch points from the drives' latches (the test run above used the model)
            interp = interp.with_measured_probing(config.probe_data());
        }
        let max_rpm = config.spindle.as_ref().map_or(0.0, |s| s.max_rpm);
        let ops = OpStream::new(interp, start, max_rpm, path);
        let checks = OpChecks {
            letters: letters.clone(),
            travel: config.axes.iter().map(|a| a.travel).collect(),
            positioning: positioning_axes(config),
            path: path.to_path_buf(),
        };
        let planner = config
            .planner(start)
            .map_err(|e| fail(RunError::Motion(e), &report))?;
        let trace = match options.trace {
            Some(w) => Some(
                TraceWriter::new(w, &letters, config.spindle.is_some())
                    .map_err(|e| fail(e.into(), &report))?,
            ),
            None => None,
        };
        io.enable().map_err(|e| fail(e.into(), &report))?;
        if !config.start_homed {
            // One cycle holding the start position tells which axes have a reference.
            let unhomed = io
                .cycle(0.0)
                .map(|()| {
                    io.feedback()
                        .iter()
                        .zip(&letters)
                        .filter(|(f, _)| !f.homed)
                        .map(|(_, &l)| l)
                        .collect::<Vec<_>>()
                })
                .map_err(|e| fail(e.into(), &report));
            let refused = match unhomed {
                Ok(u) if u.is_empty() => None,
                Ok(u) => Some(fail(RunError::NotHomed(u), &report)),
                Err(e) => Some(e),
            };
            if let Some(f) = refused {
                if let Err(e) = io.disable() {
                    tracing::warn!("disabling after a refused start: {e}");
                }
                return Err(f);
            }
        }
        let lags = io.feedback_lags();
        let functions = config
            .m_functions
            .iter()
            .filter_map(|m| Some((u32::try_from(m.number).ok()?, m.name.clone())))
            .collect();
        let (log, log_error) = LogQueue::start(functions);
        if let Some(e) = log_error {
            tracing::warn!("no log thread ({e}): the servo loop's messages are dropped");
        }
        let reader = match Reader::spawn(ops, checks) {
            Ok(r) => r,
            Err(e) => {
                if let Err(e) = io.disable() {
                    tracing::warn!("disabling after a refused start: {e}");
                }
                let (what, message) = ("program reader thread".into(), e.to_string());
                return Err(fail(MachineError::Open { what, message }.into(), &report));
            }
        };
        let mut run = Run {
            path,
            config,
            command,
            io,
            reader,
            blocks: 0,
            planner,
            input_done: false,
            pending_error: None,
            stop_requested: false,
            trace,
            report,
            pacer: Pacer::new(config.servo_period),
            wall_late: (0.0, false),
            t: 0.0,
            shift: 0.0,
            line: 0,
            commanded: at.clone(),
            actual: at.clone(),
            reference: at.clone(),
            last_sent: at.clone(),
            lags,
            warned_no_spindle: false,
            positioning: positioning_axes(config),
            end_windows: crate::testrun::end_windows(config),
            last_loc: None,
            surface_speed: None,
            stop_limits: config
                .axes
                .iter()
                .map(|a| (a.max_acceleration, a.max_jerk))
                .collect(),
            fe_limits: config
                .axes
                .iter()
                .map(|a| a.following_error_limit)
                .collect(),
            stopping: None,
            stop_report: None,
            stalls: {
                let mut s: Vec<(f64, f64)> = config
                    .faults
                    .iter()
                    .filter(|f| f.kind == crate::faults::FaultKind::Stall)
                    .map(|f| (f.at, f.stall_seconds()))
                    .collect();
                s.sort_by(|a, b| a.0.total_cmp(&b.0));
                s.into()
            },
            enforce_wall_lateness: config.max_setpoint_lateness.is_some()
                || config
                    .axes
                    .iter()
                    .any(|a| !matches!(a.backend, crate::config::BackendConfig::Sim(_))),
            letters,
            operator: None,
            operator_seen: StopLevel::None,
            sync: None,
            tap: tap::TapPass::idle(64),
            pass_hold: None,
            warp: per_rev::RevWarp::new(),
            log,
            deferred: None,
            probing: None,
        };
        // Start-up: the planner fills its look-ahead before the first cycle, waiting for
        // the reader as long as it takes.
        run.feed_planner(true);
        Ok(run)
    }

    /// Advances the run by one planner step (a servo cycle or an event). Returns false once
    /// the program has ended (or a requested stop has come to rest).
    pub fn step(&mut self) -> Result<bool, RunError> {
        if self.stop_report.is_some() {
            return Err(RunError::Stopped { line: self.line });
        }
        if self.sync.is_some() || self.tap.active() {
            // Inside a geared pass neither hold nor stop acts: the pass runs to its end.
            let geared = if self.tap.active() {
                self.tap_step()
            } else {
                self.sync_step()
            };
            return match geared {
                Ok(()) => {
                    self.apply_pass_hold();
                    Ok(true)
                }
                Err(
                    e @ (RunError::Fault { .. } | RunError::Backend(_) | RunError::Setpoint { .. }),
                ) => Err(self.quick_stop(e)),
                Err(e) => Err(e),
            };
        }
        if self.probe_moving() {
            return match self.probe_step() {
                Ok(()) => Ok(true),
                Err(
                    e @ (RunError::Fault { .. } | RunError::Backend(_) | RunError::Setpoint { .. }),
                ) => Err(self.quick_stop(e)),
                Err(e) => Err(e),
            };
        }
        let wait = !self.report.realtime;
        let mut fed = self.feed_planner(wait);
        // A stop waiting for the retract after a geared pass ends once that hold is in force.
        let stop_waits =
            self.pass_hold.is_some() || (self.planner.hold_pending() && !self.planner.is_held());
        if self.planner.path_speed() == 0.0
            && !stop_waits
            && let Some(pending) = self.stopping.take()
        {
            return Err(self.end_path_stop(pending));
        }
        let mut next = self.planner.next_step();
        while next.is_none() && !self.input_done && self.planner.needs_input() {
            // The step freed a place in a full planner (a stop reached): it wants more input
            // before it goes on, which is not the end of the program. Each round takes an op
            // or ends the input.
            if !fed {
                if self.probing.is_some() {
                    // Before a probing move: the machine comes to rest, then the run moves.
                    if self.planner.drained() {
                        return self.start_probe_move().map(|()| true);
                    }
                    next = self.planner.next_step_starved();
                    break;
                }
                // Starved: the reader has not kept up. The path goes on with what it has,
                // braking for its end (the planner always can), and the cycle is counted.
                self.report.starved += 1;
                next = self.planner.next_step_starved();
                break;
            }
            fed = self.feed_planner(wait);
            next = self.planner.next_step();
        }
        let result = match next {
            None => self
                .settle_all()
                .and_then(|()| self.settle_end())
                .map(|()| false),
            Some(Step::Sample(sample)) => self.warped_sample(sample).map(|()| true),
            // While stopping, events (spindle, stops) of blocks not reached are not executed.
            Some(Step::Event(op)) if self.stopping.is_some() => {
                self.reader.give_back(op);
                Ok(true)
            }
            Some(Step::Event(op)) => {
                let handled = self.handle_event(&op).map(|()| true);
                self.reader.give_back(op);
                handled
            }
        };
        match result {
            Err(
                e @ (RunError::Fault { .. } | RunError::Backend(_) | RunError::Setpoint { .. }),
            ) => Err(self.quick_stop(e)),
            other => other,
        }
    }

    /// Feed hold: slows down along the path to a stop and waits. Inside a pass geared to
    /// the spindle it waits for the pass to end (see `pass_hold`): after a thread pass
    /// and its retract, after a rigid tap.
    pub fn hold(&mut self) {
        if self.in_geared_pass() {
            self.defer_hold();
        } else {
            self.planner.hold();
        }
    }

    /// Ends a feed hold (or cancels one not yet in force).
    pub fn resume(&mut self) {
        self.pass_hold = None;
        self.planner.resume();
    }

    /// Sets the feed override (0.0 to 1.5); returns the factor in effect.
    pub fn set_feed_override(&mut self, factor: f64) -> f64 {
        self.planner.set_feed_override(factor)
    }

    /// Stops the run in a controlled way: a feed hold, then the run ends at rest with
    /// [`RunError::Stopped`].
    pub fn request_stop(&mut self) {
        if self.stopping.is_none() && !self.stop_requested {
            self.stop_requested = true;
            let line = self.line;
            self.begin_path_stop(StopCause::Requested, None, RunError::Stopped { line });
        }
    }

    /// The report of the stop that ended the run, once it is at rest.
    pub fn stop_report(&self) -> Option<&StopReport> {
        self.stop_report.as_ref()
    }

    /// Tells the spindle the chip cross-section the tool cuts now, mm² (0 out of the cut):
    /// a simulated spindle slows by its `load_droop` (for tests, or a process model that
    /// knows the cut).
    pub fn set_spindle_load(&mut self, section_mm2: f64) {
        if let Some(s) = self.io.spindle_mut() {
            s.set_load(section_mm2);
        }
    }

    /// The simulated axes of the machine (fault injection, inspection), if it has any.
    pub fn sim_axes(&self) -> Option<&crate::faults::SimAxes> {
        self.io.sim_axes()
    }

    /// A snapshot for displays.
    pub fn status(&mut self) -> RunStatus {
        let mut status = RunStatus::default();
        self.status_into(&mut status);
        status
    }

    /// Fills `status` as [`Run::status`] would, reusing its buffers: once they hold the
    /// machine's axes this allocates nothing, so a loop that steps the run can read it every
    /// cycle.
    pub fn status_into(&mut self, status: &mut RunStatus) {
        status.spindle_rpm = self.io.spindle_mut().map(|s| s.feedback().rpm);
        status.t = self.t;
        status.line = self.line;
        status.commanded.clone_from(&self.commanded);
        status.actual.clone_from(&self.actual);
        status.following_error.clear();
        status
            .following_error
            .extend(self.io.feedback().iter().map(|f| f.following_error));
        status.held = self.planner.is_held() || self.hold_deferred();
        status.feed_override = self.planner.feed_override();
        status.path_speed = self.planner.path_speed();
        status.blocks = self.blocks;
    }

    /// Program line of the motion being executed (1-based; 0 before the first), read
    /// without the allocations of [`Run::status`].
    pub fn line(&self) -> u32 {
        self.line
    }

    /// Machine time of the last cycle, s.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Where each axis stood when the run started, and whether it is referenced.
    pub fn start_positions(&self) -> &[AxisStart] {
        &self.report.start
    }

    /// The test run's planned machine time of the whole program, s (see
    /// [`RunReport::planned_time`]).
    pub fn planned_time(&self) -> Option<f64> {
        self.report.planned_time
    }

    /// The machine axis letters, in trace order.
    pub fn letters(&self) -> &[AxisLetter] {
        &self.letters
    }

    /// Ends the run: stops the spindle, disables the axes, flushes the trace and reports.
    /// `error` is the error that ended the run early, if any; an error found while reading
    /// ahead (reported after the motion before it finished) comes out here too.
    pub fn finish(mut self, error: Option<RunError>) -> Result<RunReport, Box<RunFailure>> {
        self.report.blocks = self.blocks;
        self.log.close();
        self.report.log_dropped = self.log.dropped;
        if let Some((what, e)) = self.deferred.take() {
            tracing::warn!("{what}: {e}");
        }
        if let Some(stop) = &self.stop_report {
            tracing::warn!("{stop}");
        }
        if self.report.log_dropped > 0 {
            tracing::warn!(
                "{} log records from the servo loop were dropped (queue full)",
                self.report.log_dropped
            );
        }
        self.report.blends = self.planner.blends_made();
        self.report.blends_refused = self.planner.blends_refused();
        if self.report.blends_refused > 0 {
            tracing::warn!(
                "{} corners stopped exactly: every blend slot was held by the path ahead",
                self.report.blends_refused
            );
        }
        if self.report.starved > 0 {
            tracing::warn!(
                "the program reader fell behind in {} servo cycles: the path braked for the end \
                 of the ops it had",
                self.report.starved
            );
        }
        let disabled = self.io.disable();
        self.report.spindle_warning = self.io.spindle_mut().and_then(|s| s.stop_warning());
        if self.report.realtime {
            self.report.lateness = Some(self.pacer.histogram.summary());
            self.report.cycle_work = Some(self.pacer.work.summary());
            self.report.work_overruns = self.pacer.overruns;
        }
        let report = self.report;
        let trace_done = match self.trace {
            Some(t) => t.finish(),
            None => Ok(()),
        };
        let fail = |error: RunError| {
            Box::new(RunFailure {
                error,
                report: report.clone(),
            })
        };
        if let Some(e) = error.or(self.pending_error) {
            return Err(fail(e));
        }
        disabled.map_err(|e| fail(e.into()))?;
        trace_done.map_err(|e| fail(e.into()))?;
        Ok(report)
    }

    /// Moves ops from the reader into the planner while it wants more, waiting for them
    /// when `wait`. Returns false when the planner wants more and the reader has none yet.
    fn feed_planner(&mut self, wait: bool) -> bool {
        while !self.input_done && self.planner.needs_input() {
            if self.probing.is_some() {
                // nothing comes before the probing move is measured
                return false;
            }
            match self.reader.next(wait) {
                None => return false,
                Some(Feed::Probe(request, blank, blocks)) => {
                    self.blocks = blocks;
                    if let Err(e) = self.planner.end_in_stop() {
                        self.stop_reading(RunError::Motion(e));
                        return true;
                    }
                    self.probing = Some(probing::Probing::new(request, blank));
                    return false;
                }
                Some(Feed::Op(op, blocks, basis)) => {
                    self.blocks = blocks;
                    if matches!(
                        op.kind,
                        OpKind::Line { .. } | OpKind::Arc { .. } | OpKind::Spline { .. }
                    ) {
                        self.warp.remember(op.loc, basis);
                    }
                    if let Err(e) = self.planner.push(op) {
                        self.stop_reading(RunError::Motion(e));
                    }
                    // A spline block's coefficients are freed by the reader, not here.
                    if let Some(spent) = self.planner.take_spent() {
                        self.reader.give_back(spent);
                    }
                }
                Some(Feed::Error(e, blocks)) => {
                    self.blocks = self.blocks.max(blocks);
                    self.stop_reading(e);
                }
                Some(Feed::End(blocks)) => {
                    self.blocks = blocks;
                    self.planner.finish();
                    self.input_done = true;
                }
            }
        }
        true
    }

    /// Keeps an error met during a stop that goes on, for the log when the run finishes
    /// (the first one: what follows from it adds nothing).
    fn defer(&mut self, what: &'static str, error: RunError) {
        if self.deferred.is_none() {
            self.deferred = Some((what, error));
        }
    }

    /// An error found while reading ahead: the motion of the blocks before it finishes, then
    /// the run reports it.
    fn stop_reading(&mut self, error: RunError) {
        self.pending_error = Some(error);
        self.planner.finish();
        self.input_done = true;
    }
}
