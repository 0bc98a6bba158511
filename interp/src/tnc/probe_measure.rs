//! Measuring cycles 425 (inside width), 426 (ridge width) and 430 (bolt-hole circle), and the
//! tolerance limits of all measuring cycles (420 … 427, 430); what happens with the results
//! (status, stop, log) is in [`super::probe_report`].
//!
//! Each cycle's rules, as klar applies them from the TNC 640 touch-probe manual:
//! - **425**: the probe starts at Q328/Q329 (measuring height Q261) and probes in the positive
//!   direction of the measuring axis Q272 (1 reference, 2 minor). For the second touch it
//!   moves toward the opposite wall, to the clearance before where the nominal width Q311
//!   puts it (never past the start point), displaced by Q310 across the measuring axis (0:
//!   on the same line), over the clearance height when Q301=1, and probes in the negative
//!   direction.
//! - **426**: touch point 1 (Q263/Q264) is probed in the negative direction of the measuring
//!   axis, touch point 2 (Q265/Q266) in the positive one, each from the clearance before it;
//!   the probe moves over the clearance height between them.
//! - 425/426: Q156 the width measured, Q157 the centre line, Q166 the width's deviation from
//!   Q311; limits Q288 (largest) and Q289 (smallest width).
//! - **430**: three holes probed as for 416 (see [`super::probe_ref`]); Q151/Q152 the centre
//!   and Q153 the diameter of the bolt-hole circle, Q161/Q162 the centre's and Q163 the
//!   diameter's deviations; limits Q288/Q289 of the diameter, Q279/Q280 the tolerance of the
//!   centre in the reference and the minor axis.
//! - The limits of the other measuring cycles: **421/422** Q275/Q276 the largest and
//!   smallest diameter, Q279/Q280 the centre's tolerance; **423/424** Q284/Q285 the largest
//!   and smallest first side, Q286/Q287 the second side, Q279/Q280 the centre; **427**
//!   Q288/Q289 the largest and smallest coordinate. **420** checks nothing and only logs.
//! - All measuring cycles: Q281 the measuring log, Q309 the stop on a tolerance error (see
//!   [`super::probe_report`]). Q330 (tool monitoring) is not supported: a value other than 0
//!   is refused.

use std::collections::VecDeque;

use super::cycle_exec::CycleDef;
use super::exec::{ExecError, Machine};
use super::expr::{ParamKind, ParamRef, Value};
use super::probe_exec::Run;
use super::probe_ref::bad;
use super::probe_report::Item;
use crate::cycles::{ParamKey, ParamSource};
use crate::op::Op;

/// A parameter as programmed (program units), `None` when not given.
fn raw(def: &CycleDef, q: u32) -> Option<f64> {
    def.get(ParamKey::Q(q))
}

impl Machine {
    /// The value of Q parameter `n`.
    fn q_value(&self, n: u32) -> f64 {
        self.params.value(Value::Param {
            param: ParamRef {
                kind: ParamKind::Q,
                index: n,
            },
            negate: false,
        })
    }

    /// Q281/Q309 of `def` and the report of `items`.
    fn finish(&mut self, def: &CycleDef, items: &[Item], run: Run) -> Result<(), ExecError> {
        if raw(def, 330).is_some_and(|v| v != 0.0) {
            return Err(bad(
                def.number,
                "Q330 (tool monitoring) is not supported yet: program Q330=0",
            ));
        }
        let log = raw(def, 281).unwrap_or(0.0);
        let stop = raw(def, 309).unwrap_or(0.0) == 1.0;
        for (lo, hi) in items.iter().map(|i| (i.min, i.max)) {
            if let (Some(lo), Some(hi)) = (lo, hi)
                && lo > hi
            {
                return Err(bad(
                    def.number,
                    format!("the smallest size {lo} lies above the largest {hi}"),
                ));
            }
        }
        self.report(def.number, items, log, stop, run.loc)
    }

