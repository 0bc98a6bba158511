//! Tool radius compensation against independent constructions: closed-form offset points,
//! and dense sampling of the tool-centre path measured against the programmed contour.

mod comp_support;

use comp_support::*;
use klar_interp::{AxisLetter, CompSide, Op, OpKind, Pose};
use klar_motion::comp::{CompError, Compensator};

/// A little program builder: tracks the programmed position and numbers the blocks.
struct Prog {
    ops: Vec<Op>,
    pos: Pose,
    line: u32,
}

impl Prog {
    fn new(tool: f64) -> Prog {
        Prog {
            ops: vec![tool_op(1, tool)],
            pos: Pose::ZERO,
            line: 1,
        }
    }
    fn next(&mut self) -> u32 {
        self.line += 1;
        self.line
    }
    fn comp(&mut self, side: CompSide) -> u32 {
        let l = self.next();
        self.ops.push(comp_op(l, side));
        l
    }
    /// Line in the plane to (x, y); returns its block line.
    fn l(&mut self, x: f64, y: f64) -> u32 {
        let l = self.next();
        let mut to = self.pos;
        to[AxisLetter::X] = x;
        to[AxisLetter::Y] = y;
        self.ops.push(line_op(l, self.pos, to));
        self.pos = to;
        l
    }
    /// Line in the tool axis only.
    fn lz(&mut self, z: f64) -> u32 {
        let l = self.next();
        let mut to = self.pos;
        to[AxisLetter::Z] = z;
        self.ops.push(line_op(l, self.pos, to));
        self.pos = to;
        l
    }
    /// Arc about `c` through `sweep` degrees, with `dz` of helix travel.
    fn c(&mut self, c: [f64; 2], sweep: f64, dz: f64) -> u32 {
        let l = self.next();
        let mut to = arc_end(self.pos, c, sweep);
        to[AxisLetter::Z] += dz;
        self.ops.push(arc_op(l, self.pos, to, c, sweep));
        self.pos = to;
        l
    }
    fn op(&mut self, kind: OpKind) -> u32 {
        let l = self.next();
        self.ops.push(Op { kind, loc: at(l) });
        l
    }
    /// The programmed contour pieces of blocks `lines`.
    fn contour(&self, lines: std::ops::RangeInclusive<u32>) -> Vec<Piece> {
        let sel: Vec<Op> = self
            .ops
            .iter()
            .filter(|o| lines.contains(&o.loc.line))
            .cloned()
            .collect();
        pieces(&sel)
    }
}

/// Expected motion: a line ending at a point, or an arc with centre, sweep (deg) and end.
#[derive(Debug)]
enum Want {
    L([f64; 2]),
    A([f64; 2], f64, [f64; 2]),
}

fn assert_path(out: &[Op], want: &[Want]) {
    let m = motions(out);
    assert_eq!(m.len(), want.len(), "motion ops: {m:#?}");
    for (op, w) in m.iter().zip(want) {
        match (w, &op.kind) {
            (Want::L(e), OpKind::Line { .. }) => {
                assert!(close(end_xy(op), *e, 1e-9), "{op:?} should end at {e:?}")
            }
            (Want::A(c, s, e), OpKind::Arc { center, sweep, .. }) => {
                assert!(
                    close(*center, *c, 1e-9),
                    "{op:?} should be centred at {c:?}"
                );
                assert!((sweep - s).abs() < 1e-9, "{op:?} should sweep {s}°");
                assert!(close(end_xy(op), *e, 1e-9), "{op:?} should end at {e:?}");
            }
            _ => panic!("{op:?} is not the expected {w:?}"),
        }
    }
}

/// The rectangle (0,0)-(100,50) counter-clockwise, entered from (50,-20) to the middle of
/// its first edge (the manual warns against starting inside-corner work at a corner).
fn rectangle(side: CompSide, r: f64) -> (Prog, Pose) {
    let mut g = Prog::new(r);
    g.pos = p(50.0, -20.0);
    g.comp(side); // 2
    g.l(50.0, 0.0); // 3: switches compensation on
    g.l(100.0, 0.0); // 4
    g.l(100.0, 50.0); // 5
    g.l(0.0, 50.0); // 6
    g.l(0.0, 0.0); // 7
    g.l(50.0, 0.0); // 8
    g.comp(CompSide::Off); // 9
    g.l(50.0, -20.0); // 10
    (g, p(50.0, -20.0))
}

