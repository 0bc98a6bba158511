//! The canonical operation stream: what the interpreter hands to motion.
//!
//! Every op is fully resolved: coordinates are absolute, in millimetres and degrees, with all
//! program transforms (datum shift, mirror, rotation, scaling, INCH → MM) already applied.
//! Feeds are in mm/s. Each op carries the source location of the block that produced it.
//! Radius compensation is *not* applied here: ops describe the programmed contour and carry
//! the compensation state as separate [`OpKind::RadiusComp`] ops; motion offsets the path.
//!
//! Lathe programs (lathe DIN) use the same ops: X is always a **radius** in ops — the
//! interpreter halves the diameter the program writes — so op geometry does not depend on the
//! machine, and the lathe kinematics maps X, Z, C, Y, B without a diameter factor. Turning
//! arcs lie in [`Plane::ZX`]; face machining with the C axis turns C so that the point lies
//! on the X axis (X = radius, Y = 0) or, with a Y axis, moves Y in the turned system.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A programmable axis letter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum AxisLetter {
    /// Linear principal axis X.
    X,
    /// Linear principal axis Y.
    Y,
    /// Linear principal axis Z.
    Z,
    /// Rotary axis about X (degrees).
    A,
    /// Rotary axis about Y (degrees).
    B,
    /// Rotary axis about Z (degrees).
    C,
    /// Secondary linear axis parallel to X.
    U,
    /// Secondary linear axis parallel to Y.
    V,
    /// Secondary linear axis parallel to Z.
    W,
}

impl AxisLetter {
    /// All letters in pose order.
    pub const ALL: [AxisLetter; 9] = [
        AxisLetter::X,
        AxisLetter::Y,
        AxisLetter::Z,
        AxisLetter::A,
        AxisLetter::B,
        AxisLetter::C,
        AxisLetter::U,
        AxisLetter::V,
        AxisLetter::W,
    ];

    /// Index of this axis in a [`Pose`].
    pub const fn index(self) -> usize {
        self as usize
    }

    /// True for the rotary axes A, B and C (values in degrees).
    pub const fn is_rotary(self) -> bool {
        matches!(self, AxisLetter::A | AxisLetter::B | AxisLetter::C)
    }

    /// The letter as written in programs.
    pub const fn as_char(self) -> char {
        match self {
            AxisLetter::X => 'X',
            AxisLetter::Y => 'Y',
            AxisLetter::Z => 'Z',
            AxisLetter::A => 'A',
            AxisLetter::B => 'B',
            AxisLetter::C => 'C',
            AxisLetter::U => 'U',
            AxisLetter::V => 'V',
            AxisLetter::W => 'W',
        }
    }

    /// Parses an axis letter (case-insensitive).
    pub fn from_char(c: char) -> Option<Self> {
        AxisLetter::ALL
            .into_iter()
            .find(|a| a.as_char() == c.to_ascii_uppercase())
    }
}

impl fmt::Display for AxisLetter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.as_char())
    }
}

/// A position of all programmable axes: mm for linear axes, degrees for rotary axes.
///
/// Serialized as an object keyed by axis letter; X, Y and Z are always written, the other
/// axes only when they are not zero.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose(pub [f64; 9]);

impl Pose {
    /// The origin: every axis at zero.
    pub const ZERO: Pose = Pose([0.0; 9]);

