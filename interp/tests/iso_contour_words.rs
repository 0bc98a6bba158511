//! TNC ISO G43/G44 (paraxial compensation) and G26/G27 (tangential approach and departure)
//! against their Klartext twins (R+/R-, RND after the first and before the last compensated
//! element), with the geometry checked against hand-computed values.

mod common;
use common::*;
use klar_interp::{Interpreter, OpKind, Pose};

fn kinds(name: &str, text: &str) -> Vec<OpKind> {
    Interpreter::from_source(name, text, Pose::ZERO)
        .map(|r| r.unwrap_or_else(|d| panic!("{d}")).kind)
        .collect()
}

fn assert_twins(klartext: &str, iso: &str) -> Vec<OpKind> {
    let k = kinds("twin.h", klartext);
    let i = kinds("twin.i", iso);
    assert!(k.len() > 2, "the Klartext twin produced too few ops: {k:?}");
    for (n, (a, b)) in k.iter().zip(&i).enumerate() {
        assert_eq!(a, b, "op {n} differs");
    }
    assert_eq!(k.len(), i.len(), "op counts differ");
    i
}

/// End points (X, Y) of the line and arc ops, in order.
fn ends(ops: &[OpKind]) -> Vec<(f64, f64)> {
    ops.iter()
        .filter_map(|k| match k {
            OpKind::Line { to, .. } | OpKind::Arc { to, .. } => Some((to.0[0], to.0[1])),
            _ => None,
        })
        .collect()
}

#[test]
fn g43_lengthens_and_g44_shortens_by_the_tool_radius() {
    let k = program(
        "TOOL DEF 1 L+50 R+4\n\
         TOOL CALL 1 Z S1000\n\
         L X+0 Y+0 Z-5 R0 F300 M3\n\
         L X+30 R+ F200\n\
         L Y+20 R-\n\
         L Z+50 R0 FMAX M30",
    );
    let i = "%PARAX G71 *\n\
             N10 G99 T1 L+50 R+4 *\n\
             N20 T1 G17 S1000 *\n\
             N30 G01 G40 X+0 Y+0 Z-5 F300 M03 *\n\
             N40 G43 X+30 F200 *\n\
             N50 G44 Y+20 *\n\
             N60 G00 Z+50 M30 *\n\
             N99999999 %PARAX G71 *\n";
    let ops = assert_twins(&k, i);
    let e = ends(&ops);
    // X+30 lengthened by R4 to 34; Y+20 shortened by R4 to 16 (X stays at 34)
    assert!(e.contains(&(34.0, 0.0)), "{e:?}");
    assert!(e.contains(&(34.0, 16.0)), "{e:?}");
}

#[test]
fn g26_and_g27_round_into_and_out_of_the_compensated_contour() {
    let k = program(
        "TOOL DEF 1 L+50 R+3\n\
         TOOL CALL 1 Z S1000\n\
         L X+0 Y-20 Z-5 R0 F300 M3\n\
         L X+0 Y+0 RL\n\
         RND R5\n\
         L X+40 Y+0\n\
         RND R5\n\
         L X+40 Y-20 R0\n\
         L Z+50 FMAX M30",
    );
    let i = "%TANG G71 *\n\
             N10 G99 T1 L+50 R+3 *\n\
             N20 T1 G17 S1000 *\n\
             N30 G01 G40 X+0 Y-20 Z-5 F300 M03 *\n\
             N40 G41 X+0 Y+0 * ; first contour point\n\
             N50 G26 R5 * ; tangential approach\n\
             N60 X+40 Y+0 * ; last contour element\n\
             N70 G27 R5 * ; tangential departure\n\
             N80 G40 X+40 Y-20 *\n\
             N90 G00 Z+50 M30 *\n\
             N99999999 %TANG G71 *\n";
    let ops = assert_twins(&k, i);
    let arcs: Vec<_> = ops
        .iter()
        .filter_map(|k| match k {
            OpKind::Arc {
                from, to, center, ..
            } => Some((
                (from.0[0], from.0[1]),
                (to.0[0], to.0[1]),
                (center[0], center[1]),
            )),
            _ => None,
        })
        .collect();
    // approach: +Y into +X, R5 corner at (0,0): from (0,-5) to (5,0) about (5,-5);
    // departure: +X into -Y, R5 corner at (40,0): from (35,0) to (40,-5) about (35,-5)
    assert_eq!(arcs.len(), 2, "{ops:?}");
    let want = [
        ((0.0, -5.0), (5.0, 0.0), (5.0, -5.0)),
        ((35.0, 0.0), (40.0, -5.0), (35.0, -5.0)),
    ];
    for (got, want) in arcs.iter().zip(want) {
        close(got.0.0, want.0.0);
        close(got.0.1, want.0.1);
        close(got.1.0, want.1.0);
        close(got.1.1, want.1.1);
        close(got.2.0, want.2.0);
        close(got.2.1, want.2.1);
    }
}

#[test]
fn g43_with_a_diagonal_move_is_an_error_at_its_block() {
    let text = "%P G71 *\n\
                N10 G99 T1 L+50 R+4 *\n\
                N20 T1 G17 S1000 *\n\
                N30 G01 X+0 Y+0 F300 *\n\
                N40 G43 X+10 Y+10 *\n\
                N99999999 %P G71 *\n";
    let mut it = Interpreter::from_source("p.i", text, Pose::ZERO);
    let d = it
        .find_map(Result::err)
        .expect("a diagonal G43 move is refused");
    assert_eq!(d.line, 5, "{d}");
    assert!(d.to_string().starts_with("p.i:5:"), "{d}");
}
