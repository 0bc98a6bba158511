//! The thread cycle G31: the depth of every pass for each infeed type, the flank offset of
//! every pass, the starting angle of every start, air cuts, tapers, contour threads and
//! the approach/return moves, against closed forms worked out here from the manual's rules.

mod common;
use common::lathe::{near, run_text, zx};
use klar_interp::op::ThreadLead;
use klar_interp::{Feed, Interpreter, Op, OpKind, Pose};

/// A program that stands the tool at X`x` Z`z` (diameter) and runs `cycle`.
fn program(x: f64, z: f64, cycle: &str) -> String {
    format!("%t.nc\nMACHINING\nN1 T1\nN2 G97 S600 M3\nN3 G0 X{x} Z{z}\nN4 {cycle}\nN5 M30\nEND\n")
}

/// One geared pass: (z, x radius) of its start and end, start angle, section, lead.
#[derive(Debug, Clone, Copy)]
struct Pass {
    from: [f64; 2],
    to: [f64; 2],
    angle: f64,
    section: f64,
    lead: ThreadLead,
    run_in: Option<f64>,
    run_out: Option<f64>,
}

fn passes(ops: &[Op]) -> Vec<Pass> {
    ops.iter()
        .filter_map(|o| match o.kind {
            OpKind::SpindleSync {
                from,
                to,
                start_angle,
                section,
                lead,
                run_in,
                run_out,
                ..
            } => Some(Pass {
                from: zx(&from),
                to: zx(&to),
                angle: start_angle,
                section,
                lead,
                run_in,
                run_out,
            }),
            _ => None,
        })
        .collect()
}

/// Every move of block 4 as (rapid?, from, to); geared passes as (false, from, to).
fn path(ops: &[Op]) -> Vec<(bool, [f64; 2], [f64; 2])> {
    ops.iter()
        .filter(|o| o.loc.block == Some(4))
        .filter_map(|o| match o.kind {
            OpKind::Line { from, to, feed } => Some((feed == Feed::Rapid, zx(&from), zx(&to))),
            OpKind::SpindleSync { from, to, .. } => Some((false, zx(&from), zx(&to))),
            _ => None,
        })
        .collect()
}

/// Checks the passes of an external longitudinal thread on radius `r` from Z`z0` to Z`z1`
/// at the cumulative depths `depths`.
#[track_caller]
fn at_depths(ps: &[Pass], r: f64, z0: f64, z1: f64, depths: &[f64]) {
    assert_eq!(ps.len(), depths.len(), "{ps:?}");
    for (p, d) in ps.iter().zip(depths) {
        near(p.from, [z0, r - d]);
        near(p.to, [z1, r - d]);
        assert_eq!(p.lead, ThreadLead::Z);
    }
}

#[test]
fn v0_constant_section_deepens_with_the_square_root_of_the_cut_number() {
    // M20x1.5 external, U-0.9, I0.3: the chip of cut k is ∝ d_k² − d_{k−1}², equal when
    // d_k = I·√k; (U/I)² = 9 cuts, the 9th ends at 0.3·3 = 0.9 = U.
    let ops = run_text(&program(22.0, 5.0, "G31 X20 Z-30 F1.5 U-0.9 I0.3 V0")).unwrap();
    let want: Vec<f64> = (1..=9).map(|k| 0.3 * f64::from(k).sqrt()).collect();
    let ps = passes(&ops);
    at_depths(&ps, 10.0, 5.0, -30.0, &want);
    // equal chip areas: d_k² − d_{k−1}² = I² for every cut
    let mut prev: f64 = 0.0;
    for p in &ps {
        let d = 10.0 - p.from[1];
        assert!((d * d - prev * prev - 0.09).abs() < 1e-9);
        prev = d;
    }
    // without I and IC, V0 takes I = F/3 = 0.5: (0.9/0.5)² = 3.24 → 4 cuts
    let ops = run_text(&program(22.0, 5.0, "G31 X20 Z-30 F1.5 U-0.9")).unwrap();
    let want = [0.5, 0.5 * 2f64.sqrt(), 0.5 * 3f64.sqrt(), 0.9];
    at_depths(&passes(&ops), 10.0, 5.0, -30.0, &want);
}

