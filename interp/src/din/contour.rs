//! The FINISHED PART contour and the finishing cycle G890 that follows it.
//!
//! Contour blocks (G0 start point, G1 line, G2/G3 arcs with incremental centre, G12/G13 with
//! absolute centre or R) are turned into path elements when the section is read, with the
//! same geometry rules as machining moves (X diameters halved, arcs in the ZX plane). G890
//! runs the stored contour: a rapid move to its start point, then every element at the
//! active feed; `NS`/`NE` limit it to the elements from block NS to block NE.
//!
//! `BR` at an element inserts a transition to the next element: BR>0 a rounding arc of
//! radius BR tangent to both, BR<0 a chamfer whose ends lie |BR| from the corner on both
//! elements (between two straight elements; next to an arc it is reported as not supported).
//! Unknown coordinates (`X?`, `Z?`) of straight elements are solved from the line's angle A
//! and, when both are unknown, from the next element (see `unknown`).

use std::collections::VecDeque;

use super::block::{DinValue, DinWord};
use super::grooving::{self, Recess};
use super::lathe::{Group, Lathe, err_at, groups, num};
use super::unknown::{self, LineSpec};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Feed, Op, OpKind, Plane, Pose, SourceLoc};
use crate::tnc::exec::ExecError;

/// A contour element in the turning plane: points are (z, x radius).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Seg {
    /// A straight element from `a` to `b`.
    Line {
        /// Start.
        a: [f64; 2],
        /// End.
        b: [f64; 2],
    },
    /// An arc from `a` to `b` about `centre`, `sweep` degrees (positive from Z towards X).
    Arc {
        /// Start.
        a: [f64; 2],
        /// End.
        b: [f64; 2],
        /// Centre.
        centre: [f64; 2],
        /// Signed sweep, degrees.
        sweep: f64,
    },
}

/// Why a contour block failed: at this block, or at an unknown coordinate of an earlier one.
#[derive(Debug)]
pub(crate) enum ContourError {
    /// At a byte position of the current block.
    Here(ExecError),
    /// At a place of an earlier block.
    Earlier {
        /// Line.
        line: u32,
        /// Column.
        col: u32,
        /// Block number.
        block: Option<u64>,
        /// What is wrong.
        error: ProgramError,
    },
}

const NEXT_NEEDS: &str = "the next element must be a line with its end point X, Z and its angle A";

/// A line with both coordinates of its end unknown, waiting for the next element.
#[derive(Debug)]
struct Pending {
    words: Vec<DinWord>,
    number: Option<u64>,
    line: u32,
    col: u32,
    start: [f64; 2],
    angle: f64,
}

impl Pending {
    fn fail(&self, why: &str) -> ContourError {
        self.fail_with(ProgramError::Geometry(format!(
            "X?/Z? cannot be solved: {why}"
        )))
    }

    fn fail_with(&self, error: ProgramError) -> ContourError {
        ContourError::Earlier {
            line: self.line,
            col: self.col,
            block: self.number,
            error,
        }
    }
}

/// The words of a line with its end point replaced by `end` (z, x radius).
fn with_end(words: &[DinWord], end: [f64; 2]) -> Vec<DinWord> {
    let pos = words
        .iter()
        .find(|w| matches!(w.addr.as_str(), "X" | "Z" | "Xi" | "Zi" | "A"))
        .map_or(0, |w| w.pos);
    let mut out: Vec<DinWord> = words
        .iter()
        .filter(|w| !matches!(w.addr.as_str(), "X" | "Z" | "Xi" | "Zi" | "A"))
        .cloned()
        .collect();
    out.push(DinWord {
        addr: "X".into(),
        value: DinValue::Num(end[1] * 2.0),
        pos,
    });
    out.push(DinWord {
        addr: "Z".into(),
        value: DinValue::Num(end[0]),
        pos,
    });
    out
}

/// One stored contour element: the path op (feed to be replaced) and its block number.
#[derive(Debug, Clone, PartialEq)]
struct Element {
    number: Option<u64>,
    kind: OpKind,
}

