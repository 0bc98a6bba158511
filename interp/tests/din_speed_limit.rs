//! Lathe DIN G26 speed limit with constant surface speed G96, and G36 on the turning axis
//! as a rigid tap geared to the main spindle: the ops the interpreter gives.

mod common;
use common::lathe::run_nc as run;
use klar_interp::op::{SpindleDir, SpindleId, SpindleSpeed};
use klar_interp::{AxisLetter, Op, OpKind};

/// The speeds of the main spindle's commands to turn.
fn spindle_speeds(ops: &[Op]) -> Vec<SpindleSpeed> {
    ops.iter()
        .filter_map(|o| match &o.kind {
            OpKind::Spindle {
                spindle: SpindleId::Main,
                speed,
                dir,
            } if *dir != SpindleDir::Off => Some(*speed),
            _ => None,
        })
        .collect()
}

#[test]
fn g26_caps_constant_surface_speed_before_and_after_the_spindle_starts() {
    // Limit first: the start carries it.
    let ops = run("MACHINING\nN1 G26 S2500\nN2 G96 S200 M3\nN3 G0 X20 Z2\nEND\n");
    assert_eq!(
        spindle_speeds(&ops),
        [SpindleSpeed::SurfaceSpeedCapped(200.0, 2500.0)]
    );
    // Limit while the spindle turns under G96: a new spindle op with the cap.
    let ops = run("MACHINING\nN1 G96 S200 M3\nN2 G26 S1800\nN3 G0 X20 Z2\nEND\n");
    assert_eq!(
        spindle_speeds(&ops),
        [
            SpindleSpeed::SurfaceSpeed(200.0),
            SpindleSpeed::SurfaceSpeedCapped(200.0, 1800.0)
        ]
    );
    // G97 returns to a constant speed, whatever the limit.
    let ops = run("MACHINING\nN1 G26 S2500\nN2 G96 S200 M3\nN3 G97 S800\nEND\n");
    assert_eq!(spindle_speeds(&ops).last(), Some(&SpindleSpeed::Rpm(800.0)));
}

#[test]
fn g36_on_the_turning_axis_with_the_work_turning_is_one_rigid_tap() {
    let ops = run("MACHINING\nN1 G97 S400 M3\nN2 G0 X0 Z5\nN3 G36 ZS2 ZE-12 F1.25\nEND\n");
    let taps: Vec<&OpKind> = ops
        .iter()
        .map(|o| &o.kind)
        .filter(|k| matches!(k, OpKind::RigidTap { .. }))
        .collect();
    assert_eq!(taps.len(), 1);
    let OpKind::RigidTap {
        from,
        to,
        pitch,
        hand,
        strokes,
        retract_factor,
    } = taps[0]
    else {
        unreachable!()
    };
    assert_eq!(from[AxisLetter::Z], 2.0);
    assert_eq!(to[AxisLetter::Z], -12.0);
    assert_eq!(
        (*pitch, *hand, *retract_factor),
        (1.25, SpindleDir::Cw, 1.0)
    );
    assert_eq!(strokes, &[14.0, 0.0]);
    // No feed move into the hole besides the tap.
    assert!(!ops.iter().any(|o| matches!(
        &o.kind,
        OpKind::Line { to, .. } if to[AxisLetter::Z] < 2.0 - 1e-9
    )));
}
