//! The test run (`klar check PROGRAM --machine FILE`): executes the whole program against a
//! machine without moving anything and reports every problem it can find before motion —
//! interpreter errors anywhere in the program (each erroneous block is skipped and the check
//! goes on), soft limits per axis with the block and the axis named, spindle speeds above the
//! machine's, TOOL CALLs of tools missing from the machine's tool table, moves the planner
//! refuses (contour and compensation violations), positioning axes programmed together with
//! others, and feeds the axes cannot reach (a warning: the control limits them).
//!
//! The planner pass follows the run's own commanded trajectory: the ops reach the planner as
//! the run feeds them, and every sample goes through the run's command path
//! ([`crate::runtime::command::CommandPath`]: kinematics with TCPM switched by the planner's
//! events, then the setpoint guard of [`crate::runtime::guard`]), so a step beyond an axis's
//! velocity or acceleration limit, or a setpoint outside its travel, that would stop the run
//! is refused here first, at its block and line.
//!
//! What it cannot decide statically is listed too: after the first interpreter error the
//! program's later positions depend on how the error is resolved, so the machine checks stop
//! there; without a tool table, tool existence is not checked. `klar run` refuses to start a
//! program the test run refuses (see [`crate::config::MachineConfig::check_before_run`]).

use crate::bounds::op_bounds;
use crate::config::{BackendConfig, MachineConfig};
use crate::runtime::RunError;
use crate::runtime::command::{CommandPath, refused_in_check};
use crate::runtime::guard::Violation;
use crate::runtime::stream::OpStream;
use crate::runtime::sync::SyncProfile;
use klar_interp::op::{SpindleDir, SpindleSpeed};
use klar_interp::{AxisLetter, Diagnostic, Feed, Op, OpKind, Pose, SourceLoc};
use klar_motion::{Planner, Sample, Step};
use std::path::Path;

/// Slack on soft-limit comparisons, mm or degrees.
const TRAVEL_SLACK: f64 = 1e-9;

/// Longest planned machine time the test run simulates, s: a program that has not ended by
/// then (an endless loop with motion) is reported as undecided at the block reached.
pub const MAX_PLANNED_TIME: f64 = 24.0 * 3600.0;

/// Most servo cycles the test run plans (the bound on its computing time when the servo
/// period is short: at 1 ms, [`MAX_PLANNED_TIME`] comes first).
pub const MAX_SERVO_CYCLES: u64 = 100_000_000;

/// Most executed blocks with an action (moves, machine functions: the ops the interpreter
/// hands out) the test run follows. Blocks without one are bounded by the interpreter's
/// [`klar_interp::RUN_IDLE_JUMP_LIMIT`] between two actions.
pub const MAX_EXECUTED_BLOCKS: u64 = 10_000_000;

/// What the interpreter's check says when it stops at [`klar_interp::CHECK_JUMP_LIMIT`].
const LOOP_MARK: &str = "jumps: the check stops";

/// Where the test run gives up on a program that does not end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TestRunLimits {
    /// Planned machine time, s.
    pub machine_time: f64,
    /// Planned servo cycles.
    pub servo_cycles: u64,
    /// Executed blocks with an action.
    pub blocks: u64,
}

impl Default for TestRunLimits {
    fn default() -> Self {
        TestRunLimits {
            machine_time: MAX_PLANNED_TIME,
            servo_cycles: MAX_SERVO_CYCLES,
            blocks: MAX_EXECUTED_BLOCKS,
        }
    }
}

/// What the test run found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TestRunReport {
    /// Problems that refuse the run, in program order per check.
    pub errors: Vec<Diagnostic>,
    /// Problems the control handles itself (feeds it limits); the run may start.
    pub warnings: Vec<Diagnostic>,
    /// What could not be decided before motion, in words.
    pub undecided: Vec<String>,
    /// Motion ops checked against the machine.
    pub motion_ops: u64,
    /// Moves geared to the spindle (thread passes) among them: their setpoints follow the
    /// measured spindle angle, so their jerk is the spindle's, not the planner's.
    pub geared_ops: u64,
    /// Planned machine time of the checked part of the program, s.
    pub planned_time: f64,
    /// Lowest and highest position per machine axis over the checked moves.
    pub envelope: Vec<(AxisLetter, f64, f64)>,
    /// The program did not end within the [`TestRunLimits`]: an endless loop, or a program
    /// longer than them. Neither passed nor refused: the block reached and why.
    pub gave_up: Option<Diagnostic>,
}

