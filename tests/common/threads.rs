//! Thread passes read back from a trace: the rows of each pass, the lead error against the
//! measured spindle angle, and the spindle angle at which a pass starts.

use super::Trace;

/// One thread pass found in a trace: its rows whose commanded Z lies within the thread
/// proper (between the end of the run-in and the start of the run-out).
pub struct Pass {
    /// Trace row indices.
    pub rows: Vec<usize>,
    /// Commanded X (radius) per row.
    pub x: Vec<f64>,
    /// Commanded Z per row.
    pub z: Vec<f64>,
    /// Measured Z per row.
    pub z_act: Vec<f64>,
    /// Measured spindle angle per row, degrees.
    pub angle: Vec<f64>,
}

/// The passes of a trace: maximal runs of rows with commanded Z strictly inside
/// `(z_lo, z_hi)` and commanded X below `x_max`, each at least `min_rows` long.
pub fn passes(trace: &Trace, z_lo: f64, z_hi: f64, x_max: f64, min_rows: usize) -> Vec<Pass> {
    let col = |n: &str| trace.column(n).unwrap_or_else(|| panic!("column {n}"));
    let (x, z, za, s) = (col("X"), col("Z"), col("Z_act"), col("S_deg"));
    let mut out = Vec::new();
    let mut cur: Option<Pass> = None;
    for i in 0..=z.len() {
        let inside = i < z.len() && z[i] > z_lo && z[i] < z_hi && x[i] < x_max;
        if inside {
            let p = cur.get_or_insert_with(|| Pass {
                rows: Vec::new(),
                x: Vec::new(),
                z: Vec::new(),
                z_act: Vec::new(),
                angle: Vec::new(),
            });
            p.rows.push(i);
            p.x.push(x[i]);
            p.z.push(z[i]);
            p.z_act.push(za[i]);
            p.angle.push(s[i]);
        } else if let Some(p) = cur.take()
            && p.z.len() >= min_rows
        {
            out.push(p);
        }
    }
    out
}

/// Largest |z − (z0 − dir·pitch·(angle − a0)/360)| over a pass, with the reference (z0, a0)
/// taken at its first row: the lead error, mm. `z` picks the commanded or measured values.
pub fn lead_error(z: &[f64], angle: &[f64], pitch: f64, dir: f64) -> f64 {
    let (z0, a0) = (z[0], angle[0]);
    z.iter()
        .zip(angle)
        .map(|(&z, &a)| (z - (z0 - dir * pitch * (a - a0) / 360.0)).abs())
        .fold(0.0, f64::max)
}

/// The spindle angle (mod 360) at which the tool, as measured, passes `z_start`: the angle
/// of the pass's first row moved back by the measured Z still to go, at `pitch` per
/// revolution.
pub fn start_angle(p: &Pass, z_start: f64, pitch: f64, dir: f64) -> f64 {
    (p.angle[0] - dir * (z_start - p.z_act[0]) * 360.0 / pitch).rem_euclid(360.0)
}

/// Circular distance of two angles, degrees.
pub fn angle_apart(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}