#[test]
fn rectangle_rl_meets_inside_corners_at_their_intersections() {
    let r = 5.0;
    let (g, start) = rectangle(CompSide::Left, r);
    let out = run(start, g.ops.clone()).expect("valid contour");
    assert_continuous(start, &out);
    // Inside the counter-clockwise rectangle: the offset lines meet at (100-r, r) etc.
    assert_path(
        &out,
        &[
            Want::L([50.0, r]),
            Want::L([100.0 - r, r]),
            Want::L([100.0 - r, 50.0 - r]),
            Want::L([r, 50.0 - r]),
            Want::L([r, r]),
            Want::L([50.0, r]),
            Want::L([50.0, -20.0]),
        ],
    );
    let worst = worst_offset_error(&out, &g.contour(4..=8), r, |l| (4..=8).contains(&l));
    assert!(worst < 1e-6, "offset error {worst}");
}

#[test]
fn rectangle_rr_rolls_around_outside_corners_centred_on_them() {
    let r = 5.0;
    let (g, start) = rectangle(CompSide::Right, r);
    let out = run(start, g.ops.clone()).expect("valid contour");
    assert_continuous(start, &out);
    assert_arcs_consistent(&out);
    assert_path(
        &out,
        &[
            Want::L([50.0, -r]),
            Want::L([100.0, -r]),
            Want::A([100.0, 0.0], 90.0, [100.0 + r, 0.0]),
            Want::L([100.0 + r, 50.0]),
            Want::A([100.0, 50.0], 90.0, [100.0, 50.0 + r]),
            Want::L([0.0, 50.0 + r]),
            Want::A([0.0, 50.0], 90.0, [-r, 50.0]),
            Want::L([-r, 0.0]),
            Want::A([0.0, 0.0], 90.0, [0.0, -r]),
            Want::L([50.0, -r]),
            Want::L([50.0, -20.0]),
        ],
    );
    let worst = worst_offset_error(&out, &g.contour(4..=8), r, |l| (4..=8).contains(&l));
    assert!(worst < 1e-6, "offset error {worst}");
}

#[test]
fn collinear_blocks_add_nothing() {
    let mut g = Prog::new(2.0);
    g.pos = p(0.0, -10.0);
    g.comp(CompSide::Left);
    g.l(0.0, 0.0);
    g.l(10.0, 0.0);
    g.l(20.0, 0.0);
    g.l(35.0, 0.0);
    let out = run(p(0.0, -10.0), g.ops).unwrap();
    assert_path(
        &out,
        &[
            Want::L([0.0, 2.0]),
            Want::L([10.0, 2.0]),
            Want::L([20.0, 2.0]),
            Want::L([35.0, 2.0]),
        ],
    );
}

#[test]
fn reversal_of_180_degrees_is_a_half_circle_around_the_turning_point() {
    let r = 2.0;
    let mut g = Prog::new(r);
    g.pos = p(0.0, -10.0);
    g.comp(CompSide::Left);
    g.l(0.0, 0.0); // 3
    g.l(10.0, 0.0); // 4
    g.l(0.0, 0.0); // 5
    let out = run(p(0.0, -10.0), g.ops.clone()).unwrap();
    assert_continuous(p(0.0, -10.0), &out);
    // Left of +X is +Y; left of −X is −Y: the tool turns clockwise around (10, 0).
    assert_path(
        &out,
        &[
            Want::L([0.0, r]),
            Want::L([10.0, r]),
            Want::A([10.0, 0.0], -180.0, [10.0, -r]),
            Want::L([0.0, -r]),
        ],
    );
    let worst = worst_offset_error(&out, &g.contour(4..=5), r, |l| (4..=5).contains(&l));
    assert!(worst < 1e-6, "offset error {worst}");
}