    /// 425 (inside width) and 426 (ridge width).
    fn width(
        &mut self,
        def: &CycleDef,
        inside: bool,
        mut run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let k = self.plane_axis(def)?;
        let h = self.need(def, 261)?;
        let clear = self.need(def, 260)?;
        let nominal = self.need(def, 311)?;
        let lead = self.lead(def);
        let mut plus = [0.0; 3];
        plus[k] = 1.0;
        let minus = plus.map(|v| -v);
        // the coordinates touched on the + side and on the − side of the feature
        let (hi, lo) = if inside {
            let s = [self.need(def, 328)?, self.need(def, 329)?];
            let offset = self.opt(def, 310, 0.0);
            let high = self.opt(def, 301, 1.0) == 1.0;
            self.go_to_point(s, h, clear, true, run, out)?;
            let t1 = self.touch_surface(plus, run, out)?;
            let mut s2 = s;
            s2[k] = s[k].min(t1[k] - nominal + lead);
            s2[1 - k] += offset;
            run.point = 2;
            self.go_to_point(s2, h, clear, high, run, out)?;
            let t2 = self.touch_surface(minus, run, out)?;
            (t1[k], t2[k])
        } else {
            let mut p1 = [self.need(def, 263)?, self.need(def, 264)?];
            let mut p2 = [self.need(def, 265)?, self.need(def, 266)?];
            p1[k] += lead;
            p2[k] -= lead;
            self.go_to_point(p1, h, clear, true, run, out)?;
            let t1 = self.touch_surface(minus, run, out)?;
            run.point = 2;
            self.go_to_point(p2, h, clear, true, run, out)?;
            let t2 = self.touch_surface(plus, run, out)?;
            (t1[k], t2[k])
        };
        self.up_to(clear, run, out)?;
        let u = self.unit;
        let width = hi - lo;
        self.set_q(156, width / u);
        self.set_q(157, (hi + lo) / 2.0 / u);
        self.set_q(166, (width - nominal) / u);
        let item = Item::size(
            "Q156 width",
            nominal / u,
            width / u,
            raw(def, 288),
            raw(def, 289),
            inside,
        );
        self.finish(def, &[item], run)
    }

    /// 425: measure inside width.
    pub(super) fn cycle425(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        self.width(def, true, run, out)
    }

    /// 426: measure ridge width.
    pub(super) fn cycle426(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        self.width(def, false, run, out)
    }

    /// 430's deviations, limits and report (the centre and diameter already measured, mm).
    pub(super) fn report430(
        &mut self,
        def: &CycleDef,
        centre: [f64; 2],
        dia: f64,
        run: Run,
    ) -> Result<(), ExecError> {
        let u = self.unit;
        let c = [self.need(def, 273)? / u, self.need(def, 274)? / u];
        let nominal = self.need(def, 262)? / u;
        let (cx, cy, d) = (centre[0] / u, centre[1] / u, dia / u);
        self.set_q(161, cx - c[0]);
        self.set_q(162, cy - c[1]);
        self.set_q(163, d - nominal);
        let mut size = Item::size(
            "Q153 diameter",
            nominal,
            d,
            raw(def, 288),
            raw(def, 289),
            true,
        );
        // a bolt-hole circle off its diameter is off either way: scrap
        size.below = super::probe_report::Status::Scrap;
        let items = [
            size,
            Item::position("Q151 centre", c[0], cx, raw(def, 279)),
            Item::position("Q152 centre", c[1], cy, raw(def, 280)),
        ];
        self.finish(def, &items, run)
    }

    /// The limits, status, log and stop of the measuring cycles 420 … 424 and 427, after the
    /// cycle wrote its results.
    pub(super) fn measured(&mut self, def: &CycleDef, run: Run) -> Result<(), ExecError> {
        let q = |m: &Machine, n: u32| m.q_value(n);
        let items: Vec<Item> = match def.number {
            420 => vec![Item::position(
                "Q150 angle",
                raw(def, 307).unwrap_or(0.0),
                q(self, 150),
                None,
            )],
            421 | 422 => {
                let centre = [raw(def, 273).unwrap_or(0.0), raw(def, 274).unwrap_or(0.0)];
                vec![
                    Item::size(
                        "Q153 diameter",
                        raw(def, 262).unwrap_or(0.0),
                        q(self, 153),
                        raw(def, 275),
                        raw(def, 276),
                        def.number == 421,
                    ),
                    Item::position("Q151 centre", centre[0], q(self, 151), raw(def, 279)),
                    Item::position("Q152 centre", centre[1], q(self, 152), raw(def, 280)),
                ]
            }
            423 | 424 => {
                let centre = [raw(def, 273).unwrap_or(0.0), raw(def, 274).unwrap_or(0.0)];
                let inner = def.number == 423;
                vec![
                    Item::size(
                        "Q154 1st side",
                        raw(def, 282).unwrap_or(0.0),
                        q(self, 154),
                        raw(def, 284),
                        raw(def, 285),
                        inner,
                    ),
                    Item::size(
                        "Q155 2nd side",
                        raw(def, 283).unwrap_or(0.0),
                        q(self, 155),
                        raw(def, 286),
                        raw(def, 287),
                        inner,
                    ),
                    Item::position("Q151 centre", centre[0], q(self, 151), raw(def, 279)),
                    Item::position("Q152 centre", centre[1], q(self, 152), raw(def, 280)),
                ]
            }
            427 => {
                let (hi, lo) = (raw(def, 288), raw(def, 289));
                let mut it = Item::position("Q160 coordinate", 0.0, q(self, 160), None);
                it.nominal = match (hi, lo) {
                    (Some(h), Some(l)) => (h + l) / 2.0,
                    _ => it.actual,
                };
                it.max = hi;
                it.min = lo;
                vec![it]
            }
            _ => Vec::new(),
        };
        self.finish(def, &items, run)
    }
}
