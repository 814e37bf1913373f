//! Verlet neighbour lists with a skin, built from a cell grid.
//!
//! The list is *full* (each pair appears under both grains) and stored CSR-style
//! (`start`, `j`): every grain sums its own forces from its own list, so the force pass runs
//! in parallel without atomics or a reduction, and gives the same bits for any thread count.
//! Each entry carries the pair's tangential history (the accumulated slip, m), which both
//! grains of a pair update identically. At a rebuild the grains are reordered along the cell
//! grid (a stable counting sort, so the order is a function of the state alone) and every
//! contact's history is carried over by grain identity.

use super::grains::Grains;

/// A full neighbour list.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NeighbourList {
    /// Grain `i`'s entries are `start[i]..start[i + 1]`.
    pub start: Vec<u32>,
    /// Neighbour slot of each entry.
    pub j: Vec<u32>,
    /// Tangential history of each entry, m (empty when friction is off).
    pub hist: Vec<f64>,
    /// Positions at the build, m (a rebuild is due once a grain moved half the skin).
    pub x_ref: Vec<f64>,
    /// Positions at the build, m.
    pub y_ref: Vec<f64>,
    /// Skin, m.
    pub skin_m: f64,
    /// Builds so far.
    pub builds: u64,
}

/// Grid bounds: cells of side `cell_m` over the grains' bounding box.
struct CellGrid {
    x0: f64,
    y0: f64,
    inv_cell: f64,
    nx: usize,
    ny: usize,
}

impl CellGrid {
    fn new(g: &Grains, cell_m: f64) -> Self {
        if g.is_empty() {
            return Self {
                x0: 0.0,
                y0: 0.0,
                inv_cell: 1.0 / cell_m.max(f64::MIN_POSITIVE),
                nx: 1,
                ny: 1,
            };
        }
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for i in 0..g.len() {
            x0 = x0.min(g.x[i]);
            x1 = x1.max(g.x[i]);
            y0 = y0.min(g.y[i]);
            y1 = y1.max(g.y[i]);
        }
        // A grain flung far must not make the grid huge: grow the cells instead.
        let mut cell = cell_m;
        let limit = (4 * g.len()).max(64) as f64;
        while ((x1 - x0) / cell + 1.0) * ((y1 - y0) / cell + 1.0) > limit {
            cell *= 1.5;
        }
        let nx = ((x1 - x0) / cell) as usize + 1;
        let ny = ((y1 - y0) / cell) as usize + 1;
        Self {
            x0,
            y0,
            inv_cell: 1.0 / cell,
            nx,
            ny,
        }
    }

    #[inline]
    fn cell_of(&self, x: f64, y: f64) -> (usize, usize) {
        let cx = (((x - self.x0) * self.inv_cell) as usize).min(self.nx - 1);
        let cy = (((y - self.y0) * self.inv_cell) as usize).min(self.ny - 1);
        (cx, cy)
    }
}

impl NeighbourList {
    /// Whether some grain moved more than half the skin since the build.
    pub fn due(&self, g: &Grains) -> bool {
        if self.x_ref.len() != g.len() {
            return true;
        }
        let lim = 0.25 * self.skin_m * self.skin_m;
        (0..g.len()).any(|i| {
            let dx = g.x[i] - self.x_ref[i];
            let dy = g.y[i] - self.y_ref[i];
            dx * dx + dy * dy > lim
        })
    }

