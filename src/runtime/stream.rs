//! The op stream a run plans from: the interpreter's ops through radius compensation, with
//! the spindle-dependent feeds resolved.
//!
//! - Radius compensation ([`Compensator`]) turns the programmed contour into the tool-centre
//!   path and resolves APPR/DEP, with its bounded look-ahead window.
//! - Feed per revolution (lathe G95, G195) becomes a path feed from the programmed speed of the
//!   spindle that turns last: `F · rpm / 60` mm/s. Under constant surface speed (G96) the speed
//!   is taken at the block's end point radius, `v·1000 / (2π·r)`, limited to the machine's
//!   maximum — an approximation for blocks that change the radius, where a real control
//!   varies the feed along the block.
//!
//! The run, the test run and the whole-pipeline fuzz target (`fuzz/common.rs`) all plan from
//! this stream, so what they check is what a run executes.

use super::RunError;
use klar_interp::op::{SpindleDir, SpindleId, SpindleSpeed};
use klar_interp::{AxisLetter, Diagnostic, Feed, Interpreter, Op, OpKind, Pose};
use klar_motion::comp::{CompError, Compensator};
use std::collections::VecDeque;

/// What the stream knows of the programmed spindles.
#[derive(Debug, Clone, Copy, Default)]
struct Spindles {
    /// Main spindle: programmed rpm (0 when stopped).
    main_rpm: f64,
    /// Main spindle: constant surface speed in m/min and the speed limit (G26, else the
    /// machine's maximum), when G96 is active.
    surface_speed: Option<(f64, f64)>,
    /// Driven tool: programmed rpm (0 when stopped).
    driven_rpm: f64,
    /// Which spindle turned last: feeds per revolution refer to it.
    last: Option<SpindleId>,
}

/// Interpreter → compensation (with the tilted working plane) → feed resolution: yields the
/// ops in the order the planner takes them. Its errors are program diagnostics
/// ([`RunError::Program`]); a run stops reading at the first.
pub struct OpStream {
    interp: Interpreter,
    comp: Compensator,
    ready: VecDeque<Op>,
    done: bool,
    spindles: Spindles,
    max_rpm: f64,
    path: std::path::PathBuf,
    /// The basis rpm of the last op given out, when it is fed per main-spindle revolution.
    basis: Option<f64>,
}

impl OpStream {
    /// A stream over `interp`, compensating from `start`; `max_rpm` limits surface-speed
    /// conversions.
    pub fn new(mut interp: Interpreter, start: Pose, max_rpm: f64, path: &std::path::Path) -> Self {
        // Compensation runs in a tilted working plane; the compensator turns its output.
        interp.set_working_plane_ops(true);
        Self {
            interp,
            comp: Compensator::new(start),
            ready: VecDeque::new(),
            done: false,
            spindles: Spindles::default(),
            max_rpm,
            path: path.to_path_buf(),
            basis: None,
        }
    }

    /// The main-spindle speed (rpm) the last op given out was planned at when it is fed per
    /// revolution of the main spindle: the run scales its path speed by the measured over
    /// this speed (see `per_rev.rs`).
    pub fn per_rev_basis(&self) -> Option<f64> {
        self.basis
    }

    /// The probing move the interpreter waits for the machine to measure (measured
    /// probing): every op before it has been given out.
    pub fn probe_request(&self) -> Option<klar_interp::ProbeRequest> {
        self.interp.probe_request()
    }

    /// The machine's answer to [`OpStream::probe_request`].
    pub fn answer_probe(&mut self, answer: klar_interp::ProbeAnswer) {
        // the next op starts where the axes came to rest; under radius compensation the
        // planner refuses the gap (probe cycles move with compensation off)
        if !self.comp.moved_to(answer.stop) {
            tracing::warn!("a probing move under radius compensation");
        }
        self.interp.answer_probe(answer);
    }

    /// The program's BLK FORM (for a simulated part shaped after it).
    pub fn blank(&self) -> Option<klar_interp::Blank> {
        self.interp.blank()
    }

    /// Blocks the interpreter executed.
    pub fn blocks_executed(&self) -> u64 {
        self.interp.blocks_executed()
    }

    /// The spindle speed in rpm for constant surface speed `v` (m/min) at radius `r` (mm):
    /// `n = v·1000 / (2π·r)`, limited to `max_rpm` (which it reaches towards the centre).
    pub fn surface_speed_rpm(v: f64, r: f64, max_rpm: f64) -> f64 {
        if r.abs() < 1e-9 {
            return max_rpm;
        }
        (v * 1000.0 / (2.0 * std::f64::consts::PI * r.abs())).min(max_rpm)
    }

    fn track_spindle(&mut self, op: &Op) {
        if let OpKind::Spindle {
            spindle,
            dir,
            speed,
        } = &op.kind
        {
            let on = *dir != SpindleDir::Off;
            match (spindle, speed) {
                (SpindleId::Main, SpindleSpeed::Rpm(r)) => {
                    self.spindles.main_rpm = if on { *r } else { 0.0 };
                    self.spindles.surface_speed = None;
                }
                (SpindleId::Main, SpindleSpeed::SurfaceSpeed(v)) => {
                    self.spindles.surface_speed = Some((*v, self.max_rpm));
                    self.spindles.main_rpm = if on { self.max_rpm } else { 0.0 };
                }
                (SpindleId::Main, SpindleSpeed::SurfaceSpeedCapped(v, n)) => {
                    self.spindles.surface_speed = Some((*v, n.min(self.max_rpm)));
                    self.spindles.main_rpm = if on { self.max_rpm } else { 0.0 };
                }
                (SpindleId::Driven, SpindleSpeed::Rpm(r)) => {
                    self.spindles.driven_rpm = if on { *r } else { 0.0 };
                }
                (
                    SpindleId::Driven,
                    SpindleSpeed::SurfaceSpeed(_) | SpindleSpeed::SurfaceSpeedCapped(..),
                ) => {}
            }
            if on {
                self.spindles.last = Some(*spindle);
            }
        }
    }

