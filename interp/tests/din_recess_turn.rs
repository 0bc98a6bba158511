//! Recess turning G869: the levels, plunge places and turning stretches against values
//! worked out by hand, the finishing path, and a check that no cut enters the contour.

mod common;
use common::lathe::{
    block_lines as moves, check_moves as check, lathe_program as read, run_text, samples,
};
use common::recess::{RAPID, overlap, sloped};
use klar_interp::{Feed, Op};

fn program() -> String {
    read("recess_turn_g869.nc")
}

#[test]
fn g869_on_a_g22_recess_plunges_and_turns_back_and_forth() {
    let ops = run_text(&program()).unwrap();
    // recess Z-20..-40, Ø50 surface (r25), floor Ø30 (r15); SB4: the +Z corner runs from
    // Z-20 down to Z-36. Depth 10 with P3: ceil(10/3) = 4 levels of 2.5 → r22.5, 20, 17.5,
    // 15. The tool starts at X54 Z5 (r27); the safety distance above r25 is r26.
    let (f, o, e) = (
        Feed::PerRevolution(0.1),
        Feed::PerRevolution(0.05),
        Feed::PerRevolution(0.04),
    );
    let want = [
        (RAPID, [-20.0, 27.0]),
        (RAPID, [-20.0, 26.0]),
        (o, [-20.0, 22.5]),
        (f, [-36.0, 22.5]),
        (o, [-36.0, 20.0]),
        (f, [-20.0, 20.0]),
        (o, [-20.0, 17.5]),
        (f, [-36.0, 17.5]),
        (o, [-36.0, 15.0]),
        (f, [-20.0, 15.0]),
        (RAPID, [-20.0, 26.0]),
        // finishing: down the wall at Z-20, along the floor, up the wall at Z-40
        (e, [-20.0, 15.0]),
        (e, [-36.0, 15.0]),
        (e, [-36.0, 26.0]),
        // out in X, then back along Z
        (RAPID, [-36.0, 27.0]),
        (RAPID, [5.0, 27.0]),
    ];
    check(&moves(&ops, 23), &want);
}

#[test]
fn g869_with_oversizes_and_one_way_passes_on_sloped_walls() {
    let ops = run_text(&program()).unwrap();
    // SB3, K0.5, I1 (0.5 radius): standing at z the tool may reach the highest point
    // under z−3.5…z+0.5, plus 0.5. Lowest: 22.5 (z from -80.5 to -74.5). Depth from r30:
    // 7.5 with P3 → 3 levels of 2.5: r27.5, 25, 22.5. On the left wall 2z + 171.5 = x,
    // on the right wall −138.5 − 2z = x:
    //   r27.5: Z-72 … -83, r25: Z-73.25 … -81.75, r22.5: Z-74.5 … -80.5.
    // Start X64 Z-65 (r32), safety r31. Every pass runs from the NS end (+Z) to the NE end.
    let f = Feed::PerRevolution(0.1);
    let want = [
        (RAPID, [-72.0, 32.0]),
        (RAPID, [-72.0, 31.0]),
        (f, [-72.0, 27.5]),
        (f, [-83.0, 27.5]),
        (RAPID, [-83.0, 31.0]),
        (RAPID, [-73.25, 31.0]),
        (RAPID, [-73.25, 28.5]),
        (f, [-73.25, 25.0]),
        (f, [-81.75, 25.0]),
        (RAPID, [-81.75, 31.0]),
        (RAPID, [-74.5, 31.0]),
        (RAPID, [-74.5, 26.0]),
        (f, [-74.5, 22.5]),
        (f, [-80.5, 22.5]),
        (RAPID, [-80.5, 31.0]),
        // finishing on the contour itself, the tool's edges meeting its corners
        (RAPID, [-70.0, 31.0]),
        (f, [-70.0, sloped(-73.0, -70.0)]),
        (f, [-71.0, sloped(-74.0, -71.0)]),
        (f, [-74.0, sloped(-77.0, -74.0)]),
        (f, [-81.0, sloped(-84.0, -81.0)]),
        (f, [-84.0, sloped(-87.0, -84.0)]),
        (f, [-85.0, sloped(-88.0, -85.0)]),
        (f, [-85.0, 31.0]),
        (RAPID, [-85.0, 32.0]),
        (RAPID, [-65.0, 32.0]),
    ];
    check(&moves(&ops, 25), &want);
    assert!((sloped(-77.0, -74.0) - 22.0).abs() < 1e-12);
    assert!((sloped(-74.0, -71.0) - 28.0).abs() < 1e-12);
}

