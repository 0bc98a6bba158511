//! The machine thread behind the dashboard: owns the machine configuration and, while a
//! program runs, the [`Run`]; takes [`Command`]s from the web side and publishes
//! [`Snapshot`]s of the machine a few dozen times a second.
//!
//! A [`Run`] holds parts that must stay on one thread, so it is created and stepped here and
//! never leaves this thread; the web side only talks to it through channels.

mod manual_ops;
pub mod publisher;
mod readings;
pub mod spindle;

use super::manual::{ManualOp, Refusal};
use crate::config::{BackendConfig, MachineConfig};
use crate::runtime::{OperatorStop, Run, RunError, RunOptions, StopLevel};
use klar_interp::ProbeResult;
use publisher::{PUBLISH_PERIOD, Publisher, Record};
use serde::Serialize;
use spindle::{HeldSpindle, SpindleRequest, SpindleStatus};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::broadcast;

/// Wall time between two snapshots while idle.
const IDLE_PUBLISH_PERIOD: Duration = Duration::from_millis(500);

/// Longest the idle loop waits for a command before it looks at the operator's stop.
const IDLE_POLL: Duration = Duration::from_millis(100);

/// Machine time between two points of the executed-path trail, s.
const TRAIL_PERIOD: f64 = 0.005;

/// Machine time one axis may take to home, s.
const HOMING_TIMEOUT: f64 = 300.0;

/// Where the machine thread answers a request: accepted (the operation begins) or refused
/// with the reason.
pub type Reply = tokio::sync::oneshot::Sender<Result<(), Refusal>>;

/// What the operator asks of the machine.
#[derive(Debug)]
pub enum Command {
    /// Makes `path` (shown as `name`) the program that [`Command::Start`] runs.
    Load {
        /// Name shown on the page.
        name: String,
        /// The program file.
        path: PathBuf,
    },
    /// Runs the loaded program from its start, from where the axes stand; refused while
    /// the machine runs or has an unacknowledged fault.
    Start(Option<Reply>),
    /// A manual operation (jog, homing, MDI); refused like [`Command::Start`].
    Manual(ManualOp, Reply),
    /// The spindle by hand (on, off, speed); refused like [`Command::Start`].
    Spindle(SpindleRequest, Reply),
    /// Acknowledges the fault or error that ended the last run (refused while running).
    Reset(Reply),
    /// Feed hold: brake along the path and wait.
    Hold,
    /// End a feed hold.
    Resume,
    /// Controlled stop: a feed hold, then the run ends.
    Stop,
    /// Feed override factor (0.0 to 1.5).
    Override(f64),
    /// Single block on or off: with it on, the machine holds as each new block begins.
    SingleBlock(bool),
}

/// What the machine is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MachineState {
    /// No program running.
    Idle,
    /// A program is moving the axes.
    Running,
    /// A feed hold is active.
    Held,
    /// The last run ended at the program's end.
    Finished,
    /// The last run was stopped on request.
    Stopped,
    /// The last run ended with an axis or spindle fault.
    Fault,
    /// The last run ended with a program or machine error.
    Error,
}

/// One picture of the machine for the page (serialised to JSON).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Snapshot {
    /// Increases with every snapshot.
    pub seq: u64,
    /// Machine state.
    pub state: MachineState,
    /// Name of the loaded program.
    pub program: Option<String>,
    /// Machine time of the current run, s.
    pub t: f64,
    /// Program line being executed (1-based; 0 before the first motion).
    pub line: u32,
    /// Blocks executed.
    pub blocks: u64,
    /// Axis letters, in machine order.
    pub letters: Vec<String>,
    /// Commanded position per axis (mm or degrees).
    pub commanded: Vec<f64>,
    /// Measured position per axis.
    pub actual: Vec<f64>,
    /// Per axis: its position is referenced (homed, an absolute encoder, or a machine file
    /// with `start_homed`); taken from the drives when a run starts.
    pub referenced: Vec<bool>,
    /// Following error per axis.
    pub following_error: Vec<f64>,
    /// Commanded velocity per axis over the last servo cycle, per second.
    pub velocity: Vec<f64>,
    /// Commanded acceleration per axis over the last servo cycle, per second².
    pub acceleration: Vec<f64>,
    /// Path speed, mm/s.
    pub path_speed: f64,
    /// Feed override factor in force.
    pub feed_override: f64,
    /// Single block mode.
    pub single_block: bool,
    /// Spindle speed (rpm, signed) when the machine has a spindle.
    pub spindle_rpm: Option<f64>,
    /// The spindle (commanded direction and speed, measured speed) when the machine has
    /// one.
    pub spindle: Option<SpindleStatus>,
    /// The tool's measured position (X, Y, Z) in the frame of the program's path (see
    /// [`readings::tool_of`]).
    pub tool: [f64; 3],
    /// What the last touch-probe cycle measured, and the preset it wrote.
    pub probe: Option<ProbeResult>,
    /// The last fault or error message, if the last run ended with one.
    pub message: Option<String>,
    /// The manual operation running or last run (`jog X +2.500`, `MDI L X+10`, …), `None`
    /// while the loaded program runs.
    pub manual: Option<String>,
    /// Executed tool positions (X, Y, Z) since the previous snapshot.
    pub trail: Vec<[f64; 3]>,
}

