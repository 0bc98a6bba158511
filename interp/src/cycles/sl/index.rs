//! A grid over the boundary edges of a region, so that the tests of the SL paths look
//! only at the edges near the place in question.

use super::region::{Region, dist_point_seg, dist_seg_seg};

/// One boundary edge and the polygon it belongs to.
#[derive(Debug, Clone, Copy)]
pub(super) struct Edge {
    /// Start.
    pub a: [f64; 2],
    /// End.
    pub b: [f64; 2],
    /// Polygon number (pockets first, then islands).
    poly: usize,
}

/// The edges of a region sorted into grid cells; each edge sits in every cell its
/// bounding box widened by `pad` touches, so a query box finds every edge that comes
/// closer than `pad` to it.
#[derive(Debug, Clone)]
pub(super) struct Index {
    edges: Vec<Edge>,
    /// Pocket or island, per polygon.
    pocket: Vec<bool>,
    origin: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
    /// Right end of everything, for rays.
    xmax: f64,
}

/// Grid cells per side at most.
const GRID: f64 = 64.0;

impl Index {
    /// Indexes `region` for queries closer than `pad`.
    pub fn new(region: &Region, pad: f64) -> Self {
        let mut edges = Vec::new();
        let mut pocket = Vec::new();
        for (i, (poly, is_pocket)) in region
            .pockets
            .iter()
            .map(|p| (p, true))
            .chain(region.islands.iter().map(|p| (p, false)))
            .enumerate()
        {
            pocket.push(is_pocket);
            edges.extend(poly.edges().map(|(a, b)| Edge { a, b, poly: i }));
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for e in &edges {
            for p in [e.a, e.b] {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k] - pad);
                    hi[k] = hi[k].max(p[k] + pad);
                }
            }
        }
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let cell = if span.is_finite() && span > 0.0 {
            span / GRID
        } else {
            1.0
        };
        let count = |k: usize| ((hi[k] - lo[k]) / cell).ceil().clamp(1.0, GRID + 1.0) as usize;
        let (nx, ny) = if span.is_finite() {
            (count(0), count(1))
        } else {
            (1, 1)
        };
        let mut index = Self {
            edges: Vec::new(),
            pocket,
            origin: if span.is_finite() { lo } else { [0.0, 0.0] },
            cell,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
            xmax: hi[0],
        };
        for (n, e) in edges.iter().enumerate() {
            let bmin = [e.a[0].min(e.b[0]) - pad, e.a[1].min(e.b[1]) - pad];
            let bmax = [e.a[0].max(e.b[0]) + pad, e.a[1].max(e.b[1]) + pad];
            let (i0, i1, j0, j1) = index.range(bmin, bmax);
            // Only the cells that come within the pad of the edge itself: a cell's points
            // lie within half its diagonal of its centre.
            let reach = pad + cell * std::f64::consts::FRAC_1_SQRT_2;
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let centre = [
                        index.origin[0] + (i as f64 + 0.5) * cell,
                        index.origin[1] + (j as f64 + 0.5) * cell,
                    ];
                    if dist_point_seg(centre, e.a, e.b) > reach {
                        continue;
                    }
                    if let Some(c) = index.cells.get_mut(j * nx + i) {
                        c.push(n as u32);
                    }
                }
            }
        }
        index.edges = edges;
        index
    }

    /// Cell ranges covering a box, clamped to the grid.
    fn range(&self, min: [f64; 2], max: [f64; 2]) -> (usize, usize, usize, usize) {
        let at = |v: f64, k: usize, n: usize| {
            let c = ((v - self.origin[k]) / self.cell).floor();
            // Saturating conversion of a clamped value.
            c.clamp(0.0, (n - 1) as f64) as usize
        };
        (
            at(min[0], 0, self.nx),
            at(max[0], 0, self.nx),
            at(min[1], 1, self.ny),
            at(max[1], 1, self.ny),
        )
    }

    /// Every edge that may come closer than the pad to the box `min`–`max`.
    pub fn near(&self, min: [f64; 2], max: [f64; 2]) -> Vec<Edge> {
        let (i0, i1, j0, j1) = self.range(min, max);
        let mut ids: Vec<u32> = Vec::new();
        for j in j0..=j1 {
            for i in i0..=i1 {
                if let Some(c) = self.cells.get(j * self.nx + i) {
                    ids.extend_from_slice(c);
                }
            }
        }
        ids.sort_unstable();
        ids.dedup();
        ids.into_iter()
            .filter_map(|n| self.edges.get(n as usize).copied())
            .collect()
    }

    /// Whether `p` lies in a pocket and in no island (even-odd rule per polygon).
    pub fn contains(&self, p: [f64; 2]) -> bool {
        let mut inside = vec![false; self.pocket.len()];
        for e in self.near(p, [self.xmax, p[1]]) {
            let (a, b) = (e.a, e.b);
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if x > p[0]
                    && let Some(f) = inside.get_mut(e.poly)
                {
                    *f = !*f;
                }
            }
        }
        let mut in_pocket = false;
        for (f, is_pocket) in inside.iter().zip(&self.pocket) {
            if *f && !*is_pocket {
                return false;
            }
            in_pocket |= *f && *is_pocket;
        }
        in_pocket
    }

    /// Whether a tool centre moving straight from `p` to `q` stays in the region at least
    /// `rho` (not more than the pad) from its boundary everywhere.
    pub fn segment_clear(&self, p: [f64; 2], q: [f64; 2], rho: f64) -> bool {
        let min = [p[0].min(q[0]), p[1].min(q[1])];
        let max = [p[0].max(q[0]), p[1].max(q[1])];
        self.contains(p)
            && self
                .near(min, max)
                .iter()
                .all(|e| dist_seg_seg(p, q, e.a, e.b) >= rho)
    }
}