#[test]
fn g869_never_cuts_into_the_contour() {
    let ops = run_text(&program()).unwrap();
    for (n, w) in [(23, 4.0), (25, 3.0)] {
        for (_, from, to) in moves(&ops, n) {
            for p in samples(from, to) {
                assert!(overlap(p, w) < 1e-6, "N{n}: {p:?} cuts the contour");
            }
        }
    }
}

#[test]
fn g869_q1_roughs_only_and_q2_finishes_only() {
    let text = program();
    let rough = run_text(&text.replace("N23 G869 NS4", "N23 G869 Q1 NS4")).unwrap();
    let m = moves(&rough, 23);
    assert!(m.iter().all(|c| c.0 != Feed::PerRevolution(0.04)), "{m:?}");
    assert_eq!(m.len(), 13, "{m:?}");
    let finish = run_text(&text.replace("N23 G869 NS4", "N23 G869 Q2 NS4")).unwrap();
    let m = moves(&finish, 23);
    let cuts: Vec<_> = m.iter().filter(|c| c.0 != RAPID).collect();
    assert_eq!(cuts.len(), 3, "{m:?}");
    assert!(cuts.iter().all(|c| c.0 == Feed::PerRevolution(0.04)));
}

#[test]
fn g869_x_limit_stops_the_levels() {
    // X36: no cut below r18 → depth 7 with P3: 3 levels of 7/3
    let text = program().replace("N23 G869 NS4", "N23 G869 X36 Q1 NS4");
    let ops = run_text(&text).unwrap();
    let plunges: Vec<f64> = moves(&ops, 23)
        .iter()
        .filter(|c| c.0 == Feed::PerRevolution(0.05))
        .map(|c| c.2[1])
        .collect();
    let want = [25.0 - 7.0 / 3.0, 25.0 - 14.0 / 3.0, 18.0];
    assert_eq!(plunges.len(), 3, "{plunges:?}");
    for (g, w) in plunges.iter().zip(want) {
        assert!((g - w).abs() < 1e-9, "{plunges:?}");
    }
}

#[test]
fn g869_z_limit_keeps_the_tool_above_it() {
    // Z-30: the tool's −Z edge stays at Z-30 or above, so its +Z corner turns from Z-20
    // to Z-26 only; the levels are those of the whole recess (r22.5, 20, 17.5, 15)
    let text = program().replace("N23 G869 NS4", "N23 G869 Z-30 Q1 NS4");
    let ops = run_text(&text).unwrap();
    let turns: Vec<_> = moves(&ops, 23)
        .into_iter()
        .filter(|c| c.0 == Feed::PerRevolution(0.1))
        .collect();
    assert_eq!(turns.len(), 4, "{turns:?}");
    for (t, x) in turns.iter().zip([22.5, 20.0, 17.5, 15.0]) {
        let mut zs = [t.1[0], t.2[0]];
        zs.sort_by(f64::total_cmp);
        assert!(
            (zs[0] + 26.0).abs() < 1e-9 && (zs[1] + 20.0).abs() < 1e-9,
            "{t:?}"
        );
        assert!(
            (t.1[1] - x).abs() < 1e-9 && (t.2[1] - x).abs() < 1e-9,
            "{t:?}"
        );
    }
}

