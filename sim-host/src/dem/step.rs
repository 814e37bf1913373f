//! One time step of a [`World`] in **one fused pass** over the grains: each grain's pairs,
//! then its walls, drag and gravity, then its integration, before the next grain.
//!
//! The half neighbour list puts a pair under its lower slot, so when the pass reaches grain
//! `i` every pair `(h, i)` with `h < i` has already been computed and its force scattered
//! into `i`'s accumulator; `i` adds its own pairs (scattering their reactions forward), and
//! its force is complete: it is integrated in place at once. No later grain reads it (they
//! only read partners above themselves), so the pass reads every grain's state of the step
//! before, as a two-pass scheme would, with one sweep of memory instead of two and no
//! per-pair force array. LAMMPS runs the pair force, each fix (gravity, walls, the move of
//! the intruder, `enforce2d`) and the integrator's two halves as separate passes.
//!
//! **Parallel, the same bits on any thread count.** The slots are cut into chunks of whole
//! cell rows (see [`super::neighbours`]); a pair's partner lies in the owner's chunk or the
//! next. A pair reaching into the next chunk writes its reaction to a spill slot instead.
//! Even chunks run first, in parallel: a grain that gathers spills from the chunk before
//! (its first row, about) is left for later with its partial force. Odd chunks run next:
//! their spills from the even chunk before are ready, so every grain finishes in turn; the
//! even chunk after them still holds its first row unintegrated, as they need. Last, the
//! even chunks' deferred grains gather their spills and integrate. Each grain's force is
//! summed in one fixed order, `((scattered from lower slots of its chunk) + own pairs) +
//! spills`, and per-chunk sums (forces on the intruder and the floor) are added in chunk
//! order: the result depends on the chunks, which depend on the state alone, never on the
//! threads.
//!
//! Integrators:
//! - forward Euler (Supplementary I): `x' = x + v dt`, `v' = v + a(x, v) dt`;
//! - velocity Verlet, in its leapfrog form: the integrated velocity is the half-step one,
//!   `v' = v + a dt`, `x' = x + v' dt`. LAMMPS's `fix nve/sphere` lets the dashpot see that
//!   half-step velocity, which makes a damped contact first order in the step (1.5 % error
//!   in the restitution at t_c/40); here the dashpot sees the full-step velocity predicted
//!   from the last acceleration, `u = v + a dt / 2`, written by the same pass, which makes it
//!   second order (0.1 % at t_c/40) at no extra pass. The default.

use rayon::prelude::*;

use super::contact::GammaRule;
use super::neighbours::NeighbourList;
use super::world::{Integrator, NEAR_WALL, PRESCRIBED, StepSums, Walls, World};

/// Constants of one step, read by every grain.
pub(super) struct StepConst {
    kn: f64,
    gamma_const: Option<f64>,
    gamma_rule: GammaRule,
    friction: bool,
    mu: f64,
    mu_wall: f64,
    kt: f64,
    gt_ratio: f64,
    dt: f64,
    g: f64,
    drag: f64,
    euler: bool,
    walls: Walls,
    intruder: Option<(f64, f64)>,
}

impl StepConst {
    /// The constants of `w`'s next step.
    pub(super) fn of(w: &World) -> Self {
        let law = w.cfg.law;
        let f = law.friction;
        Self {
            kn: law.kn_n_per_m,
            gamma_const: law.constant_gamma_n(),
            gamma_rule: law.gamma_rule(),
            friction: f.is_some(),
            mu: f.map_or(0.0, |f| f.mu),
            mu_wall: f.map_or(0.0, |f| f.mu_wall),
            kt: f.map_or(0.0, |f| f.kt_over_kn * law.kn_n_per_m),
            gt_ratio: f.map_or(0.0, |f| f.gammat_over_gamman),
            dt: w.cfg.dt_s,
            g: w.cfg.gravity_m_s2,
            drag: w.cfg.drag_per_s,
            euler: w.cfg.integrator == Integrator::ForwardEuler,
            walls: w.cfg.walls,
            intruder: w.intruder_next,
        }
    }

