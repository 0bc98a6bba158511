//! Face patterns and the drilling/milling cycles they repeat: G745 (circular pattern on the
//! face), G71 (simple drilling), G74 (deep-hole drilling), G36 (tapping), G791 (linear slot
//! on the face).
//!
//! Face machining with the C axis: a face point (x, y), in the face coordinate system seen
//! onto the face, is reached by turning the spindle to the angle atan2(y, x) — the shortest
//! way from where C stands, so C counts on past 180° instead of jumping back — and moving X
//! to the radius √(x² + y²), Y = 0. A cycle at a pattern position keeps C there; moves within the
//! face (a slot) are then expressed in the turned system: (X, Y) = rot(−C)·(x, y).
//!
//! At each position: rapid in X/Y/C at the clearance Z (where the tool stood when the
//! pattern began), rapid to the start ZS (when given), the cycle's motion, rapid back to the
//! clearance Z. Drilling feeds from ZS to the end ZE and returns at rapid. Deep-hole drilling
//! feeds the first depth P, each further infeed reduced by I but not below J, and after each
//! infeed retracts by the return distance B (without B: to the start ZS), then moves back at
//! rapid to the depth reached. Tapping feeds to ZE with the thread pitch F per revolution,
//! reverses the spindle and feeds back to the start; with the driven tool stopped and the
//! main spindle turning (a tap on the turning axis) it is rigid tapping geared to the main
//! spindle's measured angle ([`OpKind::RigidTap`]), in and out through the reversal. The linear slot starts at the
//! position, runs K long at the angle A (face system), and is cut in infeeds of P from ZS to
//! ZE, going back and forth along the slot.

use std::collections::VecDeque;

use super::lathe::{Group, Lathe, err_at, num};
use super::pattern::{CircleLayout, LinearStep, PatternEnd, linear_positions};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Feed, Op, OpKind, Pose, SourceLoc, SpindleDir};
use crate::tnc::exec::ExecError;

/// A G745 pattern waiting for its cycle (or drilling by itself with ZE).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FacePattern {
    /// Positions on the face, (x, y) in mm.
    pub points: Vec<[f64; 2]>,
    /// ZS: start of drilling/milling.
    pub zs: Option<f64>,
    /// ZE: end of drilling/milling.
    pub ze: Option<f64>,
    /// The block number of the pattern (for diagnostics).
    pub block: Option<u64>,
}

/// Reads a G743 group (linear pattern on the face) into a pattern.
///
/// First position: `XK`, `YK` (Cartesian) or `X` (diameter) and `C` (angle), as for G745.
/// Q positions (default 1) follow in a row given by one of: the last position `I`, `J`
/// (Cartesian; a coordinate left out stays that of the first position) and the span
/// divided into Q − 1 equal steps; the distances `Ii`, `Ji` between neighbours; or the
/// direction `A` (degrees from the XK axis, default 0) with the total length `R` or the
/// distance `Ri` between neighbours. `ZS`/`ZE` as for G745.
pub(crate) fn g743(g: &Group<'_>, block: Option<u64>) -> Result<FacePattern, ExecError> {
    let start = pattern_centre(g)?;
    let count = pattern_count(g)?;
    let axis = |abs: &str, inc: &str| -> Result<Option<LinearStep>, ExecError> {
        match (g.get(abs), g.get(inc)) {
            (Some(_), Some(w)) => Err(err_at(
                w,
                ProgramError::Unexpected(format!("{abs} and {inc} in one pattern: give one")),
            )),
            (Some(w), None) => Ok(Some(LinearStep::To(num(w)?))),
            (None, Some(w)) => Ok(Some(LinearStep::By(num(w)?))),
            (None, None) => Ok(None),
        }
    };
    let along = axis("R", "Ri")?;
    let steps = match along {
        None => [axis("I", "Ii")?, axis("J", "Ji")?],
        Some(step) => {
            if let Some(w) = ["I", "Ii", "J", "Ji"].iter().find_map(|a| g.get(a)) {
                return Err(err_at(
                    w,
                    ProgramError::Unexpected(
                        "a linear pattern is given by I/J, Ii/Ji or A with R/Ri: give one".into(),
                    ),
                ));
            }
            let (sa, ca) = g.value("A")?.unwrap_or(0.0).to_radians().sin_cos();
            match step {
                LinearStep::To(r) => [
                    Some(LinearStep::To(start[0] + r * ca)),
                    Some(LinearStep::To(start[1] + r * sa)),
                ],
                LinearStep::By(d) => [Some(LinearStep::By(d * ca)), Some(LinearStep::By(d * sa))],
            }
        }
    };
    Ok(FacePattern {
        points: linear_positions(start, steps, count),
        zs: g.value("ZS")?,
        ze: g.value("ZE")?,
        block,
    })
}

