//! Committing waiting elements onto the path: when the front element's corner can be
//! decided, the vertices of the polyline around it, and the pieces, stops and events the
//! commit produces.

use super::path::PieceError;
use super::path::{Committed, Element, NewPiece, Piece, Shape, Vertices, commit, piece_limits};
use super::{Marker, Planner, deep, path, run, smooth, speed};
use crate::error::MotionError;
use crate::geom::Metric;
use crate::limits::Headroom;
use klar_interp::{Feed, SourceLoc};

/// Elements kept back at most: more wait while the lines after the next corner but one
/// are shorter than a run of dense code and the split-point fit at its end reach
/// ([`run::RUN_ELEMENTS`], [`smooth::SPAN`]).
const ELEMENTS_AHEAD_MAX: usize = run::RUN_ELEMENTS + smooth::LOOK + 2;

/// Polyline vertices kept behind the corner being decided, for the split-point fit.
const VERTICES_BEHIND: usize = smooth::LOOK;

/// Path length (mm) of the lines waiting after the next corner but one that lets the front
/// element's corner be decided: a run and the fit at its end.
const AHEAD_REACH: f64 = run::RUN_LENGTH + smooth::SPAN;

/// Periods of travel at a piece's top speed over which it shares a lower jerk limit with its
/// neighbour when it is long enough to be cut ([`Planner::push_piece`]).
const SHARED_PERIODS: f64 = 2.0;

/// The stretch of `piece` next to a neighbour with a lower jerk limit that takes that
/// limit, when the piece is an element or a part of a corner blend more than twice that
/// long (the cut keeps the piece's limits, which hold on any stretch of it). Blends through
/// dense code are not cut: that would cost a tenth of the planning throughput in pieces.
fn shared_stretch(piece: &Piece, period: f64) -> Option<f64> {
    let cuttable = match piece.shape {
        Shape::Element(_) => true,
        Shape::Blend(_) => piece.headroom == Headroom::Lean,
    };
    if !cuttable {
        return None;
    }
    let reach = speed::period_travel(piece.vmax, piece.grip.most(), piece.jerk, period);
    let stretch = SHARED_PERIODS * reach;
    (stretch.is_finite() && piece.length > 2.0 * stretch).then_some(stretch)
}

impl Planner {
    /// True when enough elements wait for the front one's corner (and the split point
    /// after it) to be decided: the lines after the next corner but one reach as far as a
    /// run and the split-point fit look, or end, or turn sharply, or the queue is full.
    pub(super) fn front_decidable(&self) -> bool {
        if self.waiting.len() >= ELEMENTS_AHEAD_MAX {
            return true;
        }
        let mut reach = 0.0;
        let mut before: Option<&Element> = self.waiting.get(1).map(|w| &w.element);
        for w in self.waiting.iter().skip(2) {
            let e = &w.element;
            if !e.is_linear_line() {
                return true;
            }
            // A corner sharper than a split point allows ends any run before it.
            if let Some(b) = before {
                let end = b.segment.point(b.segment.length()).d1;
                let start = e.segment.point(0.0).d1;
                if Metric::Linear.dot(&end, &start) < path::SPLIT_MAX_ANGLE.cos() {
                    return true;
                }
            }
            before = Some(e);
            reach += e.segment.length();
            if reach >= AHEAD_REACH {
                return true;
            }
        }
        false
    }

    /// Adds the front element's end to the vertices behind (or starts them anew there
    /// after anything but a linear line), then the ends of the linear lines waiting after
    /// it; returns the index of the front element's end.
    fn gather_vertices(&mut self, front: &Element) -> usize {
        let v = &mut self.vertices;
        if !front.is_linear_line() || v.last() != Some(&front.segment.start()) {
            v.clear();
            if front.is_linear_line() {
                v.push(front.segment.start());
            }
        }
        v.push(front.segment.end());
        if v.len() > 2 * VERTICES_BEHIND {
            v.drain(..v.len() - VERTICES_BEHIND);
        }
        let first = v.len() - 1;
        for w in &self.waiting {
            if !w.element.is_linear_line() {
                break;
            }
            v.push(w.element.segment.end());
        }
        first
    }

    /// Commits every waiting element, the last one ending in a stop.
    pub(super) fn flush(&mut self) -> Result<(), MotionError> {
        while !self.waiting.is_empty() {
            self.commit_front(true)?;
        }
        Ok(())
    }

