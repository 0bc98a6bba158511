//! Contour-parallel roughing G830: every cut on the contour (with its allowances) offset by
//! equal steps towards the blank, clipped to the blank, against positions worked out by
//! hand.

mod common;
use common::lathe::{block_lines, near, run_text};
use klar_interp::Feed;

/// The moves of block `n` as (rapid?, to).
fn moves(ops: &[klar_interp::Op], n: u64) -> Vec<(bool, [f64; 2])> {
    block_lines(ops, n)
        .into_iter()
        .map(|(feed, _, to)| (feed == Feed::Rapid, to))
        .collect()
}

/// A Ø34 bar 50 long, front face at Z1; the part: face at Z0 up to Ø20, Ø20 to Z-20,
/// shoulder up to Ø30, Ø30 to Z-40.
const PART: &str = "%p.nc\nBLANK\nN1 G20 X34 Z50 K1\nFINISHED PART\nN2 G0 X0 Z0\nN3 G1 X20\n\
                    N4 G1 Z-20\nN5 G1 X30\nN6 G1 Z-40\nMACHINING\nN10 T1\n\
                    N11 G96 S200 G95 F0.3 M4\nN12 G0 X40 Z5\n";

#[test]
fn g830_cuts_offset_contours_in_equal_steps_down_to_the_allowance() {
    let text = format!("{PART}N13 G830 P2 I0.4 K0.2 F0.25\nN14 M30\nEND\n");
    let ops = run_text(&text).unwrap();
    let m = moves(&ops, 13);
    // The allowances shift the contour by K0.2 in Z and I/2 = 0.2 in X: face at Z0.2 up to
    // radius 10.2, Ø20.4 to Z-19.8, shoulder to radius 15.2, then along radius 15.2.
    // The blank's surface lies farthest from it at the corner (Z1, radius 17):
    // √(0.8² + 6.8²); P2 gives ⌈T/2⌉ = 4 equal steps.
    let t = 0.8f64.hypot(6.8);
    let step = t / 4.0;
    let o: Vec<f64> = (1..=4).map(|k| t - step * f64::from(k)).collect();
    // Each offset contour clipped to the blank Z ≤ 1, radius ≤ 17, Z ≥ 1 − 50:
    // 1, 2: the face lies in front of the blank (0.2 + o > 1); the shoulder leaves the bar
    //       at radius 17 (15.2 + o > 17)
    // 3:    the face in front; the shoulder's top 15.2 + o < 17 runs on to the back
    // 4:    o = 0: the contour itself from the axis
    let cut = |o: f64| -> Vec<[f64; 2]> {
        let (face, cyl, shoulder, top) = (0.2 + o, 10.2 + o, -19.8 + o, 15.2 + o);
        let mut v = Vec::new();
        if face <= 1.0 {
            v.push([face, 0.0]);
            v.push([face, cyl]);
        } else {
            v.push([1.0, cyl]);
        }
        v.push([shoulder, cyl]);
        if top >= 17.0 {
            v.push([shoulder, 17.0]);
        } else {
            v.push([shoulder, top]);
            v.push([-49.0, top]);
        }
        v
    };
    let mut i = 0;
    for (k, &ok) in o.iter().enumerate() {
        let want = cut(ok);
        // rapid along the clearance Z5 to the cut's radius, then at the feed along Z
        assert!(m[i].0, "cut {k}: {:?}", m[i]);
        near(m[i].1, [5.0, want[0][1]]);
        i += 1;
        for q in &want {
            assert!(!m[i].0, "cut {k}: {:?}", m[i]);
            near(m[i].1, *q);
            i += 1;
        }
        // out in X to the clearance radius 20, back along Z to the clearance point
        let end_z = want[want.len() - 1][0];
        assert!(m[i].0 && m[i + 1].0);
        near(m[i].1, [end_z, 20.0]);
        near(m[i + 1].1, [5.0, 20.0]);
        i += 2;
    }
    // the clearance point is the start point X40 Z5: nothing more to move
    assert_eq!(i, m.len(), "{m:?}");
    // the last cut lies on the contour with its allowances
    assert!(o[3].abs() < 1e-12);
}

#[test]
fn g830_ns_alone_roughs_one_element() {
    // NS4 without NE: the Ø20 element alone, extended along Z both ways, no allowance.
    // The blank's surface on the material side (above radius 10) lies at most 17 − 10 = 7
    // from it (the axis below is the part's side and does not count): ⌈7/2⌉ = 4 cuts of
    // 1.75.
    let text = format!("{PART}N13 G830 NS4 P2 F0.25\nN14 M30\nEND\n");
    let ops = run_text(&text).unwrap();
    let feeds: Vec<[f64; 2]> = moves(&ops, 13)
        .into_iter()
        .filter(|m| !m.0)
        .map(|m| m.1)
        .collect();
    // each cut: along Z from the front Z1 to the end of the element Z-20 extended to the
    // back Z-49, at radius 10 + o
    assert_eq!(feeds.len(), 4 * 2, "{feeds:?}");
    for (k, c) in feeds.chunks(2).enumerate() {
        let r = 10.0 + 7.0 - 1.75 * (k + 1) as f64;
        near(c[0], [1.0, r]);
        near(c[1], [-49.0, r]);
    }
}

#[test]
fn bad_g830_is_refused_before_anything_moves() {
    for (cycle, what) in [
        ("G830 F0.2", "infeed P"),
        ("G830 P0 F0.2", "P0"),
        ("G830 P2 Q1 F0.2", "Q1"),
        ("G830 P2 A45 F0.2", "A45"),
        ("G830 NS99 P2 F0.2", "N99"),
    ] {
        let text = format!("{PART}N13 {cycle}\nN14 M30\nEND\n");
        let e = run_text(&text).unwrap_err();
        assert!(e.starts_with("t.nc:14:") && e.contains("block 13:"), "{e}");
        assert!(e.contains(what), "{cycle}: {e}");
    }
    // standing inside the blank
    let text = PART.replace("N12 G0 X40 Z5", "N12 G0 X30 Z-5") + "N13 G830 P2\nN14 M30\nEND\n";
    let e = run_text(&text).unwrap_err();
    assert!(e.contains("inside the blank"), "{e}");
}