/// The centre (G745) or first position (G743) of a face pattern: `XK`, `YK` or `X`
/// (diameter) with `C`.
fn pattern_centre(g: &Group<'_>) -> Result<[f64; 2], ExecError> {
    match (g.value("XK")?, g.value("YK")?, g.value("X")?, g.value("C")?) {
        (xk, yk, None, None) => Ok([xk.unwrap_or(0.0), yk.unwrap_or(0.0)]),
        (None, None, x, c) => {
            let r = x.unwrap_or(0.0) / 2.0;
            let a = c.unwrap_or(0.0).to_radians();
            Ok([r * a.cos(), r * a.sin()])
        }
        _ => {
            let w = g.get("X").or(g.get("C"));
            Err((
                w.map(|w| w.pos as u32),
                ProgramError::Unexpected("pattern position given both as XK/YK and as X/C".into()),
            ))
        }
    }
}

/// Q of a pattern: a whole number from 1 to 10000, default 1.
pub(crate) fn pattern_count(g: &Group<'_>) -> Result<u32, ExecError> {
    match g.get("Q") {
        None => Ok(1),
        Some(q) => {
            let n = num(q)?;
            if !(n >= 1.0 && n.fract() == 0.0 && n <= 10_000.0) {
                return Err(err_at(
                    q,
                    ProgramError::OutOfRange(format!(
                        "pattern count Q{n} must be a whole number from 1 to 10000"
                    )),
                ));
            }
            Ok(n as u32)
        }
    }
}

/// Reads a G745 group into a pattern.
pub(crate) fn g745(g: &Group<'_>, block: Option<u64>) -> Result<FacePattern, ExecError> {
    let centre = pattern_centre(g)?;
    let end = match (g.get("W"), g.get("Wi")) {
        (Some(_), Some(wi)) => {
            return Err(err_at(
                wi,
                ProgramError::Unexpected("W and Wi in one pattern: give one of them".into()),
            ));
        }
        (Some(w), None) => PatternEnd::EndAngle(num(w)?),
        (None, Some(wi)) => PatternEnd::Increment(num(wi)?),
        (None, None) => PatternEnd::None,
    };
    let count = pattern_count(g)?;
    let direction = match g.get("V") {
        None => 0,
        Some(v) => {
            let n = num(v)?;
            if !(n == 0.0 || n == 1.0 || n == 2.0) {
                return Err(err_at(
                    v,
                    ProgramError::OutOfRange(format!("pattern direction V{n}: expected 0, 1 or 2")),
                ));
            }
            n as u8
        }
    };
    let k = g.get("K").ok_or((
        g.g_word.map(|w| w.pos as u32),
        ProgramError::Missing("G745 needs the pattern diameter K"),
    ))?;
    let radius = num(k)? / 2.0;
    let layout = CircleLayout {
        start: g.value("A")?.unwrap_or(0.0),
        end,
        count,
        direction,
    };
    let angles = layout
        .angles()
        .map_err(|e| (g.g_word.map(|w| w.pos as u32), e))?;
    let points = angles
        .iter()
        .map(|a| {
            let (s, c) = a.to_radians().sin_cos();
            [centre[0] + radius * c, centre[1] + radius * s]
        })
        .collect();
    Ok(FacePattern {
        points,
        zs: g.value("ZS")?,
        ze: g.value("ZE")?,
        block,
    })
}

/// The machine pose (X radius, Y, C) that puts face point `p` under the tool, at height `z`.
pub fn face_pose(base: Pose, p: [f64; 2], z: f64) -> Pose {
    let mut pose = base;
    pose[AxisLetter::X] = p[0].hypot(p[1]);
    pose[AxisLetter::Y] = 0.0;
    if pose[AxisLetter::X] >= 1e-12 {
        // the shortest turn from where C stands to the point's angle
        let c0 = base[AxisLetter::C];
        let target = p[1].atan2(p[0]).to_degrees();
        let mut d = (target - c0).rem_euclid(360.0);
        if d > 180.0 {
            d -= 360.0;
        }
        pose[AxisLetter::C] = c0 + d;
    }
    pose[AxisLetter::Z] = z;
    pose
}

/// A face point expressed in the system turned by `c` degrees: (X, Y) = rot(−c)·p.
pub fn face_in_turned(p: [f64; 2], c: f64) -> [f64; 2] {
    let (s, co) = c.to_radians().sin_cos();
    [co * p[0] + s * p[1], -s * p[0] + co * p[1]]
}

