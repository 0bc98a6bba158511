//! `klar plot`: draws a program's toolpath as SVG or PNG — the working plane beside an
//! isometric 3D view, rapid moves dashed, feed moves solid, the radius-compensated tool-centre
//! path beside the programmed contour, with axes and a millimetre scale. With a profile
//! ([`profile`]) the picture also shows path speed and per-axis velocity, acceleration and jerk
//! over time from a simulated run.
//!
//! The contour comes from the op stream, the tool-centre path from the same ops through the
//! radius compensation stage; arcs and splines are flattened to a chord error of at most
//! [`CHORD_TOLERANCE`].

pub mod profile;

use crate::config::MachineConfig;
use klar_interp::{AxisLetter, Diagnostic, Feed, Interpreter, Op, OpKind, Pose};
use klar_motion::comp::Compensator;
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
    /// The simulated run for the profile failed.
    #[error("simulated run: {0}")]
    Run(String),
}

/// One polyline of the toolpath.
#[derive(Debug, Clone, PartialEq)]
pub struct Stroke {
    /// True for rapid traverse.
    pub rapid: bool,
    /// Points (X, Y, Z).
    pub points: Vec<[f64; 3]>,
}

/// Flattens a program's motion (the programmed contour) into strokes. The program runs on
/// `machine` as `klar run` would run it there (see [`crate::config::open_on`]); `None` draws
/// it on its own, without a machine's tools, rotary axes or M functions.
pub fn toolpath(
    program: &Path,
    machine: Option<&MachineConfig>,
    start: Pose,
) -> Result<Vec<Stroke>, PlotError> {
    let mut strokes = Strokes::default();
    let mut interp = open(program, machine, start)?;
    // A tilted working plane: the programmed contour turned into the workpiece system.
    interp.set_working_plane_ops(true);
    let mut tilt = klar_motion::tilt::TiltStage::new();
    let mut turned = std::collections::VecDeque::new();
    for op in interp {
        let op = op.map_err(|d| PlotError::Program(vec![d]))?;
        tilt.push(op, &mut turned);
        while let Some(op) = turned.pop_front() {
            strokes.add(&op);
        }
    }
    Ok(strokes.done())
}

/// Flattens the tool-centre path: the program's ops through tool radius compensation (RL/RR,
/// APPR/DEP). Where no compensation is programmed it equals [`toolpath`]. A contour that
/// cannot be compensated is an error naming the blocks. `machine` as for [`toolpath`].
pub fn tool_centre_path(
    program: &Path,
    machine: Option<&MachineConfig>,
    start: Pose,
) -> Result<Vec<Stroke>, PlotError> {
    let mut comp = Compensator::new(start);
    let mut strokes = Strokes::default();
    let comp_error = |e: klar_motion::comp::CompError, loc: klar_interp::SourceLoc| {
        PlotError::Program(vec![Diagnostic {
            file: program.to_path_buf(),
            line: loc.line,
            col: loc.col,
            block: loc.block,
            message: e.to_string(),
        }])
    };
    let mut interp = open(program, machine, start)?;
    // Compensation runs in a tilted working plane; the compensator turns its output.
    interp.set_working_plane_ops(true);
    for op in interp {
        let op = op.map_err(|d| PlotError::Program(vec![d]))?;
        let loc = op.loc;
        comp.push(op).map_err(|e| comp_error(e, loc))?;
        while let Some(out) = comp.pop() {
            strokes.add(&out);
        }
    }
    comp.finish()
        .map_err(|e| comp_error(e, klar_interp::SourceLoc::default()))?;
    while let Some(out) = comp.pop() {
        strokes.add(&out);
    }
    Ok(strokes.done())
}

fn open(
    program: &Path,
    machine: Option<&MachineConfig>,
    start: Pose,
) -> Result<Interpreter, PlotError> {
    klar_interp::syntax_check(program).map_err(PlotError::Program)?;
    crate::config::open_on(machine, program, start).map_err(|d| PlotError::Program(vec![d]))
}

/// Collects flattened motion ops into strokes, joining pieces of the same kind.
#[derive(Default)]
struct Strokes {
    strokes: Vec<Stroke>,
    total: usize,
}

