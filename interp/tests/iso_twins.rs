//! TNC ISO programs against hand-translated Klartext twins: both must yield the same ops.
//!
//! The Klartext interpreter is the independent peer here: its blocks are parsed and executed
//! by the Klartext front end, the ISO ones by the ISO block parser and G-code mapping. Op
//! kinds are compared exactly (source locations differ by design).

mod common;
use common::*;
use klar_interp::{Interpreter, OpKind, Pose};
use std::path::PathBuf;

fn kinds(name: &str, text: &str) -> Vec<OpKind> {
    Interpreter::from_source(name, text, Pose::ZERO)
        .map(|r| r.unwrap_or_else(|d| panic!("{d}")).kind)
        .collect()
}

fn assert_twins(klartext: &str, iso: &str) {
    let k = kinds("twin.h", klartext);
    let i = kinds("twin.i", iso);
    assert!(k.len() > 2, "the Klartext twin produced too few ops: {k:?}");
    for (n, (a, b)) in k.iter().zip(&i).enumerate() {
        assert_eq!(a, b, "op {n} differs");
    }
    assert_eq!(k.len(), i.len(), "op counts differ");
}

fn program_file(rel: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("programs")
        .join(rel);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn rectangle_example_matches_its_klartext_twin() {
    assert_twins(
        &program_file("rectangle.h"),
        &program_file("iso/rectangle.i"),
    );
}

#[test]
fn helix_example_matches_its_klartext_twin() {
    assert_twins(
        &program_file("helix_thread.h"),
        &program_file("iso/helix_thread.i"),
    );
}

#[test]
fn arcs_with_modal_pole_radius_and_direction_words() {
    let k = program(
        "TOOL CALL 3 Z S1000\n\
         L X+10 Y+0 Z-2 R0 F250 M3\n\
         CC X+0 Y+0\n\
         C X+0 Y+10 DR+\n\
         C X-10 Y+0 DR+\n\
         CR X+0 Y-10 R+10 DR+\n\
         CR X+10 Y+0 R-10 DR-\n\
         CC X+10 Y+10\n\
         C DR-\n\
         L X+30 RL F400\n\
         CT X+40 Y+20\n\
         L X+50 R0 FMAX M5",
    );
    let i = "%ARCS G71 *\n\
             N10 T3 G17 S1000 *\n\
             N20 G01 G40 X+10 Y+0 Z-2 F250 M03 *\n\
             N30 I+0 J+0 *\n\
             N40 G03 X+0 Y+10 *\n\
             N50 G05 X-10 Y+0 *\n\
             N60 G03 X+0 Y-10 R+10 *\n\
             N70 G02 X+10 Y+0 R-10 *\n\
             N80 G02 I+10 J+10 *\n\
             N85 G02 *\n\
             N90 G01 G41 X+30 F400 *\n\
             N100 G06 X+40 Y+20 *\n\
             N110 G00 G40 X+50 M05 *\n\
             N120 M30 *\n\
             N99999999 %ARCS G71 *\n";
    // the Klartext twin ends with END PGM; ISO with M30 then the closing block
    let k = k.replace("END PGM T MM", "M30\nEND PGM T MM");
    assert_twins(&k, i);
}

#[test]
fn polar_lines_and_arcs_absolute_and_incremental() {
    let k = program(
        "TOOL CALL 1 Z S500\n\
         CC X+50 Y+50\n\
         LP PR+20 PA+0 FMAX\n\
         LP PR+20 PA+30 F200\n\
         CP PA+90 DR+\n\
         CP IPA-45 DR-\n\
         LP IPR+5 IPA+10\n\
         CC\n\
         L IX+5 IY-5\n\
         L X+0 Y+0 FMAX\n\
         M30",
    );
    let i = "%POLAR G71 *\n\
             N10 T1 G17 S500 *\n\
             N20 I+50 J+50 *\n\
             N30 G10 R+20 H+0 *\n\
             N40 G11 R+20 H+30 F200 *\n\
             N50 G13 H+90 *\n\
             N60 G91 *\n\
             N70 G12 H-45 *\n\
             N80 G11 R+5 H+10 *\n\
             N90 G29 *\n\
             N100 G01 X+5 Y-5 *\n\
             N110 G90 G00 X+0 Y+0 *\n\
             N120 M30 *\n\
             N99999999 %POLAR G71 *\n";
    assert_twins(&k, i);
}

#[test]
fn q_formulas_and_d_functions_drive_coordinates() {
    let k = program(
        "Q1 = 10\n\
         Q2 = Q1 * 3 + 2\n\
         FN 1: Q3 = +Q1 + +Q2\n\
         FN 4: Q4 = +Q3 DIV +4\n\
         FN 6: Q5 = SIN +30\n\
         FN 8: Q6 = +3 LEN +4\n\
         FN 13: Q7 = +1 ANG +1\n\
         TOOL CALL Q1 Z S+Q2\n\
         L X+Q3 Y-Q4 Z+Q5 F+Q2\n\
         L X+Q6 Y+Q7\n\
         M30",
    );
    let i = "%QPARAM G71 *\n\
             N10 Q1 = 10 *\n\
             N20 Q2 = Q1 * 3 + 2 *\n\
             N30 D01 Q3 P01 +Q1 P02 +Q2 *\n\
             N40 D04 Q4 P01 +Q3 P02 +4 *\n\
             N50 D06 Q5 P01 +30 *\n\
             N60 D08 Q6 P01 +3 P02 +4 *\n\
             N70 D13 Q7 P01 +1 P02 +1 *\n\
             N80 TQ1 G17 SQ2 *\n\
             N90 G01 X+Q3 Y-Q4 Z+Q5 FQ2 *\n\
             N100 X+Q6 Y+Q7 *\n\
             N110 M30 *\n\
             N99999999 %QPARAM G71 *\n";
    assert_twins(&k, i);
    // and the values are the closed forms: Q3 = 10 + 32, Q4 = 42 / 4, sin 30° = 0.5
    let ops = kinds("q.i", i);
    let first = ops
        .iter()
        .find_map(|k| match k {
            OpKind::Line { to, .. } => Some(*to),
            _ => None,
        })
        .expect("a line");
    close(first.0[0], 42.0);
    close(first.0[1], -10.5);
    close(first.0[2], 0.5);
}

#[test]
fn subprogram_calls_and_section_repeats_unrolled() {
    // A square of 10 mm side drawn by a subprogram called twice at two depths, and a
    // section repeated twice more (three runs): the Klartext twin is written out in full.
    let i = "%SUB G71 *\n\
             N10 T1 G17 S1000 *\n\
             N20 G00 X+0 Y+0 Z+2 *\n\
             N30 G01 Z-1 F100 *\n\
             N40 L1,0 *\n\
             N50 G01 Z-2 *\n\
             N60 L1,0 *\n\
             N70 G98 L2 *\n\
             N80 G91 G01 X+1 *\n\
             N90 G90 *\n\
             N100 L2,2 *\n\
             N110 G00 Z+50 M30 *\n\
             N120 G98 L1 *\n\
             N130 G91 G01 X+10 *\n\
             N140 Y+10 *\n\
             N150 X-10 *\n\
             N160 Y-10 *\n\
             N170 G90 *\n\
             N180 G98 L0 *\n\
             N99999999 %SUB G71 *\n";
    let square = "L IX+10\nL IY+10\nL IX-10\nL IY-10\n";
    let k = program(&format!(
        "TOOL CALL 1 Z S1000\nL X+0 Y+0 Z+2 FMAX\nL Z-1 F100\n{square}L Z-2\n{square}\
         L IX+1\nL IX+1\nL IX+1\nL Z+50 FMAX M30"
    ));
    assert_twins(&k, i);
}

#[test]
fn conditional_jump_loops_until_the_condition_fails() {
    // D12: jump to label 1 while Q1 < 3; Q1 counts the passes
    let i = "%LOOP G71 *\n\
             N10 T1 G17 S1000 *\n\
             N20 Q1 = 0 *\n\
             N30 G98 L1 *\n\
             N40 Q1 = Q1 + 1 *\n\
             N50 G01 X+Q1 F100 *\n\
             N60 D12 P01 +Q1 P02 +3 P03 1 *\n\
             N70 M30 *\n\
             N99999999 %LOOP G71 *\n";
    let k = program("TOOL CALL 1 Z S1000\nL X+1 F100\nL X+2\nL X+3\nM30");
    assert_twins(&k, i);
}

#[test]
fn inch_programs_scale_like_klartext() {
    let k = "BEGIN PGM IN INCH\nTOOL CALL 1 Z S100\nL X+1 Y+2 F10\nCC X+0 Y+0\nC X-2 Y+1 DR+\nM30\nEND PGM IN INCH\n";
    let i = "%IN G70 *\nN10 T1 G17 S100 *\nN20 G01 X+1 Y+2 F10 *\nN30 G03 X-2 Y+1 I+0 J+0 *\nN40 M30 *\nN50 %IN G70 *\n";
    assert_twins(k, i);
    let first = kinds("in.i", i)
        .into_iter()
        .find_map(|k| match k {
            OpKind::Line { to, feed, .. } => Some((to, feed)),
            _ => None,
        })
        .expect("a line");
    close(first.0.0[0], 25.4);
    close(first.0.0[1], 50.8);
}

#[test]
fn tool_block_with_m_words_and_fauto() {
    let k = program("TOOL CALL 2 Z S800 F150\nM3\nL X+5 FAUTO\nL Y+5 F300\nM30");
    let i = "%T G71 *\nN10 T2 G17 S800 F150 M03 *\nN20 G01 X+5 F150 *\nN30 Y+5 F300 *\n\
             N40 M30 *\nN50 %T G71 *\n";
    assert_twins(&k, i);
}

#[test]
fn chamfer_rounding_and_tangential_polar_arc() {
    let k = program(
        "TOOL CALL 1 Z S1000\n\
         L X+0 Y+0 Z-1 R0 F200\n\
         L X+40\n\
         RND R5\n\
         L Y+30\n\
         CHF 4\n\
         L X+0\n\
         CC X+0 Y+0\n\
         CTP PR+20 PA+180\n\
         L Z+10 FMAX\n\
         M30",
    );
    let i = "%CORNERS G71 *\n\
             N10 T1 G17 S1000 *\n\
             N20 G01 G40 X+0 Y+0 Z-1 F200 *\n\
             N30 X+40 *\n\
             N40 G25 R5 *\n\
             N50 Y+30 *\n\
             N60 G24 R4 *\n\
             N70 X+0 *\n\
             N80 I+0 J+0 *\n\
             N90 G16 R+20 H+180 *\n\
             N100 G00 Z+10 *\n\
             N110 M30 *\n\
             N120 %CORNERS G71 *\n";
    assert_twins(&k, i);
    // the rounding replaced the corner (40, 0): an arc of radius 5 is among the ops
    let rounded = kinds("c.i", i).iter().any(|k| {
        matches!(k, OpKind::Arc { center, .. } if (center[0] - 35.0).abs() < 1e-9 && (center[1] - 5.0).abs() < 1e-9)
    });
    assert!(rounded);
}

#[test]
fn tool_definition_g99_is_tool_def() {
    let k = program("TOOL DEF 5 L+40 R+3\nTOOL CALL 5 Z S900 DR-0.5\nL X+10 R0 F100\nM30");
    let i = "%TD G71 *\nN10 G99 T5 L+40 R+3 *\nN20 T5 G17 S900 DR-0.5 *\n\
             N30 G01 G40 X+10 F100 *\nN40 M30 *\nN50 %TD G71 *\n";
    assert_twins(&k, i);
    // length 40, radius 3 − 0.5
    let tool = kinds("td.i", i).into_iter().find_map(|k| match k {
        OpKind::ToolChange { length, radius, .. } => Some((length, radius)),
        _ => None,
    });
    assert_eq!(tool, Some((40.0, 2.5)));
}