    /// Tangential force (scalar along `t = (-n_y, n_x)`) for slip speed `vt` and normal
    /// force `fn_`, updating the slip history.
    #[inline(always)]
    fn tangential(&self, hist: &mut f64, vt: f64, fn_: f64, gamma_n: f64, mu: f64) -> f64 {
        let gt = self.gt_ratio * gamma_n;
        if self.kt <= 0.0 {
            *hist = 0.0;
            let ft = -gt * vt;
            let cap = mu * fn_.max(0.0);
            return if ft.abs() > cap { cap.copysign(ft) } else { ft };
        }
        *hist += vt * self.dt;
        let mut ft = -(self.kt * *hist) - gt * vt;
        let cap = mu * fn_.max(0.0);
        if ft.abs() > cap {
            ft = cap.copysign(ft);
            *hist = -(ft + gt * vt) / self.kt;
        }
        ft
    }

    /// The force on the owner `i` from its partner `j`, N, and the pair's tangential force
    /// (along `(-n_y, n_x)`, `n` from `i` to `j`; both grains feel the torque `r ft`), N;
    /// `None` without contact (the history is then cleared). `d = (x_j - x_i, y_j - y_i)`,
    /// `rv` the velocity of `i` relative to `j`, `spin` the surface speed `w_i r_i + w_j r_j`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn pair<const FRICTION: bool>(
        &self,
        dx: f64,
        dy: f64,
        rsum: f64,
        rvx: f64,
        rvy: f64,
        spin: f64,
        inv_mass_sum: f64,
        hist: &mut f64,
    ) -> Option<(f64, f64, f64)> {
        let d2 = dx * dx + dy * dy;
        if d2 >= rsum * rsum || d2 == 0.0 {
            if FRICTION {
                *hist = 0.0;
            }
            return None;
        }
        let d = d2.sqrt();
        let inv_d = 1.0 / d;
        let (nxu, nyu) = (dx * inv_d, dy * inv_d);
        let delta = rsum - d;
        let vn = rvx * nxu + rvy * nyu;
        let gamma = match self.gamma_const {
            Some(gm) => gm,
            None => pair_gamma(self.gamma_rule, inv_mass_sum),
        };
        let fn_ = self.kn * delta + gamma * vn;
        let (mut fx, mut fy) = (-fn_ * nxu, -fn_ * nyu);
        let mut ft = 0.0;
        if FRICTION {
            let (tx, ty) = (-nyu, nxu);
            let vt = rvx * tx + rvy * ty + spin;
            ft = self.tangential(hist, vt, fn_, gamma, self.mu);
            fx += ft * tx;
            fy += ft * ty;
        }
        Some((fx, fy, ft))
    }
}

/// `gamma_n` for a pair whose inverse masses sum to `inv_mass_sum` (1/kg). Kept out of
/// line: inlined, the compiler hoists its division and square root out of the branch that
/// needs them and pays them for every pair even when `gamma_n` is a constant.
#[inline(never)]
pub(super) fn pair_gamma(rule: GammaRule, inv_mass_sum: f64) -> f64 {
    rule.at(1.0 / inv_mass_sum)
}

/// Force accumulators reused from step to step: per grain (zero between steps) and per
/// spill slot.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scratch {
    fx: Vec<f64>,
    fy: Vec<f64>,
    ft: Vec<f64>,
    spill_x: Vec<f64>,
    spill_y: Vec<f64>,
    spill_t: Vec<f64>,
}

impl Scratch {
    /// Sized for `n` grains and `spills` spill slots, zeroed (`friction`: with the
    /// tangential sums).
    pub fn sized(n: usize, spills: usize, friction: bool) -> Self {
        let t = |len| if friction { vec![0.0; len] } else { Vec::new() };
        Self {
            fx: vec![0.0; n],
            fy: vec![0.0; n],
            ft: t(n),
            spill_x: vec![0.0; spills],
            spill_y: vec![0.0; spills],
            spill_t: t(spills),
        }
    }