    /// Cuts the front element at its next corner and appends its pieces to the path.
    pub(super) fn commit_front(&mut self, flushing: bool) -> Result<(), MotionError> {
        let Some(mut front) = self.waiting.pop_front() else {
            return Ok(());
        };
        let first = self.gather_vertices(&front.element);
        let done: Committed = {
            let vertices = Vertices {
                all: &self.vertices,
                first,
            };
            commit(
                &mut front.element,
                self.waiting.make_contiguous(),
                flushing,
                &vertices,
                &self.config.limits,
                self.config.period,
                &mut self.blends,
            )
        };
        // The vertices behind end at the start of the new front element.
        self.vertices
            .truncate((first + done.consumed + 1).min(self.vertices.len()));
        if done.stop_first {
            self.add_stop(self.committed_end);
        }
        let mut events_at = self.committed_end;
        for new in done.pieces {
            let NewPiece {
                shape,
                offset,
                length,
                feed,
                loc,
                headroom,
            } = new;
            let is_element = matches!(shape, Shape::Element(_));
            // A blend's part has bounds of its own: computed once for both uses.
            let bounds = shape.bounds(offset, length, self.blends.memo());
            let mut limits = self.limits_for(&shape, &bounds, offset, length);
            if is_element && !front.element.derate.is_none() {
                limits = front.element.derate.apply(&limits);
            }
            let l = piece_limits(&bounds, length, feed, &limits, headroom)
                .map_err(|e| piece_error(e, loc))?;
            let mut piece = Piece {
                drop: false,
                shape,
                offset,
                length,
                start: self.committed_end,
                vmax: l.velocity,
                feed,
                grip: l.grip,
                jerk: l.jerk,
                headroom,
                loc,
            };
            piece.drop = self.drops.next(piece.speed_limit(1.0));
            let turns = deep::turns_rotary(&bounds, length);
            if turns && self.too_close_for(&piece) {
                self.add_stop(self.committed_end);
            }
            self.push_piece(piece);
            if let Some(p) = self.pieces.back() {
                let floors = (self.accel_floor, self.jerk_floor);
                self.low_ahead.record(p, turns, floors);
            }
            self.committed_end += length;
            if is_element {
                events_at = self.committed_end;
            }
        }
        let mut events = front.events;
        for op in events.drain(..) {
            self.markers.push_back(Marker::Event { at: events_at, op });
        }
        self.give_back_event_list(events);
        // Elements a run used up: their events follow the run's blend.
        for _ in 0..done.consumed {
            if let Some(w) = self.waiting.pop_front() {
                let mut events = w.events;
                for op in events.drain(..) {
                    self.markers.push_back(Marker::Event {
                        at: self.committed_end,
                        op,
                    });
                }
                self.give_back_event_list(events);
            }
        }
        if done.stop_at_end && !(flushing && self.waiting.is_empty()) {
            self.markers.push_back(Marker::Stop {
                at: self.committed_end,
                op: None,
                dwell: 0.0,
                corner: done.stop_corner,
            });
        }
        Ok(())
    }

    /// Appends a piece to the path. A period that crosses from one piece into the next
    /// uses one jerk, so neighbours share the lower of their jerk limits near their joint:
    /// over the whole of the one with the higher limit where that is short, over
    /// [`SHARED_PERIODS`] periods' travel at its top speed (cut off as a piece of its own)
    /// where it is a long element. Not across a stop, where no period crosses, and not when
    /// the path state already moves on the piece before, whose limits must not change
    /// under it (the generator may be half-way through a ramp planned with them): that
    /// drop is met by the scan ([`Planner::scan`]) instead.
    fn push_piece(&mut self, mut piece: Piece) {
        let state = self.state.s;
        let period = self.config.period;
        // The path stands still at a stop: no period crosses it.
        let stop_between = self
            .markers
            .iter()
            .rev()
            .map_while(|m| match m {
                Marker::Stop { at, .. } => (*at >= piece.start).then_some(true),
                Marker::Event { at, .. } => (*at >= piece.start).then_some(false),
            })
            .any(|stop| stop);
        if let Some(prev) = self.pieces.back_mut()
            && prev.start > state
            && !stop_between
        {
            if piece.jerk < prev.jerk {
                match shared_stretch(prev, period) {
                    Some(tail) => {
                        let mut cut = prev.clone();
                        prev.length -= tail;
                        cut.offset += prev.length;
                        cut.start = prev.end();
                        cut.length = tail;
                        cut.jerk = piece.jerk;
                        cut.drop = false;
                        self.pieces.push_back(cut);
                    }
                    None => prev.jerk = piece.jerk,
                }
            } else if prev.jerk < piece.jerk {
                let low = prev.jerk;
                match shared_stretch(&piece, period) {
                    Some(head) => {
                        let mut cut = piece.clone();
                        cut.length = head;
                        cut.jerk = low;
                        piece.offset += head;
                        piece.start += head;
                        piece.length -= head;
                        piece.drop = false;
                        self.pieces.push_back(cut);
                    }
                    None => piece.jerk = low,
                }
            }
        }
        self.pieces.push_back(piece);
    }

