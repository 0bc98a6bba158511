//! `[probe]` and `[workpiece]`: the touch probe of the machine and the simulated part it
//! finds. A machine with a `[workpiece]` gets a simulated probe (its data from `[probe]`, or
//! klar's defaults); `TCH PROBE` cycles are refused on a machine without one.

use super::MachineConfig;
use super::probe_features::{self, HoleCircleConfig, RidgeConfig, SlotConfig};
use crate::workpiece::{Bore, Boss, Pocket, SimWorkpiece};
use klar_interp::{AxisLetter, Interpreter, ProbeData, ProbeStop};
use serde::Deserialize;

/// `[probe]`: the touch probe's data (the TNC's touch-probe table).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeConfig {
    /// Stylus ball radius, mm.
    #[serde(default = "default_radius")]
    pub radius: f64,
    /// Set-up clearance added to the cycles' Q320, mm.
    #[serde(default = "default_set_up")]
    pub set_up: f64,
    /// Longest probing move, mm.
    #[serde(default = "default_distance")]
    pub distance: f64,
    /// Probing feed, mm/min.
    #[serde(default = "default_feed")]
    pub feed: f64,
    /// Positioning feed between touch points, mm/min; none: rapid traverse.
    #[serde(default)]
    pub positioning_feed: Option<f64>,
    /// Time from the touch until the control reacts, s. With it or `overtravel` the simulated
    /// axes run past the touch point and brake as a real probe's do.
    #[serde(default)]
    pub trigger_delay: Option<f64>,
    /// Allowed stylus deflection, mm: a probing move whose axes would stop further past the
    /// touch point is refused.
    #[serde(default)]
    pub overtravel: Option<f64>,
    /// The probe's signal goes to the touch-probe inputs of the X, Y and Z drives (CiA 402):
    /// a run takes each touch point from their latches, waiting for each probing move
    /// (`klar check` still answers from `[workpiece]`).
    #[serde(default)]
    pub latch: bool,
}

fn default_radius() -> f64 {
    ProbeData::default().radius
}
fn default_set_up() -> f64 {
    ProbeData::default().set_up
}
fn default_distance() -> f64 {
    ProbeData::default().distance
}
fn default_feed() -> f64 {
    ProbeData::default().feed
}

/// `[[workpiece.bore]]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoreConfig {
    /// Centre X, Y in program coordinates, mm.
    pub centre: [f64; 2],
    /// Diameter, mm.
    pub diameter: f64,
    /// Depth below the top of the part, mm.
    pub depth: f64,
}

/// `[[workpiece.pocket]]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PocketConfig {
    /// Centre X, Y in program coordinates, mm.
    pub centre: [f64; 2],
    /// Side lengths in X and Y, mm.
    pub size: [f64; 2],
    /// Depth below the top of the part, mm.
    pub depth: f64,
}

/// `[[workpiece.boss]]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BossConfig {
    /// Centre X, Y in program coordinates, mm.
    pub centre: [f64; 2],
    /// Diameter, mm.
    pub diameter: f64,
    /// Height above the top of the part, mm.
    pub height: f64,
}