    /// A pose with X, Y, Z set and every other axis at zero.
    pub const fn xyz(x: f64, y: f64, z: f64) -> Pose {
        Pose([x, y, z, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    }

    /// Value of one axis.
    pub fn get(&self, axis: AxisLetter) -> f64 {
        self.0[axis.index()]
    }

    /// Sets one axis.
    pub fn set(&mut self, axis: AxisLetter, value: f64) {
        self.0[axis.index()] = value;
    }
}

impl std::ops::Index<AxisLetter> for Pose {
    type Output = f64;
    fn index(&self, axis: AxisLetter) -> &f64 {
        &self.0[axis.index()]
    }
}

impl std::ops::IndexMut<AxisLetter> for Pose {
    fn index_mut(&mut self, axis: AxisLetter) -> &mut f64 {
        &mut self.0[axis.index()]
    }
}

impl Serialize for Pose {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(None)?;
        for a in AxisLetter::ALL {
            let v = self[a];
            if a.index() < 3 || v != 0.0 {
                m.serialize_entry(&a, &v)?;
            }
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for Pose {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let m = std::collections::BTreeMap::<AxisLetter, f64>::deserialize(d)?;
        let mut p = Pose::ZERO;
        for (a, v) in m {
            p[a] = v;
        }
        Ok(p)
    }
}

/// A working plane, named by its two in-plane axes; the third is the tool axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Plane {
    /// X/Y plane, tool axis Z (G17).
    XY,
    /// Z/X plane, tool axis Y (G18); also the turning plane of a lathe, where a positive
    /// sweep turns Z towards X (counter-clockwise with Z to the right and X up: G3/G13).
    ZX,
    /// Y/Z plane, tool axis X (G19).
    YZ,
}

impl Plane {
    /// (first in-plane axis, second in-plane axis, normal axis), right-handed: a positive
    /// (counter-clockwise, DR+) rotation turns the first axis towards the second.
    pub const fn axes(self) -> (AxisLetter, AxisLetter, AxisLetter) {
        match self {
            Plane::XY => (AxisLetter::X, AxisLetter::Y, AxisLetter::Z),
            Plane::ZX => (AxisLetter::Z, AxisLetter::X, AxisLetter::Y),
            Plane::YZ => (AxisLetter::Y, AxisLetter::Z, AxisLetter::X),
        }
    }

    /// The plane perpendicular to a tool axis (X, Y or Z; None for other letters).
    pub const fn from_tool_axis(axis: AxisLetter) -> Option<Plane> {
        match axis {
            AxisLetter::Z => Some(Plane::XY),
            AxisLetter::Y => Some(Plane::ZX),
            AxisLetter::X => Some(Plane::YZ),
            _ => None,
        }
    }
}

/// How fast a motion op moves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Feed {
    /// Rapid traverse (FMAX, G0): as fast as the machine allows.
    Rapid,
    /// Path feed in mm/s (the interpreter converts mm/min and inch/min).
    Rate(f64),
    /// Feed per spindle revolution in mm (lathe G95, FU).
    PerRevolution(f64),
}

/// Which travel a thread's pitch measures (DIN G33 `H`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ThreadLead {
    /// Z travel per revolution (longitudinal and taper threads up to 45° from Z).
    Z,
    /// X travel (radius) per revolution (face threads and tapers steeper than 45°).
    X,
    /// Travel along the path per revolution.
    Path,
}

/// A block-wise corner rule of radius compensation (TNC M97 / M98).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CornerRule {
    /// M97, small contour steps: at an outside corner the offset paths are extended to
    /// their intersection instead of rolling around the corner on a transition arc.
    Intersect,
    /// M98, open contour corner: at an inside corner the offset paths are not cut at their
    /// intersection; the first runs to its full end, a straight move joins it to the full
    /// start of the second, so both corners are machined completely.
    Open,
}

/// M numbers klar itself gives a meaning to in Klartext and TNC ISO programs; a machine file
/// cannot define them as machine functions.
pub const BUILT_IN_M_NUMBERS: &[u32] = &[
    0, 1, 2, 3, 4, 5, 6, 8, 9, 13, 14, 30, 89, 91, 92, 97, 98, 99, 116, 117, 126, 127, 128, 129,
    136, 137, 140,
];

/// Highest M number a machine function may have.
pub const MAX_MACHINE_FUNCTION: u32 = 9999;

/// When within its block a machine function acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MachineFunctionTime {
    /// Before the block's motion.
    Start,
    /// After the block's motion.
    #[default]
    End,
}

/// A machine-dependent M function as the machine defines it (see
/// [`OpKind::MachineFunction`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MachineFunctionDef {
    /// The M number.
    pub number: u32,
    /// When in its block it acts.
    pub at: MachineFunctionTime,
    /// True when the path stops exactly before it acts.
    pub stop: bool,
    /// Seconds the machine waits after it (with `stop` only), finite and ≥ 0.
    pub wait: f64,
}

/// Side of tool radius compensation, looking in the direction of travel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CompSide {
    /// No compensation (R0, G40).
    Off,
    /// Tool left of the contour (RL, G41).
    Left,
    /// Tool right of the contour (RR, G42).
    Right,
}

/// Which spindle an op addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpindleId {
    /// The main (work or tool) spindle.
    Main,
    /// A driven tool on a lathe turret (G197, M103/M104).
    Driven,
}

/// Spindle rotation command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpindleDir {
    /// Clockwise (M3).
    Cw,
    /// Counter-clockwise (M4).
    Ccw,
    /// Stopped (M5).
    Off,
}

/// Spindle speed setting.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpindleSpeed {
    /// Revolutions per minute.
    Rpm(f64),
    /// Constant cutting speed in m/min (lathe G96).
    SurfaceSpeed(f64),
    /// Constant cutting speed in m/min (lathe G96) under a speed limit in rpm (G26).
    SurfaceSpeedCapped(f64, f64),
}

