//! G860 on a recess in the front face: axial plunges along −Z with the tool's width along
//! X, against values worked out by hand.

mod common;
use common::lathe::{block_lines, lathe_program, near, run_lathe, run_text};
use klar_interp::{Feed, Op};

fn ops() -> Vec<Op> {
    run_lathe("groove_g860_face.nc")
}

/// The moves of block 13 as (feed, to) with to = (z, x radius).
fn moves(ops: &[Op]) -> Vec<(Feed, [f64; 2])> {
    block_lines(ops, 13)
        .into_iter()
        .map(|(feed, _, to)| (feed, to))
        .collect()
}

/// The face recess: Z0 at r15 sloping to Z-6 at r16, floor Z-6 to r26, sloping back to Z0
/// at r27. The highest Z of it over the radii `lo`…`hi` (closed: the walls are sloped).
fn face_depth(lo: f64, hi: f64) -> f64 {
    let z = |r: f64| {
        if r <= 16.0 {
            -6.0 * (r - 15.0)
        } else if r <= 26.0 {
            -6.0
        } else {
            -6.0 + 6.0 * (r - 26.0)
        }
    };
    [lo, hi, 16.0, 26.0]
        .into_iter()
        .filter(|r| *r >= lo.max(15.0) && *r <= hi.min(27.0))
        .map(z)
        .fold(f64::NEG_INFINITY, f64::max)
}

#[test]
fn g860_on_a_face_recess_plunges_along_z() {
    let m = moves(&ops());
    // radii 15…27 with P4: the +X corner from r27 down to r19, travel 8 in ⌈8/3.2⌉ = 3
    // steps of 8/3; each plunge from the start Z2 down to the highest contour point under
    // the tool's width.
    let rough: Vec<_> = m
        .iter()
        .filter(|c| c.0 == Feed::PerRevolution(0.06))
        .collect();
    assert_eq!(rough.len(), 4, "{m:?}");
    for (i, c) in rough.iter().enumerate() {
        let r = 27.0 - 8.0 / 3.0 * i as f64;
        near(c.1, [face_depth(r - 4.0, r), r]);
    }
    // the inner plunges reach the floor
    near(rough[1].1, [-6.0, 27.0 - 8.0 / 3.0]);
    // every plunge starts at Z2, the tool's Z: the move before each is at rapid to Z2
    for (i, c) in m.iter().enumerate() {
        if c.0 == Feed::PerRevolution(0.06) {
            assert_eq!(m[i - 1].0, Feed::Rapid);
            assert!((m[i - 1].1[0] - 2.0).abs() < 1e-12, "{:?}", m[i - 1]);
            assert!((m[i + 1].1[0] - 2.0).abs() < 1e-12, "{:?}", m[i + 1]);
        }
    }
    // finishing at E: where an element's corner meets an edge of the tool (r27, 26, 20,
    // 19), then back out along Z to Z2
    let finish: Vec<_> = m
        .iter()
        .filter(|c| c.0 == Feed::PerRevolution(0.04))
        .collect();
    let stops = [27.0, 26.0, 20.0, 19.0];
    assert_eq!(finish.len(), stops.len() + 1, "{finish:?}");
    for (c, r) in finish.iter().zip(stops) {
        near(c.1, [face_depth(r - 4.0, r), r]);
    }
    near(finish[4].1, [2.0, 19.0]);
    // out along Z first (already at Z2), then along X back to X60 (r30)
    near(m.last().unwrap().1, [2.0, 30.0]);
    assert!(
        m.iter()
            .all(|c| c.1[0] <= 2.0 + 1e-12 && c.1[1] <= 30.0 + 1e-12)
    );
}

#[test]
fn g860_on_a_face_recess_needs_the_tool_in_front_of_it() {
    let text = lathe_program("groove_g860_face.nc").replace("N12 G0 X60 Z2", "N12 G0 X60 Z-1");
    let e = run_text(&text).unwrap_err();
    assert!(e.contains("stand in front of it"), "{e}");
    // G869 works axially too, but not from inside the face recess's depth
    let text = text.replace("N13 G860 NS3 NE5 P4 E0.04", "N13 G869 NS3 NE5 SB4 P2");
    let e = run_text(&text).unwrap_err();
    assert!(e.contains("G869 starts at Z-1.000"), "{e}");
}
