//! Bad TNC ISO input: located diagnostics, no panics, no ops from the failing block.

mod common;
use common::{random_text, run_until_error_named};
use klar_interp::{Diagnostic, Interpreter, Op, Pose};

/// Runs `text` as `bad.i` until its first diagnostic: the ops before it and the diagnostic.
fn until_error(text: &str) -> (Vec<Op>, Diagnostic) {
    run_until_error_named("bad.i", text)
}

#[test]
fn unknown_g_code_is_located_at_its_word() {
    let (ops, d) = until_error("%A G71 *\nN10 G01 X+1 F100 *\nN20 G01 G123 X+5 *\n");
    assert_eq!((d.line, d.col), (3, 9), "{d}");
    assert!(d.message.contains("G123"), "{d}");
    assert_eq!(d.to_string().split(':').next(), Some("bad.i"));
    // only the first block moved
    assert_eq!(ops.iter().filter(|o| o.kind.is_motion()).count(), 1);
}

#[test]
fn a_program_without_header_is_rejected() {
    let (ops, d) = until_error("N10 G01 X+1 F100 *\n");
    assert!(ops.is_empty());
    assert_eq!((d.line, d.col), (1, 1));
    assert!(d.message.contains("%NAME"), "{d}");
}

#[test]
fn a_missing_closing_block_is_reported_at_the_end() {
    let (_, d) = until_error("%A G71 *\nN10 G00 X+1 *\n");
    assert_eq!(d.line, 3, "{d}");
    assert!(d.message.contains("closing"), "{d}");
}

#[test]
fn calls_to_undefined_labels_and_motion_without_g() {
    let (_, d) = until_error("%A G71 *\nN10 L7,0 *\nN20 M30 *\nN30 %A G71 *\n");
    assert_eq!((d.line, d.block), (2, Some(10)), "{d}");
    assert!(d.message.contains("label 7"), "{d}");
    let (_, d) = until_error("%A G71 *\nN10 X+5 *\nN20 %A G71 *\n");
    assert!(d.message.contains("no motion G code"), "{d}");
}

#[test]
fn bad_values_and_unsupported_functions() {
    let (_, d) = until_error("%A G71 *\nN10 G01 X+1 E5 F100 *\n");
    assert_eq!((d.line, d.col), (2, 13), "{d}");
    let (_, d) = until_error("%A G71 *\nN10 G01 X+1 R+2 F100 *\n");
    assert_eq!((d.line, d.col), (2, 13), "{d}");
    let (_, d) = until_error("%A G71 *\nN10 G01 X *\n");
    assert_eq!((d.line, d.col), (2, 9), "{d}");
    let (_, d) = until_error("%A G71 *\nN10 G01 Y+1 X F100 *\n");
    assert!(d.message.contains("missing value"), "{d}");
    // G28 lists the mirrored axes without values
    let (_, d) = until_error("%A G71 *\nN10 G28 X+0 *\n");
    assert!(d.message.contains("mirror"), "{d}");
    assert_eq!((d.line, d.col), (2, 9), "{d}");
    let (_, d) = until_error("%A G71 *\nN10 G02 X+5 Y+0 F100 *\n");
    assert!(d.message.contains("CC"), "{d}");
    let (_, d) = until_error("%A G71 *\nN10 G01 X+5 F100 *\nN20 G02 X+0 R+1 *\n");
    assert!(d.message.contains("longer than 2R"), "{d}");
}

#[test]
fn endless_loops_and_random_bytes_end_without_panic() {
    // a D09 jump that always holds and never moves: stopped by the idle-jump guard
    let text = "%L G71 *\nN10 G98 L1 *\nN20 D09 P01 +0 P02 +0 P03 1 *\nN30 %L G71 *\n";
    let (ops, d) = until_error(text);
    assert!(ops.is_empty());
    assert!(d.message.contains("loops endlessly"), "{d}");
    for seed in 0u32..300 {
        let alphabet = b"NGXYZIJKRHFQLDPMT0123456789+-.,*; =%\n/";
        let text = random_text(seed, 12345, b"%F G71 *\n", 120, alphabet);
        let _ = Interpreter::from_source("fuzz.i", &text, Pose::ZERO)
            .take(2000)
            .count();
    }
}