#[test]
fn g869_errors_name_what_is_wrong() {
    let text = program();
    let with = |cycle: &str| run_text(&text.replace("N23 G869 NS4 SB4 P3 O0.05 E0.04", cycle));
    let e = with("N23 G869 NS4 P3").unwrap_err();
    assert!(e.contains("cutting width SB"), "{e}");
    assert!(e.starts_with("t.nc:22:5:"), "{e}");
    let e = with("N23 G869 NS4 SB4").unwrap_err();
    assert!(e.contains("largest infeed P"), "{e}");
    let e = with("N23 G869 NS4 SB30 P3").unwrap_err();
    assert!(e.contains("narrower than SB30"), "{e}");
    let e = with("N23 G869 NS4 SB4 P3 R0.1").unwrap_err();
    assert!(e.contains("G869 R"), "{e}");
    let e = with("N23 G869 NS4 SB4 P-3").unwrap_err();
    assert!(e.contains("must be positive"), "{e}");
    let e = with("N23 G869 NS4 SB4 P3 Q3").unwrap_err();
    assert!(e.contains("expected 0 to 2"), "{e}");
    let e = with("N22 G0 X40 Z5\nN23 G869 NS4 SB4 P3").unwrap_err();
    assert!(e.contains("below the area's top"), "{e}");
    // the whole contour from N4 to N9 has two valleys at the depth of the first level
    let e = with("N22 G0 X64 Z5\nN23 G869 NS4 NE9 SB3 P3").unwrap_err();
    assert!(e.contains("several valleys"), "{e}");
}

#[test]
fn g869_refuses_more_levels_than_it_cuts() {
    // depth 10 with P0.004: 2500 levels
    let text = program().replace("N23 G869 NS4 SB4 P3", "N23 G869 NS4 SB4 P0.004");
    let e = run_text(&text).unwrap_err();
    assert!(e.contains("more than 2000"), "{e}");
    // P0.005: exactly 2000 levels of 0.005, each a plunge
    let text = program().replace("N23 G869 NS4 SB4 P3", "N23 G869 NS4 SB4 P0.005 Q1");
    let ops = run_text(&text).unwrap();
    let plunges = moves(&ops, 23)
        .iter()
        .filter(|c| c.0 == Feed::PerRevolution(0.05))
        .count();
    assert_eq!(plunges, 2000);
}

#[test]
fn g869_inside_a_bore_comes_from_the_axis() {
    let ops = run_text(&read("recess_turn_g869_inside.nc")).unwrap();
    // bore Ø20 (r10), recess Z-20..-36 out to Ø30 (r15); the tool starts at X10 (r5), below
    // the section's lowest point, so it cuts from the inside: depth 5 with P2 → ceil(2.5)
    // = 3 levels of 5/3 outwards: r11.667, 13.333, 15. SB4 with its +Z corner from Z-20 to
    // Z-32. The safety distance is 1 mm inside the bore: r9.
    let (f, o, e) = (
        Feed::PerRevolution(0.1),
        Feed::PerRevolution(0.05),
        Feed::PerRevolution(0.04),
    );
    let (l1, l2) = (10.0 + 5.0 / 3.0, 10.0 + 10.0 / 3.0);
    let want = [
        (RAPID, [-20.0, 5.0]),
        (RAPID, [-20.0, 9.0]),
        (o, [-20.0, l1]),
        (f, [-32.0, l1]),
        (o, [-32.0, l2]),
        (f, [-20.0, l2]),
        (o, [-20.0, 15.0]),
        (f, [-32.0, 15.0]),
        (RAPID, [-32.0, 9.0]),
        // finishing starts at the NS end: back to Z-20 at the safety distance, then out
        // along the wall, along the recess's floor, back in
        (RAPID, [-20.0, 9.0]),
        (e, [-20.0, 15.0]),
        (e, [-32.0, 15.0]),
        (e, [-32.0, 9.0]),
        // in along X to where it started, then back along Z
        (RAPID, [-32.0, 5.0]),
        (RAPID, [5.0, 5.0]),
    ];
    check(&moves(&ops, 23), &want);
}