    /// Bytes per grain for `n` grains.
    pub fn bytes_per_grain(&self, n: usize) -> f64 {
        8.0 * (self.fx.capacity()
            + self.fy.capacity()
            + self.ft.capacity()
            + self.spill_x.capacity()
            + self.spill_y.capacity()
            + self.spill_t.capacity()) as f64
            / n.max(1) as f64
    }
}

/// What every chunk reads and no chunk writes.
struct Fixed<'a> {
    radius: &'a [f64],
    inv_mass: &'a [f64],
    inv_inertia: &'a [f64],
    class: &'a [u8],
    start: &'a [u32],
    j: &'a [u32],
    spill_in_start: &'a [u32],
    spill_in: &'a [u32],
}

/// One chunk's grains (slots `c0..c1`), entries (from `e0`) and spill slots (from `s0`):
/// the parts of the arrays its grains own.
struct Part<'a> {
    c0: usize,
    c1: usize,
    e0: usize,
    s0: usize,
    x: &'a mut [f64],
    y: &'a mut [f64],
    vx: &'a mut [f64],
    vy: &'a mut [f64],
    w: &'a mut [f64],
    ux: &'a mut [f64],
    uy: &'a mut [f64],
    uw: &'a mut [f64],
    fx: &'a mut [f64],
    fy: &'a mut [f64],
    ft: &'a mut [f64],
    wall_hist: &'a mut [[f64; 4]],
    hist: &'a mut [f64],
    spill_x: &'a mut [f64],
    spill_y: &'a mut [f64],
    spill_t: &'a mut [f64],
}

/// `v` cut at the consecutive offsets `cuts` (first 0, last `v.len()`); an empty `v` (an
/// array a frictionless run leaves empty) gives empty pieces.
fn cut<'a, T>(mut v: &'a mut [T], cuts: &[usize]) -> Vec<&'a mut [T]> {
    let mut out = Vec::with_capacity(cuts.len().saturating_sub(1));
    for c in cuts.windows(2) {
        let len = if v.is_empty() { 0 } else { c[1] - c[0] };
        let (head, tail) = v.split_at_mut(len);
        out.push(head);
        v = tail;
    }
    out
}