    /// Resolves a feed per revolution into a path feed for a move from `from` to `to`.
    fn resolve_feed(&self, feed: Feed, from: &Pose, to: &Pose, op: &Op) -> Result<Feed, RunError> {
        let Feed::PerRevolution(f) = feed else {
            return Ok(feed);
        };
        let rpm = match self.spindles.last {
            Some(SpindleId::Driven) => self.spindles.driven_rpm,
            Some(SpindleId::Main) => match self.spindles.surface_speed {
                // At the smaller radius of the two ends: the fastest the spindle turns on
                // a line (the run follows the spindle's measured speed below it).
                Some((v, limit)) if self.spindles.main_rpm != 0.0 => Self::surface_speed_rpm(
                    v,
                    from[AxisLetter::X].abs().min(to[AxisLetter::X].abs()),
                    limit,
                ),
                _ => self.spindles.main_rpm,
            },
            None => 0.0,
        };
        if rpm.abs() < 1e-9 {
            return Err(RunError::Program(Diagnostic {
                file: self.path.clone(),
                line: op.loc.line,
                col: op.loc.col,
                block: op.loc.block,
                message: format!(
                    "{}feed per revolution needs a turning spindle",
                    op.loc
                        .block
                        .map(|n| format!("block {n}: "))
                        .unwrap_or_default()
                ),
            }));
        }
        Ok(Feed::Rate(f * rpm.abs() / 60.0))
    }

    /// A compensation refusal as a program diagnostic at the (first) block it names.
    fn comp_error(&self, e: &CompError) -> RunError {
        let loc = e.loc().unwrap_or_default();
        RunError::Program(Diagnostic {
            file: self.path.clone(),
            line: loc.line,
            col: loc.col,
            block: loc.block,
            message: format!("radius compensation: {e}"),
        })
    }

    fn resolve(&mut self, mut op: Op) -> Result<Op, RunError> {
        self.track_spindle(&op);
        self.basis = None;
        let resolved = match &op.kind {
            OpKind::Line { from, to, feed }
            | OpKind::Arc { from, to, feed, .. }
            | OpKind::Spline { from, to, feed, .. } => {
                Some(self.resolve_feed(*feed, from, to, &op)?)
            }
            _ => None,
        };
        // Fed per revolution of the main spindle: the rpm the rate was planned at.
        if let Some(Feed::Rate(r)) = resolved
            && self.spindles.last == Some(SpindleId::Main)
            && let Some(Feed::PerRevolution(f)) = op_feed(&op.kind)
            && f > 0.0
        {
            self.basis = Some(r * 60.0 / f);
        }
        if let Some(new) = resolved {
            match &mut op.kind {
                OpKind::Line { feed, .. }
                | OpKind::Arc { feed, .. }
                | OpKind::Spline { feed, .. } => *feed = new,
                _ => {}
            }
        }
        Ok(op)
    }
}

/// The feed of a motion op.
fn op_feed(kind: &OpKind) -> Option<Feed> {
    match kind {
        OpKind::Line { feed, .. } | OpKind::Arc { feed, .. } | OpKind::Spline { feed, .. } => {
            Some(*feed)
        }
        _ => None,
    }
}

impl Iterator for OpStream {
    type Item = Result<Op, RunError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if let Some(op) = self.ready.pop_front() {
                return Some(self.resolve(op));
            }
            if self.done {
                return None;
            }
            match self.interp.next() {
                Some(Ok(op)) => {
                    if let Err(e) = self.comp.push(op) {
                        self.done = true;
                        return Some(Err(self.comp_error(&e)));
                    }
                }
                Some(Err(d)) => {
                    self.done = true;
                    return Some(Err(RunError::Program(d)));
                }
                // waiting for a probing move: what compensation holds goes out, then none
                None if self.interp.probe_request().is_some() => {
                    while let Some(op) = self.comp.pop() {
                        self.ready.push_back(op);
                    }
                    if self.ready.is_empty() {
                        return None;
                    }
                    continue;
                }
                None => {
                    self.done = true;
                    if let Err(e) = self.comp.finish() {
                        return Some(Err(self.comp_error(&e)));
                    }
                }
            }
            while let Some(op) = self.comp.pop() {
                self.ready.push_back(op);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_surface_speed_follows_the_radius_and_the_limit() {
        // 200 m/min at r = 20 mm: 200000 / (2π·20) = 1591.55 rpm.
        let rpm = OpStream::surface_speed_rpm(200.0, 20.0, 4000.0);
        assert!((rpm - 1_591.549_430_918_953).abs() < 1e-9);
        assert_eq!(OpStream::surface_speed_rpm(200.0, 2.0, 4000.0), 4000.0);
        assert_eq!(OpStream::surface_speed_rpm(200.0, 0.0, 4000.0), 4000.0);
    }
}