impl TestRunReport {
    /// True when the run may start.
    pub fn passed(&self) -> bool {
        self.errors.is_empty()
    }
}

/// The start pose of a machine (program coordinates).
pub fn start_pose(config: &MachineConfig) -> Pose {
    let mut p = Pose::ZERO;
    for a in &config.axes {
        p[a.letter] = a.start;
    }
    p
}

/// Per machine axis: (in-position window, settle timeout) for positioning-only axes.
pub(crate) fn positioning_axes(config: &MachineConfig) -> Vec<Option<(f64, f64)>> {
    config
        .axes
        .iter()
        .map(|a| match &a.backend {
            BackendConfig::Modbus(m) => Some((m.in_position, m.settle_timeout)),
            _ => None,
        })
        .collect()
}

/// Per machine axis: (in-position window, timeout) the program's end waits for before the
/// drives are switched off: the drives that follow on their own (CANopen) and the
/// positioning axes.
pub(crate) fn end_windows(config: &MachineConfig) -> Vec<Option<(f64, f64)>> {
    config
        .axes
        .iter()
        .map(|a| match &a.backend {
            BackendConfig::Canopen(c) => Some((c.in_position, c.settle_timeout)),
            BackendConfig::Modbus(m) => Some((m.in_position, m.settle_timeout)),
            _ => None,
        })
        .collect()
}

/// Runs the test run of the program at `path` on `config`, within the default limits.
pub fn test_run(path: &Path, config: &MachineConfig) -> TestRunReport {
    test_run_within(path, config, &TestRunLimits::default())
}

/// Runs the test run of the program at `path` on `config`; it gives up at `limits`.
pub fn test_run_within(
    path: &Path,
    config: &MachineConfig,
    limits: &TestRunLimits,
) -> TestRunReport {
    let start = start_pose(config);
    let checked = match config.open_program(path, start) {
        Ok(it) => it.check_report(),
        Err(d) => klar_interp::CheckReport {
            errors: vec![d],
            ..klar_interp::CheckReport::default()
        },
    };
    // A file the program needs is not there: the run would stop at it.
    let mut errors = checked.errors;
    // Many jumps are no error of their own: whether the program ends is the machine pass's to
    // find out, within the limits (the jump that went on looping is named if it gives up).
    let looping = errors
        .iter()
        .position(|d| d.message.contains(LOOP_MARK))
        .map(|i| errors.remove(i));
    errors.extend(checked.missing.iter().cloned());
    errors.sort_by_key(|d| d.line);
    // Where the program depends on what happens at the machine (a missing called program,
    // positions the operator set during a stop), an error there is not the program's.
    let undecided_at: Vec<(std::path::PathBuf, u32)> = checked
        .undecided
        .iter()
        .chain(&checked.missing)
        .map(|d| (d.file.clone(), d.line))
        .collect();
    let mut report = TestRunReport {
        errors,
        // what the program's text tolerates (lines before BEGIN PGM, another END PGM name)
        warnings: checked.warnings.clone(),
        undecided: checked
            .undecided
            .iter()
            .map(|d| format!("{d} (decided only when the program runs)"))
            .collect(),
        envelope: config
            .axes
            .iter()
            .map(|a| (a.letter, a.start, a.start))
            .collect(),
        ..TestRunReport::default()
    };
    let first_error_line = report.errors.first().map(|d| d.line);
    let Ok(mut interp) = config.open_program(path, start) else {
        // `check` has already reported why the file cannot be opened.
        return report;
    };
    interp.set_dry_run(true);
    let mut machine = MachineChecks::new(path, config, start, *limits);
    let max_rpm = config.spindle.as_ref().map_or(0.0, |s| s.max_rpm);
    let mut ops = 0u64;
    // The same stream a run plans from: the compensated tool-centre path, feeds resolved.
    for item in OpStream::new(interp, start, max_rpm, path) {
        if machine.gave_up.is_some() {
            break;
        }
        ops += 1;
        if ops > limits.blocks
            && let Ok(op) = &item
        {
            machine.give_up(op.loc, format!("{} executed blocks", limits.blocks));
            break;
        }
        let item = match item {
            Ok(op) => Ok(op),
            Err(RunError::Program(d)) => Err(d),
            // The stream reports only program errors; anything else names no block.
            Err(e) => Err(Diagnostic {
                file: path.to_path_buf(),
                line: 1,
                col: 1,
                block: None,
                message: e.to_string(),
            }),
        };
        match item {
            Ok(op) => machine.op(op, &mut report),
            Err(d) => {
                let at_machine = undecided_at.contains(&(d.file.clone(), d.line));
                report.undecided.push(if at_machine {
                    format!(
                        "machine checks stop at line {}: what follows depends on the machine",
                        d.line
                    )
                } else {
                    format!(
                        "machine checks stop at line {}: the program's positions after its \
                         first error depend on how that error is resolved",
                        d.line
                    )
                });
                if first_error_line.is_none() && !at_machine {
                    report.errors.push(d);
                }
                break;
            }
        }
    }
    machine.finish(&mut report);
    report.gave_up = machine.gave_up.take().map(|mut d| {
        if let Some(j) = &looping {
            d.message.push_str(&format!(
                "; the jump at line {} ran more than {} times",
                j.line,
                klar_interp::CHECK_JUMP_LIMIT
            ));
        }
        d
    });
    if config.tools.is_none() && config.tool_table.is_none() && machine.tool_calls > 0 {
        report
            .undecided
            .push("the machine has no tool table: tool existence was not checked".into());
    }
    report
}

