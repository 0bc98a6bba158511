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
//! Unknown coordinates (`X?`, `Z?`) are reported as not supported yet.

use std::collections::VecDeque;

use super::block::{DinValue, DinWord};
use super::lathe::{Group, Lathe, err_at, groups, num};
use crate::diag::ProgramError;
use crate::klartext::exec::ExecError;
use crate::op::{AxisLetter, Feed, Op, OpKind, Plane, Pose, SourceLoc};

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
        }
    }

    /// Reads one contour block.
    pub fn add(&mut self, words: &[DinWord], number: Option<u64>) -> Result<(), ExecError> {
        if let Some(w) = words.iter().find(|w| w.value == DinValue::Unknown) {
            return Err(err_at(
                w,
                ProgramError::NotSupported(format!(
                    "{}? in a contour (unknown coordinates)",
                    w.addr
                )),
            ));
        }
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
        let picked = self.elements.get(from_index..to_index).unwrap_or(&[]);
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
