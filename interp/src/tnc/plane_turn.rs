//! PLANE … TURN on a table-table machine whose geometry the interpreter knows.
//!
//! TURN positions the rotary axes only: the machine's linear axes stay where they are, so the
//! table carries the workpiece away under the tool and the tool tip ends on another point of
//! the workpiece; the program then positions the linear axes itself. The ops of klar speak
//! of the tool tip in workpiece coordinates (TCPM is on while a plane is tilted), so the
//! interpreter has to say where the tip goes while the table turns, and for that it needs
//! the machine's pivots ([`TableGeometry`], given by the interpreter's owner through
//! `Interpreter::with_table_geometry`).
//!
//! With the tilt angle `t` and the table angle `c` (degrees, primed table axes as in the
//! motion crate's table-table kinematics) a workpiece point `p` lies at the machine position
//! `m = P_t + R_tilt(−t)·((P_c − P_t) + R_z(−c)·(p − P_c))`, where `P_t` is a point of the tilt
//! axis and `P_c` one of the table axis (machine coordinates at zero angles). Holding `m`
//! while the angles move, the tip runs along
//!
//! ```text
//! p(t, c) = P_c + R_z(c)·(R_tilt(t)·(m − P_t) − (P_c − P_t))
//! ```
//!
//! The turn is passed on as straight pieces along that curve with the angles interpolated
//! linearly. Between the ends of a piece the tip runs on the chord, and the machine's linear
//! axes leave `m` by exactly the chord's distance from the curve (the map from tip to
//! machine position is a rigid motion), so the pieces are made short enough for that
//! distance to stay below [`TURN_CHORD_TOLERANCE`].

use super::exec::Machine;
use super::plane_math::{self as pm, Tilt, V3};
use crate::op::{AxisLetter, Feed, OpKind, Pose};

/// The largest distance (mm) of a TURN piece from the tip's curve: the machine's linear axes
/// stay within it of their start while the rotary axes turn (the path blending between the
/// pieces may add a little of the same order).
pub(crate) const TURN_CHORD_TOLERANCE: f64 = 0.000_25;

/// The most pieces one TURN is split into (a turn of many revolutions is passed on with
/// longer pieces than the tolerance asks for).
const MAX_PIECES: usize = 100_000;

/// The geometry of a table-table machine: which axis tilts the cradle and where the two
/// rotary axes lie (machine coordinates, mm, with every axis at zero).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TableGeometry {
    /// The tilt axis: A (about a line parallel to X) or B (parallel to Y).
    pub tilt: Tilt,
    /// A point on the tilt axis.
    pub tilt_pivot: V3,
    /// A point on the table axis (C, parallel to Z).
    pub table_pivot: V3,
}

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn norm(a: V3) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// One point of a TURN path: the tool tip in workpiece coordinates and the tilt and table
/// angles that go with it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TurnPoint {
    /// The tool tip (workpiece coordinates, mm).
    pub tip: V3,
    /// The tilt angle (degrees).
    pub t: f64,
    /// The table angle (degrees).
    pub c: f64,
}

impl TableGeometry {
    /// Machine X Y Z of the workpiece point `p` at tilt `t` and table angle `c` (degrees).
    pub(crate) fn tip_to_machine(&self, p: V3, t: f64, c: f64) -> V3 {
        let arm = sub(self.table_pivot, self.tilt_pivot);
        let q = add(arm, pm::apply(&pm::rz(-c), sub(p, self.table_pivot)));
        add(self.tilt_pivot, pm::apply(&self.tilt.rot(-t), q))
    }

    /// The workpiece point under machine X Y Z `m` at tilt `t` and table angle `c`: the
    /// inverse of [`TableGeometry::tip_to_machine`].
    pub(crate) fn machine_to_tip(&self, m: V3, t: f64, c: f64) -> V3 {
        let arm = sub(self.table_pivot, self.tilt_pivot);
        let q = pm::apply(&self.tilt.rot(t), sub(m, self.tilt_pivot));
        add(self.table_pivot, pm::apply(&pm::rz(c), sub(q, arm)))
    }