/// The FINISHED PART contour.
#[derive(Debug)]
pub(crate) struct Contour {
    pen: Lathe,
    start: Option<(Option<u64>, Pose)>,
    elements: Vec<Element>,
    /// BR of the last element: the transition to insert before the next one.
    corner: Option<f64>,
    /// The block that wrote that BR.
    corner_block: Option<u64>,
    /// A line whose end waits for the next element.
    pending: Option<Pending>,
    /// The G22 recesses with their block numbers.
    recesses: Vec<(Option<u64>, Recess)>,
}

impl Contour {
    /// An empty contour.
    pub fn new() -> Self {
        let mut pen = Lathe::new(Pose::ZERO);
        pen.feed = Some(Feed::Rate(1.0));
        Contour {
            pen,
            start: None,
            elements: Vec::new(),
            corner: None,
            corner_block: None,
            pending: None,
            recesses: Vec::new(),
        }
    }

    /// Reads one contour block; `locate` gives the line and column of a byte position of
    /// this block (kept for an unknown coordinate solved later).
    pub fn add(
        &mut self,
        words: &[DinWord],
        number: Option<u64>,
        locate: &dyn Fn(usize) -> (u32, u32),
    ) -> Result<(), ContourError> {
        let spec = self.line_of(words)?;
        let start = [self.pen.pos[AxisLetter::Z], self.pen.pos[AxisLetter::X]];
        if let Some(p) = self.pending.take() {
            let end = match spec {
                Some(s) if !s.x_unknown && !s.z_unknown => match (s.z, s.x, s.angle) {
                    (Some(z), Some(x), Some(a)) => unknown::intersect(p.start, p.angle, [z, x], a)
                        .ok_or_else(|| p.fail("the next line runs parallel to it"))?,
                    _ => return Err(p.fail(NEXT_NEEDS)),
                },
                _ => return Err(p.fail(NEXT_NEEDS)),
            };
            let solved = with_end(&p.words, end);
            self.add_known(&solved, p.number)
                .map_err(|(_, e)| p.fail_with(e))?;
            return self.add(words, number, locate);
        }
        if let Some(s) = spec
            && (s.x_unknown || s.z_unknown)
        {
            let pos = s.pos.unwrap_or(0);
            let Some(a) = s.angle else {
                return Err(ContourError::Here((
                    Some(pos as u32),
                    ProgramError::Geometry("X?/Z? of a line needs its angle A to be solved".into()),
                )));
            };
            if s.x_unknown && s.z_unknown {
                let (line, col) = locate(pos);
                self.pending = Some(Pending {
                    words: words.to_vec(),
                    number,
                    line,
                    col,
                    start,
                    angle: a,
                });
                return Ok(());
            }
            let z = s.z.or(s.zi.map(|d| start[0] + d));
            let x = s.x.or(s.xi.map(|d| start[1] + d));
            let end = unknown::along_to(start, a, if s.z_unknown { None } else { z }, if s.x_unknown { None } else { x })
                .ok_or(ContourError::Here((
                    Some(pos as u32),
                    ProgramError::Geometry(format!(
                        "the unknown coordinate cannot be solved: a line at A{a} never reaches the given one"
                    )),
                )))?;
            return self
                .add_known(&with_end(words, end), number)
                .map_err(ContourError::Here);
        }
        if let Some(w) = words.iter().find(|w| w.value == DinValue::Unknown) {
            return Err(ContourError::Here(err_at(
                w,
                ProgramError::NotSupported(format!(
                    "{}? outside a straight element with its angle A",
                    w.addr
                )),
            )));
        }
        self.add_known(words, number).map_err(ContourError::Here)
    }

    /// At the end of the contour: an unknown still waiting for its next element fails.
    pub fn close(&mut self) -> Result<(), ContourError> {
        match self.pending.take() {
            Some(p) => Err(p.fail("the contour ends before the element it needs")),
            None => Ok(()),
        }
    }

