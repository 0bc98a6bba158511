//! Touch-probe cycles in a tilted working plane: klar does not probe there yet, so a cycle
//! defined while the plane is tilted is refused at its block, before the probe moves.

use klar_interp::{AxisLetter, Blank, Interpreter, OpKind, Pose, Probe, ProbeData};

/// A part that is never touched: the refusal must come before any probing.
#[derive(Debug)]
struct Untouchable;

impl Probe for Untouchable {
    fn touch(
        &mut self,
        _from: [f64; 3],
        _to: [f64; 3],
        _radius: f64,
        _blank: Option<&Blank>,
    ) -> Option<[f64; 3]> {
        None
    }
}

#[test]
fn a_probing_cycle_in_a_tilted_plane_is_refused_before_it_moves() {
    let text = "BEGIN PGM T MM
L X+0 Y+0 Z+50 R0 FMAX
PLANE SPATIAL SPA+0 SPB+20 SPC+0 STAY
TCH PROBE 0.0 REF. PLANE Q10 Z-
TCH PROBE 0.1 X+0 Y+0 Z+10
L Z+60 FMAX
END PGM T MM
";
    let mut start = Pose::default();
    start[AxisLetter::Z] = 100.0;
    let interp = Interpreter::from_source("t.h", text, start)
        .with_rotary_axes(&[AxisLetter::B, AxisLetter::C])
        .with_probe(ProbeData::default(), Box::new(Untouchable));
    let mut lines = 0;
    let mut error = None;
    for item in interp {
        match item {
            Ok(op) => lines += usize::from(matches!(op.kind, OpKind::Line { .. })),
            Err(d) => {
                error = Some(d.to_string());
                break;
            }
        }
    }
    let e = error.expect("refused");
    assert!(
        e.contains("t.h:4:") && e.contains("tilted working plane"),
        "{e}"
    );
    // only the move of line 2: the probe never moved in the tilted plane
    assert_eq!(lines, 1);
}
