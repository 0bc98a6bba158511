//! G810/G820 roughing cuts against cut lengths worked out by hand from the contour and the
//! bar blank.

mod common;
use common::lathe::{first_error, lathe_program, lines, near, run_named};
use klar_interp::{AxisLetter, Feed, Op, OpKind};

fn program() -> Vec<Op> {
    run_named("r.nc", &lathe_program("roughing_g810_g820.nc"))
}

/// (from, to) of the feed moves at `f` mm/rev, as (z, x radius) pairs.
fn cuts(ops: &[Op], f: f64) -> Vec<([f64; 2], [f64; 2])> {
    lines(ops)
        .into_iter()
        .filter(|(feed, _, _)| *feed == Feed::PerRevolution(f))
        .map(|(_, from, to)| (from, to))
        .collect()
}

#[test]
fn g810_cuts_parallel_to_z_end_on_the_contour() {
    let ops = program();
    let c = cuts(&ops, 0.3);
    // blank radius 30 down to the contour's smallest radius 0: 30 mm in ceil(30/4) = 8
    // equal cuts of 3.75; each starts at the start Z3 and ends where the line x = r meets
    // the contour first: r 26.25 meets the shoulder at Z-60, r 22.5 the cone
    // (Z-30, r20)–(Z-40, r25) at Z-35, the others the face at Z0
    let expect_end = [-60.0, -35.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    assert_eq!(c.len(), 8, "{c:?}");
    for (i, ((from, to), z)) in c.iter().zip(expect_end).enumerate() {
        let r = 30.0 - 3.75 * (i as f64 + 1.0);
        near(*from, [3.0, r]);
        near(*to, [z, r]);
    }
}

#[test]
fn g820_cuts_parallel_to_x_keep_the_allowances() {
    let ops = program();
    let c = cuts(&ops, 0.25);
    // allowances: I1 (diameter) → 0.5 mm on radii, K0.5 towards the front. The shifted
    // contour ends at Z-59.5, the blank front is Z1: 60.5 mm in ceil(60.5/5) = 13 cuts.
    let step = 60.5 / 13.0;
    // the shifted contour's radius at Z (r + 0.5, Z + 0.5)
    let radius = |z: f64| {
        let z = z - 0.5;
        if z >= -30.0 {
            20.5
        } else if z >= -40.0 {
            20.5 + (-30.0 - z) / 10.0 * 5.0
        } else {
            25.5
        }
    };
    assert_eq!(c.len(), 13, "{c:?}");
    for (i, (from, to)) in c.iter().enumerate() {
        let z = 1.0 - step * (i as f64 + 1.0);
        // from the start radius 32 (X64) inwards
        near(*from, [z, 32.0]);
        near(*to, [z, radius(z)]);
    }
    // after both cycles the tool is back at the start point X64 Z3 before G890
    let before_finish = ops
        .iter()
        .rposition(
            |o| matches!(o.kind, OpKind::Line { feed, .. } if feed == Feed::PerRevolution(0.25)),
        )
        .unwrap();
    let back = ops[before_finish..].iter().find_map(|o| match o.kind {
        OpKind::Line {
            to,
            feed: Feed::Rapid,
            ..
        } if to[AxisLetter::X] == 32.0 && to[AxisLetter::Z] == 3.0 => Some(to),
        _ => None,
    });
    assert!(back.is_some());
}

#[test]
fn roughing_errors() {
    let text = "BLANK\nN1 G20 X60 Z80 K1\nFINISHED PART\nN2 G0 X0 Z0\nN3 G1 X40\n\
                MACHINING\nN10 G95 F0.2\nN11 G0 X20 Z-5\nN12 G810 P2\nEND\n";
    let d = first_error(text);
    assert_eq!((d.line, d.col), (9, 5), "{d}");
    assert!(d.message.contains("inside the blank"), "{d}");
    let text = "MACHINING\nN10 G95 F0.2\nN11 G0 X80 Z5\nN12 G810 P2\nEND\n";
    let d = first_error(text);
    assert!(d.message.contains("FINISHED PART"), "{d}");
}