/// Which cycle runs at a position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Cycle {
    /// G71 simple drilling.
    Drill,
    /// G74 deep-hole drilling.
    DeepHole {
        /// P: first infeed.
        first: f64,
        /// I: reduction per infeed.
        reduction: f64,
        /// B: return distance (None: back to the start).
        retract: Option<f64>,
        /// J: minimum infeed.
        minimum: f64,
    },
    /// G36 tapping with pitch F.
    Tap {
        /// Thread pitch, mm.
        pitch: f64,
    },
    /// G791 linear slot.
    Slot {
        /// K: length.
        length: f64,
        /// A: angle on the face, degrees.
        angle: f64,
        /// P: infeed per pass (None: one pass).
        infeed: Option<f64>,
    },
}

/// A cycle with its depth range and feed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CycleCall {
    /// The cycle.
    pub cycle: Cycle,
    /// Start Z (None: the clearance Z).
    pub zs: Option<f64>,
    /// End Z.
    pub ze: f64,
    /// Feed.
    pub feed: Feed,
}

/// Reads a cycle group (G71, G74, G36, G791); ZS/ZE from the pattern fill in what the
/// cycle leaves out.
pub(crate) fn cycle_call(
    lathe: &mut Lathe,
    g: &Group<'_>,
    code: u32,
    pattern: Option<&FacePattern>,
) -> Result<CycleCall, ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    let ze = g
        .value("ZE")?
        .or(g.value("Z")?)
        .or(pattern.and_then(|p| p.ze))
        .ok_or((
            here,
            ProgramError::Missing("the cycle needs its end point ZE"),
        ))?;
    let zs = g.value("ZS")?.or(pattern.and_then(|p| p.zs));
    let (cycle, feed) = cycle_of(lathe, g, code)?;
    Ok(CycleCall {
        cycle,
        zs,
        ze,
        feed,
    })
}

/// The cycle of a G71, G74, G36 or G791 group and its feed (F of the group sets the feed,
/// except for G36, where F is the thread pitch).
pub(crate) fn cycle_of(
    lathe: &mut Lathe,
    g: &Group<'_>,
    code: u32,
) -> Result<(Cycle, Feed), ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    if let Some(f) = g.get("F")
        && code != 36
    {
        lathe.set_feed(num(f)?, f)?;
    }
    let cycle = match code {
        71 => Cycle::Drill,
        74 => {
            let first = g
                .value("P")?
                .ok_or((here, ProgramError::Missing("G74 needs the first depth P")))?;
            if first <= 0.0 {
                return Err((
                    here,
                    ProgramError::OutOfRange("G74 first depth P must be positive".into()),
                ));
            }
            let minimum = g.value("J")?.unwrap_or(first.min(1.0)).max(1e-3);
            Cycle::DeepHole {
                first,
                reduction: g.value("I")?.unwrap_or(0.0).max(0.0),
                retract: g.value("B")?,
                minimum,
            }
        }
        36 => {
            let pitch = g
                .value("F")?
                .ok_or((here, ProgramError::Missing("G36 needs the thread pitch F")))?;
            if pitch <= 0.0 {
                return Err((
                    here,
                    ProgramError::OutOfRange("G36 pitch F must be positive".into()),
                ));
            }
            Cycle::Tap { pitch }
        }
        _ => {
            let length = g
                .value("K")?
                .ok_or((here, ProgramError::Missing("G791 needs the slot length K")))?;
            let infeed = g.value("P")?.filter(|p| *p > 0.0);
            Cycle::Slot {
                length,
                angle: g.value("A")?.unwrap_or(0.0),
                infeed,
            }
        }
    };
    let feed = match cycle {
        Cycle::Tap { pitch } => Feed::PerRevolution(pitch),
        _ => lathe.need_feed().map_err(|(_, e)| (here, e))?,
    };
    Ok((cycle, feed))
}