/// The machine-side checks, op by op.
struct MachineChecks<'a> {
    path: &'a Path,
    config: &'a MachineConfig,
    letters: Vec<AxisLetter>,
    travel: Vec<[f64; 2]>,
    /// Per axis: the out-of-travel position already reported, until the axis is back.
    outside: Vec<Option<f64>>,
    positioning: Vec<Option<(f64, f64)>>,
    planner: Option<Planner>,
    /// The run's command path over the planned samples, until its guard refuses one.
    command: Option<CommandPath>,
    tool_calls: u64,
    /// The active tool and its radius (mm), until a zero-radius warning was given for it.
    tool: Option<(u32, f64)>,
    limits: TestRunLimits,
    /// Servo cycles planned so far.
    cycles: u64,
    /// The block where the test run gave up (see [`TestRunReport::gave_up`]).
    gave_up: Option<Diagnostic>,
    /// The main spindle's commanded speed, signed rpm (0 stopped or unknown), as the
    /// interpreter reads ahead.
    rpm: f64,
    /// The same where the planner's events have reached.
    event_rpm: f64,
}

impl<'a> MachineChecks<'a> {
    fn new(path: &'a Path, config: &'a MachineConfig, start: Pose, limits: TestRunLimits) -> Self {
        let planner = config.planner(start).ok();
        let at: Vec<f64> = config.axes.iter().map(|a| a.start).collect();
        Self {
            command: Some(CommandPath::new(config, &at)),
            path,
            config,
            letters: config.letters(),
            travel: config.axes.iter().map(|a| a.travel).collect(),
            outside: vec![None; config.axes.len()],
            positioning: positioning_axes(config),
            planner,
            tool_calls: 0,
            tool: None,
            limits,
            cycles: 0,
            gave_up: None,
            rpm: 0.0,
            event_rpm: 0.0,
        }
    }

    /// Gives up at the block `loc`: the program has not ended within `what`.
    fn give_up(&mut self, loc: SourceLoc, what: String) {
        self.planner = None;
        self.gave_up = Some(block_diagnostic(
            self.path,
            loc,
            format!(
                "undecided: the program did not end within {what}; the test run stops at this \
                 block (an endless loop?); `klar run` runs it for as long as the operator lets it"
            ),
        ));
    }

    /// Counts a planned step; true when a limit is reached (and the test run has given up).
    fn over_limit(&mut self, step: &Step, report: &TestRunReport) -> bool {
        if matches!(step, Step::Sample(_)) {
            self.cycles += 1;
        }
        let what = if report.planned_time > self.limits.machine_time {
            format!("{} s of machine time", self.limits.machine_time)
        } else if self.cycles > self.limits.servo_cycles {
            format!("{} servo cycles", self.limits.servo_cycles)
        } else {
            return false;
        };
        let loc = match step {
            Step::Sample(s) => s.loc,
            Step::Event(op) => op.loc,
        };
        self.give_up(loc, what);
        true
    }

    fn error(&self, report: &mut TestRunReport, loc: SourceLoc, message: String) {
        report
            .errors
            .push(block_diagnostic(self.path, loc, message));
    }