    /// True when `piece`, about to be committed at the end of the path, has limits below the
    /// look-ahead's floors that the path state can no longer meet: it is too fast and too
    /// close to slow down with them (see `deep`), and no stop lies between. Up to now the
    /// end of the committed path was its end, so a stop there can always be met.
    fn too_close_for(&self, piece: &Piece) -> bool {
        let floors = (self.accel_floor, self.jerk_floor);
        let accel = deep::lowest_accel(piece);
        if accel >= floors.0 && piece.jerk >= floors.1 {
            return false;
        }
        let stop_between = self.markers.iter().any(|m| match m {
            Marker::Stop { at, .. } => *at <= piece.start,
            Marker::Event { .. } => false,
        });
        if stop_between {
            return false;
        }
        // The path brakes into the piece with the acceleration of the pieces before it and
        // the lowest jerk on the way, the piece's own included.
        let (low_accel, low_jerk) = self.low_ahead.lowest(floors);
        deep::too_close(
            &self.state,
            piece.start,
            piece.speed_limit(self.factor),
            low_accel,
            low_jerk.min(piece.jerk),
            self.config.period,
        )
    }

    /// A plain standstill at `at`.
    pub(super) fn add_stop(&mut self, at: f64) {
        self.markers.push_back(Marker::Stop {
            at,
            op: None,
            dwell: 0.0,
            corner: None,
        });
    }
}

/// The error for a piece that cannot be planned, at the block it comes from.
pub(super) fn piece_error(e: PieceError, loc: SourceLoc) -> MotionError {
    match e {
        PieceError::Absent(axis) => MotionError::AbsentAxis { loc, axis },
        PieceError::Unplannable => MotionError::Unplannable { loc },
    }
}

/// The path speed limit of a feed: `None` for rapid traverse.
pub(super) fn path_feed(feed: Feed, loc: SourceLoc) -> Result<Option<f64>, MotionError> {
    match feed {
        Feed::Rapid => Ok(None),
        Feed::Rate(f) if f.is_finite() && f > 0.0 => Ok(Some(f)),
        Feed::Rate(f) => Err(MotionError::BadFeed { loc, feed: f }),
        Feed::PerRevolution(_) => Err(MotionError::NeedsSpindle { loc }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blend::Quintic;
    use crate::geom::{Line, PathPoint, Segment};
    use crate::limits::Grip;
    use klar_interp::{Pose, SourceLoc};

    fn planner() -> Planner {
        super::super::test_machine::planner()
    }

    /// A piece along X from `start` over `length` with jerk limit `jerk`: a line, or a
    /// (straight) blend with `headroom`.
    fn piece(start: f64, length: f64, jerk: f64, blend: Option<Headroom>) -> Piece {
        let (from, to) = (
            Pose::xyz(start, 0.0, 0.0),
            Pose::xyz(start + length, 0.0, 0.0),
        );
        let shape = match blend {
            None => match Line::new(from, to) {
                Ok(Some(line)) => Shape::Element(Segment::Line(line)),
                _ => panic!("a line"),
            },
            Some(_) => {
                let mut d1 = [0.0; 9];
                d1[0] = 1.0;
                let at = |pose| PathPoint {
                    pose,
                    d1,
                    d2: [0.0; 9],
                };
                match Quintic::hermite(&at(from), &at(to)) {
                    Some(q) => Shape::Blend(std::sync::Arc::new(q)),
                    None => panic!("a blend"),
                }
            }
        };
        Piece {
            shape,
            offset: 0.0,
            length,
            start,
            vmax: 30.0,
            feed: None,
            grip: Grip::constant(1000.0),
            jerk,
            headroom: blend.unwrap_or(Headroom::Ample),
            loc: SourceLoc::default(),
            drop: false,
        }
    }

    /// Jerk limits and lengths of the planner's pieces.
    fn jerks(p: &Planner) -> Vec<(f64, f64)> {
        p.pieces.iter().map(|q| (q.jerk, q.length)).collect()
    }

    #[test]
    fn a_corner_blend_part_shares_a_lower_jerk_near_the_joint_only() {
        // After a piece with jerk limit 5e4, a part of a corner blend 0.3 mm long takes that
        // limit over two periods' travel at its top speed (2 × 0.031 mm with its
        // acceleration), cut off as a piece of its own; a blend through dense code takes it
        // over all of its length.
        for (headroom, cut) in [(Headroom::Lean, true), (Headroom::Ample, false)] {
            let mut p = planner();
            p.push_piece(piece(0.0, 10.0, 1e5, None));
            p.push_piece(piece(10.0, 0.3, 5e4, None));
            p.push_piece(piece(10.3, 0.3, 1e5, Some(headroom)));
            let got = jerks(&p);
            if cut {
                assert_eq!(got.len(), 4, "{got:?}");
                assert_eq!((got[2].0, got[3].0), (5e4, 1e5));
                assert!((got[2].1 - 0.0622).abs() < 1e-3, "{got:?}");
                assert!((got[2].1 + got[3].1 - 0.3).abs() < 1e-12, "{got:?}");
            } else {
                assert_eq!(got.len(), 3, "{got:?}");
                assert_eq!(got[2], (5e4, 0.3));
            }
        }
    }
}