#[test]
fn inside_line_corner_at_the_bisector_intersection() {
    // Turning left by 120° with RL: the offset lines meet on the bisector of the 60° corner,
    // at R / sin 30° = 2R from the corner.
    let r = 1.5;
    let mut g = Prog::new(r);
    g.pos = p(0.0, -10.0);
    g.comp(CompSide::Left);
    g.l(0.0, 0.0);
    g.l(10.0, 0.0);
    let a = 120f64.to_radians();
    g.l(10.0 + 10.0 * a.cos(), 10.0 * a.sin());
    let out = run(p(0.0, -10.0), g.ops.clone()).unwrap();
    let bis = 150f64.to_radians();
    let x = [10.0 + 2.0 * r * bis.cos(), 2.0 * r * bis.sin()];
    let m = motions(&out);
    assert!(close(end_xy(m[1]), x, 1e-9), "{:?} vs {x:?}", m[1]);
    assert!(close(start_xy(m[2]), x, 1e-9));
    let worst = worst_offset_error(&out, &g.contour(4..=5), r, |l| (4..=5).contains(&l));
    assert!(worst < 1e-6, "offset error {worst}");
}

#[test]
fn inside_line_arc_corner_at_the_line_circle_intersection() {
    // Line along y = 0, then a counter-clockwise arc about (-6, 8), radius 10, starting at
    // the origin: a left turn of 36.87°, inside for RL. Offset line y = r, offset circle
    // radius 10 − r: they meet at x = −6 + √((10 − r)² − (8 − r)²).
    let r = 2.0;
    let mut g = Prog::new(r);
    g.pos = p(-20.0, -10.0);
    g.comp(CompSide::Left);
    g.l(-20.0, 0.0); // 3
    g.l(0.0, 0.0); // 4
    g.c([-6.0, 8.0], 90.0, 0.0); // 5
    let out = run(p(-20.0, -10.0), g.ops.clone()).unwrap();
    assert_arcs_consistent(&out);
    let x = [-6.0 + ((10.0 - r).powi(2) - (8.0 - r).powi(2)).sqrt(), r];
    let m = motions(&out);
    assert!(close(end_xy(m[1]), x, 1e-9), "{:?} vs {x:?}", m[1]);
    assert!(close(start_xy(m[2]), x, 1e-9));
    let worst = worst_offset_error(&out, &g.contour(4..=5), r, |l| (4..=5).contains(&l));
    assert!(worst < 1e-6, "offset error {worst}");
}

#[test]
fn tangent_line_arc_and_arc_arc_joins_add_nothing() {
    // A stadium (two lines, two half circles, all tangent) then an S of two tangent arcs.
    for side in [CompSide::Left, CompSide::Right] {
        let r = 1.0;
        let mut g = Prog::new(r);
        g.pos = p(0.0, -10.0);
        g.comp(side);
        g.l(0.0, 0.0); // 3
        g.l(20.0, 0.0); // 4
        g.c([20.0, 5.0], 180.0, 0.0); // 5
        g.l(0.0, 10.0); // 6
        g.c([0.0, 15.0], -90.0, 0.0); // 7: clockwise, tangent to the line (heading −X)
        g.c([-10.0, 15.0], 90.0, 0.0); // 8: counter-clockwise, tangent S join
        let out = run(p(0.0, -10.0), g.ops.clone()).unwrap();
        assert_continuous(p(0.0, -10.0), &out);
        assert_arcs_consistent(&out);
        // No transition arcs: one motion op per block.
        assert_eq!(motions(&out).len(), 6, "{out:#?}");
        let worst = worst_offset_error(&out, &g.contour(4..=8), r, |l| (4..=8).contains(&l));
        assert!(worst < 1e-6, "{side:?}: offset error {worst}");
    }
}

#[test]
fn full_circle_inside_and_outside() {
    for (side, want) in [(CompSide::Left, 8.0), (CompSide::Right, 12.0)] {
        let mut g = Prog::new(2.0);
        g.pos = p(0.0, 0.0);
        g.comp(side);
        g.l(10.0, 0.0); // 3
        g.c([0.0, 0.0], 360.0, 0.0); // 4
        let out = run(p(0.0, 0.0), g.ops.clone()).unwrap();
        assert_arcs_consistent(&out);
        let m = motions(&out);
        assert_eq!(m.len(), 2);
        assert!(close(end_xy(m[0]), [want, 0.0], 1e-9));
        match &m[1].kind {
            OpKind::Arc { center, sweep, .. } => {
                assert_eq!(*center, [0.0, 0.0]);
                assert!((sweep - 360.0).abs() < 1e-9);
            }
            k => panic!("{k:?}"),
        }
        assert!(close(end_xy(m[1]), [want, 0.0], 1e-9));
        let worst = worst_offset_error(&out, &g.contour(4..=4), 2.0, |l| l == 4);
        assert!(worst < 1e-6);
    }
}

