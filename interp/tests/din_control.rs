//! Lathe DIN PLUS variables, control structures and subprograms: each program against the
//! op stream of a hand-unrolled program without them, and against positions worked out by
//! hand; bad structures give located diagnostics.

mod common;
use common::lathe::{line_ends, program_file, run_nc as run, until_error};
use klar_interp::op::{SpindleDir, SpindleId, SpindleSpeed};
use klar_interp::{AxisLetter, Diagnostic, Feed, Op, OpKind, Pose};
use std::path::PathBuf;

fn kinds(ops: &[Op]) -> Vec<OpKind> {
    ops.iter().map(|o| o.kind.clone()).collect()
}

/// Every diagnostic of a whole-program check.
fn check(text: &str) -> Vec<Diagnostic> {
    let dir = std::env::temp_dir().join(format!("klar-din-control-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let n = CHECKS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let path = dir.join(format!("c{n}.nc"));
    std::fs::write(&path, text).unwrap();
    let d = klar_interp::check(&path, Pose::ZERO);
    let _ = std::fs::remove_file(&path);
    d
}

static CHECKS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

#[test]
fn speed_words_and_m3_give_one_spindle_op_in_either_order() {
    let a = run("MACHINING\nN10 G96 S200 M3\nN11 G0 X20 Z2\nEND\n");
    let b = run("MACHINING\nN10 M3 G96 S200\nN11 G0 X20 Z2\nEND\n");
    assert_eq!(kinds(&a), kinds(&b));
    let spindle: Vec<&OpKind> = a
        .iter()
        .map(|o| &o.kind)
        .filter(|k| matches!(k, OpKind::Spindle { dir, .. } if *dir != SpindleDir::Off))
        .collect();
    assert_eq!(
        spindle,
        [&OpKind::Spindle {
            spindle: SpindleId::Main,
            dir: SpindleDir::Cw,
            speed: SpindleSpeed::SurfaceSpeed(200.0)
        }]
    );
    // the spindle runs before the block's motion
    let first_motion = a.iter().position(|o| o.kind.is_motion()).unwrap();
    let first_spindle = a
        .iter()
        .position(|o| matches!(o.kind, OpKind::Spindle { .. }));
    assert!(first_spindle.unwrap() < first_motion);
    // driven tool: M104 with G197 in one block, before or after: one op at 1200 rpm
    let c = run("MACHINING\nN1 M104 G197 S1200\nN2 G197 S1500 M104\nEND\n");
    let driven: Vec<&OpKind> = c
        .iter()
        .map(|o| &o.kind)
        .filter(|k| matches!(k, OpKind::Spindle { spindle: SpindleId::Driven, dir, .. } if *dir != SpindleDir::Off))
        .collect();
    assert_eq!(driven.len(), 2, "{driven:?}");
    assert!(matches!(
        driven[0],
        OpKind::Spindle { speed: SpindleSpeed::Rpm(s), .. } if *s == 1200.0
    ));
    assert!(matches!(
        driven[1],
        OpKind::Spindle { speed: SpindleSpeed::Rpm(s), .. } if *s == 1500.0
    ));
}

/// The example program written out without variables or structures: 5 passes at diameters
/// 56, 52, 48, 44, 40 (the loop stops at 36 < 40), the IF branch (36 + 4 = 40), grooves at
/// Z-8, -16, -24 with diameters 36, 34, 38 (CASE 1, CASE 2, DEFAULT).
const UNROLLED: &str = "MACHINING
N1 T1
N2 G96 S180 G95 F0.25 M4
N6 G0 X60 Z2
N8 G0 X56
N9 G1 Z-30
N10 G0 Xi2 Z2
N8 G0 X52
N9 G1 Z-30
N10 G0 Xi2 Z2
N8 G0 X48
N9 G1 Z-30
N10 G0 Xi2 Z2
N8 G0 X44
N9 G1 Z-30
N10 G0 Xi2 Z2
N8 G0 X40
N9 G1 Z-30
N10 G0 Xi2 Z2
N14 G0 X38 Z1
N15 G1 X40 Z0
N19 G0 X62 Z2
N20 T2
N21 G97 S800 G95 F0.05 M3
N35 G0 X42 Z-8
N36 G1 X36
N37 G0 X42
N35 G0 X42 Z-16
N36 G1 X34
N37 G0 X42
N35 G0 X42 Z-24
N36 G1 X38
N37 G0 X42
N39 G14 Q0
N40 M30
END
";

#[test]
fn structured_program_equals_its_unrolled_version() {
    let ops = run(&program_file("lathe/variables_loops.nc"));
    assert_eq!(kinds(&ops), kinds(&run(UNROLLED)));
    // the roughing passes: five feed moves to Z-30 at radii 28, 26, 24, 22, 20
    let passes: Vec<f64> = line_ends(&ops)
        .iter()
        .filter(|(p, f)| *f != Feed::Rapid && (p[AxisLetter::Z] + 30.0).abs() < 1e-12)
        .map(|(p, _)| p[AxisLetter::X])
        .collect();
    assert_eq!(passes, [28.0, 26.0, 24.0, 22.0, 20.0]);
}

#[test]
fn if_else_picks_one_branch_and_nests() {
    let prog = |g: i32| {
        format!(
            "MACHINING\nN1 #g1 = {g}\nN2 G0 X10 Z5\nN3 IF #g1 > 0\nN4 THEN\n\
             N5 IF #g1 > 5\nN6 G0 X100\nN7 ELSE\nN8 G0 X50\nN9 ENDIF\n\
             N10 ELSE\nN11 IF #g1 < -5\nN12 G0 Z-100\nN13 ENDIF\nN14 G0 Z-50\nN15 ENDIF\n\
             N16 G0 X2\nEND\n"
        )
    };
    let xs = |g| -> Vec<(f64, f64)> {
        line_ends(&run(&prog(g)))
            .iter()
            .map(|(p, _)| (p[AxisLetter::X], p[AxisLetter::Z]))
            .collect()
    };
    assert_eq!(xs(9), [(5.0, 5.0), (50.0, 5.0), (1.0, 5.0)]);
    assert_eq!(xs(1), [(5.0, 5.0), (25.0, 5.0), (1.0, 5.0)]);
    assert_eq!(xs(-1), [(5.0, 5.0), (5.0, -50.0), (1.0, -50.0)]);
    assert_eq!(
        xs(-9),
        [(5.0, 5.0), (5.0, -100.0), (5.0, -50.0), (1.0, -50.0)]
    );
}

#[test]
fn nested_loops_run_the_product_of_their_counts() {
    // 3 × 4 passes: X steps 2 mm (diameter) per inner pass, Z 1 mm per outer pass
    let text = "MACHINING\nN1 #l1 = 0\nN2 WHILE #l1 < 3\nN3 #l2 = 0\nN4 REPEAT\n\
                N5 G0 X(2 * #l2 + 2) Z(-#l1)\nN6 #l2 = #l2 + 1\nN7 UNTIL #l2 == 4\n\
                N8 #l1 = #l1 + 1\nN9 ENDWHILE\nN10 G0 X0 Z0\nEND\n";
    let ends = line_ends(&run(text));
    assert_eq!(ends.len(), 13);
    for (k, (p, _)) in ends.iter().take(12).enumerate() {
        let (outer, inner) = (k / 4, k % 4);
        assert_eq!(p[AxisLetter::X], inner as f64 + 1.0, "pass {k}");
        assert_eq!(p[AxisLetter::Z], -(outer as f64), "pass {k}");
    }
    // a WHILE whose condition is false at once runs nothing, with nested loops inside
    let none =
        "MACHINING\nN1 WHILE 0\nN2 WHILE 1\nN3 G0 X5\nN4 ENDWHILE\nN5 ENDWHILE\nN6 G0 X8\nEND\n";
    let ends = line_ends(&run(none));
    assert_eq!(ends.len(), 1);
    assert_eq!(ends[0].0[AxisLetter::X], 4.0);
}

#[test]
fn switch_without_match_and_without_default_runs_nothing() {
    let text = "MACHINING\nN1 #c1 = 7\nN2 SWITCH #c1 * 2\nN3 CASE 1, 2\nN4 G0 X1\n\
                N5 CASE 14\nN6 G0 X14\nN7 CASE 15\nN8 G0 X15\nN9 ENDSWITCH\n\
                N10 SWITCH 3\nN11 CASE 4\nN12 G0 X4\nN13 ENDSWITCH\nN14 G0 Z1\nEND\n";
    let ends = line_ends(&run(text));
    let xz: Vec<(f64, f64)> = ends
        .iter()
        .map(|(p, _)| (p[AxisLetter::X], p[AxisLetter::Z]))
        .collect();
    assert_eq!(xz, [(7.0, 0.0), (7.0, 1.0)]);
}

#[test]
fn subprogram_with_transfer_values_and_repeats() {
    let ops = run(&program_file("lathe/subprogram_grooves.nc"));
    let unrolled = "MACHINING\nN1 T2\nN2 G97 S800 G95 F0.05 M3\nN3 G0 X62 Z2\n\
                    N100 G0 X62 Z-10\nN101 G1 X50\nN102 G0 X62\n\
                    N100 G0 X62 Z-18\nN101 G1 X50\nN102 G0 X62\n\
                    N100 G0 X62 Z-26\nN101 G1 X50\nN102 G0 X62\n\
                    N100 G0 X62 Z-34\nN101 G1 X44\nN102 G0 X62\n\
                    N7 G0 X62 Z2\nN8 G14 Q0\nN9 M30\nEND\n";
    assert_eq!(kinds(&ops), kinds(&run(unrolled)));
    // the groove bottoms: radius 25 at Z-10, -18, -26, radius 22 at Z-34
    let bottoms: Vec<(f64, f64)> = line_ends(&ops)
        .iter()
        .filter(|(_, f)| *f != Feed::Rapid)
        .map(|(p, _)| (p[AxisLetter::X], p[AxisLetter::Z]))
        .collect();
    assert_eq!(
        bottoms,
        [(25.0, -10.0), (25.0, -18.0), (25.0, -26.0), (22.0, -34.0)]
    );
}

#[test]
fn subprogram_locals_are_its_own_and_calls_nest() {
    let text = "MACHINING\nN1 #l1 = 10\nN2 L\"outer\" LA3\nN3 G0 X#l1\nN4 M30\nEND\n\
                SUBPROGRAM \"inner\"\nN30 G0 Z#__lb\nRETURN\n\
                SUBPROGRAM \"outer\"\nN20 #l1 = 99\nN21 L\"inner\" LB(#l1 + #__la)\nN22 G0 X#l1\nRETURN\n";
    let xz: Vec<(f64, f64)> = line_ends(&run(text))
        .iter()
        .map(|(p, _)| (p[AxisLetter::X], p[AxisLetter::Z]))
        .collect();
    // inner: Z = 99 + 3; outer: X99 (its own #l1); main: X10 (its #l1 unchanged)
    assert_eq!(xz, [(0.0, 102.0), (49.5, 102.0), (5.0, 102.0)]);
}

#[test]
fn structure_errors_are_located() {
    let (ops, d) = until_error("MACHINING\nN1 G0 X10 Z2\nN2 ENDIF\nEND\n");
    assert_eq!(ops.len(), 1);
    assert_eq!((d.line, d.col, d.block), (3, 4, Some(2)), "{d}");
    assert!(d.message.contains("ENDIF without IF"), "{d}");
    // a WHILE that is never closed: reported at the WHILE when its end is searched for
    let (_, d) = until_error("MACHINING\nN1 WHILE 0\nN2 G0 X1\nEND\n");
    assert_eq!((d.line, d.col), (2, 4), "{d}");
    assert!(d.message.contains("WHILE without ENDWHILE"), "{d}");
    // and when it runs into END
    let (_, d) = until_error("MACHINING\nN1 #l1 = 1\nN2 WHILE #l1 > 5\nN3 G0 X1\nEND\n");
    assert_eq!((d.line, d.col), (3, 4), "{d}");
    let (_, d) = until_error("MACHINING\nN1 REPEAT\nN2 G0 X1\nEND\n");
    assert_eq!((d.line, d.col), (2, 4), "{d}");
    assert!(d.message.contains("REPEAT without UNTIL"), "{d}");
    // an endless loop ends in a diagnostic at its WHILE
    let (_, d) = until_error("MACHINING\nN1 WHILE 1\nN2 #l1 = 1\nN3 ENDWHILE\nEND\n");
    assert_eq!((d.line, d.col), (2, 4), "{d}");
    assert!(d.message.contains("does not end"), "{d}");
    // ELSE, CASE, UNTIL out of place; an unassigned variable; RETURN in the main program
    let (_, d) = until_error("MACHINING\nN1 ELSE\nEND\n");
    assert!(d.message.contains("ELSE without IF"), "{d}");
    let (_, d) = until_error("MACHINING\nN1 CASE 1\nEND\n");
    assert!(d.message.contains("CASE without SWITCH"), "{d}");
    let (_, d) = until_error("MACHINING\nN1 G0 X#l4\nEND\n");
    assert_eq!((d.line, d.col), (2, 7), "{d}");
    assert!(d.message.contains("#l4 has no value"), "{d}");
    let (_, d) = until_error("MACHINING\nN1 RETURN\nEND\n");
    assert!(d.message.contains("RETURN outside"), "{d}");
}

#[test]
fn subprogram_errors_are_located() {
    let (_, d) = until_error("MACHINING\nN1 L\"none\"\nEND\n");
    assert_eq!((d.line, d.col), (2, 4), "{d}");
    assert!(d.message.contains("SUBPROGRAM \"none\""), "{d}");
    let (_, d) = until_error("MACHINING\nN1 L\"a\"\nEND\nSUBPROGRAM \"a\"\nN2 L\"a\"\nRETURN\n");
    assert!(d.message.contains("nested deeper"), "{d}");
    let (_, d) = until_error("MACHINING\nN1 L\"a\"\nEND\nSUBPROGRAM \"a\"\nN2 G0 X1\n");
    assert!(d.message.contains("RETURN is missing"), "{d}");
    let d = check("MACHINING\nN1 M30\nEND\nSUBPROGRAM \"a\"\nRETURN\nSUBPROGRAM \"a\"\nRETURN\n");
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!((d[0].line, d[0].col), (6, 1), "{}", d[0]);
    assert!(
        d[0].message.contains("second SUBPROGRAM \"a\" (line 4)"),
        "{}",
        d[0]
    );
    let (_, d) = until_error("MACHINING\nN1 L\"a\" Q0\nEND\nSUBPROGRAM \"a\"\nRETURN\n");
    assert!(d.message.contains("repeat count"), "{d}");
    let (_, d) = until_error("MACHINING\nN1 L\"a\"\nEND\nSUBPROGRAM \"a\"\nN2 G0 X#__lc\nRETURN\n");
    assert!(d.message.contains("no transfer value LC"), "{d}");
}

#[test]
fn check_reports_structure_errors_in_every_part() {
    // an uncalled subprogram with an open IF, a stray ENDWHILE in the machining part
    let d = check(
        "MACHINING\nN1 G0 X1 Z1\nN2 ENDWHILE\nN3 M30\nEND\n\
         SUBPROGRAM \"x\"\nN10 IF 1\nN11 G0 X2\nRETURN\n",
    );
    assert_eq!(d.len(), 2, "{d:?}");
    assert_eq!((d[0].line, d[0].col), (3, 4), "{}", d[0]);
    assert_eq!((d[1].line, d[1].col), (7, 5), "{}", d[1]);
    // a syntax error in a branch that the check run skips is still reported
    let d = check("MACHINING\nN1 IF 0\nN2 G0 X$\nN3 ENDIF\nN4 G0 X1\nEND\n");
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!((d[0].line, d[0].col, d[0].block), (3, 7, None), "{}", d[0]);
    // an endless loop in a check run stops at the limit
    let d = check("MACHINING\nN1 REPEAT\nN2 G0 X1\nN3 UNTIL 0\nEND\n");
    assert_eq!(d.len(), 1, "{d:?}");
    assert!(d[0].message.contains("does not end"), "{}", d[0]);
}

#[test]
fn every_lathe_example_passes_check_and_syntax_check() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../programs/lathe");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("nc") {
            continue;
        }
        n += 1;
        let d = klar_interp::check(&path, Pose::ZERO);
        assert!(d.is_empty(), "{}: {d:?}", path.display());
        if let Err(d) = klar_interp::syntax_check(&path) {
            panic!("{}: {d:?}", path.display());
        }
    }
    assert!(n >= 8, "{n} programs");
}