/// Advance `w` one step (its neighbour list current).
pub(super) fn advance(w: &mut World) {
    let c = StepConst::of(w);
    let NeighbourList {
        start,
        j,
        chunk_start,
        spill_base,
        spill_in_start,
        spill_in,
        hist,
        ..
    } = &mut w.nl;
    let chunks: Vec<usize> = chunk_start.iter().map(|&s| s as usize).collect();
    let entries: Vec<usize> = chunks.iter().map(|&s| start[s] as usize).collect();
    let spills: Vec<usize> = spill_base.iter().map(|&s| s as usize).collect();
    let g = &mut w.g;
    let fixed = Fixed {
        radius: &g.radius,
        inv_mass: &g.inv_mass,
        inv_inertia: &g.inv_inertia,
        class: &w.class,
        start,
        j,
        spill_in_start,
        spill_in,
    };
    let s = &mut w.scratch;
    let mut pieces = (
        cut(&mut g.x, &chunks).into_iter(),
        cut(&mut g.y, &chunks).into_iter(),
        cut(&mut g.vx, &chunks).into_iter(),
        cut(&mut g.vy, &chunks).into_iter(),
        cut(&mut g.w, &chunks).into_iter(),
        cut(&mut w.u.x, &chunks).into_iter(),
        cut(&mut w.u.y, &chunks).into_iter(),
        cut(&mut w.u.w, &chunks).into_iter(),
        cut(&mut s.fx, &chunks).into_iter(),
        cut(&mut s.fy, &chunks).into_iter(),
        cut(&mut s.ft, &chunks).into_iter(),
        cut(&mut w.wall_hist, &chunks).into_iter(),
        cut(hist, &entries).into_iter(),
        cut(&mut s.spill_x, &spills).into_iter(),
        cut(&mut s.spill_y, &spills).into_iter(),
        cut(&mut s.spill_t, &spills).into_iter(),
    );
    let (mut even, mut odd) = (Vec::new(), Vec::new());
    for k in 0..chunks.len() - 1 {
        let p = &mut pieces;
        let part = Part {
            c0: chunks[k],
            c1: chunks[k + 1],
            e0: entries[k],
            s0: spills[k],
            x: p.0.next().unwrap_or_default(),
            y: p.1.next().unwrap_or_default(),
            vx: p.2.next().unwrap_or_default(),
            vy: p.3.next().unwrap_or_default(),
            w: p.4.next().unwrap_or_default(),
            ux: p.5.next().unwrap_or_default(),
            uy: p.6.next().unwrap_or_default(),
            uw: p.7.next().unwrap_or_default(),
            fx: p.8.next().unwrap_or_default(),
            fy: p.9.next().unwrap_or_default(),
            ft: p.10.next().unwrap_or_default(),
            wall_hist: p.11.next().unwrap_or_default(),
            hist: p.12.next().unwrap_or_default(),
            spill_x: p.13.next().unwrap_or_default(),
            spill_y: p.14.next().unwrap_or_default(),
            spill_t: p.15.next().unwrap_or_default(),
        };
        if k % 2 == 0 {
            even.push(part);
        } else {
            odd.push(part);
        }
    }
    let f = &fixed;
    let c = &c;
    // Even chunks (chunk 2m reads the state of odd chunk m's first row, untouched yet).
    let run = if c.friction {
        run_chunk::<true>
    } else {
        run_chunk::<false>
    };
    let late = if c.friction {
        finish_deferred::<true>
    } else {
        finish_deferred::<false>
    };
    let sums_even: Vec<StepSums> = even
        .par_iter_mut()
        .enumerate()
        .map(|(m, p)| run(c, f, p, odd.get(m), None, m > 0))
        .collect();
    // Odd chunks (chunk 2m + 1 gathers the spills of even chunk m and reads the state of
    // even chunk m + 1's first row, deferred).
    let sums_odd: Vec<StepSums> = odd
        .par_iter_mut()
        .enumerate()
        .map(|(m, p)| run(c, f, p, even.get(m + 1), Some(&even[m]), false))
        .collect();
    // The even chunks' deferred grains.
    let sums_late: Vec<StepSums> = even
        .par_iter_mut()
        .enumerate()
        .skip(1)
        .map(|(m, p)| late(c, f, p, &odd[m - 1]))
        .collect();
    let mut total = StepSums::default();
    for k in 0..chunks.len() - 1 {
        let m = k / 2;
        if k % 2 == 0 {
            total = total.add(&sums_even[m]);
            if m > 0 {
                total = total.add(&sums_late[m - 1]);
            }
        } else {
            total = total.add(&sums_odd[m]);
        }
    }
    w.drift_m += total.max_step2.sqrt();
    w.rebuild_due = w.drift_m > 0.5 * w.cfg.skin_m;
    w.last = total;
}