#[test]
fn g869_inside_keeps_the_x_limit_and_refuses_a_start_between() {
    let text = read("recess_turn_g869_inside.nc");
    // X28: no cut beyond r14 → depth 4 with P2: 2 levels, r12 and r14
    let ops = run_text(&text.replace("N23 G869 NS3", "N23 G869 X28 Q1 NS3")).unwrap();
    let plunges: Vec<f64> = moves(&ops, 23)
        .iter()
        .filter(|c| c.0 == Feed::PerRevolution(0.05))
        .map(|c| c.2[1])
        .collect();
    assert_eq!(plunges, [12.0, 14.0]);
    // X24 (r12) lies between the bore (r10) and the recess's floor (r15)
    let e = run_text(&text.replace("N22 G0 X10 Z5", "N22 G0 X24 Z5")).unwrap_err();
    assert!(e.contains("below the area's top X30.000"), "{e}");
    assert!(e.starts_with("t.nc:17:"), "{e}");
}

#[test]
fn g869_on_a_face_plunges_along_z_and_turns_along_x() {
    let ops = run_text(&read("recess_turn_g869_face.nc")).unwrap();
    // face recess from r10 to r18, 6 deep (Z0 → Z-6); SB3 along X with the reference
    // corner at its +X end: from r13 to r18. Depth 6 with P2.5 → ceil(2.4) = 3 levels of
    // 2: Z-2, -4, -6. Start X40 Z5 (r20); safety distance Z1. The section runs from r10
    // (NS) towards r18, so the first plunge is at r13.
    let (f, o, e) = (
        Feed::PerRevolution(0.1),
        Feed::PerRevolution(0.05),
        Feed::PerRevolution(0.04),
    );
    let want = [
        (RAPID, [5.0, 13.0]),
        (RAPID, [1.0, 13.0]),
        (o, [-2.0, 13.0]),
        (f, [-2.0, 18.0]),
        (o, [-4.0, 18.0]),
        (f, [-4.0, 13.0]),
        (o, [-6.0, 13.0]),
        (f, [-6.0, 18.0]),
        (RAPID, [1.0, 18.0]),
        // finishing from the NS end: down the inner wall, along the floor, up the outer
        (RAPID, [1.0, 13.0]),
        (e, [-6.0, 13.0]),
        (e, [-6.0, 18.0]),
        (e, [1.0, 18.0]),
        // axial: out along Z first, then along X to the start
        (RAPID, [5.0, 18.0]),
        (RAPID, [5.0, 20.0]),
    ];
    check(&moves(&ops, 23), &want);
}

#[test]
fn g869_on_a_face_the_z_limit_bounds_the_depth() {
    let text = read("recess_turn_g869_face.nc");
    // Z-5: depth 5 with P2.5 → 2 levels, Z-2.5 and Z-5
    let ops = run_text(&text.replace("N23 G869 NS3", "N23 G869 Z-5 Q1 NS3")).unwrap();
    let plunges: Vec<[f64; 2]> = moves(&ops, 23)
        .iter()
        .filter(|c| c.0 == Feed::PerRevolution(0.05))
        .map(|c| c.2)
        .collect();
    assert_eq!(plunges, [[-2.5, 13.0], [-5.0, 18.0]]);
    // a tool standing in front of the face's top but inside the material's Z range
    let e = run_text(&text.replace("N22 G0 X40 Z5", "N22 G0 X40 Z-3")).unwrap_err();
    assert!(e.contains("starts at Z-3.000"), "{e}");
}