/// The thread table of the helix page: (internal?, work direction Z+, right-hand?, DR+?,
/// compensation). Internal threads put the tool inside the programmed radius.
const THREADS: [(bool, bool, bool, bool, CompSide); 8] = [
    (true, true, true, true, CompSide::Left),
    (true, true, false, false, CompSide::Right),
    (true, false, true, false, CompSide::Right),
    (true, false, false, true, CompSide::Left),
    (false, true, true, true, CompSide::Right),
    (false, true, false, false, CompSide::Left),
    (false, false, true, false, CompSide::Left),
    (false, false, false, true, CompSide::Right),
];

#[test]
fn helix_thread_table_offsets_radius_inwards_or_outwards() {
    let (radius, tool, pitch, turns) = (20.0, 3.0, 1.5, 2.0);
    for (internal, up, right_hand, ccw, side) in THREADS {
        // The table itself: a right-hand thread turns counter-clockwise while rising.
        assert_eq!(right_hand, up == ccw);
        let sweep = if ccw { 360.0 * turns } else { -360.0 * turns };
        let dz = if up { pitch * turns } else { -pitch * turns };
        let mut g = Prog::new(tool);
        g.pos = p(0.0, 0.0);
        g.comp(side);
        g.l(radius, 0.0); // 3
        g.c([0.0, 0.0], sweep, dz); // 4: the helix
        g.comp(CompSide::Off);
        g.l(0.0, 0.0);
        let out = run(p(0.0, 0.0), g.ops.clone()).unwrap();
        assert_continuous(p(0.0, 0.0), &out);
        let want = if internal {
            radius - tool
        } else {
            radius + tool
        };
        let helix: Vec<&Op> = motions(&out)
            .into_iter()
            .filter(|o| o.loc.line == 4)
            .collect();
        assert_eq!(helix.len(), 1);
        let OpKind::Arc {
            from,
            to,
            center,
            sweep: s,
            ..
        } = &helix[0].kind
        else {
            panic!("helix is not an arc: {:?}", helix[0]);
        };
        let r_out = (from[AxisLetter::X] - center[0]).hypot(from[AxisLetter::Y] - center[1]);
        assert!(
            (r_out - want).abs() < 1e-9,
            "internal={internal} {side:?}: radius {r_out}, want {want}"
        );
        assert!((s - sweep).abs() < 1e-9);
        assert!((to[AxisLetter::Z] - from[AxisLetter::Z] - dz).abs() < 1e-12);
        // Every sample of the compensated helix lies at the tool radius from the programmed
        // helix in the plane, and its height follows the programmed pitch.
        for q in sample(helix[0], 500) {
            let d = contour_dist([q[AxisLetter::X], q[AxisLetter::Y]], &g.contour(4..=4));
            assert!((d - tool).abs() < 1e-6);
        }
    }
}

#[test]
fn tool_larger_than_an_inside_arc_is_refused_naming_the_block() {
    let mut g = Prog::new(5.0);
    g.pos = p(0.0, 0.0);
    g.comp(CompSide::Left);
    g.l(3.0, 0.0); // 3
    let arc = g.c([0.0, 0.0], 180.0, 0.0); // 4: radius 3, tool inside
    let err = run(p(0.0, 0.0), g.ops).unwrap_err();
    match &err {
        CompError::ArcTooSmall { loc, arc: a, tool } => {
            assert_eq!(loc.line, arc);
            assert_eq!((*a, *tool), (3.0, 5.0));
        }
        e => panic!("{e}"),
    }
    assert!(err.to_string().contains(&format!("line {arc}")));
}