/// `[workpiece]`: the simulated part on the table.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorkpieceConfig {
    /// How far the part really lies off where the program expects it, X, Y, Z, mm.
    #[serde(default)]
    pub offset: [f64; 3],
    /// How far it is turned about Z (about the program's datum), degrees.
    #[serde(default)]
    pub rotation: f64,
    /// The part's box corners in program coordinates; without them the program's BLK FORM.
    #[serde(default)]
    pub min: Option<[f64; 3]>,
    /// The other corner.
    #[serde(default)]
    pub max: Option<[f64; 3]>,
    /// Bores cut from the top.
    #[serde(default, rename = "bore")]
    pub bores: Vec<BoreConfig>,
    /// Rectangular pockets cut from the top.
    #[serde(default, rename = "pocket")]
    pub pockets: Vec<PocketConfig>,
    /// Round bosses standing on the top.
    #[serde(default, rename = "boss")]
    pub bosses: Vec<BossConfig>,
    /// Straight slots cut from the top.
    #[serde(default, rename = "slot")]
    pub slots: Vec<SlotConfig>,
    /// Straight ridges standing on the top.
    #[serde(default, rename = "ridge")]
    pub ridges: Vec<RidgeConfig>,
    /// Bolt-hole circles (bores) cut from the top.
    #[serde(default, rename = "hole_circle")]
    pub hole_circles: Vec<HoleCircleConfig>,
    /// Machine X, Y of the rotary table axis C the part turns with (a machine with a C axis;
    /// default the machine origin), mm.
    #[serde(default)]
    pub table_centre: [f64; 2],
    /// Where the probe inputs of simulated CiA 402 drives find the part, relative to this
    /// description, X, Y, Z, mm: with `[probe] latch` a run measures the part moved by it,
    /// `klar check` the part as described (a part that is not where its model says).
    #[serde(default)]
    pub actual_shift: [f64; 3],
}

impl MachineConfig {
    /// The probe's data from `[probe]` (klar's defaults without it).
    pub fn probe_data(&self) -> ProbeData {
        match &self.probe {
            Some(p) => ProbeData {
                radius: p.radius,
                set_up: p.set_up,
                distance: p.distance,
                feed: p.feed,
                positioning_feed: p.positioning_feed,
                stop: self.probe_stop(p),
            },
            None => ProbeData::default(),
        }
    }

    /// How the axes stop after a trigger, when `[probe]` has `trigger_delay` or `overtravel`.
    fn probe_stop(&self, p: &ProbeConfig) -> Option<ProbeStop> {
        if p.trigger_delay.is_none() && p.overtravel.is_none() {
            return None;
        }
        let limits = self.axis_limits();
        let mut axes = [[f64::INFINITY; 3]; 3];
        for (i, l) in limits.iter().take(3).enumerate() {
            if let Some(l) = l {
                axes[i] = [l.max_velocity, l.max_acceleration, l.max_jerk];
            }
        }
        Some(ProbeStop {
            trigger_delay: p.trigger_delay.unwrap_or(0.0),
            overtravel: p.overtravel,
            axes,
        })
    }

    /// The simulated part of `[workpiece]`, placed from the start preset.
    pub fn sim_workpiece(&self) -> Option<SimWorkpiece> {
        let w = self.workpiece.as_ref()?;
        let origin = match self.active_preset() {
            Ok(super::tables::ActivePreset::Row { values, .. }) => {
                [values[0], values[1], values[2]]
            }
            _ => [0.0; 3],
        };
        let body = match (w.min, w.max) {
            (Some(a), Some(b)) => Some([
                [a[0].min(b[0]), a[1].min(b[1]), a[2].min(b[2])],
                [a[0].max(b[0]), a[1].max(b[1]), a[2].max(b[2])],
            ]),
            _ => None,
        };
        Some(SimWorkpiece {
            origin,
            offset: w.offset,
            rotation: w.rotation,
            body,
            bores: w
                .bores
                .iter()
                .map(|b| Bore {
                    centre: b.centre,
                    diameter: b.diameter,
                    depth: b.depth,
                })
                .chain(w.hole_circles.iter().flat_map(|c| c.feature().bores()))
                .collect(),
            pockets: w
                .pockets
                .iter()
                .map(|p| Pocket {
                    centre: p.centre,
                    size: p.size,
                    depth: p.depth,
                })
                .collect(),
            bosses: w
                .bosses
                .iter()
                .map(|b| Boss {
                    centre: b.centre,
                    diameter: b.diameter,
                    height: b.height,
                })
                .collect(),
            slots: w.slots.iter().map(SlotConfig::feature).collect(),
            ridges: w.ridges.iter().map(RidgeConfig::feature).collect(),
            table_centre: w.table_centre,
            table_angle: 0.0,
        })
    }