    fn op(&mut self, op: Op, report: &mut TestRunReport) {
        if op.kind.is_motion() {
            report.motion_ops += 1;
            self.widen(&op, report);
        }
        self.travel_once(&op, report);
        if let Err(d) = check_positioning(&op, &self.letters, &self.positioning, self.path) {
            report.errors.push(d);
        }
        if let Some(w) = self.feed_warning(&op) {
            report.warnings.push(w);
        }
        match &op.kind {
            OpKind::Spindle {
                spindle: klar_interp::op::SpindleId::Main,
                dir,
                speed,
            } => {
                self.rpm = signed_rpm(*dir, *speed, self.config);
                self.spindle(op.loc, *dir, *speed, report);
            }
            OpKind::Spindle { dir, speed, .. } => self.spindle(op.loc, *dir, *speed, report),
            OpKind::SpindleSync { .. } => {
                report.motion_ops += 1;
                report.geared_ops += 1;
                self.widen(&op, report);
                self.spindle_sync(&op, report);
            }
            OpKind::RigidTap { .. } => {
                report.motion_ops += 1;
                report.geared_ops += 1;
                self.widen(&op, report);
                self.rigid_tap(&op, report);
            }
            OpKind::RadiusComp { side } if *side != klar_interp::CompSide::Off => {
                if let Some((tool, radius)) = self.tool
                    && tool != 0
                    && radius == 0.0
                {
                    report.warnings.push(block_diagnostic(
                        self.path,
                        op.loc,
                        format!(
                            "radius compensation with tool {tool}, whose radius no tool table \
                             or TOOL DEF gives: radius 0 is used"
                        ),
                    ));
                    // said once per tool call
                    self.tool = None;
                }
            }
            OpKind::ToolChange { tool, radius, .. } => {
                self.tool = Some((*tool, *radius));
                self.tool_calls += 1;
                // Tool 0 is the zero tool (length and radius 0) every TNC knows.
                if let Some(tools) = &self.config.tools
                    && *tool != 0
                    && !tools.iter().any(|t| t.number == *tool)
                {
                    self.error(
                        report,
                        op.loc,
                        format!("tool {tool} is not in the machine's tool table"),
                    );
                }
            }
            _ => {}
        }
        self.plan(op, report);
    }

    /// The travel check, once per excursion: an axis programmed outside its travel is
    /// reported at the block that sends it there; blocks that merely start from that
    /// position (their range reaches the reported point) are its consequences and stay
    /// silent until the axis is back within its travel.
    fn travel_once(&mut self, op: &Op, report: &mut TestRunReport) {
        let Some((lo, hi)) = op_bounds(&op.kind) else {
            return;
        };
        let mut said = Vec::new();
        for (k, (&l, &[min, max])) in self.letters.iter().zip(&self.travel).enumerate() {
            let (a, b) = (lo[l], hi[l]);
            let Some(flag) = self.outside.get_mut(k) else {
                continue;
            };
            if a >= min - TRAVEL_SLACK && b <= max + TRAVEL_SLACK {
                *flag = None;
                continue;
            }
            let v = if a < min - TRAVEL_SLACK { a } else { b };
            let consequence =
                flag.is_some_and(|at| a <= at + TRAVEL_SLACK && b >= at - TRAVEL_SLACK);
            if consequence {
                continue;
            }
            *flag = Some(v);
            said.push(format!(
                "axis {l} would move to {v:.4}, outside its travel [{min}, {max}]"
            ));
        }
        if !said.is_empty() {
            let message = said.join("; ");
            report
                .errors
                .push(block_diagnostic(self.path, op.loc, message));
        }
    }

    fn widen(&self, op: &Op, report: &mut TestRunReport) {
        let Some((lo, hi)) = op_bounds(&op.kind) else {
            return;
        };
        for (l, min, max) in &mut report.envelope {
            if lo[*l].is_finite() {
                *min = min.min(lo[*l]);
            }
            if hi[*l].is_finite() {
                *max = max.max(hi[*l]);
            }
        }
    }

