//! Taking ops in: checking and queueing each op the caller pushes, the ops that stop or only
//! ride along the path, and the end of input.

use super::commit::{path_feed, piece_error};
use super::corner_share::Derate;
use super::path::{Element, Shape, Waiting, piece_limits};
use super::{BUFFER_CAPACITY, CONTINUITY_TOLERANCE, ELEMENTS_AHEAD, Marker, Planner, tcpm};
use crate::error::MotionError;
use crate::geom::{Arc, GeomError, Line, Poly, Segment, finite_pose, letter};
use crate::limits::Headroom;
use klar_interp::{AxisLetter, Op, OpKind, Pose, SourceLoc};

impl Planner {
    /// Adds one op to the end of the path.
    pub fn push(&mut self, op: Op) -> Result<(), MotionError> {
        let loc = op.loc;
        if self.finished {
            return Err(MotionError::AfterFinish { loc });
        }
        if self.pieces.len() + self.markers.len() + self.waiting.len() >= BUFFER_CAPACITY {
            return Err(MotionError::BufferFull { loc });
        }
        let geometry = |e| MotionError::Geometry { loc, source: e };
        let start = self.planned_pose;
        let (segment, feed) = match &op.kind {
            OpKind::Line { from, to, feed } => {
                self.check_start(from, loc)?;
                let feed = path_feed(*feed, loc)?;
                (
                    Line::new(start, *to).map_err(geometry)?.map(Segment::Line),
                    feed,
                )
            }
            OpKind::Arc {
                from,
                to,
                center,
                plane,
                sweep,
                feed,
            } => {
                self.check_start(from, loc)?;
                let feed = path_feed(*feed, loc)?;
                let segment =
                    match Arc::new(start, *to, *center, *plane, *sweep).map_err(geometry)? {
                        Some(arc) => Some(Segment::Arc(arc)),
                        None => Line::new(start, *to).map_err(geometry)?.map(Segment::Line),
                    };
                (segment, feed)
            }
            OpKind::Spline {
                from,
                to,
                axes,
                feed,
            } => {
                self.check_start(from, loc)?;
                let feed = path_feed(*feed, loc)?;
                (
                    Poly::new(start, *to, axes)
                        .map_err(geometry)?
                        .map(|p| Segment::Poly(self.splines.store(p))),
                    feed,
                )
            }
            OpKind::Approach { .. } | OpKind::Depart { .. } => {
                return Err(MotionError::UnresolvedApproach { loc });
            }
            OpKind::Dwell { seconds } => {
                let seconds = *seconds;
                return self.stop_and_hold(op, seconds);
            }
            OpKind::Tolerance { mm } => {
                let mm = match mm {
                    Some(mm) if !(mm.is_finite() && *mm >= 0.0) => {
                        return Err(MotionError::BadTolerance { loc, mm: *mm });
                    }
                    Some(mm) => *mm,
                    None => self.config.tolerance,
                };
                self.tolerance = mm;
                self.add_event(op);
                return Ok(());
            }
            OpKind::SpindleSync { .. } | OpKind::RigidTap { .. } => {
                // The servo loop runs the move itself, geared to the spindle: the path stops
                // exactly at its start, and goes on from its end once the event is done.
                let Some((from, to)) = op.kind.geared_ends() else {
                    return Ok(());
                };
                self.check_start(&from, loc)?;
                if !finite_pose(&to) {
                    return Err(MotionError::Discontinuity {
                        loc,
                        axis: AxisLetter::Z,
                        gap: f64::NAN,
                    });
                }
                self.flush()?;
                self.markers.push_back(Marker::Stop {
                    at: self.committed_end,
                    op: Some(op),
                    dwell: 0.0,
                    corner: None,
                });
                self.planned_pose = to;
                return Ok(());
            }
            OpKind::Stop { .. }
            | OpKind::End
            | OpKind::ToolChange { .. }
            | OpKind::Spindle { .. }
            | OpKind::CAxis { .. }
            | OpKind::ExactStop => {
                self.flush()?;
                self.markers.push_back(Marker::Stop {
                    at: self.committed_end,
                    op: Some(op),
                    dwell: 0.0,
                    corner: None,
                });
                return Ok(());
            }
            OpKind::Tcpm {
                on,
                compensation_feed,
                reframe,
            } => {
                // The switch follows an exact stop: the moves after it get the new limits,
                // and start where the machine stands, expressed in the new frame.
                if let Some(p) = reframe {
                    if !finite_pose(p) {
                        return Err(MotionError::Discontinuity {
                            loc: op.loc,
                            axis: AxisLetter::X,
                            gap: f64::NAN,
                        });
                    }
                    self.flush()?;
                    self.planned_pose = *p;
                }
                self.tcpm = *on;
                self.compensation_feed = compensation_feed.filter(|_| *on);
                self.config.limits = if *on {
                    tcpm::fixed_limits(&self.base_limits)
                } else {
                    self.base_limits
                };
                self.add_event(op);
                return Ok(());
            }
            OpKind::MachineFunction {
                stop: true, wait, ..
            } => {
                // A machine function that needs the machine standing: exact stop on its
                // point, the function, then the machine holds for `wait` seconds.
                let wait = *wait;
                return self.stop_and_hold(op, wait);
            }
            // A machine function without stop is an event on the path like coolant; it has
            // no standstill to wait in, so its `wait` is not applied.
            OpKind::Coolant { .. }
            | OpKind::ProbeResult { .. }
            | OpKind::RadiusComp { .. }
            | OpKind::CornerRule { .. }
            | OpKind::WorkingPlane { .. }
            | OpKind::MachineFunction { stop: false, .. } => {
                self.add_event(op);
                return Ok(());
            }
        };
        let Some(segment) = segment else {
            tracing::trace!(line = loc.line, "zero-length move skipped");
            return Ok(());
        };
        if !segment.length().is_finite() {
            return Err(MotionError::Geometry {
                loc,
                source: GeomError::NonFinite("path length"),
            });
        }
        // Refuse absent axes and unusable limits now, at the op that causes them.
        let whole = Shape::Element(segment.clone());
        let bounds = segment.bounds();
        let limits = self.limits_for(&whole, &bounds, 0.0, segment.length());
        piece_limits(&bounds, segment.length(), feed, &limits, Headroom::Ample)
            .map_err(|e| piece_error(e, loc))?;
        self.planned_pose = segment.end();
        let events = self.take_event_list();
        self.waiting.push_back(Waiting {
            element: Element {
                segment,
                feed,
                loc,
                tolerance: self.tolerance,
                trim: 0.0,
                split: None,
                // Nothing waits only where the path ends in a stop (or has not started).
                from_rest: self.waiting.is_empty(),
                derate: Derate::default(),
            },
            events,
        });
        if matches!(op.kind, OpKind::Spline { .. }) {
            // Its coefficients are on the heap: the caller may free them outside the loop.
            self.spent = Some(op);
        }
        while self.waiting.len() >= ELEMENTS_AHEAD && self.front_decidable() {
            self.commit_front(false)?;
        }
        Ok(())
    }