    /// The part as the probe inputs of simulated drives find it: `[workpiece]` moved by its
    /// `actual_shift`.
    pub fn actual_workpiece(&self) -> Option<SimWorkpiece> {
        let shift = self.workpiece.as_ref()?.actual_shift;
        let mut w = self.sim_workpiece()?;
        for (o, d) in w.offset.iter_mut().zip(shift) {
            *o += d;
        }
        Some(w)
    }

    /// `interp` given the simulated probe when the machine has a `[workpiece]`.
    pub(super) fn with_probe(&self, interp: Interpreter) -> Interpreter {
        match self.sim_workpiece() {
            Some(w) => interp.with_probe(self.probe_data(), Box::new(w)),
            None => interp,
        }
    }

    /// Checks `[probe]` and `[workpiece]` values.
    pub(super) fn validate_probe(&self) -> Result<(), String> {
        let positive = |what: &str, v: f64| {
            if v.is_finite() && v > 0.0 && v <= 10_000.0 {
                Ok(())
            } else {
                Err(format!(
                    "{what} must be a positive number up to 10000, got {v}"
                ))
            }
        };
        if let Some(p) = &self.probe {
            positive("probe radius", p.radius)?;
            positive("probe distance", p.distance)?;
            positive("probe feed", p.feed)?;
            if !(p.set_up.is_finite() && (0.0..=10_000.0).contains(&p.set_up)) {
                return Err(format!(
                    "probe set_up must lie in 0 … 10000 mm, got {}",
                    p.set_up
                ));
            }
            if let Some(f) = p.positioning_feed {
                positive("probe positioning_feed", f)?;
            }
            if let Some(o) = p.overtravel {
                positive("probe overtravel", o)?;
            }
            if let Some(t) = p.trigger_delay
                && !(t.is_finite() && (0.0..=1.0).contains(&t))
            {
                return Err(format!("probe trigger_delay must lie in 0 … 1 s, got {t}"));
            }
            if p.latch {
                for l in [AxisLetter::X, AxisLetter::Y, AxisLetter::Z] {
                    let on_drive = self.axes.iter().any(|a| {
                        a.letter == l && matches!(a.backend, super::BackendConfig::Canopen(_))
                    });
                    if !on_drive {
                        return Err(format!(
                            "probe latch needs axis {l} on a CiA 402 drive (backend kind \"canopen\")"
                        ));
                    }
                }
            }
        }
        if let Some(w) = &self.workpiece {
            let finite = w
                .offset
                .iter()
                .chain(&[w.rotation])
                .chain(&w.table_centre)
                .chain(&w.actual_shift)
                .all(|v| v.is_finite() && v.abs() <= 1e6);
            if !finite {
                return Err("workpiece offset and rotation must be finite numbers".into());
            }
            if w.min.is_some() != w.max.is_some() {
                return Err(
                    "workpiece needs both min and max, or neither (then the program's BLK FORM)"
                        .into(),
                );
            }
            for (i, b) in w.bores.iter().enumerate() {
                positive(&format!("workpiece bore {} diameter", i + 1), b.diameter)?;
                positive(&format!("workpiece bore {} depth", i + 1), b.depth)?;
            }
            for (i, b) in w.bosses.iter().enumerate() {
                positive(&format!("workpiece boss {} diameter", i + 1), b.diameter)?;
                positive(&format!("workpiece boss {} height", i + 1), b.height)?;
            }
            for (i, p) in w.pockets.iter().enumerate() {
                positive(
                    &format!("workpiece pocket {} size", i + 1),
                    p.size[0].min(p.size[1]),
                )?;
                positive(&format!("workpiece pocket {} depth", i + 1), p.depth)?;
            }
            probe_features::validate(&w.slots, &w.ridges, &w.hole_circles, &positive)?;
        }
        Ok(())
    }
}
