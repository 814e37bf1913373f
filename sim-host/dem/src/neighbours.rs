//! Verlet neighbour lists with a skin, built from a cell grid.
//!
//! The list is a *half* list (each pair once, under its lower slot `i < j`), stored
//! CSR-style (`start`, `j`), so each pair's force is computed once (Newton's third law, as
//! LAMMPS's `newton on`). At a rebuild the grains are reordered along the cell grid, line by
//! line (a stable counting sort, so the order is a function of the state alone), and every
//! contact's tangential history is carried over by grain identity.
//!
//! The step walks the grains in slot order and scatters each pair's force to the partner
//! (see [`super::step`]). For that to run in parallel with the same bits on any thread
//! count, the slots are cut into **chunks** (`chunk_start`) such that every partner lies in
//! its owner's chunk or the next (checked at the build; chunks of whole cell lines always
//! do, as a partner lies in its owner's line or the next one).
//!
//! The lines run across the box's shorter side (columns of a wide bed, rows of a tall
//! one), so a boundary between chunks is short: on the benchmark's bed, 0.2 m wide and
//! 0.05 m deep, a cut between columns has about 75 cross pairs where one between rows had
//! about 310, and so a quarter of the state the two threads pass each other every step.
//! Entries whose partner lies in the next chunk are *cross pairs*; their owners lie near
//! the end of their chunk and their partners near the start of the next, so chunk `k`'s
//! cross pairs involve only the slots `cross_lo[k]..cross_hi[k]` (the step copies their
//! state before it starts, so both chunks can compute those pairs from it).
//!
//! The results do not depend on where the chunks are cut, only the speed does; so each
//! build cuts where the last interval's timings of the chunks say the work is even (the
//! upper part of a bed, with the intruder and the free surface, costs more per grain),
//! anywhere within a line, as long as every partner stays within the next chunk (else
//! whole lines, which always keep it there).

use rayon::prelude::*;

use super::grains::Grains;

/// A half neighbour list, cut into chunks, with each pair's slip history.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NeighbourList {
    /// Grain `i`'s entries are `start[i]..start[i + 1]`.
    pub start: Vec<u32>,
    /// Neighbour slot of each entry (always above the owner's).
    pub j: Vec<u32>,
    /// Chunk `k` holds slots `chunk_start[k]..chunk_start[k + 1]`.
    pub chunk_start: Vec<u32>,
    /// Chunk `k`'s cross pairs have their owners in `cross_lo[k]..chunk_start[k + 1]` and
    /// their partners in `chunk_start[k + 1]..cross_hi[k]` (both ends `chunk_start[k + 1]`
    /// without cross pairs).
    pub cross_lo: Vec<u32>,
    /// See `cross_lo`.
    pub cross_hi: Vec<u32>,
    /// Number of cross pairs.
    pub cross_count: usize,
    /// Tangential history of each entry, m (empty when friction is off).
    pub hist: Vec<f64>,
    /// Skin, m.
    pub skin_m: f64,
    /// Builds so far.
    pub builds: u64,
}

/// How many chunks to cut `n` grains into for `parts` threads: one for one thread; else
/// one a thread, but none under 256 grains (the pairs across a boundary are computed twice)
/// and none over 4096 (work stealing then evens out what the cut does not). Measured on
/// 2 threads (7,015 grains): one chunk a thread 148-158 M atom-steps/s, two 146-149 M.
pub fn chunk_count(n: usize, parts: usize) -> usize {
    if parts <= 1 {
        1
    } else {
        let size = (n / parts).clamp(CHUNK_SIZE.0, CHUNK_SIZE.1);
        (n / size).max(1)
    }
}

/// Slots a task of the parallel list build takes.
const BUILD_PIECE: usize = 1024;

/// Bounds of a chunk's size in [`chunk_count`], grains.
const CHUNK_SIZE: (usize, usize) = (256, 4096);