#[test]
fn g869_h2_stops_at_the_safety_distance() {
    let text = program();
    let h0 = moves(&run_text(&text).unwrap(), 23);
    let h2 = moves(
        &run_text(&text.replace("N23 G869 NS4", "N23 G869 H2 NS4")).unwrap(),
        23,
    );
    // the same cuts; the last one ends at the safety distance r26 above Z-36 and the two
    // retraction moves (out to r27, back to Z5) are left out
    assert_eq!(h2.len(), h0.len() - 2, "{h2:?}");
    assert_eq!(h2[..], h0[..h0.len() - 2]);
    assert_eq!(h2.last().map(|m| m.2), Some([-36.0, 26.0]));
    // inside, H2 ends in the bore at the safety distance r9 above Z-32
    let inside = read("recess_turn_g869_inside.nc").replace("N23 G869 NS3", "N23 G869 H2 NS3");
    let m = moves(&run_text(&inside).unwrap(), 23);
    assert_eq!(m.last().map(|m| m.2), Some([-32.0, 9.0]));
    let e = run_text(&text.replace("N23 G869 NS4", "N23 G869 H1 NS4")).unwrap_err();
    assert!(e.contains("H1"), "{e}");
    let e = run_text(&text.replace("N23 G869 NS4", "N23 G869 H3 NS4")).unwrap_err();
    assert!(e.contains("expected 0, 1 or 2"), "{e}");
}

/// A bore Ø20 with a recess from Z-20 to Z-36 whose floor is an arc of radius 10 about
/// (Z-28, r9), bulging outwards to r19 at Z-28; `arc` is the arc block.
fn arc_bore(arc: &str) -> String {
    format!(
        "FINISHED PART\nN1 G0 X20 Z0\nN2 G1 Z-20\nN3 G1 X30\n{arc}\nN5 G1 X20\nN6 G1 Z-60\n\
         MACHINING\nN20 T4\nN21 G97 S500 G95 F0.1 M3\nN22 G0 X10 Z5\n\
         N23 G869 NS3 NE5 SB4 P1.5 K0.2 O0.05 E0.04\nN24 M30\n"
    )
}

/// The bore's radius at `z` (the material lies outside it).
fn arc_bore_r(z: f64) -> f64 {
    if (-36.0..=-20.0).contains(&z) {
        9.0 + (100.0 - (z + 28.0).powi(2)).sqrt()
    } else {
        10.0
    }
}

#[test]
fn g869_inside_on_an_arc_floor_stays_off_the_material() {
    // which of G2/G3 bulges outwards is a property of the contour code; find it by the
    // cuts going beyond r18.5 (the other one bulges inwards, no deeper than r15, and
    // leaves two valleys, which G869 refuses)
    let runs: Vec<Vec<Op>> = ["N4 G2 X30 Z-36 R10", "N4 G3 X30 Z-36 R10"]
        .iter()
        .filter_map(|a| run_text(&arc_bore(a)).ok())
        .collect();
    assert_eq!(runs.len(), 1);
    let ops = runs
        .iter()
        .find(|ops| moves(ops, 23).iter().any(|m| m.2[1] > 18.5))
        .expect("one arc direction bulges outwards");
    let m = moves(ops, 23);
    // roughing: with K0.2 the window is z−4.2 … z+0.2; the deepest reach is where it is
    // centred on the arc's top: z = −28 + 2, window −30.2 … −25.8, r = 9 + √(100 − 2.2²)
    let bottom = 9.0 + (100.0f64 - 2.2 * 2.2).sqrt();
    let plunges: Vec<f64> = m
        .iter()
        .filter(|c| c.0 == Feed::PerRevolution(0.05))
        .map(|c| c.2[1])
        .collect();
    let n = ((bottom - 10.0) / 1.5).ceil();
    assert_eq!(plunges.len() as f64, n, "{plunges:?}");
    assert!(
        (plunges[plunges.len() - 1] - bottom).abs() < 1e-6,
        "{plunges:?}"
    );
    // no point of any move puts the tool (its +Z corner at p, 4 wide, its outer edge at
    // p's radius) beyond the bore's surface under its width
    for (_, from, to) in &m {
        for p in samples(*from, *to) {
            let wall = (1..200)
                .map(|i| arc_bore_r(p[0] - 4.0 * f64::from(i) / 200.0))
                .fold(f64::INFINITY, f64::min);
            assert!(p[1] <= wall + 1e-6, "{p:?} cuts into the material");
        }
    }
}

