//! What the Klartext parser produces: the statement of a block ([`Stmt`], [`Block`]) and the
//! words it keeps for the executor ([`Words`], [`ToolCall`], [`SplineWords`]).

use super::expr::{ParamRef, Rpn, Value};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, CompSide};

/// A coordinate word (`X+10`, `IX-2`, `PA+Q3`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Coord {
    /// The value as written (program units).
    pub value: Value,
    /// True for the `I` prefix.
    pub incremental: bool,
    /// Byte position of the word in the block text.
    pub pos: u32,
}

/// How the feed is given in a block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum FeedWord {
    /// `FMAX` / `F MAX`: rapid for this block only.
    Max,
    /// `FAUTO`: the feed from TOOL CALL.
    Auto,
    /// `F…` in program units per minute.
    Value(Value),
}

/// Most M words one block may carry.
pub(crate) const MAX_M: usize = 8;

/// The words of a path block (also used for CC, M-only, STOP and BLK FORM blocks).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Words {
    /// Axis coordinates, indexed by [`AxisLetter::index`].
    pub axes: [Option<Coord>; 9],
    /// Polar radius `PR`/`IPR`.
    pub pr: Option<Coord>,
    /// Polar angle `PA`/`IPA`.
    pub pa: Option<Coord>,
    /// Direction of rotation: `Some(true)` for DR+, with the word position.
    pub dr: Option<(bool, u32)>,
    /// Radius of CR (`R±r`), with the word position.
    pub radius: Option<(Value, u32)>,
    /// Radius compensation word.
    pub comp: Option<CompSide>,
    /// Feed word.
    pub feed: Option<FeedWord>,
    /// M numbers in the order written.
    pub m: [u32; MAX_M],
    /// How many of `m` are used.
    pub m_count: u8,
    /// Byte position of each M word.
    pub m_pos: [u32; MAX_M],
    /// Bit `i` set when `axes[i]` holds a word (lets [`Words::clear`] touch only those).
    pub axes_set: u16,
    /// LEN of APPR/DEP, with the word position.
    pub len: Option<(Value, u32)>,
    /// CCA of APPR/DEP CT, with the word position.
    pub cca: Option<(Value, u32)>,
    /// Paraxial compensation R+ (true) or R- (false), with the word position.
    pub paraxial: Option<(bool, u32)>,
    /// M140 retract distance: `Some(None)` for MB MAX.
    pub mb: Option<Option<Value>>,
    /// The F written directly after M128: the feed of its compensating moves, with the word
    /// position.
    pub m128_feed: Option<(Value, u32)>,
}

impl Words {
    /// Forgets the words of the previous block. Only the slots that were filled are reset,
    /// which keeps the per-block cost independent of the record's size.
    pub fn clear(&mut self) {
        let mut mask = self.axes_set;
        while mask != 0 {
            let i = mask.trailing_zeros() as usize;
            if let Some(slot) = self.axes.get_mut(i) {
                *slot = None;
            }
            mask &= mask - 1;
        }
        self.axes_set = 0;
        self.pr = None;
        self.pa = None;
        self.dr = None;
        self.radius = None;
        self.comp = None;
        self.feed = None;
        self.m_count = 0;
        self.len = None;
        self.cca = None;
        self.paraxial = None;
        self.mb = None;
        self.m128_feed = None;
    }

    /// Stores an axis word.
    pub fn set_axis(&mut self, axis: AxisLetter, c: Coord) {
        self.axes[axis.index()] = Some(c);
        self.axes_set |= 1 << axis.index();
    }

    /// The M words programmed, with their positions.
    pub fn m_words(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        let n = usize::from(self.m_count).min(MAX_M);
        self.m[..n]
            .iter()
            .copied()
            .zip(self.m_pos[..n].iter().copied())
    }
}

/// Tool identification in TOOL CALL.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum ToolId {
    /// Tool number (literal or Q parameter).
    Number(Value),
    /// Tool name: byte range in the block text.
    Name(usize, usize),
}

/// The words of TOOL CALL.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct ToolCall {
    /// Tool; `None` keeps the current tool (new deltas or speed only).
    pub tool: Option<ToolId>,
    /// Tool axis letter.
    pub axis: Option<AxisLetter>,
    /// Spindle speed, rpm.
    pub speed: Option<Value>,
    /// Automatic feed (FAUTO), program units per minute.
    pub feed: Option<Value>,
    /// Length delta DL.
    pub dl: Option<Value>,
    /// Radius delta DR.
    pub dr: Option<Value>,
    /// Corner radius delta DR2 (recorded, not used yet).
    pub dr2: Option<Value>,
}