    fn spindle(
        &self,
        loc: SourceLoc,
        dir: SpindleDir,
        speed: SpindleSpeed,
        report: &mut TestRunReport,
    ) {
        let rpm = match speed {
            SpindleSpeed::Rpm(r) => r,
            SpindleSpeed::SurfaceSpeed(_) | SpindleSpeed::SurfaceSpeedCapped(..) => {
                // Constant surface speed turns the work; the speed follows the radius and
                // is limited to the machine's maximum.
                if dir != SpindleDir::Off
                    && self.config.kinematics != crate::config::KinematicsConfig::Lathe
                {
                    self.error(
                        report,
                        loc,
                        "constant surface speed needs a lathe".to_string(),
                    );
                }
                return;
            }
        };
        if dir == SpindleDir::Off {
            return;
        }
        match &self.config.spindle {
            Some(s) if rpm.abs() > s.max_rpm => self.error(
                report,
                loc,
                format!(
                    "spindle speed S{rpm} is above this machine's {} rpm",
                    s.max_rpm
                ),
            ),
            None if rpm != 0.0 => report.warnings.push(block_diagnostic(
                self.path,
                loc,
                "this machine has no spindle: S/M3/M4 is ignored".into(),
            )),
            _ => {}
        }
    }

    /// A thread pass: the spindle must measure its angle, turn, and the axes must follow the
    /// pitch at its speed.
    fn spindle_sync(&self, op: &Op, report: &mut TestRunReport) {
        let why = self.angle_refusal("cut threads");
        let why = why.or_else(|| match SyncProfile::new(&op.kind, self.rpm, self.config) {
            Some(Err(e)) => Some(e),
            _ => None,
        });
        if let Some(message) = why {
            self.error(report, op.loc, message);
        }
    }

    /// A rigid tap: the spindle must measure its angle and turn, and the axes must follow
    /// the pitch at its speed and through its ramps.
    fn rigid_tap(&self, op: &Op, report: &mut TestRunReport) {
        let why =
            self.angle_refusal("tap rigidly").or_else(
                || match crate::runtime::tap::TapProfile::new(&op.kind, self.rpm, self.config) {
                    Some(Err(e)) => Some(e),
                    _ => None,
                },
            );
        if let Some(message) = why {
            self.error(report, op.loc, message);
        }
    }

    /// Why the machine's spindle cannot `what` (it measures no angle), if it cannot.
    fn angle_refusal(&self, what: &str) -> Option<String> {
        use crate::config::SpindleBackendConfig;
        match self.config.spindle.as_ref().map(|s| &s.backend) {
            None => Some(format!("this machine has no spindle: it cannot {what}")),
            Some(SpindleBackendConfig::Modbus(_)) => Some(format!(
                "the spindle is a Modbus VFD, which measures no spindle angle: it cannot \
                 {what} (that needs a spindle with an encoder)"
            )),
            // A CiA 402 spindle reports its actual position (0x6064), scaled by its
            // counts_per_rev, as the measured angle.
            Some(SpindleBackendConfig::Canopen(_) | SpindleBackendConfig::Sim(_)) => None,
        }
    }

    /// A warning when a programmed feed is above what the moved axes allow.
    fn feed_warning(&self, op: &Op) -> Option<Diagnostic> {
        let (from, to, feed) = match &op.kind {
            OpKind::Line {
                from,
                to,
                feed: Feed::Rate(f),
            } => (from, to, *f),
            OpKind::Arc {
                from,
                to,
                feed: Feed::Rate(f),
                ..
            } => (from, to, *f),
            _ => return None,
        };
        let (lo, hi) = op_bounds(&op.kind)?;
        // Along a line each axis moves a fixed share of the path; an arc needs each of its
        // plane axes at full path speed somewhere, so the share is taken as 1 there.
        let length: f64 = match &op.kind {
            OpKind::Line { from, to, .. } => (0..9)
                .map(|i| (to.0[i] - from.0[i]).powi(2))
                .sum::<f64>()
                .sqrt(),
            _ => 0.0,
        };
        let mut allowed = f64::INFINITY;
        let mut by = None;
        for a in &self.config.axes {
            let l = a.letter;
            let span = hi[l] - lo[l];
            if span.is_nan() || span <= 1e-12 {
                continue;
            }
            let share = if length > 1e-12 {
                (to[l] - from[l]).abs() / length
            } else {
                1.0
            };
            if share > 1e-12 {
                let v = a.max_velocity / share;
                if v < allowed {
                    allowed = v;
                    by = Some(l);
                }
            }
        }
        let l = by?;
        (feed > allowed * (1.0 + 1e-9)).then(|| {
            block_diagnostic(
                self.path,
                op.loc,
                format!(
                    "feed {:.0} mm/min is above what axis {l} allows here ({:.0} mm/min): \
                     the control limits it",
                    feed * 60.0,
                    allowed * 60.0
                ),
            )
        })
    }

