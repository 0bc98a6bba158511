//! `klar plot`: draws a program's toolpath as SVG or PNG — the working plane (top view) beside
//! an isometric 3D view, rapid moves dashed, feed moves solid, with axes and a millimetre scale.
//!
//! The path comes from the op stream (the programmed contour), with arcs and splines flattened
//! to a chord error of at most [`CHORD_TOLERANCE`].

use klar_interp::{AxisLetter, Diagnostic, Feed, Interpreter, OpKind, Pose};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Largest distance between a drawn chord and the true arc, mm.
pub const CHORD_TOLERANCE: f64 = 0.005;

/// Upper bound on points kept for one plot; longer programs are drawn with every n-th point.
const MAX_POINTS: usize = 2_000_000;

/// Why a plot could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The program has errors.
    #[error("{}", .0.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("\n"))]
    Program(Vec<Diagnostic>),
    /// The output name does not end in .svg or .png.
    #[error("{0}: the output must end in .svg or .png")]
    Format(String),
    /// Drawing or writing failed.
    #[error("drawing: {0}")]
    Draw(String),
}

/// One polyline of the toolpath.
#[derive(Debug, Clone, PartialEq)]
pub struct Stroke {
    /// True for rapid traverse.
    pub rapid: bool,
    /// Points (X, Y, Z).
    pub points: Vec<[f64; 3]>,
}

/// Flattens a program's motion into strokes.
pub fn toolpath(program: &Path, start: Pose) -> Result<Vec<Stroke>, PlotError> {
    klar_interp::syntax_check(program).map_err(PlotError::Program)?;
    let interp = Interpreter::open(program, start).map_err(|d| PlotError::Program(vec![d]))?;
    let mut strokes: Vec<Stroke> = Vec::new();
    let mut total = 0usize;
    for item in interp {
        let op = item.map_err(|d| PlotError::Program(vec![d]))?;
        let (rapid, pts) = match &op.kind {
            OpKind::Line { from, to, feed } => (*feed == Feed::Rapid, vec![xyz(from), xyz(to)]),
            OpKind::Arc {
                from,
                to,
                center,
                plane,
                sweep,
                feed,
            } => (
                *feed == Feed::Rapid,
                arc_points(from, to, *center, *plane, *sweep),
            ),
            OpKind::Spline {
                from,
                to,
                axes,
                feed,
            } => {
                let mut pts = Vec::with_capacity(33);
                for k in 0..=32 {
                    let t = 1.0 - k as f64 / 32.0;
                    let mut p = *to;
                    for s in axes {
                        p[s.axis] = ((s.k[0] * t + s.k[1]) * t + s.k[2]) * t + to[s.axis];
                    }
                    pts.push(xyz(&p));
                }
                pts[0] = xyz(from);
                (*feed == Feed::Rapid, pts)
            }
            _ => continue,
        };
        total += pts.len();
        match strokes.last_mut() {
            Some(s) if s.rapid == rapid && s.points.last() == pts.first() => {
                s.points.extend_from_slice(&pts[1..]);
            }
            _ => strokes.push(Stroke { rapid, points: pts }),
        }
    }
    if total > MAX_POINTS {
        let step = total.div_ceil(MAX_POINTS);
        for s in &mut strokes {
            let last = s.points.last().copied();
            s.points = s.points.iter().step_by(step).copied().collect();
            if let Some(l) = last
                && s.points.last() != Some(&l)
            {
                s.points.push(l);
            }
        }
    }
    Ok(strokes)
}

fn xyz(p: &Pose) -> [f64; 3] {
    [p[AxisLetter::X], p[AxisLetter::Y], p[AxisLetter::Z]]
}

fn arc_points(
    from: &Pose,
    to: &Pose,
    center: [f64; 2],
    plane: klar_interp::Plane,
    sweep: f64,
) -> Vec<[f64; 3]> {
    let (a1, a2, n) = plane.axes();
    let r = (from[a1] - center[0]).hypot(from[a2] - center[1]);
    let start = (from[a2] - center[1]).atan2(from[a1] - center[0]);
    // Chord error r(1 - cos(φ/2)) ≤ tolerance fixes the largest step angle φ.
    let max_step = if r > CHORD_TOLERANCE {
        2.0 * (1.0 - CHORD_TOLERANCE / r).acos()
    } else {
        std::f64::consts::PI / 8.0
    };
    let sweep_rad = sweep.to_radians();
    let steps = ((sweep_rad.abs() / max_step).ceil() as usize).clamp(1, 100_000);
    let mut pts = Vec::with_capacity(steps + 1);
    for k in 0..=steps {
        let f = k as f64 / steps as f64;
        let ang = start + sweep_rad * f;
        let mut p = *from;
        p[a1] = center[0] + r * ang.cos();
        p[a2] = center[1] + r * ang.sin();
        p[n] = from[n] + (to[n] - from[n]) * f;
        pts.push(xyz(&p));
    }
    if let Some(last) = pts.last_mut() {
        *last = xyz(to);
    }
    pts
}