/// Runs a cycle at face point `p` (pattern position) or, with `p` None, at the current
/// position.
pub(crate) fn run_at(
    lathe: &mut Lathe,
    call: &CycleCall,
    p: Option<[f64; 2]>,
    clearance: f64,
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) {
    let rapid = Feed::Rapid;
    let here = match p {
        Some(p) => {
            let target = face_pose(lathe.pos, p, clearance);
            lathe.line(target, rapid, loc, out);
            target
        }
        None => lathe.pos,
    };
    let zs = call.zs.unwrap_or(clearance);
    match call.cycle {
        Cycle::Drill | Cycle::DeepHole { .. } | Cycle::Tap { .. } => {
            plunge(lathe, call, AxisLetter::Z, zs, call.ze, loc, out);
        }
        Cycle::Slot {
            length,
            angle,
            infeed,
        } => {
            let c = here[AxisLetter::C];
            let start_face = p.unwrap_or_else(|| {
                let (s, co) = c.to_radians().sin_cos();
                let x = here[AxisLetter::X];
                let y = here[AxisLetter::Y];
                [co * x - s * y, s * x + co * y]
            });
            let mut q = here;
            q[AxisLetter::Z] = zs;
            lathe.line(q, rapid, loc, out);
            let (s, co) = angle.to_radians().sin_cos();
            let end_face = [start_face[0] + length * co, start_face[1] + length * s];
            let ends = [face_in_turned(start_face, c), face_in_turned(end_face, c)];
            let total = (call.ze - zs).abs();
            let down = if call.ze < zs { -1.0 } else { 1.0 };
            let step = infeed.unwrap_or(total).max(1e-3);
            let mut done = 0.0;
            let mut at_start = true;
            while done < total - 1e-9 {
                done = (done + step).min(total);
                let mut q = lathe.pos;
                q[AxisLetter::Z] = zs + down * done;
                lathe.line(q, call.feed, loc, out);
                let other = if at_start { ends[1] } else { ends[0] };
                let mut q = lathe.pos;
                q[AxisLetter::X] = other[0];
                q[AxisLetter::Y] = other[1];
                lathe.line(q, call.feed, loc, out);
                at_start = !at_start;
            }
        }
    }
    let mut up = lathe.pos;
    up[AxisLetter::Z] = clearance;
    lathe.line(up, rapid, loc, out);
}

/// The drilling motion of G71, G74 and G36 along `axis` from where the tool stands: rapid
/// to the start `s`, then to the end `e` (values of that axis in op units: Z, or X as a
/// radius), and out of the hole again to `s`.
pub(crate) fn plunge(
    lathe: &mut Lathe,
    call: &CycleCall,
    axis: AxisLetter,
    s: f64,
    e: f64,
    loc: SourceLoc,
    out: &mut VecDeque<Op>,
) {
    let rapid = Feed::Rapid;
    let here = lathe.pos;
    let at = |v: f64| {
        let mut q = here;
        q[axis] = v;
        q
    };
    lathe.line(at(s), rapid, loc, out);
    match call.cycle {
        Cycle::DeepHole {
            first,
            reduction,
            retract,
            minimum,
        } => {
            let down = if e < s { -1.0 } else { 1.0 };
            let total = (e - s).abs();
            let mut done = 0.0;
            let mut step = first;
            while done < total - 1e-9 {
                let next = (done + step).min(total);
                if done > 0.0 {
                    // back to the depth reached, at rapid
                    lathe.line(at(s + down * done), rapid, loc, out);
                }
                lathe.line(at(s + down * next), call.feed, loc, out);
                done = next;
                if done < total - 1e-9 {
                    let back = match retract {
                        Some(b) => s + down * (done - b).max(0.0),
                        None => s,
                    };
                    lathe.line(at(back), rapid, loc, out);
                }
                step = (step - reduction).max(minimum);
            }
        }
        Cycle::Tap { pitch }
            if lathe.driven_dir == SpindleDir::Off && lathe.main_dir != SpindleDir::Off =>
        {
            // On the turning axis with the work turning: rigid tapping geared to the main
            // spindle, in at its direction and out with it reversed.
            out.push_back(Op {
                kind: OpKind::RigidTap {
                    from: at(s),
                    to: at(e),
                    pitch,
                    hand: lathe.main_dir,
                    strokes: vec![(e - s).abs(), 0.0],
                    retract_factor: 1.0,
                },
                loc,
            });
        }
        Cycle::Tap { .. } => {
            lathe.line(at(e), call.feed, loc, out);
            let reverse = match lathe.driven_dir {
                SpindleDir::Cw => SpindleDir::Ccw,
                SpindleDir::Ccw => SpindleDir::Cw,
                SpindleDir::Off => SpindleDir::Off,
            };
            let forward = lathe.driven_dir;
            lathe.driven_dir = reverse;
            out.push_back(Op {
                kind: lathe.driven_op(),
                loc,
            });
            lathe.line(at(s), call.feed, loc, out);
            lathe.driven_dir = forward;
            out.push_back(Op {
                kind: lathe.driven_op(),
                loc,
            });
        }
        _ => lathe.line(at(e), call.feed, loc, out),
    }
}

/// Reads the block number of a pattern for messages.
pub(crate) fn pattern_block(p: &FacePattern) -> String {
    match p.block {
        Some(n) => format!("the pattern in block {n}"),
        None => "the pattern".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_points_map_to_radius_and_angle() {
        let p = face_pose(Pose::ZERO, [0.0, 25.0], 2.0);
        assert!((p[AxisLetter::X] - 25.0).abs() < 1e-12);
        assert!((p[AxisLetter::C] - 90.0).abs() < 1e-12);
        // turned back by C, the point lies on +X
        let t = face_in_turned([0.0, 25.0], 90.0);
        assert!((t[0] - 25.0).abs() < 1e-12 && t[1].abs() < 1e-12);
    }
}