/// The path shape of an APPR or DEP block (HEIDENHAIN approach/departure functions).
///
/// The constructions (auxiliary point PH, tangent arcs) are made on the compensated tool path
/// by the radius-compensation stage, which sees the first (or last) contour element.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum ApproachShape {
    /// LT: straight line tangent to the contour element, `len` long.
    LineTangent {
        /// Length of the line (LEN), mm.
        len: f64,
    },
    /// LN: straight line perpendicular to the contour element, `len` long.
    LineNormal {
        /// Length of the line (LEN), mm.
        len: f64,
    },
    /// CT: circular arc tangent to the contour element.
    CircleTangent {
        /// Central angle of the arc (CCA), degrees.
        cca: f64,
        /// Radius (R), mm; the sign selects the side as the manual defines.
        radius: f64,
    },
    /// LCT: straight line to an auxiliary point, then an arc tangent to both.
    LineCircleTangent {
        /// Radius (R), mm.
        radius: f64,
    },
}

/// Coefficients of one axis of a spline block: `K3, K2, K1` as written in the program.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SplineAxis {
    /// The axis.
    pub axis: AxisLetter,
    /// `[K3, K2, K1]`.
    pub k: [f64; 3],
}

/// Where an op came from in the program text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct SourceLoc {
    /// Index of the file in the interpreter's file table (0 = the main program).
    pub file: u16,
    /// 1-based line of the block's first character.
    pub line: u32,
    /// 1-based column (in characters) of the block's first character.
    pub col: u32,
    /// The block number written in the program, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub block: Option<u64>,
}

/// One canonical operation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Op {
    /// The operation.
    #[serde(flatten)]
    pub kind: OpKind,
    /// The block that produced it.
    pub loc: SourceLoc,
}

/// The results of one touch-probe cycle (see [`OpKind::ProbeResult`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProbeResult {
    /// The cycle number (`TCH PROBE 412` → 412; 0 and 1 for the old format).
    pub cycle: u32,
    /// The Q parameters the cycle wrote, in the order written: (number, value).
    pub params: Vec<(u32, f64)>,
    /// The preset the cycle wrote, if it wrote one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preset: Option<PresetWrite>,
}

/// A preset a touch-probe cycle wrote.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PresetWrite {
    /// The preset table row written; `None` when the machine has no preset table (the
    /// active preset then exists only in the run).
    pub row: Option<i64>,
    /// True when the row is the active preset, which acts at once.
    pub active: bool,
    /// The axis values written (machine coordinates of the new datum), by axis.
    pub values: Vec<(AxisLetter, f64)>,
    /// The basic rotation written, degrees, if the cycle writes one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation: Option<f64>,
}

