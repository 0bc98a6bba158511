//! The test run's machine-side checks, op by op: travel, spindle, positioning axes, feeds
//! and the planner pass, with the limits that make the check give up.

use super::following::{follow, signed_rpm};
use super::{
    TRAVEL_SLACK, TestRunLimits, TestRunReport, block_diagnostic, check_positioning, planner_ops,
    positioning_axes,
};
use crate::bounds::op_bounds;
use crate::config::MachineConfig;
use crate::runtime::command::CommandPath;
use crate::runtime::sync::SyncProfile;
use klar_interp::op::{SpindleDir, SpindleSpeed};
use klar_interp::{AxisLetter, Diagnostic, Feed, Op, OpKind, Pose, SourceLoc};
use klar_motion::{Planner, Step};
use std::path::Path;

/// The machine-side checks, op by op.
pub(super) struct MachineChecks<'a> {
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
    pub(super) tool_calls: u64,
    /// The active tool and its radius (mm), until a zero-radius warning was given for it.
    tool: Option<(u32, f64)>,
    limits: TestRunLimits,
    /// Servo cycles planned so far.
    cycles: u64,
    /// The block where the test run gave up (see [`TestRunReport::gave_up`]).
    pub(super) gave_up: Option<Diagnostic>,
    /// The main spindle's commanded speed, signed rpm (0 stopped or unknown), as the
    /// interpreter reads ahead.
    rpm: f64,
    /// The same where the planner's events have reached.
    event_rpm: f64,
}

impl<'a> MachineChecks<'a> {
    pub(super) fn new(
        path: &'a Path,
        config: &'a MachineConfig,
        start: Pose,
        limits: TestRunLimits,
    ) -> Self {
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
    pub(super) fn give_up(&mut self, loc: SourceLoc, what: String) {
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

    pub(super) fn op(&mut self, op: Op, report: &mut TestRunReport) {
        // The op's bounds, computed once for the envelope, the travel and the feed checks.
        let bounds = op_bounds(&op.kind);
        if op.kind.is_motion() {
            report.motion_ops += 1;
            self.widen(bounds, report);
        }
        self.travel_once(&op, bounds, report);
        if let Err(d) = check_positioning(&op, &self.letters, &self.positioning, self.path) {
            report.errors.push(d);
        }
        if let Some(w) = self.feed_warning(&op, bounds) {
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
                self.widen(bounds, report);
                self.spindle_sync(&op, report);
            }
            OpKind::RigidTap { .. } => {
                report.motion_ops += 1;
                report.geared_ops += 1;
                self.widen(bounds, report);
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
    /// `bounds` are the op's (see [`op_bounds`]).
    fn travel_once(&mut self, op: &Op, bounds: Option<(Pose, Pose)>, report: &mut TestRunReport) {
        let Some((lo, hi)) = bounds else {
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

    /// Widens the report's envelope by an op's `bounds` (see [`op_bounds`]).
    fn widen(&self, bounds: Option<(Pose, Pose)>, report: &mut TestRunReport) {
        let Some((lo, hi)) = bounds else {
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

    /// A warning when a programmed feed is above what the moved axes allow; `bounds` are the
    /// op's (see [`op_bounds`]).
    fn feed_warning(&self, op: &Op, bounds: Option<(Pose, Pose)>) -> Option<Diagnostic> {
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
        let (lo, hi) = bounds?;
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
                // The step is looked at where the planner put it: a sample is hundreds of
                // bytes, moved out of its option every servo period it would cost a copy.
                let next = planner.next_step();
                let Some(step) = &next else {
                    break;
                };
                if self.take(step, report) {
                    return;
                }
            }
        }
    }

    pub(super) fn finish(&mut self, report: &mut TestRunReport) {
        let Some(planner) = &mut self.planner else {
            return;
        };
        planner.finish();
        loop {
            let next = self.planner.as_mut().and_then(Planner::next_step);
            let Some(step) = &next else {
                break;
            };
            if self.take(step, report) {
                break;
            }
        }
    }

    /// Follows one step of the planner and counts it; true when the test run gives up
    /// there (see `over_limit`).
    fn take(&mut self, step: &Step, report: &mut TestRunReport) -> bool {
        follow(
            &mut self.command,
            self.path,
            step,
            report,
            &mut self.event_rpm,
            self.config,
        );
        self.over_limit(step, report)
    }
}
