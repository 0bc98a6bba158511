//! Tests of the cycle executor with a stand-in generator, so the call paths are checked
//! independently of the real machining cycles.

use std::collections::VecDeque;

use super::*;
use crate::op::{Plane, Pose};
use crate::tnc::stmt::Stmt;

/// Stand-in generator: rapid to `[a, b, depth]` and back to where the call started, where
/// depth is Q201 (current format) or the first value of sub-block 2 (old format).
fn fake(
    number: u32,
    p: &dyn ParamSource,
    ctx: &CycleContext,
    out: &mut Vec<Move>,
) -> Result<(), CycleError> {
    if number == 999 {
        return Err(CycleError::Unknown(999));
    }
    let depth = p
        .get(ParamKey::Q(201))
        .or_else(|| p.get(ParamKey::Old { line: 2, index: 0 }))
        .ok_or(CycleError::Missing {
            cycle: number,
            param: "Q201".into(),
            what: "depth",
        })?;
    let surface = p.get(ParamKey::Q(203)).unwrap_or(0.0);
    out.push(Move::Line {
        to: [ctx.pos[0], ctx.pos[1], surface + depth],
        feed: CycleFeed::Rapid,
    });
    out.push(Move::Line {
        to: ctx.pos,
        feed: CycleFeed::Rapid,
    });
    Ok(())
}

/// Runs blocks on a fresh machine (with the stand-in generator); returns the ops mapped to
/// machine coordinates, or the first error with its block index.
fn run(blocks: &[&str]) -> Result<Vec<OpKind>, (usize, ProgramError)> {
    let mut m = Machine::new(Pose::ZERO);
    m.cyc.generator = fake;
    run_on(&mut m, blocks)
}

fn run_on(m: &mut Machine, blocks: &[&str]) -> Result<Vec<OpKind>, (usize, ProgramError)> {
    let mut p = Parsed::default();
    let mut q: VecDeque<Op> = VecDeque::new();
    let mut ops = Vec::new();
    for (i, b) in blocks.iter().enumerate() {
        let block = p.parse(b.as_bytes()).map_err(|e| (i, e.error))?;
        m.exec(&block.stmt, &p, b.as_bytes(), SourceLoc::default(), &mut q)
            .map_err(|e| (i, e.1))?;
        if !matches!(block.stmt, Stmt::Empty) {
            m.release();
        }
        while let Some(op) = q.pop_front() {
            let op = m.output(op);
            m.popped();
            ops.push(op.kind);
        }
    }
    Ok(ops)
}

fn line_ends(ops: &[OpKind]) -> Vec<[f64; 3]> {
    ops.iter()
        .filter_map(|o| match o {
            OpKind::Line { to, .. } => Some([to.0[0], to.0[1], to.0[2]]),
            _ => None,
        })
        .collect()
}

fn near(a: [f64; 3], b: [f64; 3]) -> bool {
    a.iter().zip(b.iter()).all(|(x, y)| (x - y).abs() < 1e-9)
}

#[test]
fn cycle_call_runs_the_last_definition_at_the_position() {
    let ops = run(&[
        "L X+10 Y+20 Z+5 FMAX",
        "CYCL DEF 200 BOHREN ~\n Q200=+2 ;x ~\n Q201=-7 ;TIEFE ~\n Q203=+1",
        "CYCL CALL",
    ])
    .expect("runs");
    assert_eq!(
        line_ends(&ops),
        vec![[10.0, 20.0, 5.0], [10.0, 20.0, -6.0], [10.0, 20.0, 5.0]]
    );
}

#[test]
fn definitions_write_their_q_parameters() {
    let mut m = Machine::new(Pose::ZERO);
    m.cyc.generator = fake;
    run_on(
        &mut m,
        &[
            "Q5 = 3",
            "CYCL DEF 200 DRILLING ~\n Q201=-Q5 ;DEPTH ~\n Q206=MAX",
        ],
    )
    .expect("runs");
    let q = |n| {
        m.params.get(ParamRef {
            kind: ParamKind::Q,
            index: n,
        })
    };
    assert_eq!(q(201), -3.0);
    assert_eq!(q(206), 99_999.0);
}

#[test]
fn old_format_machining_cycle_collects_sub_blocks() {
    let ops = run(&[
        "L X+1 Y+2 Z+3 FMAX",
        "CYCL DEF 1.0 TIEFBOHREN",
        "CYCL DEF 1.1 ABST+1",
        "CYCL DEF 1.2 TIEFE-11,5",
        "CYCL DEF 1.5 F150",
        "L Z+2 FMAX M99",
    ])
    .expect("runs");
    assert_eq!(
        line_ends(&ops),
        vec![
            [1.0, 2.0, 3.0],
            [1.0, 2.0, 2.0],
            [1.0, 2.0, -11.5],
            [1.0, 2.0, 2.0]
        ]
    );
    let mut m = Machine::new(Pose::ZERO);
    m.cyc.generator = fake;
    run_on(&mut m, &["CYCL DEF 1.0 X", "CYCL DEF 1.5 F150 DR-"]).expect("runs");
    let def = m.cyc.machining.expect("defined");
    assert_eq!(def.get(ParamKey::OldWord("F")), Some(2.5));
    assert_eq!(def.get(ParamKey::OldWord("DR")), Some(-1.0));
}

