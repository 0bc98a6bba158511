//! Recess turning G869 with the offset width B: the shortened passes back to the NS end,
//! their offsets growing by B up to 0.8·SB, and the single clean-up cut, against moves
//! worked out by hand; a check that no cut enters the contour; the refusals.

mod common;
use common::lathe::{block_lines as moves, check_moves as check, lathe_program, run_text, samples};
use common::recess::{RAPID, overlap, sloped};
use klar_interp::Feed;

fn program() -> String {
    lathe_program("recess_turn_g869_offset.nc")
}

const F: Feed = Feed::PerRevolution(0.1);
const O: Feed = Feed::PerRevolution(0.05);
const E: Feed = Feed::PerRevolution(0.04);

#[test]
fn g869_b_shortens_the_passes_back_to_the_ns_end_and_clears_them_in_one_plunge() {
    let ops = run_text(&program()).unwrap();
    // recess Z-20..-40 from r25 to r15, SB4: the +Z corner turns from Z-20 (NS) to Z-36.
    // P2: 5 levels r23, 21, 19, 17, 15. Passes 2 and 4 run back to the NS end and turn
    // into a plunge: short by B2 = 2, then by 2·2 = 4, cut down to 0.8·4 = 3.2. The last
    // pass runs to the NE end. Left at Z-20: levels 2 to 5; level 1 was cut there down to
    // r23, so the clean-up comes down at rapid to r24 and plunges to r15.
    let want = [
        (RAPID, [-20.0, 27.0]),
        (RAPID, [-20.0, 26.0]),
        (O, [-20.0, 23.0]),
        (F, [-36.0, 23.0]),
        (O, [-36.0, 21.0]),
        (F, [-22.0, 21.0]),
        (O, [-22.0, 19.0]),
        (F, [-36.0, 19.0]),
        (O, [-36.0, 17.0]),
        (F, [-23.2, 17.0]),
        (O, [-23.2, 15.0]),
        (F, [-36.0, 15.0]),
        (RAPID, [-36.0, 26.0]),
        // the single cut at the NS end
        (RAPID, [-20.0, 26.0]),
        (RAPID, [-20.0, 24.0]),
        (O, [-20.0, 15.0]),
        (RAPID, [-20.0, 26.0]),
        // finishing and the retraction as without B
        (E, [-20.0, 15.0]),
        (E, [-36.0, 15.0]),
        (E, [-36.0, 26.0]),
        (RAPID, [-36.0, 27.0]),
        (RAPID, [5.0, 27.0]),
    ];
    check(&moves(&ops, 23), &want);
}

#[test]
fn g869_b_offsets_grow_by_b_to_the_limit_and_spare_the_last_pass() {
    // B1 with P1: 10 levels r24 … r15. The passes back to Z-20 on levels 2, 4, 6, 8 stop
    // at Z-21, -22, -23 and -23.2 (0.8·SB4 = 3.2 < 4); the one on level 10 is the last
    // and turns into no plunge: it runs to Z-20. Left at Z-20: levels 2 to 9; the clean-up
    // comes down at rapid to r25 (level 1 at r24 was cut there) and plunges to r16.
    let text = program().replace("N23 G869 NS4 SB4 P2 B2", "N23 G869 NS4 SB4 P1 B1 Q1");
    let ops = run_text(&text).unwrap();
    let m = moves(&ops, 23);
    let turns: Vec<f64> = m.iter().filter(|c| c.0 == F).map(|c| c.2[0]).collect();
    let want = [
        -36.0, -21.0, -36.0, -22.0, -36.0, -23.0, -36.0, -23.2, -36.0, -20.0,
    ];
    assert_eq!(turns.len(), want.len(), "{turns:?}");
    for (g, w) in turns.iter().zip(want) {
        assert!((g - w).abs() < 1e-9, "{turns:?}");
    }
    let last_turn = m.iter().rposition(|c| c.0 == F).unwrap();
    check(
        &m[last_turn + 1..],
        &[
            (RAPID, [-20.0, 26.0]),
            (RAPID, [-20.0, 25.0]),
            (O, [-20.0, 16.0]),
            (RAPID, [-20.0, 26.0]),
            // Q1: no finishing; back out in X, then along Z
            (RAPID, [-20.0, 27.0]),
            (RAPID, [5.0, 27.0]),
        ],
    );
}