/// The canonical operations.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "op", rename_all = "snake_case")]
pub enum OpKind {
    /// Straight line in all axes from `from` to `to` (rapid when `feed` is [`Feed::Rapid`]).
    Line {
        /// Start (the previous end point).
        from: Pose,
        /// End point.
        to: Pose,
        /// Feed.
        feed: Feed,
    },
    /// Circular arc in `plane` about `center`, or a helix when the normal axis also moves.
    ///
    /// The radius is the distance from `from` to `center` in the plane. `sweep` is the signed
    /// angle travelled in degrees (positive = counter-clockwise = DR+), may exceed 360° for
    /// helices and full circles; the in-plane position at the end equals `to`. The normal axis
    /// and any other axes move linearly with the angle.
    Arc {
        /// Start (the previous end point).
        from: Pose,
        /// End point.
        to: Pose,
        /// Centre in the plane: (first axis, second axis) of [`Plane::axes`].
        center: [f64; 2],
        /// The plane of the circle.
        plane: Plane,
        /// Signed angle in degrees, positive counter-clockwise.
        sweep: f64,
        /// Feed.
        feed: Feed,
    },
    /// Cubic polynomial per axis (SPL): `P(t) = K3·t³ + K2·t² + K1·t + to`, t from 1 to 0.
    /// Axes without coefficients stay where they are.
    Spline {
        /// Start (equals the polynomial at t = 1 within 1 µm).
        from: Pose,
        /// End point (t = 0).
        to: Pose,
        /// Coefficients per axis.
        axes: Vec<SplineAxis>,
        /// Feed.
        feed: Feed,
    },
    /// APPR: approach the first contour point `to` (PA) from `from` (PS) and switch radius
    /// compensation on to `side`. Resolved into lines and arcs by the compensation stage.
    Approach {
        /// Start point PS (the previous end point).
        from: Pose,
        /// First contour point PA, as programmed (on the contour).
        to: Pose,
        /// Path shape.
        shape: ApproachShape,
        /// Compensation side switched on (Left or Right).
        side: CompSide,
        /// Feed from PS to PH (LT/LN/CT: the last feed before the block; LCT: the block's feed).
        feed_to_aux: Feed,
        /// Feed from PH to PA (the block's feed).
        feed: Feed,
        /// Working plane.
        plane: Plane,
        /// True when the block programs the tool axis too: all axes move to PH together,
        /// then only the working plane to PA.
        with_tool_axis: bool,
    },
    /// DEP: leave the contour from `from` (PE) and switch radius compensation off.
    /// `to` is the end point PN where the block programs one (LCT), else it is computed.
    Depart {
        /// Last contour point PE (the previous end point).
        from: Pose,
        /// End point PN when programmed.
        to: Option<Pose>,
        /// Path shape.
        shape: ApproachShape,
        /// Feed.
        feed: Feed,
        /// Working plane.
        plane: Plane,
    },
    /// Wait without motion.
    Dwell {
        /// Seconds.
        seconds: f64,
    },
    /// Tool change: the active tool and its compensation data from now on.
    ToolChange {
        /// Tool number.
        tool: u32,
        /// Tool name, if known.
        #[serde(skip_serializing_if = "Option::is_none")]
        name: Option<String>,
        /// Tool axis (defines the working plane).
        axis: AxisLetter,
        /// Tool length including DL, mm.
        length: f64,
        /// Tool radius including DR, mm.
        radius: f64,
    },
    /// Spindle command.
    Spindle {
        /// Which spindle.
        spindle: SpindleId,
        /// Direction or stop.
        dir: SpindleDir,
        /// Speed (kept while stopped).
        speed: SpindleSpeed,
    },
    /// Coolant on or off.
    Coolant {
        /// True for on.
        on: bool,
    },
    /// Start, change or end of tool radius compensation for the following motion ops.
    RadiusComp {
        /// Side.
        side: CompSide,
    },
    /// How radius compensation treats the corner at the end of the next contour element
    /// (M97 / M98 in that element's block); without compensation it changes nothing.
    CornerRule {
        /// The rule.
        rule: CornerRule,
    },
    /// Path tolerance for blending; `None` returns to the machine default.
    Tolerance {
        /// Tolerance in mm.
        mm: Option<f64>,
    },
    /// Come to a full stop at the end of the previous motion before continuing.
    ExactStop,
    /// C axis mode of a lathe main spindle on (position-controlled) or off (M14/M15).
    CAxis {
        /// True when the spindle becomes the C axis.
        on: bool,
    },
    /// Tool centre point management on or off (M128/M129, FUNCTION TCPM, a tilted working
    /// plane): while on, X Y Z of the following poses are the tool tip in workpiece
    /// coordinates and the kinematics keeps it there as rotary axes that carry the workpiece
    /// turn; while off, X Y Z pass to the machine unchanged.
    Tcpm {
        /// True for on.
        on: bool,
        /// The feed (mm/s) the compensating moves of the linear machine axes keep within
        /// while rotary axes turn (`M128 F…`); `None`: the machine's own limits.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        compensation_feed: Option<f64>,
        /// Where the path goes on from in the new frame: the pose the machine stands at,
        /// re-expressed (the tool tip on the workpiece when TCPM switches on, the machine's
        /// own X Y Z when it switches off; workpiece coordinates like every op leaving the
        /// tilt stage). Nothing moves at the switch. `None` when the interpreter does not
        /// know the machine's table geometry (the pose is then taken over unchanged).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        reframe: Option<Pose>,
    },
    /// The tilted working plane (PLANE, cycle 19) in effect for the following ops, which are
    /// then in the tilted system: a point `p` of them lies at `rotation · p` in the untilted
    /// workpiece system (columns: the tilted X, Y, Z axes in workpiece coordinates). The
    /// identity resets the tilt. Only an interpreter asked for it emits this op
    /// (`Interpreter::set_working_plane_ops`); the radius compensation stage of motion
    /// compensates in the tilted system and turns its output into the workpiece system.
    WorkingPlane {
        /// Rotation matrix, row-major.
        rotation: [[f64; 3]; 3],
    },
    /// A machine-dependent M function the machine file defines (door, clamping, chip
    /// conveyor, …): the interpreter passes its number on at block start or block end, as
    /// the machine file says. With `stop` the path comes to rest before it acts (as for a
    /// tool change) and the machine then waits `wait` seconds; without `stop` it is an
    /// event on the path (like coolant) and `wait` does not hold the motion.
    MachineFunction {
        /// The M number.
        number: u32,
        /// True when the path stops exactly before the function acts.
        stop: bool,
        /// Seconds the machine waits after the function (with `stop` only).
        wait: f64,
    },
    /// A straight move position-locked to the main spindle's measured angle (a thread
    /// pass): the path from `from` to `to` advances `pitch` mm of `lead` travel per spindle
    /// revolution, accelerating over the run-in and braking over the run-out in step with
    /// the spindle, and the spindle stands at `start_angle` when the run-in ends, so every
    /// pass with the same start angle cuts the same groove. Feed override and feed hold do
    /// not act on it. The planner stops exactly at `from` first.
    SpindleSync {
        /// Start (the previous end point).
        from: Pose,
        /// End point.
        to: Pose,
        /// Travel per spindle revolution, mm, measured as `lead` says.
        pitch: f64,
        /// Which travel the pitch measures.
        lead: ThreadLead,
        /// Spindle angle at the end of the run-in, degrees.
        start_angle: f64,
        /// Run-in length along the path, mm; `None`: the shortest the axes allow.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        run_in: Option<f64>,
        /// Run-out length along the path, mm; `None`: the shortest the axes allow.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        run_out: Option<f64>,
        /// Chip cross-section the pass cuts, mm² (0 when the program does not say), for a
        /// simulated spindle's load.
        section: f64,
    },
    /// Rigid tapping position-locked to the main spindle's measured angle: the tool moves
    /// along the line from `from` towards `to` by `pitch` mm per spindle revolution, in
    /// strokes. Each stroke ends at a depth of `strokes` (mm from `from` along the line);
    /// a stroke deeper than the one before turns the spindle in `hand`, a shallower one the
    /// other way, and the tool follows the spindle through every stop and reversal. The
    /// spindle starts from rest with the tool and ends at rest at the end of the last
    /// stroke; retracting strokes turn `retract_factor` times faster. The planner stops
    /// exactly at `from` first; the tool ends at the depth of the last stroke.
    RigidTap {
        /// Start on the hole's axis (the set-up clearance).
        from: Pose,
        /// Bottom of the thread.
        to: Pose,
        /// Thread pitch, mm per revolution (positive).
        pitch: f64,
        /// Direction of rotation that enters the thread (M3 right-hand, M4 left-hand).
        hand: SpindleDir,
        /// The depths the strokes end at, mm from `from`, in order.
        strokes: Vec<f64>,
        /// Spindle speed factor of the retracting strokes.
        retract_factor: f64,
    },
    /// What a touch-probe cycle measured, once it has: the Q parameters it wrote and the
    /// preset it wrote, if any. Nothing moves; the run passes it on to displays.
    ProbeResult {
        /// The results.
        result: ProbeResult,
    },
    /// Program stop (M0, STOP) or optional stop (M1): motion halts until resumed.
    Stop {
        /// True for M1 (only when optional stop is switched on).
        optional: bool,
    },
    /// End of the program (M2, M30, END PGM).
    End,
}

