//! Clearing a region line by line: the tool-centre intervals on parallel lines and their
//! linking into zigzag runs.

use super::index::Index;
use super::region::Region;

/// One cut: the tool-centre interval `lo..=hi` on line `line` (at the height `y`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Span {
    /// Line index.
    pub line: usize,
    /// Second-axis coordinate.
    pub y: f64,
    /// Low end.
    pub lo: f64,
    /// High end.
    pub hi: f64,
}

/// The tool-centre intervals on the line at `y` (within `xr`) that lie in the indexed
/// region at least `rho` from
/// its boundary.
pub(super) fn line_spans(index: &Index, y: f64, xr: (f64, f64), rho: f64) -> Vec<(f64, f64)> {
    let edges = index.near([xr.0, y], [xr.1, y]);
    // Inside intervals from the boundary crossings.
    let mut xs: Vec<f64> = edges
        .iter()
        .filter(|e| (e.a[1] > y) != (e.b[1] > y))
        .map(|e| e.a[0] + (y - e.a[1]) / (e.b[1] - e.a[1]) * (e.b[0] - e.a[0]))
        .collect();
    xs.sort_by(f64::total_cmp);
    let mut inside: Vec<(f64, f64)> = Vec::new();
    for w in xs.windows(2) {
        let (lo, hi) = (w[0], w[1]);
        if hi > lo && index.contains([(lo + hi) / 2.0, y]) {
            match inside.last_mut() {
                Some(last) if (last.1 - lo).abs() < 1e-12 => last.1 = hi,
                _ => inside.push((lo, hi)),
            }
        }
    }
    // Intervals closer than rho to an edge.
    let mut bad: Vec<(f64, f64)> = edges
        .iter()
        .filter_map(|e| near_edge(e.a, e.b, y, rho))
        .collect();
    bad.sort_by(|p, q| p.0.total_cmp(&q.0));
    let mut merged: Vec<(f64, f64)> = Vec::new();
    for (lo, hi) in bad {
        match merged.last_mut() {
            Some(last) if lo <= last.1 => last.1 = last.1.max(hi),
            _ => merged.push((lo, hi)),
        }
    }
    let mut spans = Vec::new();
    for (mut lo, hi) in inside {
        for &(blo, bhi) in &merged {
            if bhi <= lo || blo >= hi {
                continue;
            }
            if blo > lo {
                spans.push((lo, blo));
            }
            lo = lo.max(bhi);
        }
        if hi > lo {
            spans.push((lo, hi));
        }
    }
    spans.retain(|(lo, hi)| hi - lo > 1e-6);
    spans
}

/// The interval of the line at `y` whose points lie closer than `rho` to the segment
/// `a`–`b` (the segment widened by `rho` is convex, so this is one interval).
fn near_edge(a: [f64; 2], b: [f64; 2], y: f64, rho: f64) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for c in [a, b] {
        let dy = (y - c[1]).abs();
        if dy < rho {
            let w = (rho * rho - dy * dy).sqrt();
            lo = lo.min(c[0] - w);
            hi = hi.max(c[0] + w);
        }
    }
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len = dx.hypot(dy);
    if len > 0.0 {
        let n = [-dy / len * rho, dx / len * rho];
        let quad = [
            [a[0] + n[0], a[1] + n[1]],
            [b[0] + n[0], b[1] + n[1]],
            [b[0] - n[0], b[1] - n[1]],
            [a[0] - n[0], a[1] - n[1]],
        ];
        for i in 0..4 {
            let (u, v) = (quad[i], quad[(i + 1) % 4]);
            if (u[1] - y) * (v[1] - y) <= 0.0 {
                if (v[1] - u[1]).abs() < 1e-15 {
                    lo = lo.min(u[0].min(v[0]));
                    hi = hi.max(u[0].max(v[0]));
                } else {
                    let x = u[0] + (y - u[1]) / (v[1] - u[1]) * (v[0] - u[0]);
                    lo = lo.min(x);
                    hi = hi.max(x);
                }
            }
        }
    }
    (hi > lo).then_some((lo, hi))
}

