//! TNC ISO transformations (G54, G53, G28, G73, G72, G62, G80), cycle definitions (`G2nn`
//! with `Q…=` lines) and cycle calls (G79, M99, M89) against their Klartext twins, plus the
//! errors they report.

mod common;
use common::*;
use klar_interp::{Interpreter, OpKind, Pose};
use std::path::PathBuf;

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

fn program_file(rel: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("programs")
        .join(rel);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// End points (X, Y, Z) of the line and arc ops, in order.
fn ends(ops: &[OpKind]) -> Vec<[f64; 3]> {
    ops.iter()
        .filter_map(|k| match k {
            OpKind::Line { to, .. } | OpKind::Arc { to, .. } => Some([to.0[0], to.0[1], to.0[2]]),
            _ => None,
        })
        .collect()
}

fn has_end(e: &[[f64; 3]], want: [f64; 3]) -> bool {
    e.iter()
        .any(|p| p.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-9))
}

#[test]
fn transforms_example_matches_its_klartext_twin() {
    let ops = assert_twins(
        &program_file("cycle_transforms.h"),
        &program_file("iso/cycle_transforms.i"),
    );
    let e = ends(&ops);
    // the contour corner (X+25, Y+15, Z-2) of label 1 in machine coordinates, by hand:
    // plain; shifted by X+25 → (50, 15); mirrored in X about the shifted datum:
    // 25 - 25 = 0 → (0, 15); halved (12.5, 7.5, -1), turned by 90° (x, y → -y, x)
    // → (-7.5, 12.5), shifted → (17.5, 12.5, -1)
    for want in [
        [25.0, 15.0, -2.0],
        [50.0, 15.0, -2.0],
        [0.0, 15.0, -2.0],
        [17.5, 12.5, -1.0],
    ] {
        assert!(has_end(&e, want), "no move ends at {want:?}: {e:?}");
    }
}

#[test]
fn incremental_shift_and_rotation_add_to_the_active_ones() {
    let k = program(
        "TOOL CALL 1 Z S1000\n\
         L X+0 Y+0 Z+5 R0 FMAX M3\n\
         CYCL DEF 7.0 DATUM SHIFT\n\
         CYCL DEF 7.1 X+10\n\
         CYCL DEF 7.0 DATUM SHIFT\n\
         CYCL DEF 7.1 IX+5 IY+2\n\
         CYCL DEF 10.0 ROTATION\n\
         CYCL DEF 10.1 ROT+30\n\
         CYCL DEF 10.0 ROTATION\n\
         CYCL DEF 10.1 IROT+15\n\
         L X+10 Y+0 F200\n\
         L Z+50 FMAX M30",
    );
    let i = "%INC G71 *\n\
             N10 T1 G17 S1000 *\n\
             N20 G00 G40 X+0 Y+0 Z+5 M03 *\n\
             N30 G54 X+10 *\n\
             N40 G91 G54 X+5 Y+2 *\n\
             N50 G90 G73 H+30 *\n\
             N60 G91 G73 H+15 *\n\
             N70 G90 G01 X+10 Y+0 F200 *\n\
             N80 G00 Z+50 M30 *\n\
             N99999999 %INC G71 *\n";
    let ops = assert_twins(&k, i);
    // (10, 0) turned by 45° → (7.0711, 7.0711), shifted by (15, 2)
    let h = 10.0 * std::f64::consts::FRAC_1_SQRT_2;
    assert!(
        has_end(&ends(&ops), [15.0 + h, 2.0 + h, 5.0]),
        "{:?}",
        ends(&ops)
    );
}

fn first_error(text: &str) -> klar_interp::Diagnostic {
    Interpreter::from_source("e.i", text, Pose::ZERO)
        .find_map(Result::err)
        .expect("a diagnostic")
}

#[test]
fn transformation_errors_are_located() {
    let d = first_error("%E G71 *\nN10 G73 X+5 *\nN99999999 %E G71 *\n");
    assert!(d.to_string().starts_with("e.i:2:9:"), "{d}");
    assert!(d.message.contains("rotation"), "{d}");
    let d = first_error("%E G71 *\nN10 G72 *\nN99999999 %E G71 *\n");
    assert!(d.to_string().starts_with("e.i:2:5:"), "{d}");
    assert!(d.message.contains("scaling factor F"), "{d}");
    let d = first_error("%E G71 *\nN10 G72 F0 *\nN99999999 %E G71 *\n");
    assert!(d.to_string().starts_with("e.i:2:9:"), "{d}");
    // no datum table: row 3 cannot be found
    let d = first_error("%E G71 *\nN10 G53 P01 3 *\nN99999999 %E G71 *\n");
    assert!(d.to_string().starts_with("e.i:2:9:"), "{d}");
    // the tool axis cannot be mirrored
    let d = first_error("%E G71 *\nN10 T1 G17 S100 *\nN20 G28 Z *\nN99999999 %E G71 *\n");
    assert!(d.to_string().starts_with("e.i:3:9:"), "{d}");
}