    /// The straight element of a block, if it is one (explicit or modal G1).
    fn line_of(&self, words: &[DinWord]) -> Result<Option<LineSpec>, ContourError> {
        let gs = groups(words).map_err(ContourError::Here)?;
        let mut line = None;
        for g in &gs {
            let code = match g.g {
                None if g.words.is_empty() => continue,
                None => self.pen.motion,
                Some(c) => Some(c),
            };
            match code {
                Some(1) if line.is_none() => line = Some(g.words),
                _ => return Ok(None),
            }
        }
        match line {
            Some(w) => unknown::line_spec(w)
                .map(Some)
                .map_err(|(p, e)| ContourError::Here((Some(p as u32), e))),
            None => Ok(None),
        }
    }

    fn add_known(&mut self, words: &[DinWord], number: Option<u64>) -> Result<(), ExecError> {
        let br = match words.iter().find(|w| w.addr == "BR") {
            Some(w) => {
                let v = num(w)?;
                if v == 0.0 || !v.is_finite() {
                    return Err(err_at(
                        w,
                        ProgramError::OutOfRange("BR must not be 0".into()),
                    ));
                }
                Some(v)
            }
            None => None,
        };
        let gs = groups(words)?;
        let mut out = VecDeque::new();
        for g in &gs {
            let code = match g.g {
                Some(c @ (0 | 1 | 2 | 3 | 12 | 13)) => {
                    self.pen.motion = Some(c);
                    c
                }
                None if g.words.is_empty() => continue,
                Some(22) => {
                    self.recess(g, number)?;
                    continue;
                }
                None => self.pen.motion.ok_or((
                    None,
                    ProgramError::Missing("contour element without G0, G1, G2, G3, G12 or G13"),
                ))?,
                Some(other) => {
                    return Err((
                        g.g_word.map(|w| w.pos as u32),
                        ProgramError::NotSupported(format!("G{other} in a contour section")),
                    ));
                }
            };
            self.element(g, code, &mut out)?;
            if code == 0 {
                self.start = Some((number, self.pen.pos));
            }
        }
        let mut new: Vec<OpKind> = out.into_iter().map(|op| op.kind).collect();
        if let Some(size) = self.corner.take()
            && let (Some(prev), Some(next)) = (self.elements.last_mut(), new.first_mut())
        {
            // located at this block (the one that completes the corner); the BR is named
            let inserted = corner(&mut prev.kind, next, size).map_err(|e| {
                let at = match self.corner_block {
                    Some(n) => format!("BR of block {n}: {e}"),
                    None => format!("BR: {e}"),
                };
                (None, ProgramError::Geometry(at))
            })?;
            self.elements.push(Element {
                number: self.corner_block,
                kind: inserted,
            });
        }
        for kind in new {
            self.elements.push(Element { number, kind });
        }
        if let Some(c) = br {
            self.corner = Some(c);
            self.corner_block = number;
        }
        Ok(())
    }

