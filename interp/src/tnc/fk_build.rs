//! FK equations from the words of an FL/FLT/FC/FCT block: coordinates, polar data, relative
//! data, directions, lengths, radius, auxiliary points and the closing condition.

use super::exec::{ExecError, Machine, at, here};
use super::fk_eqs::{Con, Dir, Pt};
use super::fk_words::{FkKind, FkWords, RelRef};
use super::geom::P2;
use super::stmt::Coord;
use crate::diag::ProgramError;

impl Machine {
    /// Pose indices of the working plane's first and second axis.
    pub(super) fn plane_idx(&self) -> (usize, usize) {
        let (a, b, _) = self.plane.axes();
        (a.index(), b.index())
    }

    /// A pose's working-plane coordinates.
    pub(super) fn plane_pt(&self, p: crate::op::Pose) -> P2 {
        let (a, b, _) = self.plane.axes();
        [p[a], p[b]]
    }

    /// A length word's value in mm.
    pub(super) fn len_of(&self, c: &Coord) -> f64 {
        self.params.value(c.value) * self.scale
    }

    /// The serial number of the FK element of block `r`.
    pub(super) fn fk_ref(&self, r: (u64, u32)) -> Result<u64, ExecError> {
        let st = &self.fk;
        st.pending
            .iter()
            .find(|p| p.loc.block == Some(r.0))
            .map(|p| p.sid)
            .or_else(|| {
                st.done
                    .iter()
                    .rev()
                    .find(|d| d.block == Some(r.0))
                    .map(|d| d.sid)
            })
            .ok_or_else(|| {
                at(
                    r.1,
                    ProgramError::Geometry(format!(
                        "relative FK data refer to block {}, which is not an earlier FK element",
                        r.0
                    )),
                )
            })
    }

    /// The base point of a coordinate word: block `rel`'s end, the start point for `I`
    /// words, none for absolute ones.
    pub(super) fn base(&self, c: &Coord, rel: RelRef, sid: u64) -> Result<Option<Pt>, ExecError> {
        Ok(match rel {
            Some(r) => Some(Pt::End(self.fk_ref(r)?)),
            None if c.incremental => Some(Pt::Start(sid)),
            None => None,
        })
    }

    /// The FPOL pole, or an error at the polar word at `pos`.
    pub(super) fn fk_pole(&self, pos: u32) -> Result<P2, ExecError> {
        self.fk.pole.ok_or_else(|| {
            at(
                pos,
                ProgramError::Geometry("FK polar data need a pole: program FPOL first".into()),
            )
        })
    }

