//! Reading and checking cycle parameters.

use super::super::{CycleContext, CycleError, CycleFeed, ParamKey, ParamSource};
use super::geom::EPS;
use crate::op::SpindleDir;

/// The heights and infeeds the milling cycles 251 to 257 share.
#[derive(Debug, Clone, Copy)]
pub(in crate::cycles) struct Heights {
    /// Depth Q201 (0 or negative).
    pub depth: f64,
    /// Workpiece surface Q203.
    pub surface: f64,
    /// Plunging depth Q202.
    pub infeed: f64,
    /// Finishing infeed Q338 (0: all at once).
    pub finish_infeed: f64,
    /// Set-up clearance Q200.
    pub clear: f64,
    /// 2nd set-up clearance Q204, at least the set-up clearance.
    pub clear2: f64,
}

/// The feeds the milling cycles 251 to 257 share, each given or taken from the milling feed.
#[derive(Debug, Clone, Copy)]
pub(in crate::cycles) struct Feeds {
    /// Milling feed Q207 (the modal feed when missing).
    pub mill: CycleFeed,
    /// Plunging feed Q206.
    pub plunge: CycleFeed,
    /// Finishing feed Q385.
    pub finish: CycleFeed,
}

/// Reads the parameters of one cycle definition and reports problems with the cycle number.
pub(in crate::cycles) struct Params<'a> {
    src: &'a dyn ParamSource,
    /// Cycle number for error messages.
    pub cycle: u32,
}

/// How a parameter key is written in a program, for messages.
fn key_name(key: ParamKey) -> String {
    match key {
        ParamKey::Q(n) => format!("Q{n}"),
        ParamKey::Old { line, index } => {
            if index == 0 {
                format!("sub-block {line}")
            } else {
                format!("sub-block {line} value {}", index + 1)
            }
        }
        ParamKey::OldWord(w) => w.to_string(),
        ParamKey::OldFeed { line } => format!("F of sub-block {line}"),
    }
}

impl<'a> Params<'a> {
    /// Wraps `src`, the parameters of cycle `cycle`.
    pub fn new(cycle: u32, src: &'a dyn ParamSource) -> Self {
        Self { src, cycle }
    }

    /// The value of `key` when given and finite.
    pub fn get(&self, key: ParamKey) -> Option<f64> {
        self.src.get(key)
    }

    /// A required parameter.
    pub fn req(&self, key: ParamKey, what: &'static str) -> Result<f64, CycleError> {
        let v = self.src.get(key).ok_or_else(|| CycleError::Missing {
            cycle: self.cycle,
            param: key_name(key),
            what,
        })?;
        if !v.is_finite() {
            return Err(self.range(key, v, "a finite number"));
        }
        Ok(v)
    }

    /// A required Q parameter.
    pub fn q(&self, n: u32, what: &'static str) -> Result<f64, CycleError> {
        self.req(ParamKey::Q(n), what)
    }

    /// An optional Q parameter with a default.
    pub fn q_or(&self, n: u32, default: f64) -> f64 {
        match self.src.get(ParamKey::Q(n)) {
            Some(v) if !v.is_nan() => v,
            _ => default,
        }
    }

    /// An out-of-range error for `key`.
    pub fn range(&self, key: ParamKey, value: f64, range: &'static str) -> CycleError {
        CycleError::OutOfRange {
            cycle: self.cycle,
            param: key_name(key),
            value,
            range,
        }
    }

    /// A geometry error.
    pub fn geometry(&self, msg: impl Into<String>) -> CycleError {
        CycleError::Geometry {
            cycle: self.cycle,
            msg: msg.into(),
        }
    }

    /// Checks that Q`n` = `v` lies in `lo..=hi`.
    pub fn check(
        &self,
        n: u32,
        v: f64,
        lo: f64,
        hi: f64,
        range: &'static str,
    ) -> Result<f64, CycleError> {
        if v.is_finite() && v >= lo && v <= hi {
            Ok(v)
        } else {
            Err(self.range(ParamKey::Q(n), v, range))
        }
    }

    /// Checks that Q`n` = `v` is one of the whole numbers `0..=max`.
    pub fn choice(&self, n: u32, v: f64, max: u32, range: &'static str) -> Result<u32, CycleError> {
        if v.is_finite() && v >= 0.0 && v <= f64::from(max) && v.fract() == 0.0 {
            // The value is a whole number in 0..=max, so the conversion is exact.
            Ok(v as u32)
        } else {
            Err(self.range(ParamKey::Q(n), v, range))
        }
    }

