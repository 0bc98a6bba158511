//! Tool centre point management: M128 / M129 with the feed of the compensating moves, and
//! `FUNCTION TCPM` / `FUNCTION RESET TCPM` with their words.
//!
//! While TCPM is on the linear axes make compensating moves that keep the tool tip on the
//! programmed point of the workpiece as the rotary axes turn (see [`super::plane`] for when
//! the kinematics' transformation switches).
//!
//! **M128 F…**: an F written directly after M128 is the feed of those compensating moves, not
//! the block's path feed (which is the F before it, or the modal one): `L X+10 A+10 F3000
//! M128 F500` cuts at 3000 mm/min while the compensating moves of the linear axes stay within
//! 500 mm/min. It lasts until M129 or another M128 with an F; M128 without F while M128 is
//! already on keeps it, M128 switching TCPM on without F has none (the machine's own limits
//! apply, as a control uses its machine parameter). It is passed on with
//! [`OpKind::Tcpm`]; the planner keeps the speed the turning adds to the linear machine axes
//! within it. An F anywhere else in a block that already has one stays an error.
//!
//! **FUNCTION TCPM** takes four optional groups, each at most once, in any order:
//! - `F TCP` (default): F is the speed of the tool tip relative to the workpiece; `F CONT`:
//!   F is the contouring feed of the axes the block programs, rotary axes counted in degrees
//!   like millimetres ([`super::rotary_feed`]).
//! - `AXIS POS` (default): rotary coordinates are the axes' positions. `AXIS SPAT` (they are
//!   spatial angles) is accepted in the block, but a later block that programs a rotary axis
//!   while it is in force is refused: klar has no conversion from spatial angles there.
//! - `PATHCTRL AXIS` (default): the tip runs straight and the axes' angles are interpolated
//!   linearly. `PATHCTRL VECTOR` (the tool axis swept in one plane between the block's end
//!   orientations) is accepted and run like PATHCTRL AXIS: the tip's path is the same
//!   straight line, the tool's direction between the ends follows the linear angle
//!   interpolation instead, a difference that shrinks with the square of the block's turn.
//! - `REFPNT TIP-TIP` (default): the programmed point is the tool tip, turned about. The
//!   forms with CENTER (the tool's centre point as programmed point or pivot) are refused:
//!   klar's kinematics hold the tip only.
//!
//! FUNCTION TCPM and M129 / FUNCTION RESET TCPM end an M128 feed; M128, M129 and FUNCTION
//! RESET TCPM return the FUNCTION TCPM modes to their defaults.

use std::collections::VecDeque;

use super::exec::{Flow, Machine};

use super::plane_math::{self as pm, Tilt};
use crate::op::{AxisLetter, Op, OpKind, Pose, SourceLoc};

/// The modes FUNCTION TCPM sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct TcpmMode {
    /// F CONT (true) or F TCP.
    pub cont: bool,
    /// AXIS SPAT (true) or AXIS POS.
    pub spatial: bool,
    /// PATHCTRL VECTOR (true) or PATHCTRL AXIS.
    pub vector: bool,
}

impl Machine {
    /// Passes the TCPM state on when it changed (after an exact stop): on or off, and the
    /// feed of M128's compensating moves.
    pub(super) fn sync_tcpm(&mut self, emit: &mut impl FnMut(OpKind)) {
        let want = self.tilt.m128 || self.tilt.plane_tcpm;
        let feed = if self.tilt.m128 {
            self.tilt.m128_feed
        } else {
            None
        };
        if want != self.tilt.kin_on || (want && feed != self.tilt.kin_feed) {
            let reframe = if want != self.tilt.kin_on {
                self.reframe(want)
            } else {
                None
            };
            self.tilt.kin_on = want;
            self.tilt.kin_feed = feed;
            // Switch at rest on the programmed point, not inside a blended corner.
            emit(OpKind::ExactStop);
            emit(OpKind::Tcpm {
                on: want,
                compensation_feed: feed,
                reframe,
            });
        }
    }

    /// Re-expresses the present position for TCPM switching `on` (or off) where the machine
    /// stands: with TCPM off the program's X Y Z are the machine's own axes, with it on the
    /// tool tip on the workpiece, and the table geometry maps one into the other at the
    /// present rotary angles. Axes the next block does not program keep the tool where it is.
    /// Returns the new pose in workpiece coordinates (untilted, after the cycle transforms),
    /// or `None` when the geometry is not known (the position is then left as it is).
    fn reframe(&mut self, on: bool) -> Option<Pose> {
        let g = self.tilt.geometry?;
        let w = self.workpiece_pos();
        let t = match g.tilt {
            Tilt::A => w[AxisLetter::A],
            Tilt::B => w[AxisLetter::B],
        };
        let c = w[AxisLetter::C];
        let p = [w[AxisLetter::X], w[AxisLetter::Y], w[AxisLetter::Z]];
        let q = if on {
            g.machine_to_tip(p, t, c)
        } else {
            g.tip_to_machine(p, t, c)
        };
        let mut now = w;
        (now[AxisLetter::X], now[AxisLetter::Y], now[AxisLetter::Z]) = (q[0], q[1], q[2]);
        self.set_workpiece_pos(now);
        Some(now)
    }