/// Functions the machine thread calls around the servo cycles of a run: `begin` right
/// before the first cycle (the run has started), `end` right after the last (before the
/// run's end is handled). A place to mark the thread for a measurement, such as counting
/// what it allocates while it steps.
#[derive(Debug, Clone, Copy)]
pub struct SteppingHooks {
    /// Called before the first servo cycle.
    pub begin: fn(),
    /// Called after the last servo cycle.
    pub end: fn(),
}

/// The machine thread's side of the channels.
pub struct MachineLoop {
    config: MachineConfig,
    commands: Receiver<Command>,
    /// Where snapshots and the servo cycles' readings go.
    publisher: Publisher,
    snap: Snapshot,
    program_path: Option<PathBuf>,
    feed_override: f64,
    /// Where the axes stand (machine order): every run starts from here, as the axes of a
    /// machine do; updated from the measured positions when a run ends.
    standing: Vec<f64>,
    /// Axes homed from the dashboard (a simulated axis keeps its reference across runs).
    homed: Vec<bool>,
    /// The spindle held between runs (turned on by hand, or left turning by an MDI block).
    held: Option<HeldSpindle>,
    /// Folder for the programs manual operations generate.
    scratch: PathBuf,
    /// The operator's stop from outside (signals): ends a running program and the loop.
    stop: OperatorStop,
    /// Called around the servo cycles of each run.
    hooks: Option<SteppingHooks>,
}

/// Finite differences of the commanded positions, one servo cycle apart.
struct Derivatives {
    t: f64,
    position: Vec<f64>,
    velocity: Vec<f64>,
    acceleration: Vec<f64>,
}

impl Derivatives {
    fn new(n: usize) -> Self {
        Self {
            t: 0.0,
            position: vec![0.0; n],
            velocity: vec![0.0; n],
            acceleration: vec![0.0; n],
        }
    }

    /// Takes the commanded positions at time `t`; a step that did not advance time is
    /// skipped.
    fn update(&mut self, t: f64, commanded: &[f64], first: bool) {
        let dt = t - self.t;
        if first {
            self.position.clone_from_slice(commanded);
            self.t = t;
            return;
        }
        if dt <= 0.0 {
            return;
        }
        for (i, &c) in commanded.iter().enumerate() {
            let (Some(p), Some(v), Some(a)) = (
                self.position.get_mut(i),
                self.velocity.get_mut(i),
                self.acceleration.get_mut(i),
            ) else {
                continue;
            };
            let nv = (c - *p) / dt;
            *a = (nv - *v) / dt;
            *v = nv;
            *p = c;
        }
        self.t = t;
    }
}

impl MachineLoop {
    /// A machine loop for `config`; snapshots go to `snapshots` and `latest` from a
    /// publisher thread started here (an error when it cannot be started).
    pub fn new(
        config: MachineConfig,
        commands: Receiver<Command>,
        snapshots: broadcast::Sender<Snapshot>,
        latest: Arc<Mutex<Snapshot>>,
    ) -> std::io::Result<Self> {
        let publisher = Publisher::start(snapshots, latest)?;
        let snap = idle_snapshot(&config);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        let scratch =
            std::env::temp_dir().join(format!("klar-manual-{}-{nanos:x}", std::process::id()));
        Ok(Self {
            standing: config.axes.iter().map(|a| a.start).collect(),
            homed: vec![false; config.axes.len()],
            held: None,
            scratch,
            config,
            commands,
            publisher,
            snap,
            program_path: None,
            feed_override: 1.0,
            stop: OperatorStop::new(),
            hooks: None,
        })
    }

    /// Makes the loop call `hooks` around the servo cycles of every run.
    pub fn with_stepping_hooks(mut self, hooks: SteppingHooks) -> Self {
        self.hooks = Some(hooks);
        self
    }

    /// Makes the loop watch `stop`: a request stops a running program under control (a
    /// second one with a quick stop) and then ends the loop.
    pub fn with_operator_stop(mut self, stop: OperatorStop) -> Self {
        self.stop = stop;
        self
    }

