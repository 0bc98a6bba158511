//! Recessing cycles G866/G870 on G22 recess elements and G860 on a contour area: plunge
//! positions, depths and finishing passes against values worked out by hand.

mod common;
use common::lathe::{block, lines as moves, near, run_lathe as run, run_text};
use klar_interp::{Feed, OpKind};

#[test]
fn g866_plunges_a_g22_recess_at_equal_overlapping_steps() {
    let ops = run("groove_g866_g870.nc");
    let b = block(&ops, 13);
    let m = moves(&b);
    // recess Z-20..-30 on the Ø40 surface, floor Ø30; tool 4 wide, reference at its +Z
    // corner: travel 10 − 4 = 6 in ceil(6 / 3.2) = 2 steps of 3 → Z-20, -23, -26
    let f = Feed::PerRevolution(0.05);
    near(m[0].2, [-20.0, 32.0]);
    assert_eq!(m[0].0, Feed::Rapid);
    for (i, z) in [-20.0, -23.0, -26.0].into_iter().enumerate() {
        let (down, cut, up) = (m[1 + 3 * i], m[2 + 3 * i], m[3 + 3 * i]);
        assert_eq!(down.0, Feed::Rapid);
        near(down.2, [z, 21.0]); // 1 mm above the surface
        assert_eq!(cut.0, f);
        near(cut.2, [z, 15.0]);
        assert_eq!(up.0, Feed::Rapid);
        near(up.2, [z, 21.0]);
    }
    // out first, then back along Z to the start X64 Z5
    near(m[10].2, [-26.0, 32.0]);
    near(m[11].2, [5.0, 32.0]);
    assert_eq!(m.len(), 12);
    // E0.5: a dwell at the floor of each plunge
    let dwells = b
        .iter()
        .filter(|o| matches!(o.kind, OpKind::Dwell { seconds } if seconds == 0.5))
        .count();
    assert_eq!(dwells, 3);
}

#[test]
fn g870_single_plunge_on_an_incremental_recess() {
    let ops = run("groove_g866_g870.nc");
    let m = moves(&block(&ops, 14));
    // G22 Z-56 Ii-8 Ki-4 on the Ø60 line: floor Ø52, Z-56..-60, exactly one tool width
    let feeds: Vec<_> = m.iter().filter(|c| c.0 != Feed::Rapid).collect();
    assert_eq!(feeds.len(), 1, "{m:?}");
    near(feeds[0].1, [-56.0, 31.0]);
    near(feeds[0].2, [-56.0, 26.0]);
}

#[test]
fn g866_with_allowance_roughs_short_and_finishes_walls_and_floor() {
    let ops = run("groove_g866_g870.nc");
    let m = moves(&block(&ops, 15));
    let cuts: Vec<_> = m.iter().filter(|c| c.0 != Feed::Rapid).collect();
    // I0.2: span Z-20.2..-29.8, floor r15.2; travel 5.6 in 2 steps of 2.8
    for (c, z) in cuts.iter().zip([-20.2, -23.0, -25.8]) {
        near(c.2, [z, 15.2]);
    }
    // finishing: down the front wall at Z-20, along the floor to Z-26 (tool's +Z corner
    // with its back edge on the wall at Z-30), up the back wall
    near(cuts[3].1, [-20.0, 21.0]);
    near(cuts[3].2, [-20.0, 15.0]);
    near(cuts[4].2, [-26.0, 15.0]);
    near(cuts[5].2, [-26.0, 21.0]);
    assert_eq!(cuts.len(), 6);
    assert!(cuts.iter().all(|c| c.0 == Feed::PerRevolution(0.04)));
}

#[test]
fn g890_follows_the_recesses_of_the_contour() {
    let text = std::fs::read_to_string(
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../programs/lathe/groove_g866_g870.nc"),
    )
    .unwrap()
    .replace("N16 G0 X70 Z5", "N16 G890 F0.1");
    let ops = run_text(&text).unwrap();
    let path: Vec<[f64; 2]> = moves(&block(&ops, 16))
        .iter()
        .skip(1)
        .map(|m| m.2)
        .collect();
    let expect = [
        [0.0, 20.0],
        [-20.0, 20.0],
        [-20.0, 15.0],
        [-30.0, 15.0],
        [-30.0, 20.0],
        [-50.0, 20.0],
        [-50.0, 30.0],
        [-56.0, 30.0],
        [-56.0, 26.0],
        [-60.0, 26.0],
        [-60.0, 30.0],
        [-70.0, 30.0],
    ];
    assert_eq!(path.len(), expect.len(), "{path:?}");
    for (a, b) in path.iter().zip(expect) {
        near(*a, b);
    }
}