/// A contour along y = 0 with a slot of `width` going down 20 mm at x = 40.
fn slot(width: f64, r: f64) -> Prog {
    let mut g = Prog::new(r);
    g.pos = p(0.0, 10.0);
    g.comp(CompSide::Left);
    g.l(0.0, 0.0); // 3
    g.l(40.0, 0.0); // 4
    g.l(40.0, -20.0); // 5: slot wall
    g.l(40.0 + width, -20.0); // 6: slot bottom
    g.l(40.0 + width, 0.0); // 7: slot wall
    g.l(80.0, 0.0); // 8
    g.l(100.0, 0.0); // 9
    g
}

#[test]
fn narrow_slot_is_refused_before_its_motion_is_released() {
    let g = slot(4.0, 5.0);
    let mut c = Compensator::new(p(0.0, 10.0));
    let mut popped = Vec::new();
    let mut err = None;
    for op in g.ops {
        if let Err(e) = c.push(op) {
            err = Some(e);
            break;
        }
        while let Some(o) = c.pop() {
            popped.push(o);
        }
    }
    match err.expect("the slot is narrower than the tool") {
        CompError::RunsBackwards {
            blocks, overlap, ..
        } => {
            let lines: Vec<u32> = blocks.iter().map(|l| l.line).collect();
            assert_eq!(lines, vec![5, 6, 7]);
            // The bottom's offset would need 2R = 10 mm but is 4 mm long.
            assert!((overlap - 6.0).abs() < 1e-9, "overlap {overlap}");
        }
        e => panic!("{e}"),
    }
    assert!(
        popped.iter().all(|o| !(5..=7).contains(&o.loc.line)),
        "motion into the slot was released: {popped:#?}"
    );
    assert!(c.pop().is_none());
}

#[test]
fn slot_wider_than_the_tool_is_cut_with_intersections() {
    let r = 5.0;
    let g = slot(12.0, r);
    let out = run(p(0.0, 10.0), g.ops.clone()).unwrap();
    let m = motions(&out);
    // In the slot: walls at x = 40 + r and 52 − r, bottom at y = −20 + r.
    let bottom: Vec<&&Op> = m.iter().filter(|o| o.loc.line == 6).collect();
    assert_eq!(bottom.len(), 1);
    assert!(close(start_xy(bottom[0]), [40.0 + r, -20.0 + r], 1e-9));
    assert!(close(end_xy(bottom[0]), [52.0 - r, -20.0 + r], 1e-9));
    let worst = worst_offset_error(&out, &g.contour(4..=9), r, |l| (4..=9).contains(&l));
    assert!(worst < 1e-6);
}

#[test]
fn non_motion_ops_keep_their_place_between_elements() {
    let mut g = Prog::new(1.0);
    g.pos = p(0.0, -5.0);
    g.comp(CompSide::Right);
    g.l(0.0, 0.0); // 3
    g.l(10.0, 0.0); // 4
    let cool = g.op(OpKind::Coolant { on: true }); // 5
    g.l(10.0, 10.0); // 6
    let out = run(p(0.0, -5.0), g.ops).unwrap();
    let lines: Vec<u32> = out.iter().map(|o| o.loc.line).collect();
    let at_cool = lines.iter().position(|&l| l == cool).unwrap();
    assert!(lines[..at_cool].contains(&4));
    assert!(lines[at_cool..].iter().all(|&l| l == cool || l >= 4));
    assert!(!lines[..at_cool].contains(&6));
}

#[test]
fn off_plane_move_inside_a_contour_happens_at_the_compensated_corner() {
    let r = 2.0;
    let mut g = Prog::new(r);
    g.pos = p(0.0, -5.0);
    g.comp(CompSide::Left);
    g.l(0.0, 0.0); // 3
    g.l(10.0, 0.0); // 4
    let plunge = g.lz(-3.0); // 5
    g.l(10.0, 10.0); // 6: left turn, inside corner for RL
    let out = run(p(0.0, -5.0), g.ops).unwrap();
    assert_continuous(p(0.0, -5.0), &out);
    let z: Vec<&Op> = out.iter().filter(|o| o.loc.line == plunge).collect();
    assert_eq!(z.len(), 1);
    let OpKind::Line { from, to, .. } = &z[0].kind else {
        panic!()
    };
    assert!(close(start_xy(z[0]), [10.0 - r, r], 1e-9));
    assert!(close(end_xy(z[0]), [10.0 - r, r], 1e-9));
    assert_eq!((from[AxisLetter::Z], to[AxisLetter::Z]), (0.0, -3.0));
}

