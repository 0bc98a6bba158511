//! Unknown coordinates `X?`/`Z?` of FINISHED PART lines, solved from the line's angle and
//! the next element, against intersections worked out by hand.

mod common;
use common::lathe::{first_error as until_error, run_named};
use klar_interp::{AxisLetter, Feed, Op, OpKind};

/// Runs `text` as `u.nc`; panics on a diagnostic.
fn run(text: &str) -> Vec<Op> {
    run_named("u.nc", text)
}

/// End points (z, x radius) of the finishing moves at the feed of G890.
fn finish(ops: &[Op]) -> Vec<(f64, f64)> {
    ops.iter()
        .filter_map(|o| match o.kind {
            OpKind::Line { to, feed, .. } => {
                (feed == Feed::PerRevolution(0.1)).then_some((to[AxisLetter::Z], to[AxisLetter::X]))
            }
            _ => None,
        })
        .collect()
}

#[track_caller]
fn near(a: (f64, f64), b: (f64, f64)) {
    assert!(
        (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9,
        "{a:?} != {b:?}"
    );
}

#[test]
fn cone_end_is_its_intersection_with_the_next_line() {
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../programs/lathe/unknown_coordinates.nc");
    let ops = run(&std::fs::read_to_string(p).unwrap());
    let f = finish(&ops);
    assert_eq!(f.len(), 5, "{f:?}");
    near(f[0], (0.0, 10.0));
    // N3 from (Z0, r10) at 150°: r = 10 + t/2, z = -t·√3/2; it meets r = 30 (N4, A180
    // through Z-40) at t = 40: z = -20√3
    let z3 = -20.0 * 3f64.sqrt();
    near(f[1], (z3, 30.0));
    near(f[2], (-40.0, 30.0));
    // N5 from (Z-40, r30) at 165° to Z-60: t = 20 / cos 15°, r = 30 + t·sin 15°
    let r5 = 30.0 + 20.0 * 15f64.to_radians().tan();
    near(f[3], (-60.0, r5));
    near(f[4], (-60.0, 40.0));
}

#[test]
fn unsolvable_unknowns_are_located_at_the_unknown() {
    let head = "FINISHED PART\nN1 G0 X0 Z0\nN2 G1 X20\n";
    // the next element is an arc
    let d = until_error(&format!(
        "{head}N3 G1 X? Z? A150\nN4 G12 X40 Z-30 R20\nMACHINING\nEND\n"
    ));
    assert_eq!((d.line, d.col, d.block), (4, 7, Some(3)), "{d}");
    assert!(d.message.contains("cannot be solved"), "{d}");
    // parallel to the next line
    let d = until_error(&format!(
        "{head}N3 G1 X? Z? A180\nN4 G1 X60 Z-40 A180\nMACHINING\nEND\n"
    ));
    assert_eq!((d.line, d.col), (4, 7), "{d}");
    assert!(d.message.contains("parallel"), "{d}");
    // no angle
    let d = until_error(&format!("{head}N3 G1 X? Z-10\nMACHINING\nEND\n"));
    assert_eq!((d.line, d.col), (4, 7), "{d}");
    // the contour ends first
    let d = until_error(&format!("{head}N3 G1 X? Z? A120\nMACHINING\nEND\n"));
    assert_eq!((d.line, d.col), (4, 7), "{d}");
    assert!(d.message.contains("ends before"), "{d}");
    // one unknown on a line that never reaches the given coordinate
    let d = until_error(&format!("{head}N3 G1 X? Z-10 A90\nMACHINING\nEND\n"));
    assert_eq!((d.line, d.col), (4, 7), "{d}");
    // an unknown in an arc
    let d = until_error(&format!("{head}N3 G12 X? Z? R15\nMACHINING\nEND\n"));
    assert_eq!((d.line, d.col), (4, 8), "{d}");
}