#[test]
fn v0_and_v1_with_a_number_of_cuts() {
    // IC4 U-1: V0 d_k = U·√(k/4) = 0.5, 0.7071…, 0.8660…, 1; V1 d_k = k/4
    let ops = run_text(&program(24.0, 2.0, "G31 X20 Z-20 F2 U-1 IC4 V0")).unwrap();
    let want: Vec<f64> = (1..=4).map(|k| (f64::from(k) / 4.0).sqrt()).collect();
    at_depths(&passes(&ops), 10.0, 2.0, -20.0, &want);
    let ops = run_text(&program(24.0, 2.0, "G31 X20 Z-20 F2 U-1 IC4 V1")).unwrap();
    at_depths(&passes(&ops), 10.0, 2.0, -20.0, &[0.25, 0.5, 0.75, 1.0]);
    // V1 with I0.3: ⌈1/0.3⌉ = 4 equal infeeds of 0.25 (each ≤ I)
    let ops = run_text(&program(24.0, 2.0, "G31 X20 Z-20 F2 U-1 I0.3 V1")).unwrap();
    at_depths(&passes(&ops), 10.0, 2.0, -20.0, &[0.25, 0.5, 0.75, 1.0]);
}

#[test]
fn v2_reduces_the_first_infeed_and_splits_the_last_v3_does_not_split() {
    // U-1.1, I0.4: ⌈2.75⌉ = 3 infeeds; the remainder makes the first 1.1 − 2·0.4 = 0.3;
    // V2 splits the last 0.4 into 0.2, 0.1, 0.05, 0.05.
    let ops = run_text(&program(24.0, 2.0, "G31 X20 Z-20 F2 U-1.1 I0.4 V2")).unwrap();
    let steps = [0.3, 0.4, 0.2, 0.1, 0.05, 0.05];
    let want: Vec<f64> = steps
        .iter()
        .scan(0.0, |s, x| {
            *s += x;
            Some(*s)
        })
        .collect();
    at_depths(&passes(&ops), 10.0, 2.0, -20.0, &want);
    let ops = run_text(&program(24.0, 2.0, "G31 X20 Z-20 F2 U-1.1 I0.4 V3")).unwrap();
    at_depths(&passes(&ops), 10.0, 2.0, -20.0, &[0.3, 0.7, 1.1]);
    // the chip cross-section of each pass is pitch × its infeed
    for (p, s) in passes(&ops).iter().zip([0.3, 0.4, 0.4]) {
        assert!((p.section - 2.0 * s).abs() < 1e-9);
    }
}

#[test]
fn flank_offsets_follow_the_infeed_angle() {
    // V1 IC3 U-0.9: depths 0.3, 0.6, 0.9; A30: offset d·tan30°
    let t = 30f64.to_radians().tan();
    for (h, sign) in [
        (1, [-1.0, -1.0, -1.0]),
        (2, [1.0, 1.0, 1.0]),
        (3, [-1.0, 1.0, -1.0]),
    ] {
        let cycle = format!("G31 X20 Z-20 F1.5 U-0.9 IC3 V1 H{h}");
        let ps = passes(&run_text(&program(24.0, 2.0, &cycle)).unwrap());
        assert_eq!(ps.len(), 3);
        for (k, p) in ps.iter().enumerate() {
            let d = 0.3 * (k + 1) as f64;
            near(p.from, [2.0 + sign[k] * d * t, 10.0 - d]);
            near(p.to, [-20.0 + sign[k] * d * t, 10.0 - d]);
        }
    }
    // A10 H2: d·tan10°; H0 (default) none whatever A says
    let t = 10f64.to_radians().tan();
    let ps =
        passes(&run_text(&program(24.0, 2.0, "G31 X20 Z-20 F1.5 U-0.9 IC3 V1 H2 A10")).unwrap());
    near(ps[2].from, [2.0 + 0.9 * t, 9.1]);
    let ps = passes(&run_text(&program(24.0, 2.0, "G31 X20 Z-20 F1.5 U-0.9 IC3 V1 A10")).unwrap());
    near(ps[2].from, [2.0, 9.1]);
}

#[test]
fn multi_start_air_cuts_and_the_approach_sequence() {
    // D3 C30: starts at 30°, 150°, 270° at every depth; Q2 air cuts at full depth
    let ops = run_text(&program(
        24.0,
        3.0,
        "G31 X20 Z-15 F3 U-0.6 IC2 V1 D3 C30 Q2 B2 P1",
    ))
    .unwrap();
    let ps = passes(&ops);
    assert_eq!(ps.len(), (2 + 2) * 3);
    for (i, p) in ps.iter().enumerate() {
        let depth = [0.3, 0.6, 0.6, 0.6][i / 3];
        near(p.from, [3.0, 10.0 - depth]);
        assert!((p.angle - (30.0 + 120.0 * (i % 3) as f64)).abs() < 1e-9);
        assert_eq!((p.run_in, p.run_out), (Some(2.0), Some(1.0)));
        // air cuts take no chip
        let cut = [0.3, 0.3, 0.0, 0.0][i / 3] * 3.0;
        assert!((p.section - cut).abs() < 1e-9, "{p:?}");
    }
    // every pass: in at rapid from the start radius 12, the pass, out at rapid to 12,
    // back along Z at rapid; the cycle ends at its start point
    let m = path(&ops);
    assert_eq!(m.len(), 12 * 4, "{m:?}");
    for (i, chunk) in m.chunks(4).enumerate() {
        let depth = [0.3, 0.6, 0.6, 0.6][i / 3];
        assert!(chunk[0].0);
        near(chunk[0].2, [3.0, 10.0 - depth]);
        assert!(!chunk[1].0);
        near(chunk[1].2, [-15.0, 10.0 - depth]);
        assert!(chunk[2].0);
        near(chunk[2].2, [-15.0, 12.0]);
        assert!(chunk[3].0);
        near(chunk[3].2, [3.0, 12.0]);
    }
}