/// `want` chunks of `n` slots, cut where the time measured on the `old` chunks (`seconds`
/// each since the last build) says the work is even, moving each cut halfway there from
/// where it was (timings are noisy); evenly by slots without usable timings. Increasing,
/// from 0 to `n`; any cuts give the same results, only the speed differs.
fn cuts_by_time(n: usize, want: usize, old: &[u32], seconds: &[f64]) -> Vec<u32> {
    let usable = want > 1
        && old.len() == want + 1
        && old.last() == Some(&(n as u32))
        && seconds.len() == want
        && seconds.iter().all(|&t| t > 0.0 && t.is_finite());
    increasing_cuts(
        n,
        (1..want).map(|k| {
            let even = k * n / want;
            if usable {
                // Time of slots 0..s, each old chunk's time spread evenly over its slots.
                let time_to = |s: usize| -> f64 {
                    let c = old
                        .partition_point(|&o| (o as usize) <= s)
                        .saturating_sub(1)
                        .min(want - 1);
                    let (a, b) = (old[c] as usize, old[c + 1] as usize);
                    seconds[..c].iter().sum::<f64>()
                        + seconds[c] * (s - a) as f64 / (b - a).max(1) as f64
                };
                let target = seconds.iter().sum::<f64>() * k as f64 / want as f64;
                let (mut lo, mut hi) = (0usize, n);
                while lo < hi {
                    let mid = (lo + hi) / 2;
                    if time_to(mid) < target {
                        lo = mid + 1;
                    } else {
                        hi = mid;
                    }
                }
                let was = old[k] as usize;
                (was + lo) / 2
            } else {
                even
            }
        }),
    )
}

/// `want` chunks of whole cell lines (`line_end`: each line's end slot), each cut at the
/// line end nearest an even share of the `n` slots.
fn cuts_by_lines(n: usize, want: usize, line_end: &[usize]) -> Vec<u32> {
    increasing_cuts(
        n,
        (1..want).map(|k| {
            let target = k * n / want;
            let at = line_end.partition_point(|&e| e < target);
            let below = at.checked_sub(1).map(|r| line_end[r]);
            let above = line_end.get(at).copied();
            match (below, above) {
                (Some(b), Some(a)) if target - b <= a - target => b,
                (_, Some(a)) => a,
                (Some(b), None) => b,
                (None, None) => n,
            }
        }),
    )
}

/// Chunk starts from 0 through `inner` (cuts that do not go up, or reach `n`, dropped) to
/// `n`.
fn increasing_cuts(n: usize, inner: impl Iterator<Item = usize>) -> Vec<u32> {
    let mut cuts = vec![0u32];
    for cut in inner {
        if cut > *cuts.last().unwrap_or(&0) as usize && cut < n {
            cuts.push(cut as u32);
        }
    }
    cuts.push(n as u32);
    cuts
}

/// For chunks `cuts` of the list (`start`, `js`): each chunk's `cross_lo` and `cross_hi`
/// (see [`NeighbourList`]) and the number of cross pairs; `None` if a partner lies beyond
/// the chunk after its owner's.
#[allow(clippy::type_complexity)]
fn cross_bounds(cuts: &[u32], start: &[u32], js: &[u32]) -> Option<(Vec<u32>, Vec<u32>, usize)> {
    let (mut cross_lo, mut cross_hi, mut count) = (Vec::new(), Vec::new(), 0);
    for (k, c) in cuts.windows(2).enumerate() {
        let c1 = c[1] as usize;
        let c2 = cuts.get(k + 2).map_or(c1, |&e| e as usize);
        let (mut lo, mut hi) = (c1, c1);
        for i in c[0] as usize..c1 {
            for &j in &js[start[i] as usize..start[i + 1] as usize] {
                let j = j as usize;
                if j >= c1 {
                    if j >= c2 {
                        return None;
                    }
                    lo = lo.min(i);
                    hi = hi.max(j + 1);
                    count += 1;
                }
            }
        }
        cross_lo.push(lo as u32);
        cross_hi.push(hi as u32);
    }
    Some((cross_lo, cross_hi, count))
}