#[test]
fn g869_on_a_rear_face_comes_from_minus_z() {
    // a collar's rear face at Z-30 with a ring recess into it from r18 down to r10, 6 deep
    // (to Z-24); the tool stands at Z-40, behind the face, so it plunges along +Z. SB3
    // along X, reference corner at the +X end: r13 … r18; 3 levels of 2: Z-28, -26, -24;
    // safety distance Z-31. The section runs from r18 (NS) towards r10.
    let text = "FINISHED PART\nN1 G0 X20 Z0\nN2 G1 X60\nN3 G1 Z-30\nN4 G1 X36\n\
                N5 G1 Z-24\nN6 G1 X20\nN7 G1 Z-30\nN8 G1 X0\nMACHINING\nN20 T4\n\
                N21 G97 S500 G95 F0.1 M3\nN22 G0 X40 Z-40\n\
                N23 G869 NS5 NE7 SB3 P2.5 O0.05 E0.04\nN24 M30\n";
    let (f, o, e) = (
        Feed::PerRevolution(0.1),
        Feed::PerRevolution(0.05),
        Feed::PerRevolution(0.04),
    );
    let want = [
        (RAPID, [-40.0, 18.0]),
        (RAPID, [-31.0, 18.0]),
        (o, [-28.0, 18.0]),
        (f, [-28.0, 13.0]),
        (o, [-26.0, 13.0]),
        (f, [-26.0, 18.0]),
        (o, [-24.0, 18.0]),
        (f, [-24.0, 13.0]),
        (RAPID, [-31.0, 13.0]),
        (RAPID, [-31.0, 18.0]),
        (e, [-24.0, 18.0]),
        (e, [-24.0, 13.0]),
        (e, [-31.0, 13.0]),
        (RAPID, [-40.0, 13.0]),
        (RAPID, [-40.0, 20.0]),
    ];
    check(&moves(&run_text(text).unwrap(), 23), &want);
}

#[test]
fn g869_ns_equal_ne_runs_the_element_backwards() {
    // N3 alone: a slope from r30 at Z-10 down to r24 at Z-22, r = 30 + (z + 10)/2. SB2:
    // standing at z the tool reaches r(z), from Z-20 (r25) to Z-10. Depth 5 with P3: r27.5
    // (Z-20 … -15) and r25 (Z-20 only). Start X64 Z5 (r32), safety r31.
    let at = |cycle: &str| {
        let t = format!(
            "FINISHED PART\nN1 G0 X60 Z0\nN2 G1 Z-10\nN3 G1 X48 Z-22\nN4 G1 Z-40\n\
             MACHINING\nN20 T4\nN21 G97 S500 G95 F0.1 M3\nN22 G0 X64 Z5\n{cycle}\nN24 M30\n"
        );
        moves(&run_text(&t).unwrap(), 23)
    };
    let f = Feed::PerRevolution(0.1);
    // NS3 alone: the element runs towards −Z, the first plunge at its +Z end
    let forward = at("N23 G869 NS3 SB2 P3");
    let first = forward[0].2;
    assert!(
        (first[0] + 15.0).abs() < 1e-8 && first[1] == 32.0,
        "{forward:?}"
    );
    // NS3 NE3: against its direction, from Z-22 towards Z-10: first plunge at Z-20
    let want = [
        (RAPID, [-20.0, 32.0]),
        (RAPID, [-20.0, 31.0]),
        (f, [-20.0, 27.5]),
        (f, [-15.0, 27.5]),
        (f, [-20.0, 27.5]),
        (f, [-20.0, 25.0]),
        (RAPID, [-20.0, 31.0]),
        // finishing from the new NS end (Z-20) up the slope
        (f, [-20.0, 25.0]),
        (f, [-10.0, 30.0]),
        (f, [-10.0, 31.0]),
        (RAPID, [-10.0, 32.0]),
        (RAPID, [5.0, 32.0]),
    ];
    check(&at("N23 G869 NS3 NE3 SB2 P3"), &want);
}