#[test]
fn g869_b_on_sloped_walls_follows_the_stretches_and_cleans_up_one_level() {
    let ops = run_text(&program()).unwrap();
    // SB3, K0.5, I1: three levels r27.5 (Z-72 … -83), r25 (Z-73.25 … -81.75) and r22.5
    // (Z-74.5 … -80.5), the NS end at +Z. Level 2 runs back towards Z-73.25 and turns into
    // a plunge: it stops B1 short, at Z-74.25. Level 3's stretch begins at Z-74.5, so its
    // plunge moves there first and its pass starts at its NS end: only level 2 is left at
    // Z-73.25, cleared from r28.5 (1 above level 1) down to r25. Start X64 Z-65 (r32),
    // safety r31; O and E are the active feed.
    let want = [
        (RAPID, [-72.0, 32.0]),
        (RAPID, [-72.0, 31.0]),
        (F, [-72.0, 27.5]),
        (F, [-83.0, 27.5]),
        (F, [-81.75, 27.5]),
        (F, [-81.75, 25.0]),
        (F, [-74.25, 25.0]),
        (F, [-74.5, 25.0]),
        (F, [-74.5, 22.5]),
        (F, [-80.5, 22.5]),
        (RAPID, [-80.5, 31.0]),
        (RAPID, [-73.25, 31.0]),
        (RAPID, [-73.25, 28.5]),
        (F, [-73.25, 25.0]),
        (RAPID, [-73.25, 31.0]),
        // finishing on the contour, as without B
        (RAPID, [-70.0, 31.0]),
        (F, [-70.0, sloped(-73.0, -70.0)]),
        (F, [-71.0, sloped(-74.0, -71.0)]),
        (F, [-74.0, sloped(-77.0, -74.0)]),
        (F, [-81.0, sloped(-84.0, -81.0)]),
        (F, [-84.0, sloped(-87.0, -84.0)]),
        (F, [-85.0, sloped(-88.0, -85.0)]),
        (F, [-85.0, 31.0]),
        (RAPID, [-85.0, 32.0]),
        (RAPID, [-65.0, 32.0]),
    ];
    check(&moves(&ops, 25), &want);
}

#[test]
fn g869_b_never_cuts_into_the_contour() {
    let text = program();
    for b in ["B0.7", "B2", "B5"] {
        let t = text
            .replace("P2 B2", &format!("P1.3 {b}"))
            .replace("P3 I1 K0.5 B1", &format!("P0.9 I1 K0.5 {b}"));
        let ops = run_text(&t).unwrap();
        for (n, w) in [(23, 4.0), (25, 3.0)] {
            for (_, from, to) in moves(&ops, n) {
                for p in samples(from, to) {
                    assert!(overlap(p, w) < 1e-6, "{b} N{n}: {p:?} cuts the contour");
                }
            }
        }
    }
}

#[test]
fn g869_b_refusals_name_the_word() {
    let text = program();
    let with = |cycle: &str| run_text(&text.replace("N23 G869 NS4 SB4 P2 B2", cycle));
    let e = with("N23 G869 NS4 SB4 P2 B-1").unwrap_err();
    assert!(e.starts_with("t.nc:23:21:"), "{e}");
    assert!(e.contains("B-1 must not be negative"), "{e}");
    let e = with("N23 G869 NS4 SB4 P2 B1 U1").unwrap_err();
    assert!(e.starts_with("t.nc:23:21:"), "{e}");
    assert!(e.contains("G869 B with U1"), "{e}");
    // B0 and U1 together are fine: no offset
    let plain = run_text(&text.replace("P2 B2", "P2 U1")).unwrap();
    let zero = run_text(&text.replace("P2 B2", "P2 B0 U1")).unwrap();
    assert_eq!(moves(&plain, 23), moves(&zero, 23));
}

#[test]
fn g869_b_on_a_face_shortens_along_x() {
    let text = lathe_program("recess_turn_g869_face.nc").replace("SB3 P2.5", "SB3 P1.5 B0.5");
    let ops = run_text(&text).unwrap();
    // face ring recess r10 … r18, Z0 → Z-6, SB3 along X with its reference corner at the
    // +X end: r13 (NS) … r18. P1.5: 4 levels Z-1.5, -3, -4.5, -6. The pass back to r13 on
    // level 2 turns into a plunge: B0.5 short, at r13.5; the one on level 4 is the last and
    // runs to r13. Left at r13: levels 2 and 3, cleared from Z-0.5 (1 above level 1) down
    // to Z-4.5. Start X40 Z5, safety Z1.
    let want = [
        (RAPID, [5.0, 13.0]),
        (RAPID, [1.0, 13.0]),
        (O, [-1.5, 13.0]),
        (F, [-1.5, 18.0]),
        (O, [-3.0, 18.0]),
        (F, [-3.0, 13.5]),
        (O, [-4.5, 13.5]),
        (F, [-4.5, 18.0]),
        (O, [-6.0, 18.0]),
        (F, [-6.0, 13.0]),
        (RAPID, [1.0, 13.0]),
        (RAPID, [-0.5, 13.0]),
        (O, [-4.5, 13.0]),
        (RAPID, [1.0, 13.0]),
        (E, [-6.0, 13.0]),
        (E, [-6.0, 18.0]),
        (E, [1.0, 18.0]),
        (RAPID, [5.0, 18.0]),
        (RAPID, [5.0, 20.0]),
    ];
    check(&moves(&ops, 23), &want);
}