impl Strokes {
    fn add(&mut self, op: &Op) {
        let Some((rapid, pts)) = flatten(op) else {
            return;
        };
        self.total += pts.len();
        match self.strokes.last_mut() {
            Some(s) if s.rapid == rapid && s.points.last() == pts.first() => {
                s.points.extend(pts.into_iter().skip(1));
            }
            _ => self.strokes.push(Stroke { rapid, points: pts }),
        }
    }

    /// The strokes, thinned to at most [`MAX_POINTS`] points in all.
    fn done(mut self) -> Vec<Stroke> {
        if self.total > MAX_POINTS {
            let step = self.total.div_ceil(MAX_POINTS);
            for s in &mut self.strokes {
                let last = s.points.last().copied();
                s.points = s.points.iter().step_by(step).copied().collect();
                if let Some(l) = last
                    && s.points.last() != Some(&l)
                {
                    s.points.push(l);
                }
            }
        }
        self.strokes
    }
}

/// The points of one motion op (X, Y, Z) and whether it is a rapid; None for other ops.
fn flatten(op: &Op) -> Option<(bool, Vec<[f64; 3]>)> {
    match &op.kind {
        OpKind::Line { from, to, feed } => Some((*feed == Feed::Rapid, vec![xyz(from), xyz(to)])),
        // A thread pass is a feed move along its line.
        OpKind::SpindleSync { from, to, .. } => Some((false, vec![xyz(from), xyz(to)])),
        // A rigid tap: down to the bottom and back along the hole's axis.
        OpKind::RigidTap { from, to, .. } => Some((false, vec![xyz(from), xyz(to), xyz(from)])),
        OpKind::Arc {
            from,
            to,
            center,
            plane,
            sweep,
            feed,
        } => Some((
            *feed == Feed::Rapid,
            arc_points(from, to, *center, *plane, *sweep),
        )),
        OpKind::Spline {
            from,
            to,
            axes,
            feed,
        } => {
            let mut pts = Vec::with_capacity(33);
            pts.push(xyz(from));
            for k in 1..=32 {
                let t = 1.0 - k as f64 / 32.0;
                let mut p = *to;
                for s in axes {
                    p[s.axis] = ((s.k[0] * t + s.k[1]) * t + s.k[2]) * t + to[s.axis];
                }
                pts.push(xyz(&p));
            }
            Some((*feed == Feed::Rapid, pts))
        }
        _ => None,
    }
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

/// Isometric projection: X to the upper right and Y to the upper left (both 30° above the
/// horizontal), Z straight up.
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

/// Draws `program` into `output` (.svg or .png), 1400 × 700 pixels: the contour and the
/// tool-centre path in the working plane and in an isometric view. The program is drawn on
/// its own, on no machine (see [`plot_program_with`]).
pub fn plot_program(program: &Path, start: Pose, output: &Path) -> Result<(), PlotError> {
    plot_program_with(program, None, start, output, None)
}

/// As [`plot_program`], on `machine` as for [`toolpath`]; with a `profile` the picture grows
/// to 1400 × 1500 pixels with the path speed and the per-axis velocity, acceleration and jerk
/// over time below the paths.
pub fn plot_program_with(
    program: &Path,
    machine: Option<&MachineConfig>,
    start: Pose,
    output: &Path,
    profile: Option<&profile::Profile>,
) -> Result<(), PlotError> {
    let ext = output
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if !matches!(ext.as_deref(), Some("svg" | "png")) {
        return Err(PlotError::Format(output.display().to_string()));
    }
    let contour = toolpath(program, machine, start)?;
    let centre = match tool_centre_path(program, machine, start) {
        Ok(c) => c,
        Err(e) => {
            tracing::warn!("no tool-centre path: {e}");
            Vec::new()
        }
    };
    let title = program
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    register_font();
    let size = if profile.is_some() {
        (1400, 1500)
    } else {
        (1400, 700)
    };
    let paths = Paths {
        contour: &contour,
        centre: &centre,
    };
    if ext.as_deref() == Some("svg") {
        draw(
            SVGBackend::new(output, size).into_drawing_area(),
            &paths,
            &title,
            profile,
        )
    } else {
        draw(
            BitMapBackend::new(output, size).into_drawing_area(),
            &paths,
            &title,
            profile,
        )
    }
}

/// A projection of X, Y, Z to a drawing plane.
type Projection = fn([f64; 3]) -> (f64, f64);

/// What the path panels show.
struct Paths<'a> {
    contour: &'a [Stroke],
    centre: &'a [Stroke],
}

