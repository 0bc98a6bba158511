//! The feed of blocks that turn rotary axes: M116 / M117, and FUNCTION TCPM F CONT.
//!
//! Ops measure a move's feed over the linear axes (mm/s along X Y Z U V W); a move of rotary
//! axes alone is measured in degrees over A B C. Without the functions below that is also
//! what F means: on a block that moves linear and rotary axes together the linear axes run
//! at F and the rotary axes arrive with them; a rotary axis alone turns at F degrees/min.
//!
//! **M116** (feed on rotary table axes in mm/min; M117 switches it off, so does the end of
//! the program; it acts from the start of its own block): F is the speed of the tool point
//! relative to the workpiece. For a block that turns a table axis the interpreter takes, at
//! the block's start, the distance `r` of the tool point from each turning axis. A turn of
//! `Δθ` radians then moves the tool point `Δθ·r` over the workpiece, and the block's tool
//! point path is taken as `L = √(l² + Σ (Δθᵢ·rᵢ)²)` with `l` the linear path (the linear
//! axes' own distance, an arc's helix length). The block lasts `L / F`, and the op carries
//! the feed that gives that duration in its own measure: `F·l / L` over the linear axes, or
//! `F·α / L` in degrees when only rotary axes move (`α` the degrees turned). The rates are
//! fixed for the block: the tool point coming nearer to an axis during the block does not
//! change them. A tool point on the axis of a rotary-only move travels nowhere: the block
//! then runs as fast as the axes allow. M116 does not change the feed of blocks that move
//! linear axes only, nor rapid moves.
//!
//! The tool point is where X Y Z stand at the block's start in machine coordinates (klar's
//! ops are machine coordinates while TCPM is off); the axes' places come from the machine's
//! table-table geometry (`Interpreter::with_table_geometry`): the tilt axis A (or B) is the
//! line through the tilt pivot parallel to X (Y); the table axis C passes through the table
//! pivot parallel to Z with the cradle level, and is carried by the cradle as it tilts. M116
//! works for these rotary table axes only (a control would ignore a swivel head's axes; klar
//! has none). An interpreter told no machine at all (a check or plot of the program on its
//! own) assumes an A/C table with both axes through the workpiece datum, as PLANE assumes an
//! A/C table there; the durations it gives are then those of that layout. Refused, with the
//! reason: a turning block under M116 on a machine whose table geometry is not known (its
//! file names no table-table kinematics), a turning block of an axis that is not one of the
//! table's, and M116 while TCPM is on (M128, FUNCTION TCPM, a tilted working plane): the tool
//! point then stays on the workpiece while the table turns, so the two meanings exclude each
//! other, as they do on the control.
//!
//! **FUNCTION TCPM F CONT**: F is the contouring feed of the axes the block programs, rotary
//! axes included, a degree counting like a millimetre: a block moving linear and rotary
//! axes lasts `√(l² + α²) / F`, so its op feed over the linear axes is `F·l / √(l² + α²)`.
//! F TCP (the default, and M128) keeps F as the tool tip's speed over the workpiece, which is
//! what the op feed of a TCPM move already is.
//!
//! **FUNCTION TCPM … AXIS SPAT**: a path block that turns a rotary axis while it is in force
//! is refused here (klar reads rotary coordinates as axis positions only).

use super::exec::{ExecError, Machine, here};
use super::plane_math::{self as pm, Tilt, V3};
use super::plane_turn::TableGeometry;
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Feed, OpKind, Pose};

/// Below this (mm or degrees) a distance counts as zero.
const ZERO: f64 = 1e-9;

/// Pose indices of the linear axes X Y Z U V W.
const LINEAR: [usize; 6] = [0, 1, 2, 6, 7, 8];

/// The rotary axes A B C.
const ROTARY: [AxisLetter; 3] = [AxisLetter::A, AxisLetter::B, AxisLetter::C];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Distance of `q` from the line through `a` with unit direction `u`.
fn distance_to_line(q: V3, a: V3, u: V3) -> f64 {
    let d = sub(q, a);
    let along = dot(d, u);
    (dot(d, d) - along * along).max(0.0).sqrt()
}