    /// Sets the position from workpiece coordinates `w` (untilted, after the cycle
    /// transforms), in the terms of the working plane in force.
    pub(super) fn set_workpiece_pos(&mut self, w: Pose) {
        let back = pm::apply(
            &pm::transpose(&self.tilt.r),
            [w[AxisLetter::X], w[AxisLetter::Y], w[AxisLetter::Z]],
        );
        let mut m = w;
        (m[AxisLetter::X], m[AxisLetter::Y], m[AxisLetter::Z]) = (back[0], back[1], back[2]);
        self.pos = self.cyc.xf.unmap_point(&m);
    }

    /// M128 (`on`, with the feed of the compensating moves in mm/s when an F follows it) /
    /// M129.
    pub(super) fn set_m128(&mut self, on: bool, feed: Option<f64>, emit: &mut impl FnMut(OpKind)) {
        self.tilt.tcpm_mode = TcpmMode::default();
        self.tilt.m128_feed = match (on, feed) {
            (false, _) => None,
            (true, Some(f)) => Some(f),
            // M128 again without F keeps the feed of the one in force
            (true, None) if self.tilt.m128 => self.tilt.m128_feed,
            (true, None) => None,
        };
        self.tilt.m128 = on;
        self.sync_tcpm(emit);
    }

    /// `FUNCTION TCPM` / `FUNCTION RESET TCPM` blocks.
    pub(super) fn tcpm_block(
        &mut self,
        on: bool,
        mode: TcpmMode,
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) -> Flow {
        self.tilt.m128 = on;
        self.tilt.m128_feed = None;
        self.tilt.tcpm_mode = if on { mode } else { TcpmMode::default() };
        self.sync_tcpm(&mut |kind| out.push_back(Op { kind, loc }));
        Flow::Continue
    }
}

#[cfg(test)]
mod tests {
    use crate::klartext::test_support::{klartext, mill5_ops as ops};
    use crate::op::{Feed, Op, OpKind};

    /// The TCPM ops as (on, compensation feed in mm/min).
    fn switches(ops: &[Op]) -> Vec<(bool, Option<f64>)> {
        ops.iter()
            .filter_map(|o| match o.kind {
                OpKind::Tcpm {
                    on,
                    compensation_feed,
                    ..
                } => Some((on, compensation_feed.map(|f| f * 60.0))),
                _ => None,
            })
            .collect()
    }

    fn feeds(ops: &[Op]) -> Vec<Feed> {
        ops.iter()
            .filter_map(|o| match o.kind {
                OpKind::Line { feed, .. } => Some(feed),
                _ => None,
            })
            .collect()
    }

    fn close(a: Option<f64>, b: f64) -> bool {
        a.is_some_and(|a| (a - b).abs() < 1e-9)
    }

    #[test]
    fn an_f_after_m128_is_the_feed_of_the_compensating_moves() {
        let text = klartext(
            "1 L X+0 Y+0 Z+50 A+0 C+0 R0 FMAX\n\
             2 L X+10 Y+5 Z+3 A+10 C+20 F30000 M128 F500\n\
             3 L C+40 M128\n4 L C+60 M128 F800\n5 L C+0 M129\n6 L A+0 M128",
        );
        let ops = ops("t.h", &text).unwrap();
        let s = switches(&ops);
        assert_eq!(s.len(), 4, "{s:?}");
        // block 2: on with 500 mm/min; the path feed stays 30000 mm/min
        assert!(s[0].0 && close(s[0].1, 500.0), "{s:?}");
        assert_eq!(feeds(&ops)[1], Feed::Rate(500.0));
        // block 3: M128 again without F keeps it (no new op); block 4: a new one
        assert!(s[1].0 && close(s[1].1, 800.0), "{s:?}");
        // M129 ends it; M128 switching on without F has none
        assert_eq!(&s[2..], [(false, None), (true, None)]);
        // every switch comes after an exact stop
        for (i, o) in ops.iter().enumerate() {
            if matches!(o.kind, OpKind::Tcpm { .. }) {
                assert_eq!(ops[i - 1].kind, OpKind::ExactStop);
            }
        }
    }

    #[test]
    fn the_m128_feed_follows_the_program_unit_and_parameters() {
        // INCH: F in 0.1 inch/min; Q1 as the value
        let text = "0 BEGIN PGM T INCH\n1 Q1 = 200\n2 L X+1 Y+0 Z+2 F100 M128 FQ1\n\
                    3 END PGM T INCH\n";
        let s = switches(&ops("t.h", text).unwrap());
        assert!(close(s[0].1, 200.0 * 2.54), "{s:?}");
        let err = ops("t.h", &klartext("1 Q1 = -5\n2 L X+1 F100 M128 FQ1")).unwrap_err();
        assert!(err.contains("after M128 must be positive"), "{err}");
    }

