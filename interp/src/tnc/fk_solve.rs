//! FK free contour programming: turning FL/FLT/FC/FCT data into lines and arcs.
//!
//! Rules (TNC FK programming, in the working plane of the tool axis):
//! - The start of an FK section is the position reached by the block before it; that block
//!   must fix both working-plane coordinates. FLT/FCT at the start of a section are tangent
//!   to the direction of travel at the end of that block.
//! - Each FK element's unknowns are its end point and, for arcs, its centre. Every word is an
//!   equation on them: end/centre coordinates, polar data about the FPOL pole, the direction
//!   AN (of travel for a line, of the entry tangent for an arc), LEN, the radius R, tangency to
//!   the previous element (FLT, FCT), auxiliary points on the element (for a line also on its
//!   extension), a point at distance D from it, CLSD- (its end is the start of the CLSD+
//!   element) and relative data (the incremental value counts from the element of the named
//!   block). An arc always keeps its radius: start and end are equally far from the centre.
//! - After each FK block the pending elements are solved together. The leading elements whose
//!   unknowns the data fix are emitted as ordinary lines and arcs; the rest wait for the data
//!   of later FK blocks. Nothing of a waiting element is handed out.
//! - When the fixed elements have several solutions, they wait too (later data may exclude
//!   some); `FSELECT n` picks solution n. Solutions are numbered by comparing their unknowns
//!   in program order (end point first axis, second axis, then centre) and taking the
//!   smaller value first at the first one that differs.
//! - A non-FK block that moves (or RND/CHF, END PGM) ends the section: every pending element
//!   must be determined by then, with one solution or an FSELECT. Data that no geometry
//!   satisfies are reported at the block that introduced them.
//! - Lines of length zero are not FK solutions; an arc may close to a full circle only when
//!   both coordinates of its end point are programmed.

use std::collections::VecDeque;

use super::exec::{ExecError, Flow, Machine, at, here};
use super::fk_eqs::{Con, Ctx, Pt, unit};
use super::fk_lm::{Lcg, determined, least_squares};
use super::fk_words::{FkKind, FkWords};
use super::geom::{self, P2};
use super::mfunc::MWords;
use super::stmt::Words;
use crate::diag::ProgramError;
use crate::op::{Feed, Op, OpKind, SourceLoc};

/// Most FK elements that may wait for data at one time.
const MAX_PENDING: usize = 16;
/// Solved FK elements kept for relative data (the TNC allows references 64 blocks back).
const MAX_DONE: usize = 64;
/// Start points tried per solve.
const STARTS: usize = 48;
/// Solutions whose Jacobian null space is examined.
const CHECKED: usize = 6;
/// Two solutions closer than this (mm) are the same.
const SAME: f64 = 1e-5;

/// An FK element waiting to be solved.
#[derive(Debug, Clone)]
pub(super) struct Pending {
    /// Serial number of the element.
    pub sid: u64,
    /// FL/FLT (true) or FC/FCT.
    pub line: bool,
    /// DR+ (arcs).
    pub ccw: bool,
    /// An arc whose end point is programmed in both axes may be a full circle.
    pub full: bool,
    /// Its equations.
    pub cons: Vec<Con>,
    /// Where the block is.
    pub loc: SourceLoc,
    /// Feed, M words and compensation of the block.
    pub words: Words,
    /// Feed of the motion.
    pub feed: Feed,
}

/// A solved FK element (for relative data).
#[derive(Debug, Clone, Copy)]
pub(super) struct Done {
    /// Serial number of the element.
    pub sid: u64,
    /// Block number of the FK block.
    pub block: Option<u64>,
    /// Start point.
    pub start: P2,
    /// End point.
    pub end: P2,
    /// Centre (arcs).
    pub centre: P2,
    /// Unit direction of travel at the end.
    pub end_dir: P2,
}