    /// The pieces of a turn from the angles `from` to `to` (tilt, table; degrees) with the
    /// tip at `tip` at the start: the end point of every piece, the last one at `to`.
    /// The machine's linear axes are held, so every point is the tip under the start's
    /// machine position at its angles. The number of pieces keeps each chord within
    /// `tolerance` (mm) of the curve: along the path parameter `s` in 0..1 the curve's
    /// second derivative is bounded by `(ω_t + ω_c)²·(|m − P_t| + |P_c − P_t|)` (`ω` the
    /// angles' spans in radians), and a chord of a curve with `|p''| ≤ K` over a parameter
    /// step `h` lies within `K·h²/8` of it.
    pub(crate) fn turn_path(
        &self,
        tip: V3,
        from: (f64, f64),
        to: (f64, f64),
        tolerance: f64,
    ) -> Vec<TurnPoint> {
        let m = self.tip_to_machine(tip, from.0, from.1);
        let wt = (to.0 - from.0).to_radians().abs();
        let wc = (to.1 - from.1).to_radians().abs();
        let reach = norm(sub(m, self.tilt_pivot)) + norm(sub(self.table_pivot, self.tilt_pivot));
        let bound = (wt + wc) * (wt + wc) * reach;
        let wanted = (bound / (8.0 * tolerance.max(1e-9))).sqrt().ceil();
        let n = if wanted.is_finite() {
            (wanted as usize).clamp(1, MAX_PIECES)
        } else {
            MAX_PIECES
        };
        (1..=n)
            .map(|k| {
                let f = k as f64 / n as f64;
                let (t, c) = if k == n {
                    to
                } else {
                    (from.0 + (to.0 - from.0) * f, from.1 + (to.1 - from.1) * f)
                };
                TurnPoint {
                    tip: self.machine_to_tip(m, t, c),
                    t,
                    c,
                }
            })
            .collect()
    }
}

impl Machine {
    /// Tells the interpreter the table-table geometry: the tilt axis letter (A or B) and the
    /// points on the tilt and table axes. Any other letter, or a pivot that is not finite,
    /// forgets the geometry (TURN then holds the tool tip like MOVE).
    pub fn set_table_geometry(&mut self, tilt: AxisLetter, tilt_pivot: V3, table_pivot: V3) {
        let tilt = match tilt {
            AxisLetter::A => Some(Tilt::A),
            AxisLetter::B => Some(Tilt::B),
            _ => None,
        };
        let finite = tilt_pivot.iter().chain(&table_pivot).all(|v| v.is_finite());
        self.tilt.geometry = tilt.filter(|_| finite).map(|tilt| TableGeometry {
            tilt,
            tilt_pivot,
            table_pivot,
        });
    }

    /// PLANE … TURN with the machine's geometry known: turns the rotary axes from `from` to
    /// the angles in `to` while the machine's linear axes stand still, as straight pieces of
    /// the tool tip's path on the workpiece (see the module docs). Sets the tip's end
    /// in `to`.
    pub(super) fn turn_move(
        &mut self,
        g: &TableGeometry,
        tilt_letter: AxisLetter,
        from: Pose,
        to: &mut Pose,
        feed: Feed,
        emit: &mut impl FnMut(OpKind),
    ) {
        let (t0, c0) = (from[tilt_letter], from[AxisLetter::C]);
        let (t1, c1) = (to[tilt_letter], to[AxisLetter::C]);
        if t0 == t1 && c0 == c1 {
            return;
        }
        let tip = [
            from[AxisLetter::X],
            from[AxisLetter::Y],
            from[AxisLetter::Z],
        ];
        // The turn is a positioning of its own: no blending with the moves before and after,
        // which would move the linear axes while the rotary axes still turn.
        emit(OpKind::ExactStop);
        let mut prev = from;
        for pt in g.turn_path(tip, (t0, c0), (t1, c1), TURN_CHORD_TOLERANCE) {
            let mut p = prev;
            p[tilt_letter] = pt.t;
            p[AxisLetter::C] = pt.c;
            p[AxisLetter::X] = pt.tip[0];
            p[AxisLetter::Y] = pt.tip[1];
            p[AxisLetter::Z] = pt.tip[2];
            emit(OpKind::Line {
                from: prev,
                to: p,
                feed,
            });
            prev = p;
        }
        emit(OpKind::ExactStop);
        self.last_feed = Some(feed);
        *to = prev;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The built-in 5-axis mill: A tilts about the line y = 0, z = −100; C through the origin.
    const MILL5: TableGeometry = TableGeometry {
        tilt: Tilt::A,
        tilt_pivot: [0.0, 0.0, -100.0],
        table_pivot: [0.0, 0.0, 0.0],
    };

    /// `v` turned by `deg` about X, written out.
    fn rot_x(deg: f64, v: V3) -> V3 {
        let (s, c) = deg.to_radians().sin_cos();
        [v[0], c * v[1] - s * v[2], s * v[1] + c * v[2]]
    }

    /// `v` turned by `deg` about Y, written out.
    fn rot_y(deg: f64, v: V3) -> V3 {
        let (s, c) = deg.to_radians().sin_cos();
        [c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]]
    }