    /// The last spline op [`Planner::push`] took in and no longer needs (its coefficients
    /// live on the heap), for the caller to free on another thread than the servo loop's.
    /// Left here, it is freed when the next spline op takes its place.
    pub fn take_spent(&mut self) -> Option<Op> {
        self.spent.take()
    }

    /// An op that needs the machine standing on its point: exact stop, the op, then a hold
    /// of `seconds` (finite and ≥ 0).
    fn stop_and_hold(&mut self, op: Op, seconds: f64) -> Result<(), MotionError> {
        if !(seconds.is_finite() && seconds >= 0.0) {
            return Err(MotionError::BadDwell {
                loc: op.loc,
                seconds,
            });
        }
        self.flush()?;
        self.markers.push_back(Marker::Stop {
            at: self.committed_end,
            op: Some(op),
            dwell: seconds,
            corner: None,
        });
        Ok(())
    }

    /// A non-motion op that needs no stop: after the last waiting element, or at the end
    /// of the committed path.
    fn add_event(&mut self, op: Op) {
        match self.waiting.back_mut() {
            Some(w) => w.events.push(op),
            None => self.markers.push_back(Marker::Event {
                at: self.committed_end,
                op,
            }),
        }
    }

    /// Declares the end of input: the planner drains what it holds.
    pub fn finish(&mut self) {
        if !self.finished {
            // Elements were checked when pushed; committing them cannot fail on limits.
            if let Err(e) = self.flush() {
                tracing::warn!(error = %e, "dropping the rest of the path");
                self.waiting.clear();
            }
            self.finished = true;
        }
    }

    /// Refuses an op that does not start at the previous end point.
    fn check_start(&self, from: &Pose, loc: SourceLoc) -> Result<(), MotionError> {
        if !finite_pose(from) {
            let i = from.0.iter().position(|v| !v.is_finite()).unwrap_or(0);
            return Err(MotionError::Discontinuity {
                loc,
                axis: letter(i),
                gap: f64::NAN,
            });
        }
        for (i, (a, b)) in from.0.iter().zip(&self.planned_pose.0).enumerate() {
            let gap = (a - b).abs();
            if gap > CONTINUITY_TOLERANCE {
                return Err(MotionError::Discontinuity {
                    loc,
                    axis: letter(i),
                    gap,
                });
            }
        }
        Ok(())
    }
}