#[test]
fn g80_is_cycle_19() {
    let k = program(
        "TOOL CALL 1 Z S1000\n\
         L X+0 Y+0 Z+5 R0 FMAX M3\n\
         CYCL DEF 19.0 WORKING PLANE\n\
         CYCL DEF 19.1 B+30\n\
         L X+10 Y+0 F200\n\
         L Z+50 FMAX M30",
    );
    let i = "%TILT G71 *\n\
             N10 T1 G17 S1000 *\n\
             N20 G00 G40 X+0 Y+0 Z+5 M03 *\n\
             N30 G80 B+30 *\n\
             N40 G01 X+10 Y+0 F200 *\n\
             N50 G00 Z+50 M30 *\n\
             N99999999 %TILT G71 *\n";
    let run = |name: &str, text: &str| -> Vec<Result<OpKind, String>> {
        Interpreter::from_source(name, text, Pose::ZERO)
            .map(|r| r.map(|o| o.kind).map_err(|d| d.message))
            .collect()
    };
    let (a, b) = (run("k.h", &k), run("i.i", i));
    assert!(a.len() > 3, "{a:?}");
    assert_eq!(a, b);
}

/// programs/cycle_drilling.h without its PATTERN DEF block and the CYCL CALL PAT after it
/// (the ISO twin has no point-pattern definition).
fn drilling_without_pattern() -> String {
    let full = program_file("cycle_drilling.h");
    let mut kept = Vec::new();
    let mut skipping = false;
    let mut dropped = 0;
    for line in full.lines() {
        let t = line.trim_start();
        if t.starts_with("9  PATTERN DEF") || t.starts_with("10 CYCL CALL PAT") {
            skipping = true;
        }
        if skipping {
            dropped += 1;
            skipping = line.trim_end().ends_with('~');
            continue;
        }
        kept.push(line);
    }
    assert_eq!(
        dropped, 4,
        "the PATTERN DEF part of cycle_drilling.h changed"
    );
    kept.join("\n")
}

#[test]
fn drilling_example_matches_its_klartext_twin() {
    let ops = assert_twins(
        &drilling_without_pattern(),
        &program_file("iso/cycle_drilling.i"),
    );
    let e = ends(&ops);
    // cycle 200 drills to Q203 + Q201 = -10 at (10, 10) (M99) and (30, 10) (G79), and
    // the pattern 221 at 3 × 2 points from (10, 80) spaced 10 in X and 8 in Y
    let mut holes = vec![[10.0, 10.0], [30.0, 10.0]];
    for row in 0..2 {
        for col in 0..3 {
            holes.push([10.0 + 10.0 * f64::from(col), 80.0 + 8.0 * f64::from(row)]);
        }
    }
    for h in &holes {
        assert!(has_end(&e, [h[0], h[1], -10.0]), "no hole at {h:?}: {e:?}");
    }
    let deepest = e.iter().filter(|p| (p[2] + 10.0).abs() < 1e-9).count();
    assert_eq!(deepest, holes.len(), "{e:?}");
}

#[test]
fn m89_calls_after_every_positioning_block_and_formulas_still_assign() {
    let k = program(
        "TOOL CALL 1 Z S2000 F100\n\
         L Z+10 R0 FMAX M3\n\
         CYCL DEF 200 DRILLING ~\n\
         Q200=+2 ;SET-UP ~\n\
         Q201=-Q5 ;DEPTH ~\n\
         Q206=AUTO ;FEED ~\n\
         Q202=+4 ;PLUNGE ~\n\
         Q210=+0 ~\n\
         Q203=+0 ~\n\
         Q204=+10 ~\n\
         Q211=+0\n\
         Q1 = Q201 + 1\n\
         L X+5 Y+5 FMAX M89\n\
         L X+15 Y+5 FMAX\n\
         L X+15 Y+5 Z+Q1 FMAX M99\n\
         L Z+50 FMAX M30",
    );
    let i = "%M89 G71 *\n\
             N10 T1 G17 S2000 F100 *\n\
             N20 G00 G40 Z+10 M03 *\n\
             N30 G200 DRILLING\n\
             Q200=+2 ;SET-UP\n\
             Q201=-Q5 ;DEPTH\n\
             Q206=AUTO ;FEED\n\
             Q202=+4 ;PLUNGE\n\
             Q210=+0\n\
             Q203=+0\n\
             Q204=+10\n\
             Q211=+0\n\
             N40 Q1 = Q201 + 1 *\n\
             N50 G00 X+5 Y+5 M89 *\n\
             N60 X+15 Y+5 *\n\
             N70 X+15 Y+5 Z+Q1 M99 *\n\
             N80 G00 Z+50 M30 *\n\
             N99999999 %M89 G71 *\n";
    // Q5 is 0 (depth 0 is refused) unless set first: give it a value in both programs
    let k = k.replace("TOOL CALL 1", "Q5 = 6\nTOOL CALL 1");
    let i = i.replace("N10 T1", "N5 Q5 = 6 *\nN10 T1");
    let ops = assert_twins(&k, &i);
    let e = ends(&ops);
    // Q201 = -6: holes at (5, 5) and (15, 5) down to Z-6; Q1 = -5 is the Z of the last
    // positioning block, which runs the cycle once more (M99 ends M89)
    assert!(has_end(&e, [5.0, 5.0, -6.0]), "{e:?}");
    assert!(has_end(&e, [15.0, 5.0, -6.0]), "{e:?}");
    assert!(has_end(&e, [15.0, 5.0, -5.0]), "{e:?}");
}

