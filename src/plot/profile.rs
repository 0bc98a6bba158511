//! The motion profile of a program: runs it on a simulated machine (as fast as the machine
//! can compute, not on the wall clock) and records, per servo cycle, the path speed and each
//! axis's velocity, acceleration and jerk — backward differences of the commanded positions,
//! so the figures are what the axes were told to do, whatever the planner thought.
//!
//! The machine stands still before its first cycle, so the first differences start from rest.
//! Long runs are thinned: at most [`MAX_SAMPLES`] samples are kept, each the one with the
//! largest |jerk| sum of its stretch of cycles, so that peaks survive thinning.

use super::PlotError;
use crate::config::MachineConfig;
use crate::runtime::{Run, RunOptions};
use klar_interp::AxisLetter;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Most samples a profile keeps.
pub const MAX_SAMPLES: usize = 20_000;

/// Velocity, acceleration and jerk of one axis over time.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct AxisProfile {
    /// The axis.
    pub letter: String,
    /// True for a rotary axis (degrees).
    pub rotary: bool,
    /// Velocity per sample, mm/s or °/s.
    pub velocity: Vec<f64>,
    /// Acceleration per sample, mm/s² or °/s².
    pub acceleration: Vec<f64>,
    /// Jerk per sample, mm/s³ or °/s³.
    pub jerk: Vec<f64>,
}

/// A program's motion over time.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Profile {
    /// Machine time per sample, s.
    pub t: Vec<f64>,
    /// Path speed of the linear axes per sample, mm/s.
    pub path_speed: Vec<f64>,
    /// One entry per machine axis.
    pub axes: Vec<AxisProfile>,
    /// Machine time of the whole run, s.
    pub machine_time: f64,
}

/// The last three commanded positions of every axis and what follows from them.
struct Differences {
    t: f64,
    p: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
}

/// Runs `program` on `machine` (simulated time) and records its profile.
pub fn profile(program: &Path, machine: &MachineConfig) -> Result<Profile, PlotError> {
    let options = RunOptions {
        realtime: false,
        trace: None,
    };
    let mut run = Run::start(program, machine, options).map_err(|f| run_error(&f.error))?;
    let letters = run.letters().to_vec();
    let linear: Vec<bool> = letters.iter().map(|l| !l.is_rotary()).collect();
    let n = letters.len();
    // The machine stands still at its start: no velocity, acceleration or jerk before t = 0.
    let mut d = Differences {
        t: 0.0,
        p: run.status().commanded,
        v: vec![0.0; n],
        a: vec![0.0; n],
    };
    let mut out = Profile {
        axes: letters
            .iter()
            .map(|l| AxisProfile {
                letter: l.to_string(),
                rotary: l.is_rotary(),
                ..AxisProfile::default()
            })
            .collect(),
        ..Profile::default()
    };
    let mut stride = 1usize;
    let mut bucket: Option<(f64, Sample)> = None;
    let mut in_bucket = 0usize;
    let ended = loop {
        match run.step() {
            Ok(true) => {}
            Ok(false) => break None,
            Err(e) => break Some(e),
        }
        let status = run.status();
        let Some(sample) = d.take(status.t, &status.commanded, &linear) else {
            continue;
        };
        // Keep the sample with the most jerk of each stretch of `stride` cycles.
        let weight: f64 = sample.jerk.iter().map(|j| j.abs()).sum();
        if bucket.as_ref().is_none_or(|(w, _)| weight > *w) {
            bucket = Some((weight, sample));
        }
        in_bucket += 1;
        if in_bucket >= stride {
            if let Some((_, s)) = bucket.take() {
                out.push(s);
            }
            in_bucket = 0;
            if out.t.len() >= MAX_SAMPLES {
                out.halve();
                stride *= 2;
            }
        }
    };
    if let Some((_, s)) = bucket.take() {
        out.push(s);
    }
    out.machine_time = run.status().t;
    match run.finish(ended) {
        Ok(_) => Ok(out),
        Err(f) => Err(run_error(&f.error)),
    }
}

fn run_error(e: &crate::runtime::RunError) -> PlotError {
    match e {
        crate::runtime::RunError::Syntax(d) => PlotError::Program(d.clone()),
        crate::runtime::RunError::Program(d) => PlotError::Program(vec![d.clone()]),
        other => PlotError::Run(other.to_string()),
    }
}

/// One cycle's derivatives.
struct Sample {
    t: f64,
    speed: f64,
    v: Vec<f64>,
    a: Vec<f64>,
    jerk: Vec<f64>,
}