/// FK state of a running program.
#[derive(Debug, Default)]
pub(crate) struct FkState {
    /// FPOL pole.
    pub(super) pole: Option<P2>,
    /// Start point of the first pending element.
    pub(super) origin: P2,
    /// Direction of travel arriving at `origin`.
    pub(super) origin_dir: Option<P2>,
    /// Elements waiting for data.
    pub(super) pending: Vec<Pending>,
    /// Serial number of the next element.
    pub(super) next_sid: u64,
    /// Recently solved elements.
    pub(super) done: VecDeque<Done>,
    /// The element marked CLSD+.
    pub(super) clsd_start: Option<u64>,
}

impl FkState {
    /// True while FK elements wait for data.
    pub fn pending(&self) -> bool {
        !self.pending.is_empty()
    }

    /// Serial number of the first pending element (the next one when none waits).
    pub(super) fn first(&self) -> u64 {
        self.pending.first().map_or(self.next_sid, |p| p.sid)
    }

    fn offsets(&self) -> (Vec<usize>, usize) {
        let mut off = Vec::with_capacity(self.pending.len());
        let mut n = 0;
        for p in &self.pending {
            off.push(n);
            n += if p.line { 2 } else { 4 };
        }
        (off, n)
    }

    fn label(loc: &SourceLoc) -> String {
        loc.block
            .map_or_else(|| format!("line {}", loc.line), |b| b.to_string())
    }

    fn range(&self, from: usize, to: usize) -> String {
        let a = self.pending.get(from).map(|p| Self::label(&p.loc));
        let b = self.pending.get(to).map(|p| Self::label(&p.loc));
        match (a, b) {
            (Some(a), Some(b)) if from != to => format!("{a}–{b}"),
            (Some(a), _) => a,
            _ => String::new(),
        }
    }
}

/// What a solve found.
enum Outcome {
    /// No geometry satisfies the data.
    None,
    /// `fixed` leading elements are determined; their distinct solutions (unknowns of those
    /// elements), in FSELECT order.
    Some { fixed: usize, sols: Vec<Vec<f64>> },
}

impl FkState {
    fn residuals(&self, off: &[usize], x: &[f64], out: &mut Vec<f64>) {
        out.clear();
        let ctx = Ctx { st: self, off, x };
        for p in &self.pending {
            for c in &p.cons {
                ctx.residual(c, out);
            }
        }
    }

    fn valid(&self, off: &[usize], x: &[f64]) -> bool {
        let ctx = Ctx { st: self, off, x };
        self.pending.iter().all(|p| {
            let s = ctx.pt(Pt::Start(p.sid));
            let e = ctx.pt(Pt::End(p.sid));
            let long = geom::norm(geom::sub(e, s)) > 1e-6 || p.full;
            let round = p.line || ctx.radius(p.sid) > 1e-6;
            long && round && p.cons.iter().all(|c| ctx.admissible(c))
        })
    }

    /// A length scale of the data, for start points.
    fn scale(&self) -> f64 {
        let o = self.origin;
        let far = |q: P2| geom::norm(geom::sub(q, o));
        let mut m: f64 = 10.0;
        if let Some(p) = self.pole {
            m = m.max(far(p));
        }
        for p in &self.pending {
            for c in &p.cons {
                match *c {
                    Con::Coord { v, .. } | Con::PolarR { v, .. } => m = m.max(v.abs()),
                    Con::Len { len, .. } => m = m.max(len),
                    Con::Polar { r, .. } => m = m.max(r.abs()),
                    Con::Radius { r, .. } => m = m.max(r),
                    Con::On { q, .. } | Con::Dist { q, .. } => m = m.max(far(q)),
                    Con::Close {
                        to: Pt::Const(q), ..
                    } => m = m.max(far(q)),
                    _ => {}
                }
            }
        }
        m * 1.5
    }