    /// `v` turned by `deg` about Z, written out.
    fn rot_z(deg: f64, v: V3) -> V3 {
        let (s, c) = deg.to_radians().sin_cos();
        [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]
    }

    #[track_caller]
    fn close(a: V3, b: V3, tol: f64) {
        assert!(norm(sub(a, b)) < tol, "{a:?} vs {b:?}");
    }

    #[test]
    fn a_tilt_of_30_swings_the_tip_about_the_tilt_line() {
        // Tip on the datum, A and C at zero: the machine holds (0, 0, 0). The workpiece turns
        // with the table by −30° about the line z = −100, so the point under the tool is the
        // machine point turned back by +30° about that line: (0, −100·sin30, 100·cos30 − 100)
        // (the tool now points along (0, −sin30, cos30) of the workpiece, and the tip lies
        // 13.4 mm below the untilted surface: a TURN wants the tool retracted first).
        let path = MILL5.turn_path([0.0, 0.0, 0.0], (0.0, 0.0), (30.0, 0.0), 1e-4);
        let end = path.last().expect("pieces");
        assert_eq!((end.t, end.c), (30.0, 0.0));
        let (s, c) = 30f64.to_radians().sin_cos();
        close(end.tip, [0.0, -100.0 * s, 100.0 * c - 100.0], 1e-9);
    }

    #[test]
    fn every_point_is_the_closed_form_rotation_of_the_held_machine_point() {
        // B/C table with pivots off the axes: the machine point of the start is fixed, and
        // each point of the path is it turned back through the tilt line and then the table.
        let g = TableGeometry {
            tilt: Tilt::B,
            tilt_pivot: [10.0, 0.0, -80.0],
            table_pivot: [5.0, -3.0, 0.0],
        };
        let (p0, t0, c0) = ([12.0, -7.0, 20.0], 10.0, -40.0);
        // machine point by hand: into the table frame, turn by −c, over to the tilt line, −t
        let m = {
            let q = rot_z(-c0, sub(p0, g.table_pivot));
            let q = add(q, sub(g.table_pivot, g.tilt_pivot));
            add(g.tilt_pivot, rot_y(-t0, q))
        };
        let path = g.turn_path(p0, (t0, c0), (45.0, 120.0), 1e-4);
        assert!(path.len() > 10, "{} pieces", path.len());
        for (k, pt) in path.iter().enumerate() {
            let f = (k + 1) as f64 / path.len() as f64;
            assert!((pt.t - (t0 + 35.0 * f)).abs() < 1e-9);
            assert!((pt.c - (c0 + 160.0 * f)).abs() < 1e-9);
            let q = rot_y(pt.t, sub(m, g.tilt_pivot));
            let q = sub(q, sub(g.table_pivot, g.tilt_pivot));
            close(pt.tip, add(g.table_pivot, rot_z(pt.c, q)), 1e-9);
        }
    }

    #[test]
    fn chords_stay_within_the_tolerance_of_the_curve() {
        // Along each chord the machine point (by the closed form of the held point) moves
        // from the start by no more than the tolerance; checked at 20 points per piece.
        let tol = 1e-3;
        let p0 = [40.0, -25.0, 10.0];
        let path = MILL5.turn_path(p0, (0.0, 0.0), (60.0, 270.0), tol);
        // at zero angles the workpiece frame is the machine frame
        let m0 = p0;
        let mut prev = TurnPoint {
            tip: p0,
            t: 0.0,
            c: 0.0,
        };
        let mut worst = 0.0f64;
        for pt in &path {
            for j in 0..=20 {
                let f = j as f64 / 20.0;
                let tip = add(prev.tip, sub(pt.tip, prev.tip).map(|d| d * f));
                let (t, c) = (prev.t + (pt.t - prev.t) * f, prev.c + (pt.c - prev.c) * f);
                // machine X Y Z of that tip, written out for the A/C table
                let q = add([0.0, 0.0, 100.0], rot_z(-c, tip));
                let m = add([0.0, 0.0, -100.0], rot_x(-t, q));
                worst = worst.max(norm(sub(m, m0)));
            }
            prev = *pt;
        }
        assert!(worst <= tol, "machine point left by {worst}");
        // and the pieces are not needlessly many: the worst deviation is a good part of it
        assert!(worst > tol / 8.0, "{worst} with {} pieces", path.len());
    }