impl OpKind {
    /// This op of a working plane tilted by `rotation` (see [`OpKind::WorkingPlane`]) in the
    /// untilted workpiece system: X Y Z of its points turned, an arc as lines within
    /// 1 µm of it, a spline with turned coefficients; ops without points unchanged.
    pub fn in_workpiece(&self, rotation: &[[f64; 3]; 3]) -> Vec<OpKind> {
        crate::tnc::plane_output::tilt_kind(rotation, self)
    }

    /// For an op the servo loop runs geared to the spindle ([`OpKind::SpindleSync`],
    /// [`OpKind::RigidTap`]): where it starts and where it leaves the tool.
    pub fn geared_ends(&self) -> Option<(Pose, Pose)> {
        match self {
            OpKind::SpindleSync { from, to, .. } => Some((*from, *to)),
            OpKind::RigidTap {
                from, to, strokes, ..
            } => {
                let len = (0..9)
                    .map(|i| (to.0[i] - from.0[i]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let last = strokes.last().copied().unwrap_or(0.0);
                let k = if len > 0.0 { last / len } else { 0.0 };
                let mut end = *from;
                for i in 0..9 {
                    end.0[i] = from.0[i] + (to.0[i] - from.0[i]) * k;
                }
                Some((*from, end))
            }
            _ => None,
        }
    }

    /// True for ops that move axes.
    pub fn is_motion(&self) -> bool {
        matches!(
            self,
            OpKind::Line { .. }
                | OpKind::Arc { .. }
                | OpKind::Spline { .. }
                | OpKind::Approach { .. }
                | OpKind::Depart { .. }
        )
    }
}