    /// Serves commands until every sender is gone or the operator's stop is requested.
    pub fn run(mut self) {
        self.publish();
        let mut last_publish = Instant::now();
        while self.stop.level() == StopLevel::None {
            let spinning = self.spindle_tick();
            if spinning && last_publish.elapsed() >= PUBLISH_PERIOD {
                self.publish();
                last_publish = Instant::now();
            }
            let poll = if spinning {
                spindle::SPINDLE_POLL
            } else {
                IDLE_POLL
            };
            match self.commands.recv_timeout(poll) {
                Ok(Command::Start(reply)) => self.start_program(reply),
                Ok(Command::Manual(op, reply)) => self.manual(op, reply),
                Ok(other) => self.idle_command(other),
                Err(RecvTimeoutError::Timeout) => {
                    if last_publish.elapsed() >= IDLE_PUBLISH_PERIOD {
                        self.publish();
                        last_publish = Instant::now();
                    }
                }
                Err(RecvTimeoutError::Disconnected) => {
                    let _ = std::fs::remove_dir_all(&self.scratch);
                    return;
                }
            }
        }
        let _ = std::fs::remove_dir_all(&self.scratch);
        tracing::info!("machine loop ended by the operator's stop");
    }

    /// The machine as the next run sees it: every axis starting where it stands, and a
    /// simulated axis homed from the dashboard still referenced.
    fn run_config(&self) -> MachineConfig {
        let mut c = self.config.starting_at(self.standing.iter().copied());
        for (a, &homed) in c.axes.iter_mut().zip(&self.homed) {
            if homed && let BackendConfig::Sim(p) = &mut a.backend {
                p.start_homed = true;
            }
        }
        c
    }

    /// Why nothing may start now, if anything.
    fn refusal(&self) -> Option<Refusal> {
        match self.snap.state {
            MachineState::Running | MachineState::Held => Some(Refusal::Busy),
            MachineState::Fault => Some(Refusal::Faulted(
                self.snap
                    .message
                    .as_deref()
                    .and_then(|m| m.lines().next())
                    .unwrap_or("fault")
                    .to_string(),
            )),
            _ => None,
        }
    }

    fn start_program(&mut self, reply: Option<Reply>) {
        let refused = self
            .refusal()
            .or_else(|| self.program_path.is_none().then_some(Refusal::NoProgram));
        let ok = refused.is_none();
        match reply {
            Some(r) => {
                let _ = r.send(refused.map_or(Ok(()), Err));
            }
            None => {
                if let Some(r) = refused {
                    tracing::warn!("start refused: {r}");
                }
            }
        }
        if ok && let Some(path) = self.program_path.clone() {
            self.snap.manual = None;
            self.run_program(&path);
        }
    }

    fn idle_command(&mut self, command: Command) {
        match command {
            Command::Load { name, path } => {
                // A fault stays until it is acknowledged; loading does not hide it.
                if self.snap.state != MachineState::Fault {
                    self.snap.state = MachineState::Idle;
                    self.snap.message = None;
                }
                self.snap.program = Some(name);
                self.program_path = Some(path);
                self.snap.line = 0;
                self.snap.blocks = 0;
                self.snap.t = 0.0;
                self.snap.manual = None;
            }
            Command::Reset(reply) => {
                self.snap.state = MachineState::Idle;
                self.snap.message = None;
                self.snap.line = 0;
                self.snap.t = 0.0;
                // After Reset the spindle stands, as after a fault.
                self.stop_spindle();
                self.show_held_spindle();
                let _ = reply.send(Ok(()));
            }
            Command::Override(f) => {
                if f.is_finite() {
                    self.feed_override = f.clamp(0.0, 1.5);
                    self.snap.feed_override = self.feed_override;
                }
            }
            Command::SingleBlock(on) => self.snap.single_block = on,
            Command::Hold | Command::Resume | Command::Stop => {}
            Command::Start(reply) => self.start_program(reply),
            Command::Manual(op, reply) => self.manual(op, reply),
            Command::Spindle(request, reply) => self.spindle(request, reply),
        }
        self.publish();
    }

    /// Hands the whole snapshot to the publisher (not between servo cycles: it allocates).
    fn publish(&mut self) {
        self.publisher.send(self.snap.clone());
        self.snap.trail.clear();
    }

    /// Takes the readings of a run back from the publisher's slot and from `record` (the
    /// newest) into the snapshot, before a whole one is published between servo cycles.
    fn settle(&mut self, record: &mut Record) {
        let axes = record.commanded.len();
        self.publisher.take_back(&mut self.snap, axes);
        record.apply(&mut self.snap);
        record.trail.clear();
    }

