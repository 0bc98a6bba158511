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

mod checks;
mod following;

use crate::bounds::op_bounds;
use crate::config::{BackendConfig, MachineConfig};
use crate::runtime::RunError;
use crate::runtime::stream::OpStream;
use checks::MachineChecks;
use klar_interp::{AxisLetter, Diagnostic, Op, OpKind, Pose, SourceLoc};
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