    /// Reorder `g` along the cell grid, rebuild the list for interaction range
    /// `r_i + r_j + skin`, and carry every tangential history over (`with_history`: friction
    /// on). Returns the permutation applied (new slot `s` took old slot `perm[s]`), which the
    /// caller applies to its own per-grain arrays ([`super::grains::permute`]).
    pub fn rebuild(&mut self, g: &mut Grains, skin_m: f64, with_history: bool) -> Vec<usize> {
        self.skin_m = skin_m;
        let n = g.len();
        let r_max = g.radius.iter().copied().fold(0.0, f64::max);
        let grid = CellGrid::new(g, 2.0 * r_max + skin_m);
        let ncell = grid.nx * grid.ny;
        // Stable counting sort by cell: the new order.
        let cells: Vec<usize> = (0..n)
            .map(|i| {
                let (cx, cy) = grid.cell_of(g.x[i], g.y[i]);
                cy * grid.nx + cx
            })
            .collect();
        let mut cell_start = vec![0usize; ncell + 1];
        for &c in &cells {
            cell_start[c + 1] += 1;
        }
        for c in 0..ncell {
            cell_start[c + 1] += cell_start[c];
        }
        let mut fill = cell_start.clone();
        let mut perm = vec![0usize; n];
        for (i, &c) in cells.iter().enumerate() {
            perm[fill[c]] = i;
            fill[c] += 1;
        }
        // Old contacts with history, by old slot, before the grains move.
        let old_id = g.id.clone();
        let old = std::mem::take(self);
        g.permute(&perm);
        // Grains of cell c are now slots cell_start[c]..cell_start[c + 1].
        let mut start = Vec::with_capacity(n + 1);
        let mut js: Vec<u32> = Vec::with_capacity(n * 8);
        start.push(0u32);
        for i in 0..n {
            let (cx, cy) = grid.cell_of(g.x[i], g.y[i]);
            let (xi, yi, ri) = (g.x[i], g.y[i], g.radius[i]);
            let intruder_i = g.kind[i] != super::grains::FREE;
            for ny in cy.saturating_sub(1)..(cy + 2).min(grid.ny) {
                for nx in cx.saturating_sub(1)..(cx + 2).min(grid.nx) {
                    let c = ny * grid.nx + nx;
                    for j in cell_start[c]..cell_start[c + 1] {
                        if j == i || (intruder_i && g.kind[j] != super::grains::FREE) {
                            continue;
                        }
                        let dx = g.x[j] - xi;
                        let dy = g.y[j] - yi;
                        let reach = ri + g.radius[j] + skin_m;
                        if dx * dx + dy * dy < reach * reach {
                            js.push(j as u32);
                        }
                    }
                }
            }
            start.push(js.len() as u32);
        }
        let mut hist = Vec::new();
        if with_history {
            hist = vec![0.0; js.len()];
            let carried = !old.hist.is_empty() && old.start.len() == n + 1;
            if carried {
                for s in 0..n {
                    let os = perm[s];
                    let (o0, o1) = (old.start[os] as usize, old.start[os + 1] as usize);
                    for e in start[s] as usize..start[s + 1] as usize {
                        let idj = g.id[js[e] as usize];
                        for oe in o0..o1 {
                            if old.hist[oe] != 0.0 && old_id[old.j[oe] as usize] == idj {
                                hist[e] = old.hist[oe];
                                break;
                            }
                        }
                    }
                }
            }
        }
        *self = Self {
            start,
            j: js,
            hist,
            x_ref: g.x.clone(),
            y_ref: g.y.clone(),
            skin_m,
            builds: old.builds + 1,
        };
        perm
    }

    /// The contacts with history as `(id_i, id_j, slip_m)` (for a checkpoint).
    pub fn history_by_id(&self, g: &Grains) -> Vec<(u32, u32, f64)> {
        let mut out = Vec::new();
        for i in 0..g.len().min(self.start.len().saturating_sub(1)) {
            for e in self.start[i] as usize..self.start[i + 1] as usize {
                if let Some(&h) = self.hist.get(e)
                    && h != 0.0
                {
                    out.push((g.id[i], g.id[self.j[e] as usize], h));
                }
            }
        }
        out
    }

    /// Restore histories saved by [`Self::history_by_id`] into a freshly built list.
    pub fn restore_history(&mut self, g: &Grains, saved: &[(u32, u32, f64)]) {
        if self.hist.is_empty() || saved.is_empty() {
            return;
        }
        let mut slot_of = vec![usize::MAX; g.len()];
        for (s, &id) in g.id.iter().enumerate() {
            if (id as usize) < slot_of.len() {
                slot_of[id as usize] = s;
            }
        }
        for &(a, b, h) in saved {
            let (Some(&i), Some(&j)) = (slot_of.get(a as usize), slot_of.get(b as usize)) else {
                continue;
            };
            if i == usize::MAX || j == usize::MAX {
                continue;
            }
            for e in self.start[i] as usize..self.start[i + 1] as usize {
                if self.j[e] as usize == j {
                    self.hist[e] = h;
                }
            }
        }
    }

    /// Bytes held per grain (list, history, reference positions), at the current fill.
    pub fn bytes_per_grain(&self) -> f64 {
        let n = self.start.len().saturating_sub(1).max(1) as f64;
        (4.0 * self.start.len() as f64
            + 4.0 * self.j.capacity() as f64
            + 8.0 * self.hist.capacity() as f64
            + 16.0 * n)
            / n
    }
}
