//! The words of a cycle block as the TNC core executes them: the Q assignments of a
//! current-format `CYCL DEF`, the items of an old-format sub-block and the elements of a
//! `PATTERN DEF` (Klartext writes them in [`crate::klartext::cycle`], TNC ISO in
//! [`crate::iso`]).

use super::expr::Value;

/// The value of a cycle parameter as written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum CycleValue {
    /// A number or a parameter.
    Val(Value),
    /// `AUTO` / `FAUTO`: the feed rate of the last TOOL CALL.
    Auto,
    /// `MAX` / `FMAX`: rapid traverse.
    Max,
    /// `PREDEF`: a global default (not available here: treated as not given).
    Predef,
}

/// One `Qn=value` assignment of a current-format cycle definition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct QEntry {
    /// The parameter number.
    pub q: u32,
    /// Its value.
    pub value: CycleValue,
    /// Byte position of the assignment in the block text.
    pub pos: u32,
}

/// Longest word kept in an old-format sub-block (longer words are cut).
pub(crate) const OLD_WORD_LEN: usize = 12;

/// One word of an old-format sub-block: a word with or without a value, or a plain value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct OldItem {
    /// The word, upper case (`X`, `IX`, `ROT`, `SCL`, `TIEFE`, `#` for a table row); empty
    /// for a plain value.
    pub word: [u8; OLD_WORD_LEN],
    /// Used length of `word`.
    pub len: u8,
    /// The value after the word.
    pub value: Option<Value>,
    /// A sign written without a value (`DR+`): true for minus.
    pub sign_only: Option<bool>,
    /// Byte position of the item in the block text.
    pub pos: u32,
}

impl OldItem {
    /// The word as bytes.
    pub fn word(&self) -> &[u8] {
        self.word.get(..usize::from(self.len)).unwrap_or(&[])
    }
}

/// How a cycle is called.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum CallKind {
    /// `CYCL CALL [M…]`: at the current position.
    Here,
    /// `CYCL CALL POS X.. Y.. Z.. [F..|FMAX] [M…]`: at the given position.
    Pos,
    /// `CYCL CALL PAT [F..|FMAX] [M…]`: at every point of the last `PATTERN DEF`.
    Pat,
}

/// The kinds of point-pattern elements of `PATTERN DEF`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PatternKind {
    /// `POSn (X Y Z)`: one point.
    Pos,
    /// `ROWn (X Y D NUM ROT Z)`: points on a straight line.
    Row,
    /// `PATn (X Y DX DY NUMX NUMY ROT ROTX ROTY Z)`: a grid.
    Pat,
    /// `FRAMEn (…)`: the outline of a grid.
    Frame,
    /// `CIRCn (X Y D START NUM Z)`: a full circle.
    Circ,
    /// `PITCHCIRCn (X Y D START STEP NUM Z)`: a pitch circle.
    PitchCirc,
}

/// Most words one pattern element may carry.
pub(crate) const PATTERN_WORDS: usize = 12;

/// One element of `PATTERN DEF`: its kind and its words (upper case name, value).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PatternItem {
    /// Kind.
    pub kind: PatternKind,
    /// Words as (name, length, value).
    pub words: [([u8; 8], u8, Value); PATTERN_WORDS],
    /// Used entries of `words`.
    pub count: u8,
    /// Byte position of the element.
    pub pos: u32,
}

impl PatternItem {
    /// The value of word `name`, if written.
    pub fn get(&self, name: &[u8]) -> Option<Value> {
        self.words
            .iter()
            .take(usize::from(self.count))
            .find(|(w, n, _)| w.get(..usize::from(*n)) == Some(name))
            .map(|(_, _, v)| *v)
    }
}

/// The words of the last parsed cycle block.
#[derive(Debug, Default)]
pub(crate) struct CycleWords {
    /// Q assignments of a current-format definition.
    pub q: Vec<QEntry>,
    /// Items of an old-format sub-block.
    pub items: Vec<OldItem>,
    /// Elements of a `PATTERN DEF`.
    pub pattern: Vec<PatternItem>,
}