/// Grid bounds: cells of side `cell_m` over the grains' bounding box, numbered line by
/// line along its longer side (columns of a wide bed, rows of a tall one), so that a chunk
/// boundary, which runs along a line, crosses the box the short way.
struct CellGrid {
    x0: f64,
    y0: f64,
    inv_cell: f64,
    nx: usize,
    ny: usize,
    /// Lines are columns (`true`: the box is wider than tall) or rows.
    columns: bool,
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
                columns: false,
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
            columns: nx > ny,
        }
    }

    /// Number of lines (see [`CellGrid`]) and of cells in each.
    fn lines(&self) -> (usize, usize) {
        if self.columns {
            (self.nx, self.ny)
        } else {
            (self.ny, self.nx)
        }
    }

    /// Cell (`cx`, `cy`) as (its line, its place along the line).
    #[inline]
    fn line_of(&self, cx: usize, cy: usize) -> (usize, usize) {
        if self.columns { (cx, cy) } else { (cy, cx) }
    }

    /// Index of cell (`cx`, `cy`): line by line.
    #[inline]
    fn index(&self, cx: usize, cy: usize) -> usize {
        let (line, along) = self.line_of(cx, cy);
        line * self.lines().1 + along
    }

    /// The cells around (`cx`, `cy`), itself included, in increasing index.
    #[inline]
    fn around(&self, cx: usize, cy: usize) -> impl Iterator<Item = usize> + use<> {
        let (lines, per_line) = self.lines();
        let (line, along) = self.line_of(cx, cy);
        let alongs = along.saturating_sub(1)..(along + 2).min(per_line);
        (line.saturating_sub(1)..(line + 2).min(lines))
            .flat_map(move |l| alongs.clone().map(move |a| l * per_line + a))
    }

    #[inline]
    fn cell_of(&self, x: f64, y: f64) -> (usize, usize) {
        let cx = (((x - self.x0) * self.inv_cell) as usize).min(self.nx - 1);
        let cy = (((y - self.y0) * self.inv_cell) as usize).min(self.ny - 1);
        (cx, cy)
    }
}