#[test]
fn m89_calls_after_every_positioning_until_m99() {
    let ops = run(&[
        "CYCL DEF 200 X ~\n Q201=-1",
        "L X+0 Y+0 Z+10 FMAX M89",
        "L X+5 FMAX",
        "L X+6 FMAX M99",
        "L X+7 FMAX",
    ])
    .expect("runs");
    // positioning, plunge, back — three times — then the last move alone
    assert_eq!(line_ends(&ops).len(), 3 * 3 + 1);
    // a new cycle definition ends M89 too
    let ops = run(&[
        "CYCL DEF 200 X ~\n Q201=-1",
        "L X+0 Z+10 FMAX M89",
        "CYCL DEF 200 X ~\n Q201=-2",
        "L X+5 FMAX",
    ])
    .expect("runs");
    assert_eq!(line_ends(&ops).len(), 3 + 1);
    // a positioning block already at its target still calls the cycle under M89
    let ops = run(&["CYCL DEF 200 X ~\n Q201=-1", "L Z+10 FMAX M89", "L Z+10"]).expect("runs");
    assert_eq!(line_ends(&ops).len(), 3 + 2);
}

#[test]
fn cycle_call_pos_positions_then_shifts_the_surface() {
    let ops = run(&[
        "L X+0 Y+0 Z+50 FMAX",
        "CYCL DEF 200 X ~\n Q201=-5 ~\n Q203=+0",
        "CYCL CALL POS X+10 Y+20 Z-2 FMAX",
    ])
    .expect("runs");
    // above the target: plane first, then the tool axis; depth from the shifted surface
    assert_eq!(
        line_ends(&ops),
        vec![
            [0.0, 0.0, 50.0],
            [10.0, 20.0, 50.0],
            [10.0, 20.0, -2.0],
            [10.0, 20.0, -7.0],
            [10.0, 20.0, -2.0]
        ]
    );
}

#[test]
fn cycle_moves_follow_the_transforms() {
    let ops = run(&[
        "CYCL DEF 7.0 DATUM SHIFT",
        "CYCL DEF 7.1 X+100",
        "CYCL DEF 200 X ~\n Q201=-5",
        "L X+1 Y+2 Z+3 FMAX M99",
    ])
    .expect("runs");
    assert_eq!(
        line_ends(&ops),
        vec![[101.0, 2.0, 3.0], [101.0, 2.0, -5.0], [101.0, 2.0, 3.0]]
    );
}

#[test]
fn tool_axis_y_maps_the_cycle_frame() {
    let mut m = Machine::new(Pose::ZERO);
    m.cyc.generator = fake;
    m.plane = Plane::ZX;
    m.tool_axis = AxisLetter::Y;
    let ops = run_on(
        &mut m,
        &[
            "L X+1 Y+2 Z+3 FMAX",
            "CYCL DEF 200 X ~\n Q201=-5",
            "CYCL CALL",
        ],
    )
    .expect("runs");
    // frame [a, b, t] = [Z, X, Y]: the plunge runs along Y
    assert_eq!(line_ends(&ops)[1], [1.0, -5.0, 3.0]);
}

#[test]
fn call_errors() {
    assert!(matches!(
        run(&["CYCL CALL"]),
        Err((0, ProgramError::NoCycle(_)))
    ));
    assert!(matches!(
        run(&["L X+1 FMAX M99"]),
        Err((0, ProgramError::NoCycle(_)))
    ));
    let e = run(&["CYCL DEF 262 GEWINDEFRAESEN ~\n Q335=10"]).expect_err("unknown");
    assert_eq!(e.1.to_string(), "cycle 262 is not supported");
    // after a refused definition, a call does not fall back on the cycle defined before
    let mut m = Machine::new(Pose::ZERO);
    m.cyc.generator = fake;
    run_on(&mut m, &["CYCL DEF 200 X ~\n Q201=-1"]).expect("defines");
    assert!(run_on(&mut m, &["CYCL DEF 262 X ~\n Q335=1"]).is_err());
    assert!(matches!(
        run_on(&mut m, &["CYCL CALL"]),
        Err((0, ProgramError::NoCycle(_)))
    ));
    let e = run(&["CYCL DEF 200 X ~\n Q200=2", "CYCL CALL"]).expect_err("missing");
    assert!(matches!(
        e,
        (1, ProgramError::Cycle(CycleError::Missing { .. }))
    ));
    assert!(matches!(
        run(&["CYCL DEF 1.2 TIEFE-5"]),
        Err((0, ProgramError::Missing(_)))
    ));
}