    /// Runs the loaded program on the wall clock until it ends, taking commands between
    /// servo cycles.
    fn run_program(&mut self, path: &Path) {
        let path = path.to_path_buf();
        let config = self.run_config();
        let options = RunOptions {
            realtime: true,
            trace: None,
        };
        self.snap.message = None;
        self.snap.trail.clear();
        // Running from here on (the test run and the start included): the web side refuses
        // loading and replacing the program from now.
        self.snap.state = MachineState::Running;
        self.publish();
        let mut run = match Run::start(&path, &config, options) {
            Ok(r) => r,
            Err(f) => {
                self.end_with(Some(f.error), &path);
                return;
            }
        };
        // A spindle turning from before goes on turning under this run's commands.
        self.spindle_into_run(&mut run);
        run.set_feed_override(self.feed_override);
        run.watch_operator_stop(self.stop.clone());
        // Where the axes stand as their drives report it, before the first cycle.
        let start = run.start_positions();
        self.snap.referenced = start.iter().map(|a| a.referenced).collect();
        self.snap.actual = start.iter().map(|a| a.position).collect();
        self.snap.commanded.clone_from(&self.snap.actual);
        tracing::info!(program = %path.display(), "run started");
        let axes = run.letters().len();
        let mut derivatives = Derivatives::new(axes);
        let mut first = true;
        // Each cycle's reading, handed to the publisher through its slot (both sized here).
        let mut record = Record::sized(axes);
        let slot = self.publisher.slot();
        self.publisher.take_back(&mut self.snap, axes);
        let mut probes = run.probe_results().len();
        let mut last_trail_t = f64::NEG_INFINITY;
        let mut last_line = 0u32;
        let mut last_actual = self.standing.clone();
        // Read every cycle into the same buffers (no allocation per cycle).
        let mut status = run.status();
        if let Some(h) = self.hooks {
            (h.begin)();
        }
        let outcome = loop {
            match self.commands.try_recv() {
                Ok(c) => self.run_command(&mut run, c),
                Err(TryRecvError::Empty) => {}
                Err(TryRecvError::Disconnected) => run.request_stop(),
            }
            let stepped = run.step();
            run.status_into(&mut status);
            derivatives.update(status.t, &status.commanded, first);
            first = false;
            if self.snap.single_block && status.line != last_line && last_line != 0 {
                run.hold();
            }
            last_line = status.line;
            // Before the first servo cycle there is no measured position yet.
            if status.t > 0.0 && status.t - last_trail_t >= TRAIL_PERIOD {
                last_trail_t = status.t;
                record.push_trail(run.tool_position());
            }
            readings::read_cycle(&mut record, &status, &derivatives, &mut run);
            record.single_block = self.snap.single_block;
            // Never waits: while the publisher reads the slot, this reading waits for the
            // next cycle (its trail points stay in `record`).
            if let Ok(mut r) = slot.try_lock() {
                r.take_from(&mut record);
            }
            // A touch-probe cycle's result (once per cycle, the motion at rest): published
            // whole, which allocates.
            if run.probe_results().len() != probes {
                probes = run.probe_results().len();
                self.snap.probe = run.probe_results().last().cloned();
                self.settle(&mut record);
                self.publish();
            }
            // At rest the drives hold the commanded position; after a fault the measured
            // one counts (see below).
            self.standing.clone_from(&status.commanded);
            last_actual.clone_from(&status.actual);
            match stepped {
                Ok(true) => {}
                Ok(false) => break None,
                Err(e) => break Some(e),
            }
        };
        if let Some(h) = self.hooks {
            (h.end)();
        }
        // The last reading, whole.
        self.settle(&mut record);
        self.publish();
        // A manual run that ended normally leaves the spindle as it was (turning on); any
        // other run's end stops it.
        let keep =
            self.snap.manual.is_some() && matches!(outcome, None | Some(RunError::Stopped { .. }));
        self.spindle_out_of_run(&mut run, keep);
        let (error, stop, spindle_warning) = match run.finish(outcome) {
            Ok(report) => (None, report.stop, report.spindle_warning),
            Err(f) => (Some(f.error), f.report.stop, f.report.spindle_warning),
        };
        self.end_with(error, &path);
        if self.snap.state == MachineState::Fault {
            // A quick stop brakes in the drives, off the commanded path.
            self.standing = last_actual;
        }
        // How the safety monitor brought the machine to rest, under the fault message.
        if let Some(stop) = stop
            && matches!(self.snap.state, MachineState::Fault | MachineState::Error)
        {
            let line = stop.to_string();
            self.snap.message = Some(match self.snap.message.take() {
                Some(m) => format!("{m}\n{line}"),
                None => line,
            });
            self.publish();
        }
        // A spindle whose stop its device did not confirm: said last, whatever the end.
        if let Some(w) = spindle_warning {
            tracing::error!("{w}");
            self.snap.message = Some(match self.snap.message.take() {
                Some(m) => format!("{m}\n{w}"),
                None => w,
            });
            self.publish();
        }
    }