    /// A feed parameter in mm/min (already converted when `per_second`), checked positive;
    /// an infinite value (FMAX) is rapid traverse.
    pub fn feed_value(
        &self,
        key: ParamKey,
        v: f64,
        per_second: bool,
    ) -> Result<CycleFeed, CycleError> {
        if v == f64::INFINITY {
            return Ok(CycleFeed::Rapid);
        }
        if !(v.is_finite() && v > 0.0) {
            return Err(self.range(key, v, "a feed rate greater than 0"));
        }
        Ok(CycleFeed::Rate(if per_second { v } else { v / 60.0 }))
    }

    /// Feed Q`n` (mm/min) as a cycle feed, or `default` when not given.
    pub fn feed_or(&self, n: u32, default: CycleFeed) -> Result<CycleFeed, CycleError> {
        match self.src.get(ParamKey::Q(n)) {
            Some(v) => self.feed_value(ParamKey::Q(n), v, false),
            None => Ok(default),
        }
    }

    /// Depth Q201 (a positive depth is refused), surface Q203, plunging depth Q202,
    /// finishing infeed Q338, set-up clearance Q200 and 2nd set-up clearance Q204, read and
    /// checked in that order.
    pub fn heights(&self) -> Result<Heights, CycleError> {
        let depth = self.q(201, "depth")?;
        if depth > 0.0 {
            return Err(self.range(ParamKey::Q(201), depth, "negative (0 skips the cycle)"));
        }
        let surface = self.q(203, "workpiece surface coordinate")?;
        let infeed = self.q(202, "plunging depth")?;
        self.check(202, infeed, EPS, f64::MAX, "greater than 0")?;
        let finish_infeed = self.check(338, self.q_or(338, 0.0), 0.0, f64::MAX, "0 or more")?;
        let clear = self.check(200, self.q_or(200, 2.0), 0.0, f64::MAX, "0 or more")?;
        let clear2 = self
            .check(204, self.q_or(204, 50.0), 0.0, f64::MAX, "0 or more")?
            .max(clear);
        Ok(Heights {
            depth,
            surface,
            infeed,
            finish_infeed,
            clear,
            clear2,
        })
    }

    /// Milling feed Q207, plunging feed Q206 and finishing feed Q385, read in that order.
    pub fn feeds(&self, ctx: &CycleContext) -> Result<Feeds, CycleError> {
        let mill = self.feed_or(207, modal_feed(ctx))?;
        let plunge = self.feed_or(206, mill)?;
        let finish = self.feed_or(385, mill)?;
        Ok(Feeds {
            mill,
            plunge,
            finish,
        })
    }

    /// The tool radius of `ctx`, refused unless finite and positive.
    pub fn tool_radius(&self, ctx: &CycleContext) -> Result<f64, CycleError> {
        let r = ctx.tool_radius;
        if !(r.is_finite() && r > 0.0) {
            return Err(CycleError::ToolRadius {
                cycle: self.cycle,
                radius: r,
            });
        }
        Ok(r)
    }
}

/// The feed to use when a cycle gives none: the modal feed, else a slow 100 mm/min.
pub(in crate::cycles) fn modal_feed(ctx: &CycleContext) -> CycleFeed {
    match ctx.feed {
        Some(f) if f.is_finite() && f > 0.0 => CycleFeed::Rate(f),
        _ => CycleFeed::Rate(100.0 / 60.0),
    }
}

/// Whether the tool runs counter-clockwise round an inside contour (pocket wall) for the
/// milling type `q351`.
///
/// Q351 names the milling type for a spindle turning clockwise (M3). Seen from the
/// positive tool axis an M3 cutter turns clockwise, so its teeth sweep the wall in the
/// direction of feed (climb milling) when the wall lies on the right of the travel. Inside
/// a pocket that means running counter-clockwise; an up-cut (−1) runs clockwise. A spindle
/// turning the other way (M4) swaps both. Outside contours (studs) run the opposite way.
pub(in crate::cycles) fn pocket_ccw(q351: f64, spindle: SpindleDir) -> bool {
    let climb = q351 >= 0.0;
    climb != (spindle == SpindleDir::Ccw)
}