/// A stroke projected to 2D, with its style.
#[derive(Clone)]
struct Flat {
    style: PathStyle,
    points: Vec<(f64, f64)>,
}

#[derive(Clone, Copy, PartialEq)]
enum PathStyle {
    Rapid,
    Feed,
    Centre,
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    paths: &Paths<'_>,
    title: &str,
    profile: Option<&profile::Profile>,
) -> Result<(), PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError::Draw(e.to_string());
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (top, bottom) = match profile {
        Some(_) => root.split_vertically(700),
        None => root.split_vertically(root.dim_in_pixel().1),
    };
    let (left, right) = top.split_horizontally(top.dim_in_pixel().0 / 2);
    // A path with no Y extent but a Z extent is a lathe contour: Z across, X up.
    let (lo, hi) = extent(paths.contour);
    let lathe = hi[1] - lo[1] < 1e-9 && hi[2] - lo[2] > 1e-9;
    let (plane_of, plane_name, labels): (Projection, _, _) = if lathe {
        (|p| (p[2], p[0]), "Z/X", ("Z [mm]", "X ⌀ [mm]"))
    } else {
        (|p| (p[0], p[1]), "X/Y", ("X [mm]", "Y [mm]"))
    };
    // The centre path is drawn only where compensation changed it.
    let centre = if paths.centre == paths.contour {
        &[][..]
    } else {
        paths.centre
    };
    let flat = |f: &dyn Fn([f64; 3]) -> (f64, f64)| -> Vec<Flat> {
        let centre = centre.iter().filter(|s| !s.rapid).map(|s| Flat {
            style: PathStyle::Centre,
            points: s.points.iter().map(|&p| f(p)).collect(),
        });
        let contour = paths.contour.iter().map(|s| Flat {
            style: if s.rapid {
                PathStyle::Rapid
            } else {
                PathStyle::Feed
            },
            points: s.points.iter().map(|&p| f(p)).collect(),
        });
        centre.chain(contour).collect()
    };
    panel(
        &left,
        &flat(&plane_of),
        &format!("{title}: working plane {plane_name}"),
        labels,
        lathe,
    )?;
    panel(
        &right,
        &flat(&isometric),
        &format!("{title}: isometric"),
        ("", ""),
        false,
    )?;
    if let Some(p) = profile {
        profile::draw(&bottom, p)?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// Smallest and largest X, Y, Z of the strokes.
fn extent(strokes: &[Stroke]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in strokes.iter().flat_map(|s| &s.points) {
        for i in 0..3 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    (lo, hi)
}

/// Equal-aspect bounds around the points, with a margin.
fn bounds(paths: &[Flat], aspect: f64) -> ((f64, f64), (f64, f64)) {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for f in paths {
        for &(x, y) in &f.points {
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
    paths: &[Flat],
    caption: &str,
    labels: (&str, &str),
    lathe: bool,
) -> Result<(), PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError::Draw(e.to_string());
    let (w, h) = area.dim_in_pixel();
    // Plot area is the panel less the label areas (60 px left, 40 px bottom, caption ~40 px).
    let aspect = (w as f64 - 80.0).max(1.0) / (h as f64 - 90.0).max(1.0);
    // A lathe's view frames the cutting moves (when there are any), so a far tool change
    // position does not shrink the part into a corner; rapids beyond it are clipped.
    let cutting: Vec<Flat> = paths
        .iter()
        .filter(|f| f.style != PathStyle::Rapid)
        .cloned()
        .collect();
    let framed = if lathe && !cutting.is_empty() {
        &cutting[..]
    } else {
        paths
    };
    let ((x0, x1), (y0, y1)) = bounds(framed, aspect);
    // the lathe's X runs in radius: its ticks read as diameters
    let tick = move |v: &f64| {
        let v = if lathe { v * 2.0 } else { *v };
        let t = format!("{v:.3}");
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    };
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
        .y_label_formatter(&tick)
        .label_style(("sans-serif", 14))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(|e| err(&e))?;
    let style = |color: RGBAColor, width: u32| ShapeStyle {
        color,
        filled: false,
        stroke_width: width,
    };
    let feed = style(BLUE.mix(0.9), 1);
    let rapid = style(RED.mix(0.7), 1);
    let centre = style(RGBColor(46, 157, 74).mix(0.8), 2);
    let mut labelled = Vec::new();
    for f in paths {
        let pts = f.points.iter().copied();
        let series = match f.style {
            PathStyle::Rapid => chart.draw_series(DashedLineSeries::new(pts, 6, 4, rapid)),
            PathStyle::Feed => chart.draw_series(LineSeries::new(pts, feed)),
            PathStyle::Centre => chart.draw_series(LineSeries::new(pts, centre)),
        }
        .map_err(|e| err(&e))?;
        if !labelled.contains(&f.style) {
            labelled.push(f.style);
            let (name, st) = match f.style {
                PathStyle::Rapid => ("rapid", rapid),
                PathStyle::Feed => ("feed (contour)", feed),
                PathStyle::Centre => ("tool centre (compensated)", centre),
            };
            let dashed = f.style == PathStyle::Rapid;
            series.label(name).legend(move |(x, y)| {
                // A dashed key for rapids: two short strokes.
                let first = if dashed { x + 8 } else { x + 20 };
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (first - x, 0)], st)
                    + PathElement::new(
                        vec![
                            (if dashed { 12 } else { 0 }, 0),
                            (if dashed { 20 } else { 0 }, 0),
                        ],
                        st,
                    )
            });
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(|e| err(&e))?;
    draw_scale_bar(area, (x1 - x0) / (w as f64 - 80.0))?;
    Ok(())
}

/// A scale bar of a round length (1, 2 or 5 × 10ⁿ mm) in the panel's lower right corner;
/// `mm_per_px` is the chart's scale.
fn draw_scale_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    mm_per_px: f64,
) -> Result<(), PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError::Draw(e.to_string());
    if !(mm_per_px.is_finite() && mm_per_px > 0.0) {
        return Ok(());
    }
    let len = scale_bar_length(120.0 * mm_per_px);
    let px = (len / mm_per_px).round() as i32;
    let (w, h) = area.dim_in_pixel();
    let (x1, y) = (w as i32 - 30, h as i32 - 60);
    let x0 = x1 - px;
    let ink = ShapeStyle {
        color: BLACK.to_rgba(),
        filled: false,
        stroke_width: 2,
    };
    area.draw(&PathElement::new(vec![(x0, y), (x1, y)], ink))
        .and_then(|()| area.draw(&PathElement::new(vec![(x0, y - 5), (x0, y + 5)], ink)))
        .and_then(|()| area.draw(&PathElement::new(vec![(x1, y - 5), (x1, y + 5)], ink)))
        .and_then(|()| {
            area.draw(&Text::new(
                format!("{len} mm"),
                (x0, y - 20),
                ("sans-serif", 14).into_font(),
            ))
        })
        .map_err(|e| err(&e))
}

/// The largest length of the form 1, 2 or 5 × 10ⁿ not above `at_most` (which must be > 0).
pub fn scale_bar_length(at_most: f64) -> f64 {
    let pow = 10f64.powf(at_most.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * pow)
        .find(|&l| l <= at_most * (1.0 + 1e-12))
        .unwrap_or(pow)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_bars_are_round_lengths_not_above_the_room() {
        assert_eq!(scale_bar_length(120.0), 100.0);
        assert_eq!(scale_bar_length(100.0), 100.0);
        assert_eq!(scale_bar_length(7.9), 5.0);
        assert_eq!(scale_bar_length(4.0), 2.0);
        assert!((scale_bar_length(0.37) - 0.2).abs() < 1e-15);
        assert_eq!(scale_bar_length(1999.0), 1000.0);
    }

    #[test]
    fn the_isometric_view_keeps_the_axes_at_their_drawing_angles() {
        // X runs up to the right at 30°, Y up to the left at 30°, Z straight up.
        let (x, y) = isometric([1.0, 0.0, 0.0]);
        assert!((y.atan2(x).to_degrees() - 30.0).abs() < 1e-12);
        let (x, y) = isometric([0.0, 1.0, 0.0]);
        assert!((y.atan2(x).to_degrees() - 150.0).abs() < 1e-12);
        assert_eq!(isometric([0.0, 0.0, 2.5]), (0.0, 2.5));
    }
}
