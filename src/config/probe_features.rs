//! `[[workpiece.slot]]`, `[[workpiece.ridge]]` and `[[workpiece.hole_circle]]`: the straight
//! and patterned features of the simulated part (see [`crate::workpiece`]).

use crate::workpiece::{HoleCircle, Ridge, Slot};
use serde::Deserialize;

/// `[[workpiece.slot]]`: a straight slot cut from the top, square ends.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlotConfig {
    /// Start of the centre line, program X/Y, mm.
    pub from: [f64; 2],
    /// End of the centre line, program X/Y, mm.
    pub to: [f64; 2],
    /// Width, mm.
    pub width: f64,
    /// Depth below the top of the part, mm.
    pub depth: f64,
}

/// `[[workpiece.ridge]]`: a straight bar standing on the top, square ends.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RidgeConfig {
    /// Start of the centre line, program X/Y, mm.
    pub from: [f64; 2],
    /// End of the centre line, program X/Y, mm.
    pub to: [f64; 2],
    /// Width, mm.
    pub width: f64,
    /// Height above the top of the part, mm.
    pub height: f64,
}

/// `[[workpiece.hole_circle]]`: `count` bores evenly spread on a circle.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HoleCircleConfig {
    /// Centre, program X/Y, mm.
    pub centre: [f64; 2],
    /// Diameter of the circle through the hole centres, mm.
    pub diameter: f64,
    /// Number of holes (1 … 360).
    pub count: u32,
    /// Polar angle of the first hole, degrees.
    #[serde(default)]
    pub start: f64,
    /// Diameter of each hole, mm.
    pub hole_diameter: f64,
    /// Depth of each hole, mm.
    pub depth: f64,
}

impl SlotConfig {
    /// The slot of the simulated part.
    pub fn feature(&self) -> Slot {
        Slot {
            from: self.from,
            to: self.to,
            width: self.width,
            depth: self.depth,
        }
    }
}

impl RidgeConfig {
    /// The ridge of the simulated part.
    pub fn feature(&self) -> Ridge {
        Ridge {
            from: self.from,
            to: self.to,
            width: self.width,
            height: self.height,
        }
    }
}

impl HoleCircleConfig {
    /// The hole circle of the simulated part.
    pub fn feature(&self) -> HoleCircle {
        HoleCircle {
            centre: self.centre,
            diameter: self.diameter,
            count: self.count,
            start: self.start,
            hole_diameter: self.hole_diameter,
            depth: self.depth,
        }
    }
}

/// Checks the values of the features: `positive` accepts a positive size.
pub(super) fn validate(
    slots: &[SlotConfig],
    ridges: &[RidgeConfig],
    circles: &[HoleCircleConfig],
    positive: &dyn Fn(&str, f64) -> Result<(), String>,
) -> Result<(), String> {
    let finite = |what: &str, v: &[f64]| {
        if v.iter().all(|x| x.is_finite() && x.abs() <= 1e6) {
            Ok(())
        } else {
            Err(format!("{what} must be finite numbers"))
        }
    };
    for (i, s) in slots.iter().enumerate() {
        let n = i + 1;
        finite(
            &format!("workpiece slot {n} from/to"),
            &[s.from[0], s.from[1], s.to[0], s.to[1]],
        )?;
        positive(&format!("workpiece slot {n} width"), s.width)?;
        positive(&format!("workpiece slot {n} depth"), s.depth)?;
    }
    for (i, r) in ridges.iter().enumerate() {
        let n = i + 1;
        finite(
            &format!("workpiece ridge {n} from/to"),
            &[r.from[0], r.from[1], r.to[0], r.to[1]],
        )?;
        positive(&format!("workpiece ridge {n} width"), r.width)?;
        positive(&format!("workpiece ridge {n} height"), r.height)?;
    }
    for (i, c) in circles.iter().enumerate() {
        let n = i + 1;
        finite(
            &format!("workpiece hole_circle {n} centre and start"),
            &[c.centre[0], c.centre[1], c.start],
        )?;
        positive(&format!("workpiece hole_circle {n} diameter"), c.diameter)?;
        positive(
            &format!("workpiece hole_circle {n} hole_diameter"),
            c.hole_diameter,
        )?;
        positive(&format!("workpiece hole_circle {n} depth"), c.depth)?;
        if !(1..=360).contains(&c.count) {
            return Err(format!(
                "workpiece hole_circle {n} count must lie in 1 … 360, got {}",
                c.count
            ));
        }
    }
    Ok(())
}