    #[test]
    fn a_second_f_anywhere_else_stays_an_error() {
        for body in [
            "1 L X+10 F500 F600",
            "1 L X+10 F500 M3 F600",
            "1 L X+10 F500 M128 F600 F700",
            "1 L X+10 F500 M128 M3 F600",
        ] {
            let err = ops("t.h", &klartext(body)).unwrap_err();
            assert!(
                err.contains("word F programmed twice in one block"),
                "{body}: {err}"
            );
        }
        // ISO the same way
        let iso = |b: &str| format!("%T G71 *\nN10 G01 X+1 {b} *\nN99999999 %T G71 *\n");
        let err = ops("t.i", &iso("F500 F600")).unwrap_err();
        assert!(err.contains("word F programmed twice"), "{err}");
        let s = switches(&ops("t.i", &iso("F500 M128 F250")).unwrap());
        assert!(s[0].0 && close(s[0].1, 250.0), "{s:?}");
    }

    /// The op feed of `L X+30 C+40 F600` from the origin after `tcpm`, in mm/s.
    fn cont_feed(tcpm: &str) -> Feed {
        let text = klartext(&format!(
            "1 L X+0 Y+0 Z+10 A+0 C+0 R0 FMAX\n2 {tcpm}\n3 L X+30 C+40 F600"
        ));
        *feeds(&ops("t.h", &text).unwrap()).last().unwrap()
    }

    #[test]
    fn f_tcp_is_the_tip_speed_and_f_cont_the_contouring_feed_of_the_block() {
        // F TCP: the tip runs its 30 mm at 600 mm/min
        assert_eq!(
            cont_feed("FUNCTION TCPM F TCP AXIS POS PATHCTRL AXIS"),
            Feed::Rate(10.0)
        );
        assert_eq!(cont_feed("FUNCTION TCPM"), Feed::Rate(10.0));
        // F CONT: 30 mm and 40° make a 50-unit contour at 600/min: 5 s, so the 30 mm run
        // at 6 mm/s
        let Feed::Rate(v) = cont_feed("FUNCTION TCPM F CONT AXIS POS PATHCTRL AXIS") else {
            panic!()
        };
        assert!((v - 6.0).abs() < 1e-12, "{v}");
        // M128 is F TCP again
        assert_eq!(
            cont_feed("FUNCTION TCPM F CONT AXIS POS PATHCTRL AXIS\n3 M128"),
            Feed::Rate(10.0)
        );
    }

    #[test]
    fn the_standard_forms_parse_in_any_order() {
        for words in [
            "F TCP AXIS POS PATHCTRL AXIS",
            "F CONT AXIS POS PATHCTRL VECTOR",
            "F TCP AXIS POS PATHCTRL AXIS REFPNT TIP-TIP",
            "PATHCTRL VECTOR F CONT",
            "AXIS SPAT",
            "f tcp axis pos pathctrl axis",
        ] {
            let text = klartext(&format!("1 FUNCTION TCPM {words}\n2 FUNCTION RESET TCPM"));
            let s = switches(&ops("t.h", &text).unwrap_or_else(|e| panic!("{words}: {e}")));
            assert_eq!(s, [(true, None), (false, None)], "{words}");
        }
    }

    #[test]
    fn other_words_are_refused_at_their_place() {
        for (words, what) in [
            ("F TCP F CONT", "word F programmed twice"),
            ("F FAST", "expected TCP or CONT"),
            ("AXIS", "expected POS or SPAT"),
            ("PATHCTRL LINE", "expected AXIS or VECTOR"),
            (
                "REFPNT TIP-CENTER",
                "REFPNT TIP-CENTER (klar holds the tool tip",
            ),
            ("REFPNT CENTER-CENTER", "REFPNT CENTER-CENTER"),
            ("REFPNT TOP", "expected TIP-TIP"),
            ("SPEED", "unexpected"),
        ] {
            let err = ops("t.h", &klartext(&format!("1 FUNCTION TCPM {words}"))).unwrap_err();
            assert!(err.contains(what), "{words}: {err}");
        }
        // the column of the second F (line 2 of the file)
        let err = ops("t.h", &klartext("1 FUNCTION TCPM F TCP F CONT")).unwrap_err();
        let col = "1 FUNCTION TCPM F TCP F CONT".rfind('F').unwrap() + 1;
        assert!(err.starts_with(&format!("2:{col}:")), "{err}");
    }

    #[test]
    fn axis_spat_refuses_rotary_coordinates_until_reset() {
        let base =
            "1 L X+0 Y+0 Z+10 A+0 C+0 R0 FMAX\n2 FUNCTION TCPM F TCP AXIS SPAT PATHCTRL AXIS";
        // linear moves are fine
        assert!(ops("t.h", &klartext(&format!("{base}\n3 L X+20 F500"))).is_ok());
        let err = ops("t.h", &klartext(&format!("{base}\n3 L A+10 F500"))).unwrap_err();
        assert!(err.starts_with("4:") && err.contains("AXIS SPAT"), "{err}");
        let ok = format!("{base}\n3 FUNCTION RESET TCPM\n4 L A+10 F500");
        assert!(ops("t.h", &klartext(&ok)).is_ok());
    }
}
