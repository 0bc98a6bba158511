//! The words of an FK block as the TNC core solves them ([`super::fk_solve`]); the
//! Klartext front-end reads them in [`crate::klartext::fk`].

use super::expr::Value;
use super::stmt::{Coord, Words};

/// Which FK block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FkKind {
    /// `FPOL`: pole for polar FK data.
    Pole,
    /// `FL`: straight line.
    Line,
    /// `FLT`: straight line tangent to the previous element.
    LineTangent,
    /// `FC`: circular arc.
    Arc,
    /// `FCT`: circular arc tangent to the previous element.
    ArcTangent,
    /// `FSELECT n`: solution choice.
    Select,
}

/// A relative-data reference: the block number the value refers to, and the word position.
pub(crate) type RelRef = Option<(u64, u32)>;

/// Words of an FK block; coordinates are indexed 0 = X, 1 = Y, 2 = Z.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct FkWords {
    /// End point (or FPOL pole) coordinates.
    pub end: [Option<Coord>; 3],
    /// Polar radius of the end point.
    pub pr: Option<Coord>,
    /// Polar angle of the end point.
    pub pa: Option<Coord>,
    /// Direction angle AN.
    pub an: Option<Coord>,
    /// Angle of the arc end point about the centre, CCA.
    pub cca: Option<Coord>,
    /// Length LEN.
    pub len: Option<(Value, u32)>,
    /// Radius R.
    pub radius: Option<(Value, u32)>,
    /// Direction of rotation (true = DR+).
    pub dr: Option<(bool, u32)>,
    /// Centre coordinates.
    pub cc: [Option<Coord>; 3],
    /// Polar radius of the centre.
    pub ccpr: Option<Coord>,
    /// Polar angle of the centre.
    pub ccpa: Option<Coord>,
    /// CLSD+ (true) or CLSD- (false).
    pub clsd: Option<(bool, u32)>,
    /// Auxiliary points P1..P3 on the element.
    pub aux: [[Option<Value>; 3]; 3],
    /// Position of each auxiliary point's first word.
    pub aux_pos: [u32; 3],
    /// Auxiliary point at distance D.
    pub pd: [Option<Value>; 3],
    /// Distance D of the PD point.
    pub dist: Option<(Value, u32)>,
    /// RX/RY/RZ references.
    pub rel_end: [RelRef; 3],
    /// RPR reference.
    pub rel_pr: RelRef,
    /// RPA reference.
    pub rel_pa: RelRef,
    /// RAN reference.
    pub rel_an: RelRef,
    /// RCCX/RCCY/RCCZ references.
    pub rel_cc: [RelRef; 3],
    /// RCCPR reference.
    pub rel_ccpr: RelRef,
    /// RCCPA reference.
    pub rel_ccpa: RelRef,
    /// FSELECT number.
    pub select: Option<(u32, u32)>,
    /// Feed, M words and radius compensation, in the form of L blocks.
    pub base: Words,
}
