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
mod cycle;
mod display;
mod error;
mod events;
mod feed;
pub mod guard;
mod log;
mod operator;
mod pass_hold;
mod per_rev;
mod probing;
mod reader;
mod report;
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
use crate::trace::TraceWriter;
use command::CommandPath;
pub use error::RunError;
use klar_interp::{AxisLetter, SourceLoc};
use klar_motion::{Planner, Step};
use log::{LogQueue, LogRecord};
pub use operator::{OperatorStop, StopLevel};
use reader::{OpChecks, Reader};
pub use report::{AxisStart, RunFailure, RunReport, RunStatus};
use std::collections::VecDeque;
use std::io::Write;
use std::path::Path;
use stop::PendingStop;
use stream::OpStream;

/// How to run.
pub struct RunOptions<'a> {
    /// Run the servo loop on the wall clock instead of as fast as possible.
    pub realtime: bool,
    /// Where to write the trace CSV, if anywhere.
    pub trace: Option<&'a mut dyn Write>,
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
}
