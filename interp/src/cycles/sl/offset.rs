//! Tool-centre paths along the walls of a region: each contour offset towards the area
//! to machine, with the parts that come too close to another contour cut away.

use super::index::Index;
use super::region::Region;

/// Largest distance between a true offset arc round a corner and the chords that stand
/// for it (the chords lie outside the arc, never closer to the corner), mm.
const ARC_TOL: f64 = 1e-3;

/// An open or closed polyline of tool-centre points.
pub(super) type Polyline = Vec<[f64; 2]>;

/// The paths at distance `rho` from the walls of `region`, inside the area to machine.
/// Pocket walls are run counter-clockwise and island walls clockwise (both with the area
/// on the left of the travel) when `area_left`, the other way otherwise. A closed path
/// repeats its first point at the end.
pub(super) fn wall_paths(
    region: &Region,
    index: &Index,
    rho: f64,
    area_left: bool,
) -> Vec<Polyline> {
    let mut paths = Vec::new();
    let polys = region
        .pockets
        .iter()
        .map(|p| (p, true))
        .chain(region.islands.iter().map(|p| (p, false)));
    for (poly, pocket) in polys {
        // Orient so that the area lies on the left: pockets counter-clockwise.
        let mut pts = poly.pts.clone();
        if (poly.area2() > 0.0) != pocket {
            pts.reverse();
        }
        let raw = raw_offset(&pts, rho);
        let mut pieces = clip(index, &raw, rho);
        if !area_left {
            pieces.reverse();
            for p in &mut pieces {
                p.reverse();
            }
        }
        paths.extend(pieces);
    }
    paths
}

/// The closed polyline at distance `rho` to the left of the closed polygon `pts`
/// (offset edges, joined round right-hand corners by chords outside the corner's circle).
fn raw_offset(pts: &[[f64; 2]], rho: f64) -> Polyline {
    let n = pts.len();
    let mut out: Polyline = Vec::new();
    if n < 2 {
        return out;
    }
    let normal = |i: usize| {
        let (a, b) = (pts[i % n], pts[(i + 1) % n]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = dx.hypot(dy).max(1e-300);
        [-dy / len, dx / len]
    };
    for i in 0..n {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        let m = normal(i);
        out.push([a[0] + rho * m[0], a[1] + rho * m[1]]);
        out.push([b[0] + rho * m[0], b[1] + rho * m[1]]);
        // Corner at b: a right turn needs a way round it.
        let m2 = normal(i + 1);
        let turn = m[0] * m2[1] - m[1] * m2[0];
        if turn < 0.0 {
            let a0 = m[1].atan2(m[0]);
            let a1 = m2[1].atan2(m2[0]);
            let mut sweep = a1 - a0;
            while sweep > 0.0 {
                sweep -= std::f64::consts::TAU;
            }
            // Chord angle with rho (1/cos(θ/2) − 1) ≤ ARC_TOL.
            let max = 2.0 * (rho / (rho + ARC_TOL)).acos();
            let k = (sweep.abs() / max.max(1e-3)).ceil().clamp(1.0, 10_000.0);
            let r_out = rho / (sweep.abs() / k / 2.0).cos();
            // k is a small positive whole number.
            let count = k as usize;
            for j in 0..count {
                let ang = a0 + sweep * (j as f64 + 0.5) / k;
                out.push([b[0] + r_out * ang.cos(), b[1] + r_out * ang.sin()]);
            }
        }
    }
    if let Some(&first) = out.first() {
        out.push(first);
    }
    out
}

/// The parts of the closed polyline `raw` that lie in the indexed region at least `rho` (less a
/// hair) from every edge, as polylines in order; a piece running on across the start
/// is joined up.
fn clip(index: &Index, raw: &Polyline, rho: f64) -> Vec<Polyline> {
    let lim = rho - 1e-7;
    let mut pieces: Vec<Polyline> = Vec::new();
    let mut open = false;
    let mut run_inside = false;
    for w in raw.windows(2) {
        let (p, q) = (w[0], w[1]);
        if (q[0] - p[0]).hypot(q[1] - p[1]) < 1e-12 {
            continue;
        }
        // Parameter intervals of p–q closer than lim to some edge.
        let bmin = [p[0].min(q[0]), p[1].min(q[1])];
        let bmax = [p[0].max(q[0]), p[1].max(q[1])];
        let mut bad: Vec<(f64, f64)> = index
            .near(bmin, bmax)
            .iter()
            .filter_map(|e| near(p, q, e.a, e.b, lim))
            .collect();
        bad.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut t = 0.0;
        let mut good: Vec<(f64, f64)> = Vec::new();
        for (lo, hi) in bad {
            if lo > t {
                good.push((t, lo.min(1.0)));
            }
            t = t.max(hi);
            if t >= 1.0 {
                break;
            }
        }
        if t < 1.0 {
            good.push((t, 1.0));
        }
        let at = |s: f64| [p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])];
        let was_open = open;
        let was_inside = run_inside;
        open = false;
        for (i, (lo, hi)) in good.into_iter().enumerate() {
            if hi - lo < 1e-12 {
                continue;
            }
            // A run that goes on from the previous segment keeps its distance from every
            // edge, so it cannot cross into or out of the area: it stays as it was.
            let continues = i == 0 && was_open && lo <= 1e-12;
            let inside = if continues {
                was_inside
            } else {
                index.contains(at((lo + hi) / 2.0))
            };
            run_inside = inside;
            open = hi >= 1.0 - 1e-12;
            if !inside {
                continue;
            }
            match pieces.last_mut() {
                Some(last) if continues => last.push(at(hi)),
                _ => pieces.push(vec![at(lo), at(hi)]),
            }
        }
    }
    // Join the last piece to the first when the path runs on across the start.
    if pieces.len() > 1 && open && run_inside {
        let first_start = pieces.first().and_then(|f| f.first().copied());
        let last_end = pieces.last().and_then(|l| l.last().copied());
        if let (Some(s), Some(e)) = (first_start, last_end)
            && (e[0] - s[0]).hypot(e[1] - s[1]) < 1e-9
            && let Some(mut last) = pieces.pop()
        {
            let first = pieces.remove(0);
            last.extend(first.into_iter().skip(1));
            pieces.insert(0, last);
        }
    }
    pieces.retain(|pc| pc.len() >= 2);
    pieces
}

