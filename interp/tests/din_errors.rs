//! Bad lathe DIN input: `file:line:col` diagnostics and no motion from the failing block.

mod common;
use common::lathe::until_error;
use klar_interp::{Interpreter, Op, Pose};

fn motions(ops: &[Op]) -> usize {
    ops.iter().filter(|o| o.kind.is_motion()).count()
}

const SETUP: &str = "N1 T1 G197 S1000 G94 F100 M103\nN2 M14\nN3 G0 X100 Z2\n";

#[test]
fn sections_out_of_order_or_twice() {
    let (ops, d) = until_error("HEADER\nMACHINING\nTURRET\nEND\n");
    assert!(ops.is_empty());
    assert_eq!((d.line, d.col), (3, 1), "{d}");
    assert!(d.message.contains("section TURRET"), "{d}");
    let (_, d) = until_error("HEADER\nBLANK\nBLANK\nMACHINING\nEND\n");
    assert_eq!(d.line, 3, "{d}");
    assert!(d.to_string().starts_with("bad.nc:3:1: "), "{d}");
}

#[test]
fn motion_outside_machining_and_unknown_sections() {
    let (ops, d) = until_error("HEADER\nN1 G0 X10 Z5\nMACHINING\nEND\n");
    assert!(ops.is_empty());
    assert_eq!((d.line, d.col, d.block), (2, 4, Some(1)), "{d}");
    assert!(d.message.contains("outside a MACHINING section"), "{d}");
    let (_, d) = until_error("FINISHED PART\nN1 T3\nMACHINING\nEND\n");
    assert_eq!((d.line, d.col), (2, 4), "{d}");
    // a block after END: found by the whole-program check
    let path = common::temp_file(
        "after_end.nc",
        b"HEADER\nMACHINING\nN1 G0 X10\nEND\nN2 G0 X20\n",
    );
    let diags = klar_interp::check(&path, Pose::ZERO);
    common::remove_temp(&path);
    assert_eq!(diags.len(), 1, "{diags:?}");
    assert_eq!((diags[0].line, diags[0].block), (5, Some(2)));
    let (_, d) = until_error("HEADER\nMACHINNG\nN1 G0 X5\nEND\n");
    assert_eq!((d.line, d.col), (2, 1), "{d}");
    assert!(d.message.contains("MACHINNG"), "{d}");
    let (_, d) = until_error("LATERAL_Y X118 C0 B130 Q7\nMACHINING\nEND\n");
    assert_eq!((d.line, d.col), (1, 24), "{d}");
}

#[test]
fn pattern_errors_w_with_wi_q_below_one_and_no_cycle() {
    let (ops, d) = until_error(&format!("{SETUP}N4 G745 XK0 YK0 K50 A0 W90 Wi30 Q3\nEND\n"));
    assert_eq!((d.line, d.col), (4, 28), "{d}");
    assert!(d.message.contains("W and Wi"), "{d}");
    // only the set-up moved
    assert_eq!(motions(&ops), 1);
    let (_, d) = until_error(&format!("{SETUP}N4 G745 XK0 YK0 K50 A0 Q0\nEND\n"));
    assert_eq!((d.line, d.col), (4, 24), "{d}");
    assert!(d.message.contains("Q0"), "{d}");
    let (ops, d) = until_error(&format!("{SETUP}N4 G745 XK0 YK0 K50 Q3\nN5 G0 X50\nEND\n"));
    assert_eq!((d.line, d.block), (5, Some(5)), "{d}");
    assert!(d.message.contains("block 4"), "{d}");
    assert_eq!(motions(&ops), 1);
    // a face pattern without the C axis
    let (_, d) = until_error("N1 T1 G94 F100\nN2 G745 XK0 YK0 K50 Q3 ZE-2\nEND\n");
    assert!(d.message.contains("M14"), "{d}");
}

#[test]
fn unknown_g_words_and_missing_end() {
    let (_, d) = until_error(&format!("{SETUP}N4 G999 X5\nEND\n"));
    assert_eq!((d.line, d.col), (4, 4), "{d}");
    assert!(d.message.contains("G999"), "{d}");
    let (_, d) = until_error(&format!("{SETUP}N4 G1 X5 Q9\nEND\n"));
    assert_eq!((d.line, d.col), (4, 10), "{d}");
    let (_, d) = until_error(&format!("{SETUP}N4 G1 Z-5\n"));
    assert!(d.message.contains("END"), "{d}");
    let (_, d) = until_error("N1 G1 X5 Z5\nEND\n");
    assert!(d.message.contains("feed"), "{d}");
}

#[test]
fn random_bytes_never_panic() {
    for seed in 0u32..300 {
        let alphabet = b"NGXZCYBIKRFSTMPQAWiVEKS0123456789+-.?[]\" \n";
        let text = common::random_text(seed, 7, b"MACHINING\n", 150, alphabet);
        let _ = Interpreter::from_source("fuzz.nc", &text, Pose::ZERO)
            .take(5000)
            .count();
    }
}