    /// G22: splits the line before it around the recess (see `grooving`).
    fn recess(&mut self, g: &Group<'_>, number: Option<u64>) -> Result<(), ExecError> {
        let here = g.g_word.map(|w| w.pos as u32);
        if self.corner.is_some() {
            return Err((
                here,
                ProgramError::NotSupported("G22 on an element with a BR transition".into()),
            ));
        }
        let Some(Element {
            number: line_no,
            kind: OpKind::Line { from, to, feed },
        }) = self.elements.last().cloned()
        else {
            return Err((
                here,
                ProgramError::Geometry(
                    "G22 needs an axis-parallel straight element just before it".into(),
                ),
            ));
        };
        let zx = |p: &Pose| [p[AxisLetter::Z], p[AxisLetter::X]];
        let (recess, pts) = grooving::g22(g, zx(&from), zx(&to))?;
        self.elements.pop();
        for (i, pair) in pts.windows(2).enumerate() {
            let (Some(a), Some(b)) = (pair.first(), pair.get(1)) else {
                continue;
            };
            if (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-9 {
                continue;
            }
            let mut f = from;
            f[AxisLetter::Z] = a[0];
            f[AxisLetter::X] = a[1];
            let mut t = from;
            t[AxisLetter::Z] = b[0];
            t[AxisLetter::X] = b[1];
            self.elements.push(Element {
                // the first and last piece are the reference line's
                number: if i == 0 || i == 4 { line_no } else { number },
                kind: OpKind::Line {
                    from: f,
                    to: t,
                    feed,
                },
            });
        }
        self.recesses.push((number, recess));
        Ok(())
    }

    /// The G22 recess of block `ns` (the last one without NS).
    pub fn recess_of(&self, ns: Option<u64>) -> Result<Recess, ProgramError> {
        let found = match ns {
            None => self.recesses.last(),
            Some(n) => self.recesses.iter().rev().find(|(b, _)| *b == Some(n)),
        };
        found.map(|(_, r)| *r).ok_or_else(|| match ns {
            Some(n) => ProgramError::OutOfRange(format!("NS{n}: no G22 recess in block N{n}")),
            None => ProgramError::Missing(
                "the recessing cycle needs a G22 recess in the FINISHED PART contour",
            ),
        })
    }

    fn element(
        &mut self,
        g: &Group<'_>,
        code: u32,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let loc = SourceLoc::default();
        match code {
            0 => {
                self.pen.pos = self.pen.target(g)?;
                Ok(())
            }
            1 => {
                let to = self.pen.target(g)?;
                self.pen.line(to, Feed::Rate(1.0), loc, out);
                Ok(())
            }
            _ => self.pen.arc(g, code, loc, out),
        }
    }

    /// G890: finishes the contour from block `ns` to block `ne` at `feed`.
    pub fn finish(
        &self,
        lathe: &mut Lathe,
        ns: Option<u64>,
        ne: Option<u64>,
        feed: Feed,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ProgramError> {
        let Some((_, first)) = self.start else {
            return Err(ProgramError::Missing(
                "G890 needs a FINISHED PART contour starting with G0",
            ));
        };
        let picked = self.pick(ns, ne)?;
        let start = match picked.first().map(|e| &e.kind) {
            Some(OpKind::Line { from, .. } | OpKind::Arc { from, .. }) => *from,
            _ => first,
        };
        let mut approach = lathe.pos;
        approach[AxisLetter::X] = start[AxisLetter::X];
        approach[AxisLetter::Z] = start[AxisLetter::Z];
        lathe.line(approach, Feed::Rapid, loc, out);
        for e in picked {
            let mut kind = e.kind.clone();
            match &mut kind {
                OpKind::Line {
                    from, to, feed: f, ..
                }
                | OpKind::Arc {
                    from, to, feed: f, ..
                } => {
                    *f = feed;
                    *from = lathe.pos;
                    // keep the axes the contour does not describe (C, Y, B) where they are
                    for ax in [AxisLetter::X, AxisLetter::Z] {
                        from[ax] = lathe.pos[ax];
                    }
                    let mut t = lathe.pos;
                    t[AxisLetter::X] = to[AxisLetter::X];
                    t[AxisLetter::Z] = to[AxisLetter::Z];
                    *to = t;
                    lathe.pos = t;
                }
                _ => continue,
            }
            out.push_back(Op { kind, loc });
        }
        Ok(())
    }

    /// The contour elements from block `ns` to block `ne` as (z, x radius) segments.
    pub fn segments(&self, ns: Option<u64>, ne: Option<u64>) -> Result<Vec<Seg>, ProgramError> {
        let zx = |p: &Pose| [p[AxisLetter::Z], p[AxisLetter::X]];
        Ok(self
            .pick(ns, ne)?
            .iter()
            .filter_map(|e| match &e.kind {
                OpKind::Line { from, to, .. } => Some(Seg::Line {
                    a: zx(from),
                    b: zx(to),
                }),
                OpKind::Arc {
                    from,
                    to,
                    center,
                    sweep,
                    ..
                } => Some(Seg::Arc {
                    a: zx(from),
                    b: zx(to),
                    centre: *center,
                    sweep: *sweep,
                }),
                _ => None,
            })
            .collect())
    }

    /// The elements from block `ns` to block `ne` (all without them).
    fn pick(&self, ns: Option<u64>, ne: Option<u64>) -> Result<&[Element], ProgramError> {
        let from_index = match ns {
            None => 0,
            Some(n) => self
                .elements
                .iter()
                .position(|e| e.number == Some(n))
                .ok_or_else(|| ProgramError::OutOfRange(format!("NS{n}: no contour block N{n}")))?,
        };
        let to_index = match ne {
            None => self.elements.len(),
            Some(n) => {
                self.elements
                    .iter()
                    .rposition(|e| e.number == Some(n))
                    .ok_or_else(|| {
                        ProgramError::OutOfRange(format!("NE{n}: no contour block N{n}"))
                    })?
                    + 1
            }
        };
        Ok(self.elements.get(from_index..to_index).unwrap_or(&[]))
    }
}

/// Inserts the BR transition between two straight elements, shortening both; returns the
/// inserted element.
fn corner(prev: &mut OpKind, next: &mut OpKind, size: f64) -> Result<OpKind, ProgramError> {
    let zx = |p: &Pose| [p[AxisLetter::Z], p[AxisLetter::X]];
    let (
        OpKind::Line {
            from: p0,
            to: c,
            feed,
        },
        OpKind::Line {
            from: c2, to: p2, ..
        },
    ) = (&mut *prev, &mut *next)
    else {
        return Err(ProgramError::NotSupported(
            "BR next to an arc (transitions between straight elements only)".into(),
        ));
    };
    let (a, k, b) = (zx(p0), zx(c), zx(p2));
    let d1 = [k[0] - a[0], k[1] - a[1]];
    let d2 = [b[0] - k[0], b[1] - k[1]];
    let (l1, l2) = (d1[0].hypot(d1[1]), d2[0].hypot(d2[1]));
    if l1 < 1e-9 || l2 < 1e-9 {
        return Err(ProgramError::Geometry(
            "BR at an element of zero length".into(),
        ));
    }
    let u1 = [d1[0] / l1, d1[1] / l1];
    let u2 = [d2[0] / l2, d2[1] / l2];
    let cross = u1[0] * u2[1] - u1[1] * u2[0];
    let dot = u1[0] * u2[0] + u1[1] * u2[1];
    if cross.abs() < 1e-12 {
        return Err(ProgramError::Geometry(
            "BR between elements in one line: there is no corner".into(),
        ));
    }
    let turn = cross.atan2(dot);
    let (d, radius) = if size > 0.0 {
        (size * (turn.abs() / 2.0).tan(), Some(size))
    } else {
        (-size, None)
    };
    if d > l1 + 1e-9 || d > l2 + 1e-9 {
        return Err(ProgramError::Geometry(format!(
            "BR{size}: the transition needs {d:.3} mm on each element, longer than the element"
        )));
    }
    let t1 = [k[0] - d * u1[0], k[1] - d * u1[1]];
    let t2 = [k[0] + d * u2[0], k[1] + d * u2[1]];
    let mut q1 = *c;
    q1[AxisLetter::Z] = t1[0];
    q1[AxisLetter::X] = t1[1];
    let mut q2 = *c2;
    q2[AxisLetter::Z] = t2[0];
    q2[AxisLetter::X] = t2[1];
    let feed = *feed;
    *c = q1;
    *c2 = q2;
    Ok(match radius {
        None => OpKind::Line {
            from: q1,
            to: q2,
            feed,
        },
        Some(r) => {
            // the centre lies on the inner side: left of the first element for a left turn
            let side = if cross > 0.0 { 1.0 } else { -1.0 };
            let centre = [t1[0] - side * r * u1[1], t1[1] + side * r * u1[0]];
            OpKind::Arc {
                from: q1,
                to: q2,
                center: centre,
                plane: Plane::ZX,
                sweep: turn.to_degrees(),
                feed,
            }
        }
    })
}
