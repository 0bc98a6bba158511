//! Helpers for the cycle tests: parameter lists, contexts and sampling of moves.

use super::super::{CycleContext, CycleFeed, Move, P3, ParamKey};
use crate::op::SpindleDir;
use std::f64::consts::TAU;

/// A parameter source from a list of Q parameters.
pub(in crate::cycles) fn qs(list: &[(u32, f64)]) -> impl Fn(ParamKey) -> Option<f64> + use<> {
    let v: Vec<(u32, f64)> = list.to_vec();
    move |k| match k {
        ParamKey::Q(n) => v.iter().find(|(q, _)| *q == n).map(|(_, x)| *x),
        _ => None,
    }
}

/// A context at `pos` with tool radius `r`, spindle M3, feed 1 mm/s.
pub(in crate::cycles) fn ctx(pos: P3, r: f64) -> CycleContext {
    CycleContext {
        pos,
        tool_radius: r,
        spindle_rpm: 1000.0,
        spindle: SpindleDir::Cw,
        feed: Some(1.0),
        rough_out_radius: None,
    }
}

/// One sampled point: position, the feed of its move and the move's index.
#[derive(Debug, Clone, Copy)]
pub(in crate::cycles) struct Sample {
    /// Position.
    pub p: P3,
    /// Feed of the move.
    pub feed: CycleFeed,
    /// Index of the move.
    pub idx: usize,
}

/// Points along `moves` starting at `start`, about every `step` mm (both ends included).
/// Panics when an arc's start and end lie at different distances from its centre.
pub(in crate::cycles) fn sample(moves: &[Move], start: P3, step: f64) -> Vec<Sample> {
    let mut cur = start;
    let mut v = Vec::new();
    for (idx, m) in moves.iter().enumerate() {
        match *m {
            Move::Line { to, feed } => {
                let len = (0..3).map(|i| (to[i] - cur[i]).powi(2)).sum::<f64>().sqrt();
                let n = (len / step).ceil().max(1.0) as usize;
                for k in 0..=n {
                    let s = k as f64 / n as f64;
                    let p = [0, 1, 2].map(|i| cur[i] + s * (to[i] - cur[i]));
                    v.push(Sample { p, feed, idx });
                }
                cur = to;
            }
            Move::Arc {
                centre,
                to,
                ccw,
                turns,
                feed,
            } => {
                let r0 = (cur[0] - centre[0]).hypot(cur[1] - centre[1]);
                let r1 = (to[0] - centre[0]).hypot(to[1] - centre[1]);
                assert!(
                    (r0 - r1).abs() < 1e-6,
                    "arc {idx}: radii {r0} and {r1} differ"
                );
                let a0 = (cur[1] - centre[1]).atan2(cur[0] - centre[0]);
                let a1 = (to[1] - centre[1]).atan2(to[0] - centre[0]);
                let mut sweep = if ccw {
                    (a1 - a0).rem_euclid(TAU)
                } else {
                    -(a0 - a1).rem_euclid(TAU)
                };
                if sweep.abs() < 1e-9 || (TAU - sweep.abs()) < 1e-9 {
                    sweep = if ccw { TAU } else { -TAU };
                }
                sweep += f64::from(turns) * if ccw { TAU } else { -TAU };
                let n = ((sweep.abs() * r0).max((to[2] - cur[2]).abs()) / step)
                    .ceil()
                    .max(2.0) as usize;
                for k in 0..=n {
                    let s = k as f64 / n as f64;
                    let a = a0 + s * sweep;
                    let p = [
                        centre[0] + r0 * a.cos(),
                        centre[1] + r0 * a.sin(),
                        cur[2] + s * (to[2] - cur[2]),
                    ];
                    v.push(Sample { p, feed, idx });
                }
                cur = to;
            }
            _ => {}
        }
    }
    v
}

/// Signed distance from `p` to a rectangle centred on the origin with half sides `ha`,
/// `hb` and corner radius `rc` (negative inside).
pub(in crate::cycles) fn sd_rbox(p: [f64; 2], ha: f64, hb: f64, rc: f64) -> f64 {
    let qx = p[0].abs() - (ha - rc);
    let qy = p[1].abs() - (hb - rc);
    qx.max(0.0).hypot(qy.max(0.0)) + qx.max(qy).min(0.0) - rc
}

/// `p` relative to `origin`, turned back by `deg` degrees.
pub(in crate::cycles) fn to_local(p: [f64; 2], origin: [f64; 2], deg: f64) -> [f64; 2] {
    let (s, c) = deg.to_radians().sin_cos();
    let (x, y) = (p[0] - origin[0], p[1] - origin[1]);
    [c * x + s * y, -s * x + c * y]
}

/// The end point of every move (lines and arcs).
pub(in crate::cycles) fn ends(moves: &[Move]) -> Vec<(P3, CycleFeed)> {
    moves
        .iter()
        .filter_map(|m| match *m {
            Move::Line { to, feed } | Move::Arc { to, feed, .. } => Some((to, feed)),
            _ => None,
        })
        .collect()
}

/// Checks that rapid moves stay at or above `height`, except straight retractions upwards.
pub(in crate::cycles) fn assert_rapids_above(moves: &[Move], start: P3, height: f64) {
    let mut cur = start;
    for (i, m) in moves.iter().enumerate() {
        if let Move::Line {
            to,
            feed: CycleFeed::Rapid,
        } = *m
        {
            let vertical_up =
                (to[0] - cur[0]).abs() < 1e-9 && (to[1] - cur[1]).abs() < 1e-9 && to[2] >= cur[2];
            assert!(
                vertical_up || (cur[2] >= height - 1e-9 && to[2] >= height - 1e-9),
                "rapid move {i} from {cur:?} to {to:?} goes below {height}"
            );
        }
        if let Move::Line { to, .. } | Move::Arc { to, .. } = *m {
            cur = to;
        }
    }
}