#[test]
fn stream_is_bounded_and_lags_by_the_lookahead() {
    // A long zigzag: the output never lags the input by more than the window.
    let mut c = Compensator::new(p(0.0, -5.0));
    c.push(tool_op(1, 0.5)).unwrap();
    c.push(comp_op(2, CompSide::Left)).unwrap();
    let mut prev = p(0.0, -5.0);
    let mut released = 0usize;
    for i in 0..5000u32 {
        let to = p(f64::from(i) * 3.0, if i % 2 == 0 { 0.0 } else { 2.0 });
        c.push(line_op(10 + i, prev, to)).unwrap();
        prev = to;
        while let Some(o) = c.pop() {
            if o.kind.is_motion() {
                released += 1;
            }
        }
        // Elements pushed minus released motion ops, counting transition arcs as extra
        // output: the window holds the pending element plus DEFAULT_LOOKAHEAD finished ones.
        let pushed = i as usize + 1;
        assert!(pushed <= released + 1 + klar_motion::comp::DEFAULT_LOOKAHEAD);
    }
    c.finish().unwrap();
}

#[test]
fn lookahead_zero_releases_each_element_once_its_corner_is_known() {
    let mut c = Compensator::with_lookahead(p(0.0, -5.0), 0);
    c.push(tool_op(1, 1.0)).unwrap();
    c.push(comp_op(2, CompSide::Left)).unwrap();
    while c.pop().is_some() {}
    c.push(line_op(3, p(0.0, -5.0), p(0.0, 0.0))).unwrap();
    assert!(c.needs_input());
    c.push(line_op(4, p(0.0, 0.0), p(10.0, 0.0))).unwrap();
    let o = c.pop().expect("the lead-in is complete");
    assert_eq!(o.loc.line, 3);
    assert!(c.pop().is_none());
}

#[test]
fn lines_and_bumps_keep_the_offset_on_both_sides() {
    // Lines alternating with clockwise half-circle bumps at changing heights: outside and
    // inside corners between lines and arcs on either side.
    for side in [CompSide::Left, CompSide::Right] {
        let r = 1.0;
        let mut g = Prog::new(r);
        g.pos = p(0.0, -10.0);
        g.comp(side);
        g.l(0.0, 0.0); // 3
        for i in 0..40 {
            let x = g.pos[AxisLetter::X];
            let y = g.pos[AxisLetter::Y];
            if i % 2 == 0 {
                g.l(x + 10.0, if i % 4 == 0 { 0.0 } else { 3.0 });
            } else {
                g.c([x + 4.0, y], -180.0, 0.0);
            }
        }
        let last = g.line;
        let out = run(p(0.0, -10.0), g.ops.clone()).unwrap();
        assert_continuous(p(0.0, -10.0), &out);
        assert_arcs_consistent(&out);
        let blocks: Vec<u32> = motions(&out).iter().map(|o| o.loc.line).collect();
        assert_eq!(blocks.last(), Some(&last));
        let worst = worst_offset_error(&out, &g.contour(4..=last), r, |l| l >= 4);
        assert!(worst < 1e-6, "{side:?}: offset error {worst}");
    }
}

/// A square spiral: out along y = 0, up, back, down to `low`, and right again above the
/// first block, ending 15 mm short of the second.
fn spiral(r: f64, low: f64) -> Prog {
    let mut g = Prog::new(r);
    g.pos = p(0.0, -10.0);
    g.comp(CompSide::Left);
    g.l(0.0, 0.0); // 3
    g.l(30.0, 0.0); // 4
    g.l(30.0, 20.0); // 5
    g.l(5.0, 20.0); // 6
    g.l(5.0, low); // 7
    g.l(15.0, low); // 8
    g
}