    fn run_command(&mut self, run: &mut Run<'_, '_>, command: Command) {
        match command {
            Command::Hold => run.hold(),
            Command::Resume => run.resume(),
            Command::Stop => run.request_stop(),
            Command::Override(f) => {
                self.feed_override = run.set_feed_override(f);
            }
            Command::SingleBlock(on) => self.snap.single_block = on,
            Command::Start(Some(reply))
            | Command::Manual(_, reply)
            | Command::Spindle(_, reply)
            | Command::Reset(reply) => {
                let _ = reply.send(Err(Refusal::Busy));
            }
            // Loading while a program runs is refused by the API; a late one is dropped.
            Command::Load { .. } | Command::Start(None) => {
                tracing::warn!("ignored while a program runs: {command:?}");
            }
        }
    }

    fn end_with(&mut self, error: Option<RunError>, path: &Path) {
        let (state, message) = match &error {
            None => (MachineState::Finished, None),
            Some(RunError::Stopped { .. }) => (MachineState::Stopped, None),
            Some(e @ RunError::Operator { .. }) => (MachineState::Stopped, Some(e.to_string())),
            Some(
                e @ (RunError::Fault { .. } | RunError::Spindle { .. } | RunError::Setpoint { .. }),
            ) => (MachineState::Fault, Some(e.to_string())),
            Some(RunError::Syntax(diags)) => (
                MachineState::Error,
                Some(
                    diags
                        .iter()
                        .map(|d| d.to_string())
                        .collect::<Vec<_>>()
                        .join("\n"),
                ),
            ),
            Some(e) => (MachineState::Error, Some(e.to_string())),
        };
        match &message {
            Some(m) => tracing::warn!(program = %path.display(), "run ended: {m}"),
            None => tracing::info!(program = %path.display(), ?state, "run ended"),
        }
        self.snap.state = state;
        self.snap.message = message;
        // At rest: no speed, no run time; the spindle stopped by the run's end unless a
        // manual run handed it back turning.
        self.snap.path_speed = 0.0;
        self.snap.t = 0.0;
        self.show_held_spindle();
        self.snap.velocity.iter_mut().for_each(|v| *v = 0.0);
        self.snap.acceleration.iter_mut().for_each(|v| *v = 0.0);
        self.publish();
    }
}

/// The snapshot of a machine at rest at its start positions.
pub fn idle_snapshot(config: &MachineConfig) -> Snapshot {
    let n = config.axes.len();
    let start: Vec<f64> = config.axes.iter().map(|a| a.start).collect();
    Snapshot {
        seq: 0,
        state: MachineState::Idle,
        program: None,
        t: 0.0,
        line: 0,
        blocks: 0,
        letters: config.axes.iter().map(|a| a.letter.to_string()).collect(),
        commanded: start.clone(),
        actual: start.clone(),
        referenced: vec![config.start_homed; n],
        following_error: vec![0.0; n],
        velocity: vec![0.0; n],
        acceleration: vec![0.0; n],
        path_speed: 0.0,
        feed_override: 1.0,
        single_block: false,
        spindle_rpm: config.spindle.as_ref().map(|_| 0.0),
        spindle: config.spindle.as_ref().map(|_| SpindleStatus::stopped()),
        tool: readings::tool_of(config, &start),
        probe: None,
        message: None,
        manual: None,
        trail: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_of_a_parabola_give_its_velocity_and_acceleration() {
        // x(t) = 3 t², sampled every 1 ms: backward differences give v = 3(2t - dt),
        // a = 6 exactly.
        let dt = 0.001;
        let mut d = Derivatives::new(1);
        d.update(0.0, &[0.0], true);
        for k in 1..=100 {
            let t = k as f64 * dt;
            d.update(t, &[3.0 * t * t], false);
        }
        let t = 0.1;
        assert!((d.velocity[0] - 3.0 * (2.0 * t - dt)).abs() < 1e-9);
        assert!((d.acceleration[0] - 6.0).abs() < 1e-6);
        // A step that does not advance time changes nothing.
        d.update(t, &[100.0], false);
        assert!((d.acceleration[0] - 6.0).abs() < 1e-6);
    }
}