/// The linear path length of a motion op (mm): the straight distance over the linear axes,
/// or an arc's helix length. `None` for ops this module leaves alone.
fn linear_length(op: &OpKind) -> Option<f64> {
    match op {
        OpKind::Line { from, to, .. } => Some(
            LINEAR
                .iter()
                .map(|&i| (to.0[i] - from.0[i]).powi(2))
                .sum::<f64>()
                .sqrt(),
        ),
        OpKind::Arc {
            from,
            to,
            center,
            plane,
            sweep,
            ..
        } => {
            let (a, b, _) = plane.axes();
            let radius = (from[a] - center[0]).hypot(from[b] - center[1]);
            let travel: f64 = LINEAR
                .iter()
                .filter(|&&i| i != a.index() && i != b.index())
                .map(|&i| (to.0[i] - from.0[i]).powi(2))
                .sum();
            Some(((radius * sweep.to_radians()).powi(2) + travel).sqrt())
        }
        _ => None,
    }
}

/// The ends of a motion op and its feed.
fn ends(op: &OpKind) -> Option<(Pose, Pose, Feed)> {
    match op {
        OpKind::Line { from, to, feed }
        | OpKind::Arc { from, to, feed, .. }
        | OpKind::Spline { from, to, feed, .. } => Some((*from, *to, *feed)),
        _ => None,
    }
}

/// `op` with its feed replaced.
fn with_feed(op: &OpKind, feed: Feed) -> OpKind {
    let mut op = op.clone();
    if let OpKind::Line { feed: f, .. } | OpKind::Arc { feed: f, .. } = &mut op {
        *f = feed;
    }
    op
}

impl Machine {
    /// The op of a path block with the feed its modes give it (M116, FUNCTION TCPM F CONT;
    /// see the module notes); unchanged when neither applies.
    pub(super) fn rotary_feed(&self, op: &OpKind) -> Result<OpKind, ExecError> {
        let Some((from, to, feed)) = ends(op) else {
            return Ok(op.clone());
        };
        let turned: Vec<(AxisLetter, f64)> = ROTARY
            .iter()
            .map(|&a| (a, to[a] - from[a]))
            .filter(|(_, d)| d.abs() > ZERO)
            .collect();
        if self.tilt.tcpm_mode.spatial && !turned.is_empty() {
            return Err(here(ProgramError::NotSupported(
                "rotary coordinates as spatial angles (FUNCTION TCPM … AXIS SPAT); \
                 program the axes' positions with AXIS POS"
                    .into(),
            )));
        }
        let Feed::Rate(f) = feed else {
            return Ok(op.clone());
        };
        if turned.is_empty() || !(self.tilt.m116 || self.tilt.tcpm_mode.cont) {
            return Ok(op.clone());
        }
        let Some(l) = linear_length(op) else {
            return Err(here(ProgramError::NotSupported(
                "M116 or F CONT on a spline block that turns a rotary axis".into(),
            )));
        };
        let degrees = turned.iter().map(|(_, d)| d * d).sum::<f64>().sqrt();
        let path = if self.tilt.m116 {
            let radii = self.table_radii(&from, &turned)?;
            let arcs: f64 = turned
                .iter()
                .zip(&radii)
                .map(|((_, d), r)| (d.to_radians() * r).powi(2))
                .sum();
            (l * l + arcs).sqrt()
        } else {
            (l * l + degrees * degrees).sqrt()
        };
        let new = if path <= ZERO {
            // the tool point stays where it is: nothing limits the turn but the axes
            Feed::Rapid
        } else if l > ZERO {
            Feed::Rate(f * l / path)
        } else {
            Feed::Rate(f * degrees / path)
        };
        Ok(with_feed(op, new))
    }