/// What a block does. The words of the block stay in the [`Parsed`] ([`Parsed::words`],
/// [`Parsed::tool`], [`Parsed::code`]), so that this value is small.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Stmt {
    /// Nothing to execute (empty line, comment, headline, number only).
    Empty,
    /// `BEGIN PGM name MM|INCH`.
    BeginPgm {
        /// True for INCH.
        inch: bool,
    },
    /// `END PGM name`.
    EndPgm,
    /// `BLK FORM 0.1 axis …` (corner 1) or `BLK FORM 0.2 …` (corner 2); corner 0 = another
    /// blank form, not recorded yet.
    BlkForm {
        /// 1 = MIN point, 2 = MAX point, 0 = other form.
        corner: u8,
        /// Tool axis given in 0.1.
        axis: Option<AxisLetter>,
    },
    /// `TOOL CALL …`.
    ToolCall,
    /// `L`.
    Line,
    /// `LP`.
    LinePolar,
    /// `C`.
    Circle,
    /// `CC`.
    Centre,
    /// `CR`.
    CircleRadius,
    /// `CT`.
    CircleTangent,
    /// `CP`.
    CirclePolar,
    /// `Qn = …` / `FN 0..8, 13`: the formula is in [`Parsed::code`].
    Assign {
        /// The parameter assigned.
        target: ParamRef,
    },
    /// `QSn = …`, `DECLARE STRING QSn = …`, `STRING FORMULA QSn = …`: the string formula
    /// is in [`Parsed::code`].
    AssignString {
        /// The QS parameter assigned.
        target: u32,
    },
    /// `FN 26 TABOPEN`, `FN 27 TABWRITE`, `FN 28 TABREAD`.
    Table(super::table::TableOp),
    /// A block of M words only.
    Misc,
    /// `STOP [M…]`.
    Stop,
    /// `LBL n` / `LBL "name"`: a jump target; `LBL 0` ends a subprogram.
    Label(LabelRef),
    /// `CALL LBL n [REP k]`: subprogram call, or section repeat with REP.
    CallLbl {
        /// The label called.
        label: LabelRef,
        /// Number of repeats (REP), when programmed.
        rep: Option<Value>,
    },
    /// `CALL PGM path`: the path as a byte range of the block text.
    CallPgm {
        /// First byte of the path.
        start: u32,
        /// One past its last byte.
        end: u32,
    },
    /// `FN 9..12: IF a cond b GOTO LBL label`.
    Jump {
        /// Left operand.
        a: Value,
        /// Comparison.
        cond: Cond,
        /// Right operand.
        b: Value,
        /// Target.
        label: LabelRef,
    },
    /// `FN 14: ERROR = n`.
    FnError {
        /// Error number.
        code: Value,
    },
    /// `FN 15: PRINT …` (`file` false) or `FN 16: F-PRINT …` (`file` true): the text after
    /// the keyword as a byte range.
    Print {
        /// True for FN 16.
        file: bool,
        /// First byte of the argument text.
        start: u32,
        /// One past its last byte.
        end: u32,
    },
    /// `FN 18: SYSREAD Qn = ID.. NR.. [IDX..]`.
    SysRead {
        /// The parameter written.
        target: ParamRef,
        /// Group number ID.
        id: Value,
        /// System data number NR.
        nr: Value,
        /// Index IDX (0 when absent).
        idx: Option<Value>,
    },
    /// `TOOL DEF n [L..] [R..]`: tool preselection, or an in-program tool definition.
    ToolDef {
        /// Tool number, when written as a number or parameter.
        number: Option<Value>,
        /// Length L.
        length: Option<Value>,
        /// Radius R.
        radius: Option<Value>,
    },
    /// `RND R..`: tangential rounding between the neighbouring contour elements.
    Round,
    /// `CHF len`: chamfer between the neighbouring lines; the length is in [`Words::radius`].
    Chamfer,
    /// `CTP PR.. PA..`: tangential arc to a polar end point.
    CircleTangentPolar,
    /// `SPL …`: spline; end point and coefficients in [`Parsed::spline`].
    Spline,
    /// `APPR …` (approach) or `DEP …` (departure).
    ApproachDepart {
        /// True for APPR.
        approach: bool,
        /// Path shape.
        kind: ApprKind,
        /// True for the polar variants (PLT, PLN, PCT, PLCT).
        polar: bool,
    },
    /// `CYCL DEF n …`: `sub` is `None` for the current format (Q assignments in
    /// [`Parsed::cycle`]), `Some(s)` for the old-format block `n.s` (items in
    /// [`Parsed::cycle`]).
    CycleDef {
        /// Cycle number.
        number: u32,
        /// Sub-block number of the old format.
        sub: Option<u8>,
    },
    /// `TCH PROBE n …`: a touch-probe cycle, DEF-active. `sub` as for [`Stmt::CycleDef`]
    /// (old format `0.0`/`0.1`, `1.0`…`1.2`; current format with Q assignments).
    TouchProbe {
        /// Cycle number.
        number: u32,
        /// Sub-block number of the old format.
        sub: Option<u8>,
    },
    /// `CYCL CALL [POS …|PAT] [F] [M…]`: words in [`Parsed::words`].
    CycleCall {
        /// Where the cycle is called.
        kind: super::cycle_words::CallKind,
    },
    /// `PATTERN DEF …`: elements in [`Parsed::cycle`].
    PatternDef,
    /// An FK block (FPOL, FL, FLT, FC, FCT, FSELECT): words in [`Parsed::fk`].
    Fk(super::fk_words::FkKind),
    /// `PLANE …`: words in [`Parsed::plane`].
    Plane,
    /// `FUNCTION TCPM …` (`on`) or `FUNCTION RESET TCPM`.
    Tcpm {
        /// True for FUNCTION TCPM.
        on: bool,
        /// Its feed, angle and interpolation modes (defaults for FUNCTION RESET TCPM).
        mode: super::tcpm::TcpmMode,
    },
    /// A block type recognised but not implemented yet.
    Unsupported {
        /// Its keyword.
        what: &'static str,
        /// Function number (FN n) when relevant.
        number: Option<u32>,
    },
}