#[test]
fn cycle_errors_are_located() {
    // G79 before any cycle definition
    let d = first_error("%E G71 *\nN10 G00 X+0 *\nN20 G79 *\nN99999999 %E G71 *\n");
    assert!(d.to_string().starts_with("e.i:3:"), "{d}");
    assert!(d.message.contains("cycle"), "{d}");
    // an unknown cycle number
    let d = first_error("%E G71 *\nN10 G299 NOTHING Q200=1 *\nN99999999 %E G71 *\n");
    assert!(d.to_string().starts_with("e.i:2:"), "{d}");
    // a missing value in a parameter line
    let d = first_error("%E G71 *\nN10 G200 DRILLING\n Q200=\n Q201=-5 *\nN99999999 %E G71 *\n");
    assert!(d.to_string().starts_with("e.i:3:"), "{d}");
    // an unknown G code keeps its word position
    let d = first_error("%E G71 *\nN10 G01 X+0 G66 *\nN99999999 %E G71 *\n");
    assert!(d.to_string().starts_with("e.i:2:13:"), "{d}");
    // G79 takes only M words
    let d = first_error("%E G71 *\nN10 G79 X+5 *\nN99999999 %E G71 *\n");
    assert!(d.to_string().starts_with("e.i:2:9:"), "{d}");
}

#[test]
fn old_pecking_g83_and_tapping_g84_are_cycles_1_and_2() {
    let k = program(
        "TOOL CALL 1 Z S1000\n\
         L Z+20 R0 FMAX M3\n\
         CYCL DEF 1.0 PECKING\n\
         CYCL DEF 1.1 SET UP 2\n\
         CYCL DEF 1.2 DEPTH -15\n\
         CYCL DEF 1.3 PECKG 5\n\
         CYCL DEF 1.4 DWELL 0.5\n\
         CYCL DEF 1.5 F150\n\
         L X+10 Y+10 Z+2 FMAX M99\n\
         CYCL DEF 2.0 TAPPING\n\
         CYCL DEF 2.1 SET UP 2\n\
         CYCL DEF 2.2 DEPTH -10\n\
         CYCL DEF 2.3 DWELL 0\n\
         CYCL DEF 2.4 F100\n\
         L X+30 Y+10 Z+2 FMAX M99\n\
         L Z+50 FMAX M30",
    );
    let i = "%OLD G71 *\n\
             N10 T1 G17 S1000 *\n\
             N20 G00 G40 Z+20 M03 *\n\
             N30 G83 P01 2 P02 -15 P03 5 P04 0.5 P05 150 *\n\
             N40 G00 X+10 Y+10 Z+2 M99 *\n\
             N50 G84 P01 2 P02 -10 P04 100 P03 0 *\n\
             N60 X+30 Y+10 Z+2 M99 *\n\
             N70 G00 Z+50 M30 *\n\
             N99999999 %OLD G71 *\n";
    let ops = assert_twins(&k, i);
    let e = ends(&ops);
    // the tool starts at the set-up clearance (Z+2) above the surface Z 0, so the hole
    // bottoms are at the total depths -15 and -10; pecking plunges 5 mm at a time
    assert!(has_end(&e, [10.0, 10.0, -15.0]), "{e:?}");
    assert!(has_end(&e, [10.0, 10.0, -5.0]), "{e:?}");
    assert!(has_end(&e, [30.0, 10.0, -10.0]), "{e:?}");
    let d = first_error("%E G71 *\nN10 G83 P01 2 P06 5 *\nN99999999 %E G71 *\n");
    assert!(d.to_string().starts_with("e.i:2:15:"), "{d}");
}