/// One chunk's grains in slot order: pairs (scattered forward, or spilled into the next
/// chunk), then, unless `defer` and the grain gathers spills, walls and integration
/// (`prev`: the chunk before, whose spills are ready). `next`: the chunk after, whose first
/// row partners read.
fn run_chunk<const FRICTION: bool>(
    c: &StepConst,
    f: &Fixed,
    p: &mut Part,
    next: Option<&Part>,
    prev: Option<&Part>,
    defer: bool,
) -> StepSums {
    let mut sums = StepSums::default();
    let (c0, c1) = (p.c0, p.c1);
    let mut slot = 0usize;
    // Every array of a part covers its grains (cut at the same bounds); the unchecked
    // partner reads below rely on it.
    let len = c1 - c0;
    let n = f.radius.len();
    assert!(
        [
            p.x.len(),
            p.y.len(),
            p.ux.len(),
            p.uy.len(),
            p.fx.len(),
            p.fy.len()
        ] == [len; 6]
            && f.inv_mass.len() == n
            && next.is_none_or(|q| {
                let l = q.c1 - q.c0;
                [q.x.len(), q.y.len(), q.ux.len(), q.uy.len()] == [l; 4]
            }),
        "a chunk's arrays disagree in length"
    );
    for i in c0..c1 {
        let l = i - c0;
        let (xi, yi, ri, imi) = (p.x[l], p.y[l], f.radius[i], f.inv_mass[i]);
        let (uxi, uyi) = (p.ux[l], p.uy[l]);
        let wri = if FRICTION { p.uw[l] * ri } else { 0.0 };
        let (mut fx, mut fy) = (p.fx[l], p.fy[l]);
        let mut ft = if FRICTION { p.ft[l] } else { 0.0 };
        let (e_lo, e_hi) = (f.start[i] as usize, f.start[i + 1] as usize);
        // An owner's partners come in increasing slot order (the build scans the cells
        // in order), so those in this chunk come first: two loops, no branch per pair on
        // where the partner lies.
        let js = &f.j[e_lo..e_hi];
        let n_here = js.iter().filter(|&&j| (j as usize) < c1).count();
        let own = Own {
            x: xi,
            y: yi,
            r: ri,
            inv_mass: imi,
            ux: uxi,
            uy: uyi,
            spin: wri,
        };
        for (e, &j) in (e_lo..).zip(&js[..n_here]) {
            let j = j as usize;
            let m = j.wrapping_sub(c0);
            let partner = state::<FRICTION>(p, m);
            let Some((pfx, pfy, pft)) = pair_with::<FRICTION>(c, f, &own, partner, j, p, e) else {
                continue;
            };
            fx += pfx;
            fy += pfy;
            ft += pft;
            // SAFETY: m < p.x.len() (read by `state`), the length of both.
            unsafe {
                *p.fx.get_unchecked_mut(m) -= pfx;
                *p.fy.get_unchecked_mut(m) -= pfy;
            }
            if FRICTION {
                p.ft[m] += pft;
            }
        }
        // Partners in the next chunk: the reaction goes to a spill slot.
        if let Some(q) = next {
            for (e, &j) in (e_lo + n_here..).zip(&js[n_here..]) {
                let j = j as usize;
                let partner = state::<FRICTION>(q, j.wrapping_sub(q.c0));
                let force = pair_with::<FRICTION>(c, f, &own, partner, j, p, e);
                let (pfx, pfy, pft) = force.unwrap_or((0.0, 0.0, 0.0));
                if force.is_some() {
                    fx += pfx;
                    fy += pfy;
                    ft += pft;
                }
                p.spill_x[slot] = -pfx;
                p.spill_y[slot] = -pfy;
                if FRICTION {
                    p.spill_t[slot] = pft;
                }
                slot += 1;
            }
        }
        let incoming = f.spill_in_start[i] as usize..f.spill_in_start[i + 1] as usize;
        if defer && !incoming.is_empty() {
            p.fx[l] = fx;
            p.fy[l] = fy;
            if FRICTION {
                p.ft[l] = ft;
            }
            continue;
        }
        let mut force = (fx, fy, ft);
        if let Some(q) = prev {
            force = add_spills::<FRICTION>(f, q, i, force);
        }
        finish::<FRICTION>(c, f, p, i, force, &mut sums);
    }
    sums
}

/// The owner of the pairs being computed: position, m; radius, m; inverse mass, 1/kg;
/// velocity the forces see, m/s; surface speed of its spin `w r`, m/s.
struct Own {
    x: f64,
    y: f64,
    r: f64,
    inv_mass: f64,
    ux: f64,
    uy: f64,
    spin: f64,
}