#[test]
fn pattern_def_points() {
    let mut m = Machine::new(Pose::ZERO);
    run_on(
        &mut m,
        &["PATTERN DEF ~\n POS1 (X+1 Y+2 Z+3) ~\n ROW1 (X+0 Y+0 D+10 NUM3 ROT+90 Z+0) ~\n CIRC1 (X+0 Y+0 D20 START+0 NUM4 Z-1) ~\n FRAME1 (X+0 Y+0 DX+1 DY+1 NUMX3 NUMY3 ROT+0 ROTX+0 ROTY+0 Z+0)"],
    )
    .expect("runs");
    let p = &m.cyc.pattern;
    let want: Vec<P3> = vec![
        [1.0, 2.0, 3.0],
        [0.0, 0.0, 0.0],
        [0.0, 10.0, 0.0],
        [0.0, 20.0, 0.0],
        [10.0, 0.0, -1.0],
        [0.0, 10.0, -1.0],
        [-10.0, 0.0, -1.0],
        [0.0, -10.0, -1.0],
    ];
    for (g, w) in p.iter().zip(want.iter()) {
        assert!(near(*g, *w), "{g:?} vs {w:?}");
    }
    // the frame skips the centre of the 3 × 3 grid: 8 points
    assert_eq!(p.len(), want.len() + 8);
    assert!(!p.iter().skip(want.len()).any(|q| near(*q, [1.0, 1.0, 0.0])));
}

#[test]
fn sweep_of_arcs() {
    assert!((sweep_of([1.0, 0.0], [0.0, 1.0], [0.0, 0.0], true, 0) - 90.0).abs() < 1e-9);
    assert!((sweep_of([1.0, 0.0], [0.0, 1.0], [0.0, 0.0], false, 0) + 270.0).abs() < 1e-9);
    assert!((sweep_of([1.0, 0.0], [1.0, 0.0], [0.0, 0.0], true, 0) - 360.0).abs() < 1e-9);
    assert!((sweep_of([1.0, 0.0], [0.0, 1.0], [0.0, 0.0], true, 2) - 810.0).abs() < 1e-9);
}

#[test]
fn datum_table_rows_shift_the_datum() {
    let mut m = Machine::new(Pose::ZERO);
    m.set_datum_table(
        DatumTable::parse("BEGIN D.D MM\nNR X Y Z\n0 0 0 0\n2 +50 -10 +0\n[END]\n").expect("table"),
    );
    let ops = run_on(
        &mut m,
        &[
            "CYCL DEF 7.0 DATUM SHIFT",
            "CYCL DEF 7.1 #2",
            "L X+1 Y+1 Z+1 FMAX",
        ],
    )
    .expect("runs");
    assert!(near(line_ends(&ops)[0], [51.0, -9.0, 1.0]));
    let e = run_on(&mut m, &["CYCL DEF 7.1 #3"]).expect_err("no row 3");
    assert_eq!(e.1.to_string(), "datum table has no row 3");
}

#[test]
fn preset_cycle_247_cancels_the_other_transforms() {
    let mut m = Machine::new(Pose::ZERO);
    m.set_preset_table(
        DatumTable::parse("BEGIN PRESET.PR MM\nNR X Y Z\n0 0 0 0\n1 +200 +100 -50\n")
            .expect("table"),
    );
    let ops = run_on(
        &mut m,
        &[
            "CYCL DEF 7.0 DATUM SHIFT",
            "CYCL DEF 7.1 X+10",
            "CYCL DEF 10.0 ROT",
            "CYCL DEF 10.1 ROT+90",
            "CYCL DEF 247 BEZUGSPUNKT SETZEN ~\n Q339=+1 ;BEZUGSPUNKT-NUMMER",
            "L X+1 Y+2 Z+3 FMAX",
        ],
    )
    .expect("runs");
    assert!(near(line_ends(&ops)[0], [201.0, 102.0, -47.0]));
}

proptest::proptest! {
    #[test]
    fn random_cycle_blocks_never_panic(
        head in proptest::sample::select(vec![
            "CYCL DEF ", "CYCL DEF 7.1 ", "CYCL DEF 26.1 ", "CYCL DEF 200 X ~\n Q",
            "CYCL CALL ", "CYCL CALL POS ", "PATTERN DEF ", "CYCL DEF 10.1 ",
        ]),
        body in "[ -~\n]{0,40}",
    ) {
        let text = format!("{head}{body}");
        let mut m = Machine::new(Pose::ZERO);
        m.cyc.generator = fake;
        let _ = run_on(&mut m, &["CYCL DEF 200 X ~\n Q201=-1", &text, "L X+1 Y+1 Z+1 FMAX M99"]);
    }
}