    /// The distance of the tool point (X Y Z of `from` in machine coordinates) from each
    /// turning axis at the block's start (M116).
    fn table_radii(
        &self,
        from: &Pose,
        turned: &[(AxisLetter, f64)],
    ) -> Result<Vec<f64>, ExecError> {
        if self.tilt.m128 || self.tilt.plane_tcpm {
            return Err(here(ProgramError::Plane(
                "M116 cannot act while TCPM is on (M128, FUNCTION TCPM or a tilted working \
                 plane): the tool point then stays put on the workpiece; program M117 first"
                    .into(),
            )));
        }
        let g = match (self.tilt.geometry, &self.tilt.rotary) {
            (Some(g), _) => g,
            // not told any machine (a check or plot of the program alone): an A/C table
            // through the workpiece datum
            (None, None) => TableGeometry {
                tilt: Tilt::A,
                tilt_pivot: [0.0; 3],
                table_pivot: [0.0; 3],
            },
            (None, Some(_)) => {
                return Err(here(ProgramError::Plane(
                    "M116 needs the places of the rotary table axes; this machine does not \
                     give them (kinematics table_table with [table_table] pivots does)"
                        .into(),
                )));
            }
        };
        let machine = if self.cyc.identity {
            *from
        } else {
            self.cyc.xf.map_point(from)
        };
        let tool = [machine.0[0], machine.0[1], machine.0[2]];
        let tilt_letter = match g.tilt {
            Tilt::A => AxisLetter::A,
            Tilt::B => AxisLetter::B,
        };
        let tilt_dir = match g.tilt {
            Tilt::A => [1.0, 0.0, 0.0],
            Tilt::B => [0.0, 1.0, 0.0],
        };
        // The cradle at its start angle carries the table axis: point and direction.
        let cradle = g.tilt.rot(-machine[tilt_letter]);
        let arm = pm::apply(&cradle, sub(g.table_pivot, g.tilt_pivot));
        let table_point = [
            g.tilt_pivot[0] + arm[0],
            g.tilt_pivot[1] + arm[1],
            g.tilt_pivot[2] + arm[2],
        ];
        let table_dir = pm::apply(&cradle, [0.0, 0.0, 1.0]);
        turned
            .iter()
            .map(|&(axis, _)| {
                if axis == tilt_letter {
                    Ok(distance_to_line(tool, g.tilt_pivot, tilt_dir))
                } else if axis == AxisLetter::C {
                    Ok(distance_to_line(tool, table_point, table_dir))
                } else {
                    Err(here(ProgramError::Plane(format!(
                        "M116: {axis} is not a rotary table axis of this machine \
                         ({tilt_letter} and C are)"
                    ))))
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use crate::interpreter::Interpreter;
    use crate::klartext::test_support::{klartext, mill5_ops as mill5};
    use crate::op::{AxisLetter, Feed, Op, OpKind, Pose};
    use std::f64::consts::PI;

    /// The lines of a program as (from, to, feed).
    fn lines(ops: &[Op]) -> Vec<(Pose, Pose, Feed)> {
        ops.iter()
            .filter_map(|o| match o.kind {
                OpKind::Line { from, to, feed } => Some((from, to, feed)),
                _ => None,
            })
            .collect()
    }

    /// Seconds a line takes at its op feed, measured as motion measures it: over the linear
    /// axes, or in degrees over A B C when no linear axis moves.
    fn seconds(from: &Pose, to: &Pose, feed: Feed) -> f64 {
        let Feed::Rate(v) = feed else {
            panic!("not a rate: {feed:?}")
        };
        let sq = |axes: &[AxisLetter]| axes.iter().map(|&a| (to[a] - from[a]).powi(2)).sum::<f64>();
        let lin = sq(&[AxisLetter::X, AxisLetter::Y, AxisLetter::Z]).sqrt();
        let len = if lin > 1e-9 {
            lin
        } else {
            sq(&[AxisLetter::A, AxisLetter::B, AxisLetter::C]).sqrt()
        };
        len / v
    }

    /// The line that ends at C = `c`.
    fn to_c(ops: &[Op], c: f64) -> (Pose, Pose, Feed) {
        *lines(ops)
            .iter()
            .find(|(_, to, _)| (to[AxisLetter::C] - c).abs() < 1e-12)
            .expect("a line to that C")
    }

    /// C turning 90° with the tool point 50 mm from the C axis at F1000: the tool point runs
    /// a quarter circle of radius 50 at 1000 mm/min.
    const QUARTER_AT_50: f64 = (PI / 2.0 * 50.0) / 1000.0 * 60.0;

    #[test]
    fn a_table_turn_takes_the_time_of_the_tool_points_arc() {
        let text = klartext("1 L X+50 Y+0 Z+10 A+0 C+0 R0 FMAX\n2 L C+90 F1000 M116");
        let ops = mill5("t.h", &text).unwrap();
        let (from, to, feed) = to_c(&ops, 90.0);
        assert!((QUARTER_AT_50 - 4.712_388_980_384_69).abs() < 1e-12);
        assert!((seconds(&from, &to, feed) - QUARTER_AT_50).abs() < 1e-9);
        // the op's feed: 90° in that time, 19.0986 °/s
        let Feed::Rate(v) = feed else { panic!() };
        assert!((v - 90.0 / QUARTER_AT_50).abs() < 1e-12 && (v - 19.0986).abs() < 1e-4);
    }

    #[test]
    fn linear_and_rotary_together_share_the_tool_points_path() {
        // X 50 → 80 while C turns 90°: 30 mm straight and a 25π mm arc, taken together as
        // √(30² + (25π)²) mm at 1000 mm/min.
        let text = klartext("1 L X+50 Y+0 Z+10 A+0 C+0 R0 FMAX\n2 L X+80 C+90 F1000 M116");
        let ops = mill5("t.h", &text).unwrap();
        let (from, to, feed) = to_c(&ops, 90.0);
        let path = (30.0f64.powi(2) + (25.0 * PI).powi(2)).sqrt();
        let want = path / 1000.0 * 60.0;
        assert!((seconds(&from, &to, feed) - want).abs() < 1e-9);
        // the linear axes run at 1000 mm/min times their share of the path
        let Feed::Rate(v) = feed else { panic!() };
        assert!((v - 1000.0 / 60.0 * 30.0 / path).abs() < 1e-12);
    }

    #[test]
    fn the_tilt_axis_measures_from_its_own_line() {
        // tool point at Y30 Z10: 30 mm beside and 110 mm above the tilt line (Y0, Z−100)
        let text = klartext("1 L X+0 Y+30 Z+10 A+0 C+0 R0 FMAX\n2 L A+20 F600 M116");
        let ops = mill5("t.h", &text).unwrap();
        let (from, to, feed) = *lines(&ops).last().unwrap();
        let r = 30.0f64.hypot(110.0);
        let want = 20f64.to_radians() * r / 600.0 * 60.0;
        assert!((seconds(&from, &to, feed) - want).abs() < 1e-9);
    }

    #[test]
    fn the_tilted_cradle_carries_the_table_axis() {
        // At A+90 the cradle has turned the table's surface from +Z to +Y: the C axis runs
        // along Y through (0, 100, −100). The tool point (40, 0, −70) is 40 mm from it in X
        // and 30 mm in Z: 50 mm, so the turn takes as long as the one at 50 mm above.
        let text = klartext("1 L A+90 C+0 R0 FMAX\n2 L X+40 Y+0 Z-70 FMAX\n3 L C+90 F1000 M116");
        let ops = mill5("t.h", &text).unwrap();
        let (from, to, feed) = to_c(&ops, 90.0);
        assert!((seconds(&from, &to, feed) - QUARTER_AT_50).abs() < 1e-9);
    }

    #[test]
    fn m116_is_modal_and_m117_restores_degrees_per_minute() {
        let text = klartext(
            "1 L X+50 Y+0 Z+10 A+0 C+0 R0 FMAX\n2 L C+90 F1000 M116\n3 L C+180\n\
             4 L X+60\n5 L C+270 M117",
        );
        let ops = mill5("t.h", &text).unwrap();
        // block 3: still M116, still 50 mm from the axis
        let (from, to, feed) = to_c(&ops, 180.0);
        assert!((seconds(&from, &to, feed) - QUARTER_AT_50).abs() < 1e-9);
        // block 4 moves X only: F as programmed
        let x = lines(&ops)
            .into_iter()
            .find(|(_, to, _)| to[AxisLetter::X] == 60.0)
            .unwrap();
        assert_eq!(x.2, Feed::Rate(1000.0 / 60.0));
        // block 5: M117 acts at its block's start: 90° at 1000°/min = 5.4 s
        let (from, to, feed) = to_c(&ops, 270.0);
        assert_eq!(feed, Feed::Rate(1000.0 / 60.0));
        assert!((seconds(&from, &to, feed) - 5.4).abs() < 1e-12);
    }

    #[test]
    fn the_datum_shift_moves_the_tool_point_not_the_axis() {
        // program X+30 under a datum shift of X+20 is machine X+50
        let text = klartext(
            "1 CYCL DEF 7.0 DATUM SHIFT\n2 CYCL DEF 7.1 X+20\n3 L X+30 Y+0 Z+10 A+0 C+0 R0 FMAX\n\
             4 L C+90 F1000 M116",
        );
        let ops = mill5("t.h", &text).unwrap();
        let (from, to, feed) = to_c(&ops, 90.0);
        assert_eq!(from[AxisLetter::X], 50.0);
        assert!((seconds(&from, &to, feed) - QUARTER_AT_50).abs() < 1e-9);
    }

    #[test]
    fn a_tool_point_on_the_axis_turns_as_fast_as_the_axes_allow() {
        let text = klartext("1 L X+0 Y+0 Z+10 A+0 C+0 R0 FMAX\n2 L C+90 F1000 M116");
        let ops = mill5("t.h", &text).unwrap();
        assert_eq!(to_c(&ops, 90.0).2, Feed::Rapid);
    }

    #[test]
    fn told_no_machine_it_assumes_an_a_c_table_through_the_datum() {
        // tool point at Y30 Z40: 50 mm from the A axis through the datum, 30 mm from C
        let text = klartext(
            "1 L X+0 Y+30 Z+40 A+0 C+0 R0 FMAX\n2 L A+90 F1000 M116\n3 L A+0 M117\n4 L C+90 F1000 M116",
        );
        let ops = Interpreter::from_source("t.h", &text, Pose::ZERO)
            .collect::<Result<Vec<_>, _>>()
            .unwrap();
        let l = lines(&ops);
        let (from, to, feed) = l[1];
        assert!((seconds(&from, &to, feed) - QUARTER_AT_50).abs() < 1e-9);
        let (from, to, feed) = to_c(&ops, 90.0);
        let want = (PI / 2.0 * 30.0) / 1000.0 * 60.0;
        assert!((seconds(&from, &to, feed) - want).abs() < 1e-9);
    }

    #[test]
    fn iso_programs_use_the_same_rule() {
        let text = "%T G71 *\nN10 G00 G40 X+50 Y+0 Z+10 A+0 C+0 *\nN20 G01 C+90 F1000 M116 *\n\
                    N30 G01 C+180 M117 *\nN99999999 %T G71 *\n";
        let ops = mill5("t.i", text).unwrap();
        let (from, to, feed) = to_c(&ops, 90.0);
        assert!((seconds(&from, &to, feed) - QUARTER_AT_50).abs() < 1e-9);
        assert_eq!(to_c(&ops, 180.0).2, Feed::Rate(1000.0 / 60.0));
    }

    #[test]
    fn refusals_name_their_reason() {
        let body = "1 L X+50 Y+0 Z+10 A+0 C+0 R0 FMAX\n2 L C+90 F1000 M116";
        // a machine without table geometry: where the axes are is unknown
        let axes = [AxisLetter::X, AxisLetter::Y, AxisLetter::Z, AxisLetter::C];
        let run = |b: &str| {
            Interpreter::from_source("t.h", &klartext(b), Pose::ZERO)
                .with_rotary_axes(&axes)
                .collect::<Result<Vec<_>, _>>()
        };
        let err = run(body).unwrap_err();
        assert_eq!(err.line, 3);
        assert!(
            err.message
                .contains("M116 needs the places of the rotary table axes")
        );
        // ... but M116 on a block that turns nothing is fine there
        assert!(run("1 L X+5 F100 M116").is_ok());
        // with TCPM on
        let err = mill5("t.h", &klartext(&format!("{body} M128"))).unwrap_err();
        assert!(err.contains("M116 cannot act while TCPM is on"), "{err}");
        // an axis that is not one of the table's
        let err = mill5(
            "t.h",
            &klartext("1 L X+50 Z+10 R0 FMAX\n2 L B+10 F100 M116"),
        )
        .unwrap_err();
        assert!(err.contains("B is not a rotary table axis"), "{err}");
    }
}