    /// A start point for the solver that follows the data element by element: known
    /// coordinates, the programmed direction, length and radius, random values for the rest.
    fn seed(&self, off: &[usize], n: usize, rng: &mut Lcg, l: f64) -> Vec<f64> {
        let mut x = vec![0.0; n];
        for (i, p) in self.pending.iter().enumerate() {
            let o = off.get(i).copied().unwrap_or(0);
            let (start, mut dir) = {
                let ctx = Ctx {
                    st: self,
                    off,
                    x: &x,
                };
                let dir = p.cons.iter().find_map(|c| match *c {
                    Con::LineDir { dir, .. } | Con::ArcStartDir { dir, .. } => Some(ctx.dir(dir)),
                    _ => None,
                });
                (ctx.pt(Pt::Start(p.sid)), dir)
            };
            let (mut len, mut r) = (None, None);
            let (mut end, mut cc) = ([None; 2], [None; 2]);
            for c in &p.cons {
                match *c {
                    Con::Len { len: v, .. } => len = Some(v),
                    Con::Radius { r: v, .. } => r = Some(v),
                    Con::Coord { pt, axis, base, v } => {
                        let b = match base {
                            None => 0.0,
                            Some(Pt::Start(_)) => start.get(axis).copied().unwrap_or(0.0),
                            Some(_) => continue,
                        };
                        match pt {
                            Pt::End(_) => end[axis % 2] = Some(b + v),
                            Pt::Centre(_) => cc[axis % 2] = Some(b + v),
                            _ => {}
                        }
                    }
                    _ => {}
                }
            }
            if dir.is_some_and(|d| geom::norm(d) < 0.5) {
                dir = None;
            }
            let s = len.unwrap_or(l * (0.05 + 0.95 * rng.next().abs()));
            let rand =
                |rng: &mut Lcg, c: P2, k: f64| [c[0] + k * rng.next(), c[1] + k * rng.next()];
            let vals: Vec<f64> = if p.line {
                let e = match dir {
                    Some(u) => [start[0] + s * u[0], start[1] + s * u[1]],
                    None => rand(rng, start, l),
                };
                vec![end[0].unwrap_or(e[0]), end[1].unwrap_or(e[1])]
            } else {
                let rad = r.unwrap_or(s);
                let c = match dir {
                    Some(u) => {
                        let nrm = if p.ccw { [-u[1], u[0]] } else { [u[1], -u[0]] };
                        [start[0] + rad * nrm[0], start[1] + rad * nrm[1]]
                    }
                    None => rand(rng, start, l),
                };
                let c = [cc[0].unwrap_or(c[0]), cc[1].unwrap_or(c[1])];
                let rr = geom::norm(geom::sub(start, c));
                let e = geom::polar(c, rr, 180.0 * rng.next());
                vec![end[0].unwrap_or(e[0]), end[1].unwrap_or(e[1]), c[0], c[1]]
            };
            for (k, v) in vals.into_iter().enumerate() {
                if let Some(slot) = x.get_mut(o + k) {
                    *slot = v;
                }
            }
        }
        x
    }

    fn solve(&self) -> Outcome {
        let (off, n) = self.offsets();
        let f = |x: &[f64], out: &mut Vec<f64>| self.residuals(&off, x, out);
        let l = self.scale();
        let mut rng = Lcg(0x9e37_79b9_7f4a_7c15 ^ n as u64);
        let mut found: Vec<(Vec<f64>, usize)> = Vec::new();
        for k in 0..STARTS {
            let x0: Vec<f64> = if k % 4 == 3 {
                (0..n)
                    .map(|k| self.origin[k % 2] + l * rng.next())
                    .collect()
            } else {
                self.seed(&off, n, &mut rng, l)
            };
            let Some(x) = least_squares(&f, x0) else {
                continue;
            };
            if !self.valid(&off, &x) {
                continue;
            }
            if found.len() >= CHECKED {
                // which unknowns are fixed does not change between solutions: the first
                // ones tell, the rest only count distinct solutions
                let fixed = found.iter().map(|f| f.1).min().unwrap_or(0);
                found.push((x, fixed));
                continue;
            }
            let det = determined(&f, &x);
            let mut fixed = 0;
            for (i, p) in self.pending.iter().enumerate() {
                let o = off.get(i).copied().unwrap_or(0);
                let w = if p.line { 2 } else { 4 };
                if det.get(o..o + w).is_some_and(|d| d.iter().all(|b| *b)) {
                    fixed = i + 1;
                } else {
                    break;
                }
            }
            found.push((x, fixed));
        }
        if found.is_empty() {
            return Outcome::None;
        }
        let fixed = found.iter().map(|f| f.1).min().unwrap_or(0);
        let width = off.get(fixed).copied().unwrap_or(n);
        let mut sols: Vec<Vec<f64>> = Vec::new();
        for (x, _) in &found {
            let head = x.get(..width).unwrap_or(&[]).to_vec();
            if !sols.iter().any(|s| same(s, &head)) {
                sols.push(head);
            }
        }
        sols.sort_by(|a, b| {
            a.iter()
                .zip(b)
                .find(|(p, q)| (*p - *q).abs() > SAME)
                .map_or(std::cmp::Ordering::Equal, |(p, q)| p.total_cmp(q))
        });
        Outcome::Some { fixed, sols }
    }
}

fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(p, q)| (p - q).abs() <= SAME)
}

impl Machine {
    /// Runs an FK block.
    pub(super) fn fk_exec(
        &mut self,
        kind: FkKind,
        f: &FkWords,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<Flow, ExecError> {
        match kind {
            FkKind::Pole => {
                self.fk_plane_only(f)?;
                let (a, b) = self.plane_idx();
                let here_pt = self.plane_pt(self.pos);
                let mut p = self.fk.pole.unwrap_or(here_pt);
                for (i, k) in [a, b].into_iter().enumerate() {
                    if let Some(c) = f.end.get(k).copied().flatten() {
                        let v = self.len_of(&c);
                        p[i] = if c.incremental { here_pt[i] + v } else { v };
                    }
                }
                self.fk.pole = Some(p);
                return Ok(Flow::Continue);
            }
            FkKind::Select => {
                let (n, pos) = f.select.unwrap_or((1, 0));
                self.fk_select(n, pos, out)?;
                return Ok(Flow::Continue);
            }
            _ => {}
        }
        self.fk_plane_only(f)?;
        if self.fk.pending.len() >= MAX_PENDING {
            return Err(here(ProgramError::FkUnderdetermined(
                self.fk.range(0, self.fk.pending.len() - 1),
            )));
        }
        if self.fk.pending.is_empty() {
            self.fk.origin = self.plane_pt(self.pos);
            let (a, b, _) = self.plane.axes();
            self.fk.origin_dir = self
                .tangent
                .map(|d| unit([d[a.index()], d[b.index()]]))
                .filter(|d| geom::norm(*d) > 0.5);
        }
        let sid = self.fk.next_sid;
        if let Some((true, _)) = f.clsd {
            self.fk.clsd_start = Some(sid);
        }
        let (cons, ccw) = self.fk_equations(f, kind, sid)?;
        let line = matches!(kind, FkKind::Line | FkKind::LineTangent);
        let ends = cons
            .iter()
            .filter(|c| matches!(c, Con::Coord { pt: Pt::End(_), .. }))
            .count();
        MWords::classify(&f.base)?;
        if let Some((_, pos)) = f.base.m_words().find(|(m, _)| matches!(m, 2 | 30)) {
            return Err(at(
                pos,
                ProgramError::Geometry(
                    "M2/M30 cannot end the program inside an FK contour: program them after it"
                        .into(),
                ),
            ));
        }
        let feed = self.feed(f.base.feed)?;
        let feed = self.need_feed(feed)?;
        self.fk.pending.push(Pending {
            sid,
            line,
            ccw,
            full: !line && ends == 2,
            cons,
            loc,
            words: f.base,
            feed,
        });
        self.fk.next_sid += 1;
        match self.fk.solve() {
            Outcome::None => {
                self.fk.pending.pop();
                self.fk.next_sid -= 1;
                Err(here(ProgramError::FkContradiction(FkState::label(&loc))))
            }
            Outcome::Some { fixed, sols } => {
                if fixed > 0
                    && let [only] = sols.as_slice()
                {
                    self.fk_commit(fixed, only, out)?;
                }
                Ok(Flow::Continue)
            }
        }
    }

    /// FSELECT n: commits solution n of the determined leading elements.
    fn fk_select(&mut self, n: u32, pos: u32, out: &mut VecDeque<Op>) -> Result<(), ExecError> {
        if !self.fk.pending() {
            return Ok(());
        }
        match self.fk.solve() {
            Outcome::Some { fixed, sols } if fixed > 0 => {
                let Some(sol) = sols.get(n as usize - 1) else {
                    return Err(at(
                        pos,
                        ProgramError::OutOfRange(format!(
                            "FSELECT {n}: the FK data have {} solution(s)",
                            sols.len()
                        )),
                    ));
                };
                self.fk_commit(fixed, sol, out)
            }
            _ => Err(at(
                pos,
                ProgramError::Geometry(
                    "FSELECT: the FK elements before it are not determined yet".into(),
                ),
            )),
        }
    }

    /// Ends an FK section: everything pending must be determined, with one solution.
    pub(super) fn fk_flush(&mut self, out: &mut VecDeque<Op>) -> Result<(), ExecError> {
        if !self.fk.pending() {
            return Ok(());
        }
        let last = self.fk.pending.len() - 1;
        match self.fk.solve() {
            Outcome::None => Err(here(ProgramError::FkContradiction(
                self.fk.range(last, last),
            ))),
            Outcome::Some { fixed, sols } => {
                if fixed == 0 || fixed <= last {
                    return Err(here(ProgramError::FkUnderdetermined(
                        self.fk.range(fixed, last),
                    )));
                }
                match sols.as_slice() {
                    [only] => self.fk_commit(fixed, only, out),
                    _ => Err(here(ProgramError::FkAmbiguous {
                        count: sols.len(),
                        blocks: self.fk.range(0, last),
                    })),
                }
            }
        }
    }

    /// Emits the first `count` pending elements with the unknowns `sol`.
    fn fk_commit(
        &mut self,
        count: usize,
        sol: &[f64],
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let (off, _) = self.fk.offsets();
        let mut solved = Vec::with_capacity(count);
        {
            let ctx = Ctx {
                st: &self.fk,
                off: &off,
                x: sol,
            };
            for p in self.fk.pending.iter().take(count) {
                let start = ctx.pt(Pt::Start(p.sid));
                let end = ctx.pt(Pt::End(p.sid));
                let centre = if p.line {
                    [0.0; 2]
                } else {
                    ctx.pt(Pt::Centre(p.sid))
                };
                let d = Done {
                    sid: p.sid,
                    block: p.loc.block,
                    start,
                    end,
                    centre,
                    end_dir: ctx.end_dir(p.sid),
                };
                solved.push((d, p.clone()));
            }
        }
        self.fk.pending.drain(..count.min(self.fk.pending.len()));
        let (a, b, _) = self.plane.axes();
        for (d, p) in solved {
            let from = self.pos;
            let mut to = from;
            to[a] = d.end[0];
            to[b] = d.end[1];
            let op = if p.line {
                OpKind::Line {
                    from,
                    to,
                    feed: p.feed,
                }
            } else {
                let sweep = if geom::norm(geom::sub(d.end, d.start)) < 1e-6 {
                    if p.ccw { 360.0 } else { -360.0 }
                } else {
                    geom::directed_sweep(
                        geom::angle(geom::sub(d.start, d.centre)),
                        geom::angle(geom::sub(d.end, d.centre)),
                        p.ccw,
                    )
                };
                OpKind::Arc {
                    from,
                    to,
                    center: d.centre,
                    plane: self.plane,
                    sweep,
                    feed: p.feed,
                }
            };
            let plain = p.words.m_count == 0;
            let ms = MWords::classify(&p.words)?;
            ms.modal(self);
            self.finish_path(op, &p.words, ms, plain, p.loc, out)?;
            self.fk.origin = d.end;
            self.fk.origin_dir = Some(d.end_dir);
            if self.fk.done.len() >= MAX_DONE {
                self.fk.done.pop_front();
            }
            self.fk.done.push_back(d);
        }
        Ok(())
    }
}