/// A label as written: a number or a quoted name (byte range in the block text).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LabelRef {
    /// `LBL n`.
    Num(u32),
    /// `LBL "name"`.
    Name(u32, u32),
    /// `LBL QSn` in a call or jump: the label named by the text of QS n.
    Qs(u32),
}

/// The comparison of a conditional jump.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Cond {
    /// FN 9: equal.
    Equ,
    /// FN 10: not equal.
    Ne,
    /// FN 11: greater than.
    Gt,
    /// FN 12: less than.
    Lt,
}

/// The path shape of an APPR or DEP block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ApprKind {
    /// LT: tangential line.
    Lt,
    /// LN: line perpendicular to the contour.
    Ln,
    /// CT: tangential arc.
    Ct,
    /// LCT: line, then an arc tangent to it and to the contour.
    Lct,
}

/// Spline coefficients of one axis: value and decimal exponent, K3, K2, K1.
pub(crate) type SplineCoef = Option<(Value, i32)>;

/// The words of an SPL block.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct SplineWords {
    /// `[K3, K2, K1]` per axis, indexed by [`AxisLetter::index`].
    pub k: [[SplineCoef; 3]; 9],
}

/// One parsed block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Block {
    /// Block number as written.
    pub number: Option<u64>,
    /// True when the block is marked `/` (skipped while block skip is on).
    pub skip: bool,
    /// Byte position of the block's first character.
    pub start: usize,
    /// The statement.
    pub stmt: Stmt,
}

/// A syntax error at a byte position of the block text.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ParseError {
    /// Byte position in the block text.
    pub pos: usize,
    /// Block number when it was already read.
    pub number: Option<u64>,
    /// What is wrong.
    pub error: ProgramError,
}

/// The words of the last parsed block that its [`Stmt`] refers to, and the reused formula
/// buffer. A front-end (Klartext: `klartext::parser`, TNC ISO: `iso`) fills it; the machine
/// reads it when it executes the statement.
#[derive(Debug, Default)]
pub(crate) struct Parsed {
    /// Postfix code of the last parsed assignment.
    pub code: Vec<Rpn>,
    /// Words of the last parsed path, CC, M, STOP or BLK FORM block.
    pub words: Words,
    /// Words of the last parsed TOOL CALL.
    pub tool: ToolCall,
    /// Coefficients of the last parsed SPL block.
    pub spline: SplineWords,
    /// Words of the last parsed cycle block (CYCL DEF, PATTERN DEF).
    pub cycle: super::cycle_words::CycleWords,
    /// Words of the last parsed FK block.
    pub fk: super::fk_words::FkWords,
    /// Words of the last parsed PLANE block.
    pub plane: crate::tnc::plane::PlaneWords,
    /// Byte range of the program name in the last parsed BEGIN PGM or END PGM block (empty
    /// when the block names none).
    pub program_name: (usize, usize),
}

/// The bytes of a block as text, one character per byte (latin-1).
pub(crate) fn text_of(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| char::from(b)).collect()
}
