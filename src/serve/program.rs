//! What the dashboard shows of a program before it runs: its text, the planned toolpath, the
//! test run's findings by line, its planned machine time, the BLK FORM blank and where each
//! block's motion ends (for the distance to go); and whether it suits the machine at all.

use super::manual::is_lathe;
use crate::config::MachineConfig;
use klar_interp::{AxisLetter, OpKind, Pose};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// Largest program file the dashboard shows, bytes (its text is sent to the page whole).
const MAX_SHOWN_PROGRAM: u64 = 16 * 1024 * 1024;

/// Motion ops read for the block end points; a longer program has no distance to go past
/// them.
const MAX_END_OPS: usize = 200_000;

/// A box given by its MIN and MAX corners (X, Y, Z).
type Corners = [[f64; 3]; 2];

/// One polyline of the planned toolpath.
#[derive(Serialize)]
pub struct PathStroke {
    rapid: bool,
    points: Vec<[f64; 3]>,
}

/// A program's text and its planned toolpath (or why it has none).
#[derive(Serialize)]
pub struct ProgramView {
    name: String,
    text: String,
    path: Vec<PathStroke>,
    errors: Vec<String>,
    /// The test run's findings from where the axes stand (errors refuse the run), or that
    /// the program is written for the other kind of machine.
    diagnostics: Vec<ViewDiagnostic>,
    /// The test run's planned machine time, s: progress and remaining time count against it.
    machine_time: f64,
    /// The BLK FORM blank, if the program has one: MIN and MAX corners (X, Y, Z).
    stock: Option<Corners>,
    /// Per program line (of the main file), where its last motion ends (X, Y, Z).
    ends: BTreeMap<u32, [f64; 3]>,
}

/// One test-run finding for the program viewer.
#[derive(Serialize)]
struct ViewDiagnostic {
    line: u32,
    col: u32,
    message: String,
    /// True for an error (the run is refused), false for a warning.
    error: bool,
}

fn xyz(p: &Pose) -> [f64; 3] {
    [p[AxisLetter::X], p[AxisLetter::Y], p[AxisLetter::Z]]
}

/// Reads the program at `path` and prepares its view on `machine`; `standing` is the same
/// machine with its axes where they stand now (the test run and the path start there).
pub fn program_view(
    name: String,
    path: &Path,
    machine: &MachineConfig,
    standing: &MachineConfig,
) -> Result<ProgramView, String> {
    let bytes = klar_interp::read_bounded(path, MAX_SHOWN_PROGRAM).map_err(|e| e.to_string())?;
    let text = String::from_utf8(bytes)
        // Older controls write latin-1: every byte is its own code point.
        .unwrap_or_else(|e| e.into_bytes().iter().map(|&b| b as char).collect());
    let start = standing.start_pose();
    let (strokes, errors) = match crate::plot::toolpath(path, Some(machine), start) {
        Ok(strokes) => (
            strokes
                .into_iter()
                .map(|s| PathStroke {
                    rapid: s.rapid,
                    points: s.points,
                })
                .collect(),
            Vec::new(),
        ),
        Err(e) => (Vec::new(), vec![e.to_string()]),
    };
    let (diagnostics, machine_time) = match wrong_machine(path, machine) {
        Some(why) => (
            vec![ViewDiagnostic {
                line: 1,
                col: 1,
                message: why,
                error: true,
            }],
            0.0,
        ),
        None => {
            let checked = crate::testrun::test_run(path, standing);
            let mut d: Vec<ViewDiagnostic> = checked
                .errors
                .iter()
                .map(|d| (d, true))
                .chain(checked.warnings.iter().map(|d| (d, false)))
                .map(|(d, error)| ViewDiagnostic {
                    line: d.line,
                    col: d.col,
                    message: d.message.clone(),
                    error,
                })
                .collect();
            d.sort_by_key(|d| (d.line, d.col));
            (d, checked.planned_time)
        }
    };
    let (stock, ends) = stock_and_ends(path, standing, start);
    Ok(ProgramView {
        name,
        text,
        path: strokes,
        errors,
        diagnostics,
        machine_time,
        stock,
        ends,
    })
}

/// The BLK FORM blank of a program and the end point of each line's motion, from one pass of
/// the interpreter (stopped at the first error or after [`MAX_END_OPS`] ops).
fn stock_and_ends(
    path: &Path,
    machine: &MachineConfig,
    start: Pose,
) -> (Option<Corners>, BTreeMap<u32, [f64; 3]>) {
    let mut ends = BTreeMap::new();
    let Ok(mut interp) = machine.open_program(path, start) else {
        return (None, ends);
    };
    let mut stock = None;
    for _ in 0..MAX_END_OPS {
        if stock.is_none()
            && let Some(b) = interp.blank()
        {
            stock = Some([xyz(&b.min), xyz(&b.max)]);
        }
        let Some(Ok(op)) = interp.next() else {
            break;
        };
        let end = match &op.kind {
            OpKind::Line { to, .. } | OpKind::Arc { to, .. } | OpKind::Spline { to, .. } => to,
            _ => continue,
        };
        if op.loc.file == 0 {
            ends.insert(op.loc.line, xyz(end));
        }
    }
    if stock.is_none()
        && let Some(b) = interp.blank()
    {
        stock = Some([xyz(&b.min), xyz(&b.max)]);
    }
    (stock, ends)
}

/// Why the program at `path` cannot run on `machine`: it is written for the other kind of
/// machine (lathe DIN on a milling machine, a milling language on a lathe).
pub fn wrong_machine(path: &Path, machine: &MachineConfig) -> Option<String> {
    let mut head = Vec::with_capacity(4096);
    if let Ok(f) = std::fs::File::open(path) {
        use std::io::Read;
        let _ = f.take(4096).read_to_end(&mut head);
    }
    let din = matches!(
        klar_interp::detect_dialect(path, &head),
        Some(klar_interp::Dialect::LatheDin)
    );
    match (din, is_lathe(machine)) {
        (true, false) => Some(format!(
            "a lathe program (lathe DIN) cannot run on {}, a milling machine",
            machine.name
        )),
        (false, true) => Some(format!(
            "a milling program cannot run on {}, a lathe: it runs lathe DIN programs (.nc)",
            machine.name
        )),
        _ => None,
    }
}