    /// Plans the op (no motion) as the run feeds it to the planner: the planner's refusals
    /// are errors.
    fn plan(&mut self, op: Op, report: &mut TestRunReport) {
        for op in planner_ops(op, &self.letters, &self.positioning) {
            let Some(planner) = &mut self.planner else {
                return;
            };
            let loc = op.loc;
            if let Err(e) = planner.push(op) {
                self.error(report, loc, e.to_string());
                report.undecided.push(format!(
                    "the planner pass stops at line {}: later moves start from an unknown point",
                    loc.line
                ));
                self.planner = None;
                return;
            }
            loop {
                let Some(planner) = &mut self.planner else {
                    return;
                };
                if planner.needs_input() {
                    break;
                }
                let Some(step) = planner.next_step() else {
                    break;
                };
                follow(
                    &mut self.command,
                    self.path,
                    &step,
                    report,
                    &mut self.event_rpm,
                    self.config,
                );
                if self.over_limit(&step, report) {
                    return;
                }
            }
        }
    }

    fn finish(&mut self, report: &mut TestRunReport) {
        let Some(planner) = &mut self.planner else {
            return;
        };
        planner.finish();
        while let Some(step) = self.planner.as_mut().and_then(Planner::next_step) {
            follow(
                &mut self.command,
                self.path,
                &step,
                report,
                &mut self.event_rpm,
                self.config,
            );
            if self.over_limit(&step, report) {
                break;
            }
        }
    }
}

/// Follows one planner step the way the run does: events switch the kinematics, samples
/// become machine-axis setpoints through the run's own command path and its setpoint guard.
/// The run stops at the first setpoint the guard refuses, so the setpoint checks stop there
/// too; a soft-limit refusal at a line whose move the travel check has already reported is
/// the same problem and is not said twice.
fn follow(
    command: &mut Option<CommandPath>,
    path: &Path,
    step: &Step,
    report: &mut TestRunReport,
    rpm: &mut f64,
    config: &MachineConfig,
) {
    let sample = match step {
        Step::Sample(s) => s,
        Step::Event(op) => {
            if let Some(c) = command {
                c.event(op);
            }
            if let OpKind::Spindle {
                spindle: klar_interp::op::SpindleId::Main,
                dir,
                speed,
            } = &op.kind
            {
                *rpm = signed_rpm(*dir, *speed, config);
            }
            if let Some(Ok(profile)) = SyncProfile::new(&op.kind, *rpm, config) {
                follow_sync(command, path, op.loc, report, &profile, *rpm, config);
            }
            return;
        }
    };
    report.planned_time = sample.t;
    let Some(c) = command else {
        return;
    };
    let Err(v) = c.positions(sample, sample.t) else {
        return;
    };
    let said = matches!(v, Violation::Travel { .. })
        && report
            .errors
            .iter()
            .any(|d| d.file == path && d.line == sample.loc.line);
    if !said {
        report.errors.push(refused_in_check(path, sample.loc, &v));
    }
    *command = None;
}

/// The main spindle's signed speed after a spindle op; under constant surface speed the
/// machine's highest speed or the G26 limit below it (the worst case for a thread pass).
fn signed_rpm(dir: SpindleDir, speed: SpindleSpeed, config: &MachineConfig) -> f64 {
    let max = config.spindle.as_ref().map_or(0.0, |s| s.max_rpm);
    let rpm = match speed {
        SpindleSpeed::Rpm(r) => r,
        SpindleSpeed::SurfaceSpeed(_) => max,
        SpindleSpeed::SurfaceSpeedCapped(_, n) => n.min(max),
    };
    match dir {
        SpindleDir::Off => 0.0,
        SpindleDir::Cw => rpm,
        SpindleDir::Ccw => -rpm,
    }
}