    /// Rejects words of the tool axis: FK elements lie in the working plane.
    pub(super) fn fk_plane_only(&self, f: &FkWords) -> Result<(), ExecError> {
        let (a, b) = self.plane_idx();
        for k in 0..3 {
            if k == a || k == b {
                continue;
            }
            let word = f.end[k]
                .or(f.cc[k])
                .map(|c| c.pos)
                .or(f.rel_end[k].map(|r| r.1))
                .or(f.rel_cc[k].map(|r| r.1));
            let stray = f.aux.iter().any(|p| p[k].is_some()) || f.pd[k].is_some();
            if word.is_some() || stray {
                return Err(at(
                    word.unwrap_or(0),
                    ProgramError::Geometry(
                        "FK elements lie in the working plane: no tool-axis coordinates".into(),
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The equations of one FK block.
    pub(super) fn fk_equations(
        &self,
        f: &FkWords,
        kind: FkKind,
        sid: u64,
    ) -> Result<(Vec<Con>, bool), ExecError> {
        let line = matches!(kind, FkKind::Line | FkKind::LineTangent);
        let (a, b) = self.plane_idx();
        let mut cons = Vec::new();
        let ccw = match f.dr {
            Some((ccw, _)) => ccw,
            None if line => true,
            None => {
                return Err(here(ProgramError::Missing(
                    "FC and FCT need the direction DR+ or DR-",
                )));
            }
        };
        for (axis, k) in [(0, a), (1, b)] {
            if let Some(c) = f.end.get(k).copied().flatten() {
                let rel = f.rel_end.get(k).copied().flatten();
                cons.push(Con::Coord {
                    pt: Pt::End(sid),
                    axis,
                    base: self.base(&c, rel, sid)?,
                    v: self.len_of(&c),
                });
            }
            if let Some(c) = f.cc.get(k).copied().flatten() {
                let rel = f.rel_cc.get(k).copied().flatten();
                cons.push(Con::Coord {
                    pt: Pt::Centre(sid),
                    axis,
                    base: self.base(&c, rel, sid)?,
                    v: self.len_of(&c),
                });
            }
        }
        for (r, rrel, a, arel, pt) in [
            (f.pr, f.rel_pr, f.pa, f.rel_pa, Pt::End(sid)),
            (f.ccpr, f.rel_ccpr, f.ccpa, f.rel_ccpa, Pt::Centre(sid)),
        ] {
            let (Some(r), Some(a)) = (r, a) else { continue };
            let pole = self.fk_pole(r.pos)?;
            cons.push(Con::Polar {
                pt,
                pole,
                rbase: self.base(&r, rrel, sid)?,
                r: self.len_of(&r),
                abase: self.base(&a, arel, sid)?,
                a: self.params.value(a.value),
            });
        }
        let polar = [
            (f.pr, f.rel_pr, Pt::End(sid), true, f.pa.is_none()),
            (f.pa, f.rel_pa, Pt::End(sid), false, f.pr.is_none()),
            (f.ccpr, f.rel_ccpr, Pt::Centre(sid), true, f.ccpa.is_none()),
            (f.ccpa, f.rel_ccpa, Pt::Centre(sid), false, f.ccpr.is_none()),
        ];
        for (c, rel, pt, radius, alone) in polar {
            if !alone {
                continue;
            }
            let Some(c) = c else { continue };
            let pole = self.fk_pole(c.pos)?;
            let base = self.base(&c, rel, sid)?;
            cons.push(if radius {
                Con::PolarR {
                    pt,
                    pole,
                    base,
                    v: self.len_of(&c),
                }
            } else {
                Con::PolarA {
                    pt,
                    pole,
                    base,
                    v: self.params.value(c.value),
                }
            });
        }
        let mut dirs = Vec::new();
        if let Some(c) = f.an {
            let deg = self.params.value(c.value);
            dirs.push(match f.rel_an {
                Some(r) => Dir::EndOf(self.fk_ref(r)?, deg),
                None => Dir::Angle(deg),
            });
        }
        if matches!(kind, FkKind::LineTangent | FkKind::ArcTangent) {
            if sid == self.fk.first() && self.fk.origin_dir.is_none() {
                return Err(here(ProgramError::Geometry(
                    "FLT/FCT needs a preceding contour element to be tangent to".into(),
                )));
            }
            dirs.push(Dir::Incoming(sid));
        }
        for dir in dirs {
            cons.push(if line {
                Con::LineDir { sid, dir }
            } else {
                Con::ArcStartDir { sid, dir }
            });
        }
        if let Some((v, pos)) = f.len {
            let len = self.params.value(v) * self.scale;
            if !(len > 0.0 && len.is_finite()) {
                return Err(at(
                    pos,
                    ProgramError::OutOfRange("LEN must be positive".into()),
                ));
            }
            cons.push(Con::Len { sid, len });
        }
        if !line {
            cons.push(Con::ArcRound { sid });
            if let Some(c) = f.cca {
                cons.push(Con::EndAngle {
                    sid,
                    a: self.params.value(c.value),
                });
            }
            if let Some((v, pos)) = f.radius {
                let r = (self.params.value(v) * self.scale).abs();
                if !(r > 0.0 && r.is_finite()) {
                    return Err(at(
                        pos,
                        ProgramError::OutOfRange("FC radius must not be 0".into()),
                    ));
                }
                cons.push(Con::Radius { sid, r });
            }
        }
        for (i, p) in f.aux.iter().enumerate() {
            if p.iter().all(Option::is_none) {
                continue;
            }
            let (Some(u), Some(v)) = (p.get(a).copied().flatten(), p.get(b).copied().flatten())
            else {
                return Err(at(
                    f.aux_pos.get(i).copied().unwrap_or(0),
                    ProgramError::Missing("an auxiliary point needs both plane coordinates"),
                ));
            };
            let q = [
                self.params.value(u) * self.scale,
                self.params.value(v) * self.scale,
            ];
            cons.push(Con::On { sid, q });
        }
        let pd = (
            f.pd.get(a).copied().flatten(),
            f.pd.get(b).copied().flatten(),
        );
        match (pd, f.dist) {
            ((None, None), None) => {}
            ((Some(u), Some(v)), Some((d, pos))) => {
                let d = self.params.value(d) * self.scale;
                if !(d >= 0.0 && d.is_finite()) {
                    return Err(at(
                        pos,
                        ProgramError::OutOfRange("D must not be negative".into()),
                    ));
                }
                let q = [
                    self.params.value(u) * self.scale,
                    self.params.value(v) * self.scale,
                ];
                cons.push(Con::Dist { sid, q, d });
            }
            _ => {
                return Err(here(ProgramError::Missing(
                    "PDX, PDY and D go together: a point and its distance from the element",
                )));
            }
        }
        if let Some((false, pos)) = f.clsd {
            let Some(s) = self.fk.clsd_start else {
                return Err(at(
                    pos,
                    ProgramError::Geometry("CLSD- without an element marked CLSD+".into()),
                ));
            };
            let to = if s == sid {
                Pt::Const(self.fk.origin)
            } else {
                Pt::Start(s)
            };
            cons.push(Con::Close { sid, to });
        }
        Ok((cons, ccw))
    }
}