impl Differences {
    /// Takes the commanded positions at time `t` (None for a step that did not advance time).
    fn take(&mut self, t: f64, commanded: &[f64], linear: &[bool]) -> Option<Sample> {
        let dt = t - self.t;
        if dt <= 0.0 {
            return None;
        }
        self.t = t;
        let mut s = Sample {
            t,
            speed: 0.0,
            v: Vec::with_capacity(commanded.len()),
            a: Vec::with_capacity(commanded.len()),
            jerk: Vec::with_capacity(commanded.len()),
        };
        let mut sq = 0.0;
        for (i, &c) in commanded.iter().enumerate() {
            let (Some(p), Some(v), Some(a)) =
                (self.p.get_mut(i), self.v.get_mut(i), self.a.get_mut(i))
            else {
                continue;
            };
            let nv = (c - *p) / dt;
            let na = (nv - *v) / dt;
            let nj = (na - *a) / dt;
            if linear.get(i).copied().unwrap_or(false) {
                sq += nv * nv;
            }
            s.v.push(nv);
            s.a.push(na);
            s.jerk.push(nj);
            *p = c;
            *v = nv;
            *a = na;
        }
        s.speed = sq.sqrt();
        Some(s)
    }
}

impl Profile {
    fn push(&mut self, s: Sample) {
        self.t.push(s.t);
        self.path_speed.push(s.speed);
        for (i, ax) in self.axes.iter_mut().enumerate() {
            ax.velocity.push(s.v.get(i).copied().unwrap_or(0.0));
            ax.acceleration.push(s.a.get(i).copied().unwrap_or(0.0));
            ax.jerk.push(s.jerk.get(i).copied().unwrap_or(0.0));
        }
    }

    /// Drops every second sample.
    fn halve(&mut self) {
        fn every_other(v: &mut Vec<f64>) {
            let mut k = 0;
            v.retain(|_| {
                k += 1;
                k % 2 == 1
            });
        }
        every_other(&mut self.t);
        every_other(&mut self.path_speed);
        for a in &mut self.axes {
            every_other(&mut a.velocity);
            every_other(&mut a.acceleration);
            every_other(&mut a.jerk);
        }
    }

    /// The axis with this letter.
    pub fn axis(&self, letter: AxisLetter) -> Option<&AxisProfile> {
        let name = letter.to_string();
        self.axes.iter().find(|a| a.letter == name)
    }
}

/// One named curve of a chart.
type Series<'a> = (String, &'a [f64]);

const AXIS_COLOURS: [RGBColor; 6] = [
    RGBColor(217, 83, 79),
    RGBColor(43, 108, 176),
    RGBColor(46, 157, 74),
    RGBColor(142, 68, 173),
    RGBColor(230, 126, 34),
    RGBColor(22, 160, 133),
];

/// Draws the four profile charts (path speed, velocity, acceleration, jerk) stacked in `area`.
pub(super) fn draw<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Profile,
) -> Result<(), PlotError> {
    let rows = area.split_evenly((4, 1));
    let speed = [("path".to_string(), p.path_speed.as_slice())];
    let pick = |f: fn(&AxisProfile) -> &[f64]| -> Vec<Series<'_>> {
        p.axes.iter().map(|a| (a.letter.clone(), f(a))).collect()
    };
    let charts: [(&str, Vec<Series<'_>>); 4] = [
        ("path speed [mm/s]", speed.to_vec()),
        ("velocity [mm/s, °/s]", pick(|a| &a.velocity)),
        ("acceleration [mm/s², °/s²]", pick(|a| &a.acceleration)),
        ("jerk [mm/s³, °/s³]", pick(|a| &a.jerk)),
    ];
    for (area, (title, series)) in rows.iter().zip(charts) {
        chart(area, &p.t, title, &series)?;
    }
    Ok(())
}

fn chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    t: &[f64],
    title: &str,
    series: &[Series<'_>],
) -> Result<(), PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError::Draw(e.to_string());
    let t_end = t.last().copied().unwrap_or(1.0).max(1e-3);
    let (mut lo, mut hi) = (0.0f64, 0.0f64);
    for v in series.iter().flat_map(|(_, s)| s.iter()) {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    if hi - lo < 1e-9 {
        hi = lo + 1.0;
    }
    let pad = (hi - lo) * 0.05;
    let mut c = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 16))
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..t_end, (lo - pad)..(hi + pad))
        .map_err(|e| err(&e))?;
    c.configure_mesh()
        .x_desc("t [s]")
        .label_style(("sans-serif", 12))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(|e| err(&e))?;
    for (k, (name, values)) in series.iter().enumerate() {
        let colour = if series.len() == 1 {
            BLACK
        } else {
            AXIS_COLOURS[k % AXIS_COLOURS.len()]
        };
        c.draw_series(LineSeries::new(
            t.iter().copied().zip(values.iter().copied()),
            colour.stroke_width(1),
        ))
        .map_err(|e| err(&e))?
        .label(name.clone())
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
    }
    c.configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .label_font(("sans-serif", 12))
        .draw()
        .map_err(|e| err(&e))?;
    Ok(())
}
