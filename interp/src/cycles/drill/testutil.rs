//! Helpers shared by the cycle tests: parameter lists and the "no rapid into the material"
//! check.

use std::collections::HashMap;

use crate::cycles::{CycleContext, CycleFeed, Move, P3, ParamKey, ParamSource};
use crate::op::SpindleDir;

/// A parameter list for tests.
pub(in crate::cycles) struct Defs(pub Vec<(ParamKey, f64)>);

impl ParamSource for Defs {
    fn get(&self, key: ParamKey) -> Option<f64> {
        self.0.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
    }
}

/// Q parameters `(number, value)`.
pub(in crate::cycles) fn qs(pairs: &[(u32, f64)]) -> Defs {
    Defs(pairs.iter().map(|&(n, v)| (ParamKey::Q(n), v)).collect())
}

/// `qs` with `(n, v)` replaced or added.
pub(in crate::cycles) fn with(d: &Defs, n: u32, v: f64) -> Defs {
    let mut out: Vec<_> =
        d.0.iter()
            .copied()
            .filter(|(k, _)| *k != ParamKey::Q(n))
            .collect();
    out.push((ParamKey::Q(n), v));
    Defs(out)
}

/// `qs` without `Qn`.
pub(in crate::cycles) fn without(d: &Defs, n: u32) -> Defs {
    Defs(
        d.0.iter()
            .copied()
            .filter(|(k, _)| *k != ParamKey::Q(n))
            .collect(),
    )
}

/// A context at `pos` with a 5 mm tool radius, 1000 rpm clockwise, no modal feed.
pub(in crate::cycles) fn ctx_at(pos: P3) -> CycleContext {
    CycleContext {
        pos,
        tool_radius: 5.0,
        spindle_rpm: 1000.0,
        spindle: SpindleDir::Cw,
        feed: None,
        rough_out_radius: None,
    }
}

/// The tool-axis end points of all straight moves, in order.
pub(in crate::cycles) fn line_ts(moves: &[Move]) -> Vec<f64> {
    moves
        .iter()
        .filter_map(|m| match m {
            Move::Line { to, .. } => Some(to[2]),
            _ => None,
        })
        .collect()
}

/// The tool-axis end points of the straight feed (non-rapid) moves, in order.
pub(in crate::cycles) fn feed_ts(moves: &[Move]) -> Vec<f64> {
    moves
        .iter()
        .filter_map(|m| match m {
            Move::Line { to, feed } if *feed != CycleFeed::Rapid => Some(to[2]),
            _ => None,
        })
        .collect()
}

/// Asserts `a` and `b` agree element by element within 1e-9.
pub(in crate::cycles) fn assert_close(a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len(), "{a:?} vs {b:?}");
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() < 1e-9, "{a:?} vs {b:?}");
    }
}

fn key(a: f64, b: f64) -> (i64, i64) {
    ((a * 1e6).round() as i64, (b * 1e6).round() as i64)
}

/// Walks `moves` from `start` and panics when a rapid move could hit material. The tool
/// works towards `-t` (`dir` = −1) or `+t` (`dir` = +1); `safe(a, b)` is the set-up clearance
/// plane over `(a, b)`. A rapid move is accepted when it stays at or in front of that plane,
/// or when it runs purely along the tool axis inside a hole already cut at that `(a, b)`,
/// ending no deeper than the deepest point a feed move has reached there (`pre_cut(a, b)`:
/// what counts as cut before the cycle, e.g. a pilot hole; the safe plane when nothing is).
pub(in crate::cycles) fn assert_no_rapid_into_material(
    moves: &[Move],
    start: P3,
    dir: f64,
    safe: impl Fn(f64, f64) -> f64,
    pre_cut: impl Fn(f64, f64) -> f64,
) {
    // heights grow away from the material
    let h = |t: f64| -dir * t;
    let mut cut: HashMap<(i64, i64), f64> = HashMap::new();
    let mut pos = start;
    for (i, m) in moves.iter().enumerate() {
        match *m {
            Move::Line { to, feed } => {
                let same_ab = (to[0] - pos[0]).abs() < 1e-9 && (to[1] - pos[1]).abs() < 1e-9;
                if feed == CycleFeed::Rapid {
                    let plane = h(safe(to[0], to[1]));
                    let start_plane = h(safe(pos[0], pos[1]));
                    let end_ok = h(to[2]) >= plane - 1e-9;
                    let start_ok = h(pos[2]) >= start_plane - 1e-9;
                    if !(end_ok && (start_ok || same_ab)) {
                        assert!(
                            same_ab,
                            "move {i}: rapid sideways below the set-up clearance: {m:?} from {pos:?}"
                        );
                        let deepest = cut
                            .get(&key(to[0], to[1]))
                            .copied()
                            .unwrap_or_else(|| h(pre_cut(to[0], to[1])));
                        assert!(
                            h(to[2]) >= deepest - 1e-9,
                            "move {i}: rapid to t={} below the deepest cut t={} : {m:?}",
                            to[2],
                            -dir * deepest
                        );
                    }
                } else if same_ab {
                    let e = cut
                        .entry(key(to[0], to[1]))
                        .or_insert_with(|| h(pre_cut(to[0], to[1])));
                    *e = e.min(h(to[2]));
                }
                pos = to;
            }
            Move::Arc { to, feed, .. } => {
                if feed == CycleFeed::Rapid {
                    let plane = h(safe(to[0], to[1]));
                    assert!(
                        h(to[2]) >= plane - 1e-9 && h(pos[2]) >= plane - 1e-9,
                        "move {i}: rapid arc below the set-up clearance"
                    );
                }
                pos = to;
            }
            _ => {}
        }
    }
}