#[test]
fn syntax_check_finds_unbalanced_structures_without_running() {
    let path = std::env::temp_dir().join(format!("klar-din-syntax-{}.nc", std::process::id()));
    std::fs::write(
        &path,
        "MACHINING\nN1 WHILE #l1 < 3\nN2 IF 1\nN3 ENDWHILE\nN4 ENDIF\nEND\n",
    )
    .unwrap();
    let d = klar_interp::syntax_check(&path).unwrap_err();
    let _ = std::fs::remove_file(&path);
    // ENDWHILE while the IF is open; at END the WHILE is still open; END itself is read
    assert_eq!(d.len(), 2, "{d:?}");
    assert_eq!((d[0].line, d[0].col), (4, 4), "{d:?}");
    assert!(d[0].message.contains("ENDIF is missing"), "{d:?}");
    assert_eq!((d[1].line, d[1].col), (2, 4), "{d:?}");
    assert!(d[1].message.contains("WHILE without ENDWHILE"), "{d:?}");
}

#[test]
fn repeated_recursive_calls_end_at_the_budget() {
    // each run of "s" calls itself 10000 times over: without a program-wide budget this
    // would not end in any reasonable time
    let text = "MACHINING\nN1 L\"s\"\nEND\nSUBPROGRAM \"s\"\nN2 L\"s\" Q10000\nRETURN\n";
    let d = check(text);
    assert!(!d.is_empty() && d.len() < 10, "{d:?}");
    assert!(
        d.iter()
            .any(|d| d.message.contains("nested deeper") || d.message.contains("does not end")),
        "{d:?}"
    );
    let (_, d) = until_error(
        "MACHINING\nN1 L\"s\" Q10000\nEND\nSUBPROGRAM \"s\"\nN2 L\"t\" Q10000\nRETURN\nSUBPROGRAM \"t\"\nN3 #g1 = 1\nRETURN\n",
    );
    assert!(d.message.contains("does not end"), "{d}");
}