    /// The lines a program makes on an A/C table (the built-in 5-axis mill's pivots when
    /// `geometry`), as (from, to).
    fn lines(text: &str, geometry: bool) -> Vec<(crate::Pose, crate::Pose)> {
        use crate::{AxisLetter as L, Interpreter, OpKind, Pose};
        let src = format!("BEGIN PGM T MM\n{text}\nEND PGM T MM\n");
        let mut it = Interpreter::from_source("t.h", &src, Pose::ZERO).with_rotary_axes(&[
            L::X,
            L::Y,
            L::Z,
            L::A,
            L::C,
        ]);
        if geometry {
            it = it.with_table_geometry(L::A, [0.0, 0.0, -100.0], [0.0; 3]);
        }
        it.collect::<Result<Vec<_>, _>>()
            .unwrap_or_else(|d| panic!("{d}"))
            .into_iter()
            .filter_map(|op| match op.kind {
                OpKind::Line { from, to, .. } => Some((from, to)),
                _ => None,
            })
            .collect()
    }

    fn xyz(p: &crate::Pose) -> V3 {
        use crate::AxisLetter as L;
        [p[L::X], p[L::Y], p[L::Z]]
    }

    #[test]
    fn plane_turn_leaves_the_tip_where_the_table_carried_it() {
        use crate::AxisLetter as L;
        let text = "L X+20 Y+10 Z+5 FMAX\nPLANE SPATIAL SPA+30 SPB+0 SPC+0 TURN FMAX\nL IX+10 FMAX";
        let ops = lines(text, true);
        // the approach, the turn in pieces, the incremental move
        assert!(ops.len() > 10, "{} lines", ops.len());
        let (turn, rest) = ops.split_at(ops.len() - 1);
        let turn = &turn[1..];
        // Machine point held at (20, 10, 5); at A t the tip is it turned by t about the
        // line y = 0, z = −100: (20, 10·cos t − 105·sin t, 10·sin t + 105·cos t − 100).
        for (_, to) in turn {
            let (s, c) = to[L::A].to_radians().sin_cos();
            let want = [20.0, 10.0 * c - 105.0 * s, 10.0 * s + 105.0 * c - 100.0];
            close(xyz(to), want, 1e-9);
            assert_eq!(to[L::C], 0.0);
        }
        let end = turn.last().expect("turn").1;
        assert!((end[L::A] - 30.0).abs() < 1e-9);
        // The next incremental move starts on that point and runs along the tilted X axis,
        // which on SPA+30 is the workpiece X.
        let (from, to) = rest[0];
        close(xyz(&from), xyz(&end), 1e-9);
        close(sub(xyz(&to), xyz(&from)), [10.0, 0.0, 0.0], 1e-9);
    }

    #[test]
    fn without_the_geometry_turn_holds_the_tip_like_move() {
        use crate::AxisLetter as L;
        let text = "L X+20 Y+10 Z+5 FMAX\nPLANE SPATIAL SPA+30 SPB+0 SPC+0 TURN FMAX";
        let ops = lines(text, false);
        assert_eq!(ops.len(), 2);
        close(xyz(&ops[1].1), [20.0, 10.0, 5.0], 1e-12);
        assert!((ops[1].1[L::A] - 30.0).abs() < 1e-9);
        // and MOVE ignores the geometry
        let moved = lines(&text.replace("TURN", "MOVE"), true);
        assert_eq!(moved, ops);
    }

    #[test]
    fn no_turn_is_one_piece_at_the_start() {
        let path = MILL5.turn_path([1.0, 2.0, 3.0], (20.0, 5.0), (20.0, 5.0), 1e-4);
        assert_eq!(path.len(), 1);
        close(path[0].tip, [1.0, 2.0, 3.0], 1e-12);
    }
}