/// Grain `m` of part `q`: position, m; velocity the forces see, m/s; spin, rad/s (0
/// without friction). Called only on parts whose arrays [`run_chunk`] checked to share one
/// length.
#[inline(always)]
fn state<const FRICTION: bool>(q: &Part, m: usize) -> [f64; 5] {
    let x = q.x[m];
    let w = if FRICTION { q.uw[m] } else { 0.0 };
    // SAFETY: m < q.x.len() (the read above), the length of these three slices too.
    let (y, ux, uy) = unsafe {
        (
            *q.y.get_unchecked(m),
            *q.ux.get_unchecked(m),
            *q.uy.get_unchecked(m),
        )
    };
    [x, y, ux, uy, w]
}

/// The pair of `own` and grain `j` (its `state`), entry `e` of part `p`: see
/// [`StepConst::pair`].
#[inline(always)]
fn pair_with<const FRICTION: bool>(
    c: &StepConst,
    f: &Fixed,
    own: &Own,
    [xj, yj, uxj, uyj, wj]: [f64; 5],
    j: usize,
    p: &mut Part,
    e: usize,
) -> Option<(f64, f64, f64)> {
    let (rj, imj) = (f.radius[j], f.inv_mass[j]);
    let mut none = 0.0;
    let hist = if FRICTION {
        &mut p.hist[e - p.e0]
    } else {
        &mut none
    };
    c.pair::<FRICTION>(
        xj - own.x,
        yj - own.y,
        own.r + rj,
        own.ux - uxj,
        own.uy - uyj,
        own.spin + wj * rj,
        own.inv_mass + imj,
        hist,
    )
}

/// The deferred grains of an even chunk: their partial force plus the spills of `prev`,
/// then walls and integration.
fn finish_deferred<const FRICTION: bool>(
    c: &StepConst,
    f: &Fixed,
    p: &mut Part,
    prev: &Part,
) -> StepSums {
    let mut sums = StepSums::default();
    for i in p.c0..p.c1 {
        let incoming = f.spill_in_start[i] as usize..f.spill_in_start[i + 1] as usize;
        if incoming.is_empty() {
            continue;
        }
        let l = i - p.c0;
        let ft = if FRICTION { p.ft[l] } else { 0.0 };
        let force = add_spills::<FRICTION>(f, prev, i, (p.fx[l], p.fy[l], ft));
        finish::<FRICTION>(c, f, p, i, force, &mut sums);
    }
    sums
}

/// `force` (x, y, tangential sum) plus the spills grain `i` gathers from chunk `prev`, in
/// slot order.
#[inline(always)]
fn add_spills<const FRICTION: bool>(
    f: &Fixed,
    prev: &Part,
    i: usize,
    (mut fx, mut fy, mut ft): (f64, f64, f64),
) -> (f64, f64, f64) {
    let incoming = f.spill_in_start[i] as usize..f.spill_in_start[i + 1] as usize;
    for &s in &f.spill_in[incoming] {
        let s = s as usize - prev.s0;
        fx += prev.spill_x[s];
        fy += prev.spill_y[s];
        if FRICTION {
            ft += prev.spill_t[s];
        }
    }
    (fx, fy, ft)
}