#[test]
fn gouge_several_blocks_apart_is_refused_naming_both_blocks() {
    // Block 7 comes down to y = 3, within the tool radius of block 4's tool path at y = 5.
    let g = spiral(5.0, 3.0);
    match run(p(0.0, -10.0), g.ops).unwrap_err() {
        CompError::Gouge {
            blocks, distance, ..
        } => {
            let lines: Vec<u32> = blocks.iter().map(|l| l.line).collect();
            assert_eq!(lines, vec![4, 7]);
            assert!(distance < 5.0);
        }
        e => panic!("{e}"),
    }
}

#[test]
fn spiral_with_room_for_the_tool_keeps_the_offset() {
    let r = 4.0;
    let g = spiral(r, 10.0);
    let out = run(p(0.0, -10.0), g.ops.clone()).unwrap();
    let worst = worst_offset_error(&out, &g.contour(4..=8), r, |l| (4..=8).contains(&l));
    assert!(worst < 1e-6, "offset error {worst}");
}

#[test]
fn tangent_join_with_an_arc_end_inside_the_radius_tolerance_is_smooth() {
    // The arc's programmed end lies 0.5 µm outside its circle (the interpreter accepts
    // 1 µm); the tangent line after it starts there. The offset circle and the offset line
    // then miss each other by 0.5 µm: that is a tangent join, not a contour violation.
    let r = 2.0;
    let mut g = Prog::new(r);
    g.pos = p(-20.0, -10.0);
    g.comp(CompSide::Left);
    g.l(-20.0, 0.0); // 3
    g.l(0.0, 0.0); // 4
    let l = g.next();
    let to = p(10.0005, 10.0);
    g.ops.push(arc_op(l, g.pos, to, [0.0, 10.0], 90.0)); // 5
    g.pos = to;
    g.l(10.0005, 30.0); // 6
    let out = run(p(-20.0, -10.0), g.ops.clone()).expect("tangent within tolerance");
    assert_continuous(p(-20.0, -10.0), &out);
    assert_eq!(motions(&out).len(), 4, "no corner added: {out:#?}");
    let worst = worst_offset_error(&out, &g.contour(4..=6), r, |l| (4..=6).contains(&l));
    assert!(worst < 1e-3, "offset error {worst}");
}

#[test]
fn transition_arc_cutting_back_into_an_arc_of_more_than_half_a_turn_is_refused() {
    // RL inside a 197.84° arc of radius 4.9118 with a 4.907 tool (offset radius 0.0048),
    // then a right turn of 121.34°: the tool rolling around the corner swings back into the
    // arc's own contour. (Found by the random-contour property test.)
    let (r, tool, sweep, turn) = (4.9118, 4.907, 197.84f64, 121.34f64);
    let mut g = Prog::new(tool);
    g.pos = p(0.0, -10.0);
    g.comp(CompSide::Left);
    g.l(0.0, 0.0); // 3
    let arc = g.c([0.0, r], sweep, 0.0); // 4
    let (x, y) = (g.pos[AxisLetter::X], g.pos[AxisLetter::Y]);
    let heading = (sweep - turn).to_radians();
    g.l(x + 3.0 * heading.cos(), y + 3.0 * heading.sin()); // 5

    // Independently: the transition arc about the corner P, from the arc's offset end
    // (towards the centre, at the tool radius from P) clockwise through the turn.
    let start = (sweep - 90.0).to_radians() + std::f64::consts::PI;
    let corner = Op {
        kind: OpKind::Arc {
            from: p(x + tool * start.cos(), y + tool * start.sin()),
            to: p(x, y),
            center: [x, y],
            plane: klar_interp::Plane::XY,
            sweep: -turn,
            feed: F,
        },
        loc: at(0),
    };
    let own = g.contour(4..=4);
    let closest = sample(&corner, 2000)
        .iter()
        .map(|q| contour_dist([q[AxisLetter::X], q[AxisLetter::Y]], &own))
        .fold(f64::INFINITY, f64::min);
    assert!(
        closest < tool - 0.05,
        "the construction itself gouges: {closest}"
    );

    match run(p(0.0, -10.0), g.ops).unwrap_err() {
        CompError::Gouge {
            blocks, distance, ..
        } => {
            assert_eq!(blocks.iter().map(|l| l.line).collect::<Vec<_>>(), vec![arc]);
            assert!((distance - closest).abs() < 1e-6, "{distance} vs {closest}");
        }
        e => panic!("{e}"),
    }
}