#[test]
fn internal_taper_thread_infeeds_outwards() {
    // U+0.5 internal: infeed towards +X; R-1: the thread starts at radius 15 − (−1)... the
    // start radius is X/2 − R = 15 + 1 = 16? No: R = (X − XA)/2, XA = X − 2R = 32 → 16.
    let ops = run_text(&program(28.0, 2.0, "G31 X30 Z-20 F1 U0.5 IC2 V1 R-1")).unwrap();
    let ps = passes(&ops);
    assert_eq!(ps.len(), 2);
    for (p, d) in ps.iter().zip([0.25, 0.5]) {
        near(p.from, [2.0, 16.0 + d]);
        near(p.to, [-20.0, 15.0 + d]);
    }
    // standing outside the bore is refused before anything moves
    let e = run_text(&program(40.0, 2.0, "G31 X30 Z-20 F1 U0.5 IC2 V1")).unwrap_err();
    assert!(
        e.starts_with("t.nc:6:4:") && e.contains("inside the thread"),
        "{e}"
    );
}

#[test]
fn contour_threads_extend_by_run_in_and_run_out() {
    // A FINISHED PART with a Ø20 cylinder from Z0 to Z-25 (N2) and a face thread element
    // on Z-25 from Ø20 to Ø40 (N3).
    let text = "%c.nc\nFINISHED PART\nN1 G0 X20 Z0\nN2 G1 Z-25\nN3 G1 X40\nN4 G1 Z-40\n\
                MACHINING\nN10 T1\nN11 G97 S500 M3\nN12 G0 X24 Z4\n\
                N13 G31 NS2 F1.5 U-0.6 IC2 V1 B3 P2\nN14 G0 X50 Z-20\n\
                N15 G31 NS3 J1 F1 U-0.4 IC2 V1 B1 P1\nN16 M30\nEND\n";
    let ops = run_text(text).unwrap();
    let ps = passes(&ops);
    assert_eq!(ps.len(), 4);
    // N2: from Z0 + 3 to Z-25 − 2, at radius 10 − d, pitch along Z
    for (p, d) in ps[..2].iter().zip([0.3, 0.6]) {
        near(p.from, [3.0, 10.0 - d]);
        near(p.to, [-27.0, 10.0 - d]);
        assert_eq!(p.lead, ThreadLead::Z);
    }
    // N3 transverse (J1): radius 10 − 1 to 20 + 1, infeed in −Z from Z-25, pitch along X
    for (p, d) in ps[2..].iter().zip([0.2, 0.4]) {
        near(p.from, [-25.0 - d, 9.0]);
        near(p.to, [-25.0 - d, 21.0]);
        assert_eq!(p.lead, ThreadLead::X);
    }
}

#[test]
fn bad_g31_blocks_are_located_and_move_nothing() {
    for (cycle, what) in [
        ("G31 X20 Z-20 U-1 I0.2", "pitch F"),
        ("G31 X20 Z-20 F1 I0.2", "depth U"),
        ("G31 X20 Z-20 F1 U-1 I0.2 V5", "V5"),
        ("G31 X20 Z-20 F1 U-1 IC3 V2", "IC"),
        ("G31 X20 Z-20 F1 U-1 I0.2 A75", "A75"),
        ("G31 X20 Z-20 F1 U-1 I0", "I0"),
        ("G31 X20 Z-20 F1 U-1 I0.2 E0.1", "variable pitch"),
        ("G31 X20 F1 U-1 I0.2", "Z"),
        ("G31 X20 Z-20 F1 U-1 I0.000001", "passes"),
        ("G31 X30 Z-20 F1 U-1 I0.2", "inside the thread"),
    ] {
        let e = run_text(&program(24.0, 2.0, cycle)).unwrap_err();
        assert!(
            e.starts_with("t.nc:6:") && e.contains(": block 4: G31"),
            "{cycle}: {e}"
        );
        assert!(e.contains(what), "{cycle}: {e}");
        // the error stops the program at this block: no pass was emitted before it
        let ops: Vec<Op> = Interpreter::from_source("t.nc", &program(24.0, 2.0, cycle), Pose::ZERO)
            .map_while(Result::ok)
            .collect();
        assert!(passes(&ops).is_empty());
    }
}