/// The contour of groove_g860.nc under a tool 3 wide whose +Z corner is at `c`: the
/// highest radius of the V (r 25 at Z-20 down to r 20 at Z-25, flat to Z-29, up to r 25
/// at Z-34) between Z c−3 and c.
fn v_depth(c: f64) -> f64 {
    let falling = |z: f64| 25.0 + (z + 20.0); // Z-25..-20
    let rising = |z: f64| 20.0 + (-29.0 - z); // Z-34..-29
    let mut d: f64 = 20.0;
    if (-25.0..=-20.0).contains(&c) {
        d = d.max(falling(c));
    }
    if (-34.0..=-29.0).contains(&(c - 3.0)) {
        d = d.max(rising(c - 3.0));
    }
    d
}

#[test]
fn g860_plunges_to_the_contour_under_the_tool_and_finishes_its_envelope() {
    let ops = run("groove_g860.nc");
    let m = moves(&block(&ops, 13));
    let rough: Vec<_> = m
        .iter()
        .filter(|c| c.0 == Feed::PerRevolution(0.06))
        .collect();
    // Z-20..-34 with P3: travel 11 in ceil(11 / 2.4) = 5 steps of 2.2
    assert_eq!(rough.len(), 6, "{m:?}");
    for (i, c) in rough.iter().enumerate() {
        let z = -20.0 - 2.2 * i as f64;
        near(c.1, [z, 27.0]); // from the start X54
        near(c.2, [z, v_depth(z)]);
    }
    let finish: Vec<_> = m
        .iter()
        .filter(|c| c.0 == Feed::PerRevolution(0.04))
        .collect();
    // the envelope bends where a corner of the V meets an edge of the tool
    let stops = [-20.0, -22.0, -25.0, -26.0, -29.0, -31.0];
    assert_eq!(finish.len(), stops.len() + 1, "{finish:?}");
    for (c, z) in finish.iter().zip(stops) {
        near(c.2, [z, v_depth(z)]);
    }
    near(finish[6].2, [-31.0, 27.0]);
    // and back to the start
    near(m.last().unwrap().2, [5.0, 27.0]);
}

#[test]
fn recess_errors_name_what_is_wrong() {
    let base = "FINISHED PART\nN1 G0 X0 Z0\nN2 G1 X40\nN3 G1 Z-50\nN4 G22 Z-20 I30 K-30\nMACHINING\nN10 T1\nN11 G97 S500 G95 F0.1 M3\nN12 G0 X50 Z5\n";
    let with = |cycle: &str| run_text(&format!("{base}{cycle}\nN99 M30\nEND\n"));
    let e = with("N13 G866 NS4 P12").unwrap_err();
    assert!(e.contains("narrower than the cutting width"), "{e}");
    let e = with("N13 G866 NS4").unwrap_err();
    assert!(e.contains("cutting width P"), "{e}");
    let e = with("N13 G866 NS7 P4").unwrap_err();
    assert!(e.contains("no G22 recess in block N7"), "{e}");
    let e = with("N13 G0 X30\nN14 G866 NS4 P4").unwrap_err();
    assert!(e.contains("below the surface"), "{e}");
    let bad = run_text(
        "FINISHED PART\nN1 G0 X0 Z0\nN2 G1 X40 Z-10\nN3 G22 Z-5 I30 K-8\nMACHINING\nN10 M30\nEND\n",
    )
    .unwrap_err();
    assert!(bad.contains("axis-parallel"), "{bad}");
    assert!(bad.starts_with("t.nc:4:"), "{bad}");
    let off = run_text("FINISHED PART\nN1 G0 X0 Z0\nN2 G1 X40\nN3 G1 Z-10\nN4 G22 Z-5 I30 K-12\nMACHINING\nN10 M30\nEND\n")
        .unwrap_err();
    assert!(off.contains("must lie on its reference element"), "{off}");
}