/// Grain `i` (of chunk `p`) with its pair force `(fx, fy)` and tangential sum `ft`: clear
/// its accumulators, add walls, drag and gravity, integrate it in place (an intruder grain
/// is put where its trajectory says), and add to the chunk's sums.
#[inline(always)]
fn finish<const FRICTION: bool>(
    c: &StepConst,
    f: &Fixed,
    p: &mut Part,
    i: usize,
    force: (f64, f64, f64),
    s: &mut StepSums,
) {
    let (mut fx, mut fy, ft_sum) = force;
    let l = i - p.c0;
    p.fx[l] = 0.0;
    p.fy[l] = 0.0;
    let (xi, yi, ri, imi) = (p.x[l], p.y[l], f.radius[i], f.inv_mass[i]);
    let (vxi, vyi) = (p.ux[l], p.uy[l]);
    let mut tq = 0.0;
    let mut wi = 0.0;
    if FRICTION {
        p.ft[l] = 0.0;
        tq = ri * ft_sum;
        wi = p.uw[l];
    }
    let class = f.class[i];
    if class == PRESCRIBED {
        s.intruder_fx_n += fx;
        s.intruder_fy_n += fy;
        (p.vx[l], p.ux[l], p.w[l], p.uw[l]) = (0.0, 0.0, 0.0, 0.0);
        if let Some((bottom, v)) = c.intruder {
            (p.y[l], p.vy[l]) = (bottom + ri, v);
        } else {
            p.vy[l] = 0.0;
        }
        p.uy[l] = p.vy[l];
        let dy = p.y[l] - yi;
        if dy * dy > s.max_step2 {
            s.max_step2 = dy * dy;
        }
    } else {
        // Walls (only for grains that were within a skin of one at the build).
        if class == NEAR_WALL {
            // Walls: (overlap, outward normal from grain to wall, index).
            let walls = [
                c.walls.floor_m.map(|w| (ri - (yi - w), 0.0, -1.0)),
                c.walls.left_m.map(|w| (ri - (xi - w), -1.0, 0.0)),
                c.walls.right_m.map(|w| (ri - (w - xi), 1.0, 0.0)),
                c.walls.lid_m.map(|w| (ri - (w - yi), 0.0, 1.0)),
            ];
            for (kw, wall) in walls.into_iter().enumerate() {
                let Some((delta, wnx, wny)) = wall else {
                    continue;
                };
                if delta <= 0.0 {
                    // Frictionless: no history to clear (and no write stream through
                    // `wall_hist` every step).
                    if FRICTION {
                        p.wall_hist[l][kw] = 0.0;
                    }
                    continue;
                }
                let gamma_w = match c.gamma_const {
                    Some(gm) => gm,
                    None => pair_gamma(c.gamma_rule, imi),
                };
                let vn = vxi * wnx + vyi * wny;
                let fn_ = c.kn * delta + gamma_w * vn;
                fx -= fn_ * wnx;
                fy -= fn_ * wny;
                if kw == 0 {
                    s.floor_n += fn_;
                }
                if FRICTION {
                    let (tx, ty) = (-wny, wnx);
                    let vt = vxi * tx + vyi * ty + wi * ri;
                    let ft = c.tangential(&mut p.wall_hist[l][kw], vt, fn_, gamma_w, c.mu_wall);
                    fx += ft * tx;
                    fy += ft * ty;
                    tq += ri * ft;
                }
            }
        }
        let ax = fx * imi - c.drag * vxi;
        let ay = fy * imi - c.g - c.drag * vyi;
        let (hx, hy) = (p.vx[l], p.vy[l]);
        let (nvx, nvy) = (hx + ax * c.dt, hy + ay * c.dt);
        let (dx, dy) = if c.euler {
            (p.ux[l], p.uy[l]) = (nvx, nvy);
            (hx * c.dt, hy * c.dt)
        } else {
            let h = 0.5 * c.dt;
            (p.ux[l], p.uy[l]) = (nvx + ax * h, nvy + ay * h);
            (nvx * c.dt, nvy * c.dt)
        };
        p.x[l] = xi + dx;
        p.y[l] = yi + dy;
        // A plain comparison, not `f64::max` (whose NaN rule costs a dependent select per
        // grain); a NaN never wins either way.
        let step2 = dx * dx + dy * dy;
        if step2 > s.max_step2 {
            s.max_step2 = step2;
        }
        (p.vx[l], p.vy[l]) = (nvx, nvy);
        // Without friction there is no torque: the spin stays as it is (and its two arrays
        // are neither read nor written).
        if FRICTION {
            let al = tq * f.inv_inertia[i];
            let nw = p.w[l] + al * c.dt;
            p.uw[l] = if c.euler { nw } else { nw + al * (0.5 * c.dt) };
            p.w[l] = nw;
        }
    }
}