/// Follows a thread pass the way the run does at a steady spindle speed `rpm`: its setpoints
/// go through the run's command path and guard.
fn follow_sync(
    command: &mut Option<CommandPath>,
    path: &Path,
    loc: SourceLoc,
    report: &mut TestRunReport,
    profile: &SyncProfile,
    rpm: f64,
    config: &MachineConfig,
) {
    let Some(c) = command else {
        return;
    };
    let w = rpm.abs() * 6.0;
    let step = w * config.servo_period;
    let total = profile.total_degrees();
    let mut k = 1.0;
    loop {
        let phi = (k * step).min(total);
        let (s, rate) = profile.at(phi);
        let sample = Sample {
            t: report.planned_time,
            pose: profile.pose(s),
            velocity: profile.velocity(rate, w),
            acceleration: [0.0; 9],
            loc,
        };
        if let Err(v) = c.positions(&sample, sample.t) {
            report.errors.push(refused_in_check(path, loc, &v));
            *command = None;
            return;
        }
        if phi >= total {
            return;
        }
        k += 1.0;
    }
}

/// A diagnostic for the block at `loc`, its message prefixed with the block number.
pub(crate) fn block_diagnostic(path: &Path, loc: SourceLoc, message: String) -> Diagnostic {
    // Planner errors name their block in words; the diagnostic's position says it already.
    let mut said = format!("line {}, column {}", loc.line, loc.col);
    if let Some(b) = loc.block {
        said.push_str(&format!(" (block {b})"));
    }
    said.push_str(": ");
    let message = match message.strip_prefix(&said) {
        Some(rest) => rest.to_string(),
        None => message,
    };
    Diagnostic {
        file: path.to_path_buf(),
        line: loc.line,
        col: loc.col,
        block: loc.block,
        message: match loc.block {
            Some(n) => format!("block {n}: {message}"),
            None => message,
        },
    }
}

/// True when a motion op moves a positioning-only axis.
fn moves_positioning_axis(
    op: &Op,
    letters: &[AxisLetter],
    positioning: &[Option<(f64, f64)>],
) -> bool {
    let Some((lo, hi)) = op_bounds(&op.kind) else {
        return false;
    };
    letters
        .iter()
        .zip(positioning)
        .any(|(l, p)| p.is_some() && hi[*l] - lo[*l] > 1e-12)
}

/// The ops the planner gets for `op`, as a run feeds them: a move of a positioning-only axis
/// comes between two exact stops, so the path is at rest before and after its block.
pub(crate) fn planner_ops(
    op: Op,
    letters: &[AxisLetter],
    positioning: &[Option<(f64, f64)>],
) -> impl Iterator<Item = Op> + use<> {
    let stop = moves_positioning_axis(&op, letters, positioning).then_some(Op {
        kind: OpKind::ExactStop,
        loc: op.loc,
    });
    [stop.clone(), Some(op), stop].into_iter().flatten()
}

/// Refuses a motion op that moves a positioning-only axis together with another axis: such an
/// axis follows its own profile behind a slow link and cannot keep to a shared path.
pub(crate) fn check_positioning(
    op: &Op,
    letters: &[AxisLetter],
    positioning: &[Option<(f64, f64)>],
    path: &Path,
) -> Result<(), Diagnostic> {
    let Some((lo, hi)) = op_bounds(&op.kind) else {
        return Ok(());
    };
    let moved: Vec<usize> = (0..9).filter(|&i| hi.0[i] - lo.0[i] > 1e-12).collect();
    if moved.len() < 2 {
        return Ok(());
    }
    for (&l, p) in letters.iter().zip(positioning) {
        if p.is_some() && moved.contains(&l.index()) {
            return Err(block_diagnostic(
                path,
                op.loc,
                format!(
                    "axis {l} is a positioning axis (Modbus): program it in a block of its own"
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses a motion op whose path leaves the travel (soft limits) of an axis, naming the
/// block and the axis.
pub fn check_travel(
    op: &Op,
    letters: &[AxisLetter],
    travel: &[[f64; 2]],
    path: &Path,
) -> Result<(), Diagnostic> {
    let Some((lo, hi)) = op_bounds(&op.kind) else {
        return Ok(());
    };
    for (&l, &[min, max]) in letters.iter().zip(travel) {
        let (a, b) = (lo[l], hi[l]);
        if a < min - TRAVEL_SLACK || b > max + TRAVEL_SLACK {
            let v = if a < min - TRAVEL_SLACK { a } else { b };
            return Err(block_diagnostic(
                path,
                op.loc,
                format!("axis {l} would move to {v:.4}, outside its travel [{min}, {max}]"),
            ));
        }
    }
    Ok(())
}