/// The parameter interval of the segment `p`–`q` whose points lie closer than `lim` to
/// the segment `a`–`b` (a convex set, so one interval), clipped to 0..1.
fn near(p: [f64; 2], q: [f64; 2], a: [f64; 2], b: [f64; 2], lim: f64) -> Option<(f64, f64)> {
    let d = [q[0] - p[0], q[1] - p[1]];
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    // The discs about both ends.
    for c in [a, b] {
        let f = [p[0] - c[0], p[1] - c[1]];
        let qa = d[0] * d[0] + d[1] * d[1];
        let qb = 2.0 * (f[0] * d[0] + f[1] * d[1]);
        let qc = f[0] * f[0] + f[1] * f[1] - lim * lim;
        let disc = qb * qb - 4.0 * qa * qc;
        if qa > 0.0 && disc > 0.0 {
            let s = disc.sqrt();
            lo = lo.min((-qb - s) / (2.0 * qa));
            hi = hi.max((-qb + s) / (2.0 * qa));
        }
    }
    // The band along the segment: four half-planes.
    let e = [b[0] - a[0], b[1] - a[1]];
    let len = e[0].hypot(e[1]);
    if len > 0.0 {
        let u = [e[0] / len, e[1] / len];
        let nrm = [-u[1], u[0]];
        // (value at p, rate along t, bound): value + t·rate < bound.
        let rel = [p[0] - a[0], p[1] - a[1]];
        let along0 = rel[0] * u[0] + rel[1] * u[1];
        let along_r = d[0] * u[0] + d[1] * u[1];
        let across0 = rel[0] * nrm[0] + rel[1] * nrm[1];
        let across_r = d[0] * nrm[0] + d[1] * nrm[1];
        let conds = [
            (along0, along_r, len),
            (-along0, -along_r, 0.0),
            (across0, across_r, lim),
            (-across0, -across_r, lim),
        ];
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        let mut empty = false;
        for (v, rate, bound) in conds {
            if rate.abs() < 1e-300 {
                if v >= bound {
                    empty = true;
                }
            } else {
                let t = (bound - v) / rate;
                if rate > 0.0 {
                    t1 = t1.min(t);
                } else {
                    t0 = t0.max(t);
                }
            }
        }
        if !empty && t1 > t0 {
            lo = lo.min(t0);
            hi = hi.max(t1);
        }
    }
    let (lo, hi) = (lo.max(0.0), hi.min(1.0));
    (hi > lo).then_some((lo, hi))
}