/// Isometric projection: X to the lower right, Y to the upper right, Z up.
fn isometric(p: [f64; 3]) -> (f64, f64) {
    let c = 30f64.to_radians().cos();
    let s = 30f64.to_radians().sin();
    ((p[0] - p[1]) * c, (p[0] + p[1]) * s + p[2])
}

fn register_font() {
    static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");
    // Registering the same font again replaces it; the result is always usable.
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
}

/// Draws `program` into `output` (.svg or .png), 1400 × 700 pixels.
pub fn plot_program(program: &Path, start: Pose, output: &Path) -> Result<(), PlotError> {
    let strokes = toolpath(program, start)?;
    let title = program
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    register_font();
    let size = (1400, 700);
    let ext = output
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("svg") => draw(
            SVGBackend::new(output, size).into_drawing_area(),
            &strokes,
            &title,
        ),
        Some("png") => draw(
            BitMapBackend::new(output, size).into_drawing_area(),
            &strokes,
            &title,
        ),
        _ => Err(PlotError::Format(output.display().to_string())),
    }
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    strokes: &[Stroke],
    title: &str,
) -> Result<(), PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError::Draw(e.to_string());
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (left, right) = root.split_horizontally(root.dim_in_pixel().0 / 2);
    let plane: Vec<(bool, Vec<(f64, f64)>)> = strokes
        .iter()
        .map(|s| (s.rapid, s.points.iter().map(|p| (p[0], p[1])).collect()))
        .collect();
    let iso: Vec<(bool, Vec<(f64, f64)>)> = strokes
        .iter()
        .map(|s| (s.rapid, s.points.iter().map(|&p| isometric(p)).collect()))
        .collect();
    panel(
        &left,
        &plane,
        &format!("{title}: working plane X/Y"),
        ("X [mm]", "Y [mm]"),
    )?;
    panel(&right, &iso, &format!("{title}: isometric"), ("", ""))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// Equal-aspect bounds around the points, with a margin.
fn bounds(paths: &[(bool, Vec<(f64, f64)>)], aspect: f64) -> ((f64, f64), (f64, f64)) {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (_, pts) in paths {
        for &(x, y) in pts {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
    }
    if x0 > x1 {
        return ((-1.0, 1.0), (-1.0, 1.0));
    }
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let mut w = (x1 - x0).max(1.0) * 1.1;
    let mut h = (y1 - y0).max(1.0) * 1.1;
    if w / h > aspect {
        h = w / aspect;
    } else {
        w = h * aspect;
    }
    ((cx - w / 2.0, cx + w / 2.0), (cy - h / 2.0, cy + h / 2.0))
}

fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    paths: &[(bool, Vec<(f64, f64)>)],
    caption: &str,
    labels: (&str, &str),
) -> Result<(), PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError::Draw(e.to_string());
    let (w, h) = area.dim_in_pixel();
    // Plot area is the panel less the label areas (60 px left, 40 px bottom, caption ~40 px).
    let aspect = (w as f64 - 80.0).max(1.0) / (h as f64 - 90.0).max(1.0);
    let ((x0, x1), (y0, y1)) = bounds(paths, aspect);
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc(labels.0)
        .y_desc(labels.1)
        .label_style(("sans-serif", 14))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(|e| err(&e))?;
    let feed = ShapeStyle {
        color: BLUE.mix(0.9),
        filled: false,
        stroke_width: 1,
    };
    let rapid = ShapeStyle {
        color: RED.mix(0.7),
        filled: false,
        stroke_width: 1,
    };
    for (is_rapid, pts) in paths {
        if *is_rapid {
            chart
                .draw_series(DashedLineSeries::new(pts.iter().copied(), 6, 4, rapid))
                .map_err(|e| err(&e))?;
        } else {
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), feed))
                .map_err(|e| err(&e))?;
        }
    }
    Ok(())
}