/// Spans on lines parallel to the first axis, spread evenly across the region at most
/// `step` apart, the outer lines `rho` (and a hair) inside the region's extent.
pub(super) fn spans(region: &Region, index: &Index, rho: f64, step: f64) -> Vec<Span> {
    let (mut ymin, mut ymax) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut xmin, mut xmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in region.pockets.iter().flat_map(|q| &q.pts) {
        ymin = ymin.min(p[1]);
        ymax = ymax.max(p[1]);
        xmin = xmin.min(p[0]);
        xmax = xmax.max(p[0]);
    }
    let (lo, hi) = (ymin + rho + 1e-6, ymax - rho - 1e-6);
    if hi.is_nan() || lo.is_nan() || hi < lo {
        return Vec::new();
    }
    let n = ((hi - lo) / step - 1e-9).ceil().clamp(0.0, 100_000.0);
    // n is a small whole number.
    let count = n as usize;
    let mut out = Vec::new();
    for j in 0..=count {
        let y = if count == 0 {
            (lo + hi) / 2.0
        } else {
            lo + (hi - lo) * j as f64 / n
        };
        for (a, b) in line_spans(index, y, (xmin - rho, xmax + rho), rho) {
            out.push(Span {
                line: j,
                y,
                lo: a,
                hi: b,
            });
        }
    }
    out
}

/// One zigzag run: spans cut one after the other with straight links at depth; `true`
/// runs a span from low to high.
pub(super) type Run = Vec<(Span, bool)>;

/// Links `spans` into zigzag runs: from the end of a span the tool moves to the nearest
/// unused span on the next line when the straight link keeps `rho` from the boundary,
/// and cuts that span the other way; otherwise a new run begins.
pub(super) fn link(index: &Index, spans: &[Span], rho: f64) -> Vec<Run> {
    let mut used = vec![false; spans.len()];
    let mut runs = Vec::new();
    // Spans come line by line: where each line's spans begin.
    let lines = spans.last().map_or(0, |s| s.line + 1);
    let mut begin = vec![spans.len(); lines + 2];
    for (i, s) in spans.iter().enumerate().rev() {
        if let Some(b) = begin.get_mut(s.line) {
            *b = i;
        }
    }
    for l in (0..=lines).rev() {
        let next = begin.get(l + 1).copied().unwrap_or(spans.len());
        if let Some(b) = begin.get_mut(l) {
            *b = (*b).min(next);
        }
    }
    let mut cursor = 0;
    while let Some(first) = used
        .iter()
        .skip(cursor)
        .position(|u| !u)
        .map(|i| i + cursor)
    {
        cursor = first;
        let mut run: Run = Vec::new();
        let mut cur = first;
        let mut up = true;
        loop {
            if let Some(u) = used.get_mut(cur) {
                *u = true;
            }
            let Some(&s) = spans.get(cur) else { break };
            run.push((s, up));
            let end = if up { [s.hi, s.y] } else { [s.lo, s.y] };
            let next_up = !up;
            let mut best: Option<(f64, usize)> = None;
            let from = begin.get(s.line + 1).copied().unwrap_or(spans.len());
            let to = begin.get(s.line + 2).copied().unwrap_or(spans.len());
            for (i, t) in spans.iter().enumerate().take(to).skip(from) {
                if used.get(i).copied().unwrap_or(true) || t.line != s.line + 1 {
                    continue;
                }
                let start = if next_up { [t.lo, t.y] } else { [t.hi, t.y] };
                let d = (start[0] - end[0]).hypot(start[1] - end[1]);
                if best.is_none_or(|(bd, _)| d < bd) && index.segment_clear(end, start, rho - 1e-7)
                {
                    best = Some((d, i));
                }
            }
            match best {
                Some((_, i)) => {
                    cur = i;
                    up = next_up;
                }
                None => break,
            }
        }
        runs.push(run);
    }
    runs
}