impl NeighbourList {
    /// Reorder `g` along the cell grid, rebuild the list for interaction range
    /// `r_i + r_j + skin`, and carry every tangential history over (`with_history`: friction
    /// on), cutting the slots into chunks for `parts` threads (see [`chunk_count`]) where
    /// `chunk_seconds` (the time each of the current chunks took since the last build, if
    /// known) says the work is even. Returns
    /// the permutation applied (new slot `s` took old slot `perm[s]`), which the caller
    /// applies to its own per-grain arrays ([`super::grains::permute`]).
    pub fn rebuild(
        &mut self,
        g: &mut Grains,
        skin_m: f64,
        with_history: bool,
        parts: usize,
        chunk_seconds: &[f64],
    ) -> Vec<usize> {
        self.skin_m = skin_m;
        let n = g.len();
        let r_max = g.radius.iter().copied().fold(0.0, f64::max);
        let grid = CellGrid::new(g, 2.0 * r_max + skin_m);
        let ncell = grid.nx * grid.ny;
        // Stable counting sort by cell: the new order.
        let cells: Vec<usize> = (0..n)
            .map(|i| {
                let (cx, cy) = grid.cell_of(g.x[i], g.y[i]);
                grid.index(cx, cy)
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
        // Each grain's partners, in slot order; pieces of slots in parallel (the list does
        // not depend on the pieces), then joined.
        let g_ref: &Grains = g;
        let partners_of = |i: usize, js: &mut Vec<u32>| {
            let (cx, cy) = grid.cell_of(g_ref.x[i], g_ref.y[i]);
            let (xi, yi, ri) = (g_ref.x[i], g_ref.y[i], g_ref.radius[i]);
            let intruder_i = g_ref.kind[i] != super::grains::FREE;
            for c in grid.around(cx, cy) {
                for j in cell_start[c]..cell_start[c + 1] {
                    if j <= i || (intruder_i && g_ref.kind[j] != super::grains::FREE) {
                        continue;
                    }
                    let dx = g_ref.x[j] - xi;
                    let dy = g_ref.y[j] - yi;
                    let reach = ri + g_ref.radius[j] + skin_m;
                    if dx * dx + dy * dy < reach * reach {
                        js.push(j as u32);
                    }
                }
            }
        };
        let pieces: Vec<(Vec<u32>, Vec<u32>)> = (0..n.div_ceil(BUILD_PIECE))
            .into_par_iter()
            .map(|k| {
                let slots = k * BUILD_PIECE..((k + 1) * BUILD_PIECE).min(n);
                let mut js = Vec::with_capacity(slots.len() * 8);
                let mut ends = Vec::with_capacity(slots.len());
                for i in slots {
                    partners_of(i, &mut js);
                    ends.push(js.len() as u32);
                }
                (ends, js)
            })
            .collect();
        let mut start = Vec::with_capacity(n + 1);
        let mut js: Vec<u32> = Vec::with_capacity(pieces.iter().map(|p| p.1.len()).sum());
        start.push(0u32);
        for (ends, piece) in pieces {
            let offset = js.len() as u32;
            start.extend(ends.iter().map(|&e| offset + e));
            js.extend_from_slice(&piece);
        }
        // Chunks: cut where the last interval's timings say the work is even; cuts that
        // put a partner beyond the next chunk (chunks too thin for the lines) fall back to
        // whole lines, which never do.
        let want = chunk_count(n, parts);
        let timed = cuts_by_time(n, want, &old.chunk_start, chunk_seconds);
        let (lines, per_line) = grid.lines();
        let line_end: Vec<usize> = (1..=lines).map(|l| cell_start[l * per_line]).collect();
        let whole_lines = cuts_by_lines(n, want, &line_end);
        // One chunk (no boundary) is the last resort; it has no cross pairs.
        let one = (vec![0, n as u32], (vec![n as u32], vec![n as u32], 0));
        let (chunk_start, (cross_lo, cross_hi, cross_count)) = [timed, whole_lines]
            .into_iter()
            .find_map(|cuts| cross_bounds(&cuts, &start, &js).map(|b| (cuts, b)))
            .unwrap_or(one);
        let mut hist = Vec::new();
        if with_history {
            hist = vec![0.0; js.len()];
            if !old.hist.is_empty() && old.start.len() == n + 1 {
                // The pair may sit under either grain in the old list; its slip is the same
                // seen from either side.
                let find = |owner: usize, partner_id: u32| {
                    (old.start[owner] as usize..old.start[owner + 1] as usize)
                        .find(|&oe| old.hist[oe] != 0.0 && old_id[old.j[oe] as usize] == partner_id)
                };
                for s in 0..n {
                    for e in start[s] as usize..start[s + 1] as usize {
                        let t = js[e] as usize;
                        let found = find(perm[s], g.id[t]).or_else(|| find(perm[t], g.id[s]));
                        if let Some(oe) = found {
                            hist[e] = old.hist[oe];
                        }
                    }
                }
            }
        }
        *self = Self {
            start,
            j: js,
            chunk_start,
            cross_lo,
            cross_hi,
            cross_count,
            hist,
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
            let (lo, hi) = if i < j { (i, j) } else { (j, i) };
            for e in self.start[lo] as usize..self.start[lo + 1] as usize {
                if self.j[e] as usize == hi {
                    self.hist[e] = h;
                }
            }
        }
    }

    /// Number of chunks.
    pub fn chunks(&self) -> usize {
        self.chunk_start.len().saturating_sub(1)
    }

    /// Number of cross pairs (entries whose partner lies in the next chunk).
    pub fn cross_pairs(&self) -> usize {
        self.cross_count
    }

    /// Bytes held per grain (list, chunks, history), at the current fill.
    pub fn bytes_per_grain(&self) -> f64 {
        let n = self.start.len().saturating_sub(1).max(1) as f64;
        (4.0 * (self.start.len()
            + self.j.capacity()
            + self.chunk_start.len()
            + self.cross_lo.len()
            + self.cross_hi.len()) as f64
            + 8.0 * self.hist.capacity() as f64)
            / n
    }
}
