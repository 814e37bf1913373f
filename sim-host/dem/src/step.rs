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
//! Grains farther than a skin from every wall at the list's build skip the walls (they
//! cannot reach one before the next build), and the list is rebuilt when the sum over the
//! steps of the largest displacement in each passes half the skin.
//!
//! **Parallel, the same bits on any thread count.** On several threads the slots are cut
//! into chunks along the cell lines, one a thread (see [`super::neighbours`]); a pair's
//! partner lies in the owner's chunk or the next. Before the step, the grains on both
//! sides of each boundary between chunks (the owners of the pairs that cross it, and
//! their partners) and those pairs' slip histories are copied. Then every chunk runs on
//! its own, in one parallel region per step: it first computes the pairs that cross in
//! from the chunk below, from the copy, and takes their reactions; then it runs the fused
//! pass, computing the pairs that cross out into the chunk above from its own owners
//! (not yet moved) and the copy of their partners. Each such pair is computed twice, from
//! the same numbers, so both sides see the same bits; only the owner's side advances the
//! slip history. Every grain's force is summed in one order whatever the chunks: the
//! reactions of the pairs below it, in increasing slot order, then its own pairs, in entry
//! order. The sums over grains (forces on the intruder and the floor) are added in slot
//! order after the pass. One thread runs one chunk (no boundaries), and gets the same bits
//! as any number of threads (tested on 1, 2 and 3).
//!
//! Integrators:
//! - forward Euler (Supplementary I): `x' = x + v dt`, `v' = v + a(x, v) dt`;
//! - velocity Verlet, in its leapfrog form: the integrated velocity is the half-step one,
//!   `v' = v + a dt`, `x' = x + v' dt`. LAMMPS's `fix nve/sphere` lets the dashpot see that
//!   half-step velocity, which makes a damped contact first order in the step (1.5 % error
//!   in the restitution at t_c/40); here the dashpot sees the full-step velocity predicted
//!   from the last acceleration, `u = v + a dt / 2`, written by the same pass, which makes it
//!   second order (0.1 % at t_c/40) at no extra pass. The default.

use std::time::Instant;

use rayon::prelude::*;

use super::contact::GammaRule;
use super::neighbours::NeighbourList;
use super::world::{Integrator, NEAR_WALL, PRESCRIBED, StepSums, Velocities, Walls, World};

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

/// The pair of entry `e` (owner `i`) of `w`'s list at its current state, as the next step
/// would compute it (the force on `i`, N, and the tangential force; `None` without
/// contact); `w` is left as it is (the slip history is read, not advanced).
pub(super) fn pair_now(w: &World, c: &StepConst, i: usize, e: usize) -> Option<(f64, f64, f64)> {
    let (g, u) = (&w.g, &w.u);
    let j = w.nl.j[e] as usize;
    let mut hist = w.nl.hist.get(e).copied().unwrap_or(0.0);
    let (dx, dy) = (g.x[j] - g.x[i], g.y[j] - g.y[i]);
    let rsum = g.radius[i] + g.radius[j];
    let (rvx, rvy) = (u.x[i] - u.x[j], u.y[i] - u.y[j]);
    let spin = u.w[i] * g.radius[i] + u.w[j] * g.radius[j];
    let ims = g.inv_mass[i] + g.inv_mass[j];
    if c.friction {
        c.pair::<true>(dx, dy, rsum, rvx, rvy, spin, ims, &mut hist)
    } else {
        c.pair::<false>(dx, dy, rsum, rvx, rvy, spin, ims, &mut hist)
    }
}

/// `gamma_n` for a pair whose inverse masses sum to `inv_mass_sum` (1/kg). Kept out of
/// line: inlined, the compiler hoists its division and square root out of the branch that
/// needs them and pays them for every pair even when `gamma_n` is a constant.
#[inline(never)]
fn pair_gamma(rule: GammaRule, inv_mass_sum: f64) -> f64 {
    rule.at(1.0 / inv_mass_sum)
}

/// What every chunk reads and no chunk writes.
struct Fixed<'a> {
    radius: &'a [f64],
    inv_mass: &'a [f64],
    inv_inertia: &'a [f64],
    class: &'a [u8],
    start: &'a [u32],
    j: &'a [u32],
}

/// The copy, taken before the step, of the grains of one chunk boundary's cross pairs:
/// owners in slots `lo..mid` (the end of the chunk below), partners in `mid..hi` (the start
/// of the chunk above).
#[derive(Clone, Copy)]
struct Boundary<'a> {
    lo: usize,
    mid: usize,
    /// Grain `s`'s state is `state[s - lo]`: see [`Scratch`]'s `snap`.
    state: &'a [[f64; 5]],
    /// Entry `e`'s slip history is `hist[e - e_lo]` (empty without friction).
    hist: &'a [f64],
    e_lo: usize,
}

/// One chunk's grains (slots `c0..c1`) and entries (from `e0`): the parts of the arrays its
/// grains own, and the boundaries with the chunks below and above.
struct Part<'a> {
    c0: usize,
    c1: usize,
    e0: usize,
    below: Option<Boundary<'a>>,
    above: Option<Boundary<'a>>,
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
    out_x: &'a mut [f64],
    out_y: &'a mut [f64],
    out_floor: &'a mut [f64],
    wall_hist: &'a mut [[f64; 4]],
    hist: &'a mut [f64],
    /// The chunk's intruder grains and grains near a wall (slots), and where their forces
    /// go when the chunk is done (see [`Scratch`]).
    prescribed: &'a [u32],
    near_wall: &'a [u32],
    packed_intruder: &'a mut [[f64; 2]],
    packed_floor: &'a mut [f64],
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
        cross_lo,
        cross_hi,
        hist,
        ..
    } = &mut w.nl;
    let chunks: Vec<usize> = chunk_start.iter().map(|&s| s as usize).collect();
    let entries: Vec<usize> = chunks.iter().map(|&s| start[s] as usize).collect();
    let nchunks = chunks.len() - 1;
    let g = &mut w.g;
    let s = &mut w.scratch;
    let u = &mut w.u;
    // The grains and histories of the cross pairs, before the step: the chunks on both
    // sides of a boundary compute its pairs from this copy while they change the grains.
    s.snap.clear();
    s.snap_hist.clear();
    let mut bases = Vec::with_capacity(nchunks);
    for k in 0..nchunks - 1 {
        let (lo, hi) = (cross_lo[k] as usize, cross_hi[k] as usize);
        bases.push((s.snap.len(), s.snap_hist.len()));
        s.snap.extend((lo..hi).map(|i| {
            let spin = if c.friction { u.w[i] } else { 0.0 };
            [g.x[i], g.y[i], u.x[i], u.y[i], spin]
        }));
        if c.friction {
            s.snap_hist
                .extend_from_slice(&hist[start[lo] as usize..start[chunks[k + 1]] as usize]);
        }
    }
    let boundary = |k: usize| {
        let (lo, mid, hi) = (cross_lo[k] as usize, chunks[k + 1], cross_hi[k] as usize);
        let (e_lo, e_hi) = (start[lo] as usize, start[mid] as usize);
        let (b, bh) = bases[k];
        Boundary {
            lo,
            mid,
            state: &s.snap[b..b + (hi - lo)],
            hist: if c.friction {
                &s.snap_hist[bh..bh + (e_hi - e_lo)]
            } else {
                &[]
            },
            e_lo,
        }
    };
    let boundaries: Vec<Boundary> = (0..nchunks - 1).map(boundary).collect();
    let fixed = Fixed {
        radius: &g.radius,
        inv_mass: &g.inv_mass,
        inv_inertia: &g.inv_inertia,
        class: &w.class,
        start,
        j,
    };
    let mut pieces = (
        cut(&mut g.x, &chunks).into_iter(),
        cut(&mut g.y, &chunks).into_iter(),
        cut(&mut g.vx, &chunks).into_iter(),
        cut(&mut g.vy, &chunks).into_iter(),
        cut(&mut g.w, &chunks).into_iter(),
        cut(&mut u.x, &chunks).into_iter(),
        cut(&mut u.y, &chunks).into_iter(),
        cut(&mut u.w, &chunks).into_iter(),
        cut(&mut s.fx, &chunks).into_iter(),
        cut(&mut s.fy, &chunks).into_iter(),
        cut(&mut s.ft, &chunks).into_iter(),
        cut(&mut s.out_x, &chunks).into_iter(),
        cut(&mut s.out_y, &chunks).into_iter(),
        cut(&mut s.out_floor, &chunks).into_iter(),
        cut(&mut w.wall_hist, &chunks).into_iter(),
        cut(hist, &entries).into_iter(),
    );
    // Where each chunk's intruder grains and grains near a wall start in their lists (the
    // scratch is sized for the list's chunks at every build).
    let (at_intruder, at_wall) = (&s.prescribed_at, &s.near_wall_at);
    debug_assert!(at_intruder.len() == chunks.len() && at_wall.len() == chunks.len());
    let mut packed = (
        cut(&mut s.packed_intruder, at_intruder).into_iter(),
        cut(&mut s.packed_floor, at_wall).into_iter(),
    );
    let mut parts = Vec::with_capacity(nchunks);
    for k in 0..nchunks {
        let p = &mut pieces;
        parts.push(Part {
            c0: chunks[k],
            c1: chunks[k + 1],
            e0: entries[k],
            below: k.checked_sub(1).map(|b| boundaries[b]),
            above: boundaries.get(k).copied(),
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
            out_x: p.11.next().unwrap_or_default(),
            out_y: p.12.next().unwrap_or_default(),
            out_floor: p.13.next().unwrap_or_default(),
            wall_hist: p.14.next().unwrap_or_default(),
            hist: p.15.next().unwrap_or_default(),
            prescribed: &s.prescribed[at_intruder[k]..at_intruder[k + 1]],
            near_wall: &s.near_wall[at_wall[k]..at_wall[k + 1]],
            packed_intruder: packed.0.next().unwrap_or_default(),
            packed_floor: packed.1.next().unwrap_or_default(),
        });
    }
    let run = if c.friction {
        run_chunk::<true>
    } else {
        run_chunk::<false>
    };
    let max_step2 = if nchunks == 1 {
        run(&c, &fixed, &mut parts[0])
    } else {
        // Each chunk's time, for the next build to balance the chunks by.
        let timed = parts
            .par_iter_mut()
            .map(|p| {
                let t0 = Instant::now();
                let max_step2 = run(&c, &fixed, p);
                (max_step2, t0.elapsed().as_secs_f64())
            })
            .collect::<Vec<_>>();
        for (total, (_, t)) in w.chunk_seconds.iter_mut().zip(&timed) {
            *total += t;
        }
        timed.iter().map(|&(m, _)| m).fold(0.0, f64::max)
    };
    // The sums, in slot order whatever the chunks.
    let mut total = StepSums {
        max_step2,
        ..StepSums::default()
    };
    for &[fx, fy] in &s.packed_intruder {
        total.intruder_fx_n += fx;
        total.intruder_fy_n += fy;
    }
    for &f in &s.packed_floor {
        total.floor_n += f;
    }
    w.drift_m += total.max_step2.sqrt();
    w.rebuild_due = w.drift_m > 0.5 * w.cfg.skin_m;
    w.last = total;
}

/// The grains of one chunk, in slot order, each one's pairs (those within the chunk
/// computed here, their reactions scattered forward; those across into the next chunk
/// from the boundary's copy), then walls and integration. The grains at its start take
/// the reactions of the chunk below's cross pairs first, computed here from the boundary's
/// copy (the chunk below computes the same pairs from the same copy, so both see the same
/// bits; only the owner's side writes the slip history). Returns the largest squared
/// displacement in the step, m^2.
///
/// Every grain's force is summed in one order, whatever the chunks: the reactions of the
/// pairs below it in increasing slot order (those of the chunk below first, as they have
/// lower slots), then its own pairs in entry order.
fn run_chunk<const FRICTION: bool>(c: &StepConst, f: &Fixed, p: &mut Part) -> f64 {
    let mut max_step2 = 0.0;
    let (c0, c1) = (p.c0, p.c1);
    // Every array of a part covers its grains (cut at the same bounds); the unchecked
    // partner reads below rely on it.
    let len = p.x.len();
    assert!(
        [p.y.len(), p.ux.len(), p.uy.len(), p.fx.len(), p.fy.len()] == [len; 5],
        "a chunk's arrays disagree in length"
    );
    // The reactions of the chunk below's cross pairs, before anything else (the first
    // chunk, and so a single one, has none).
    if let Some(b) = p.below {
        for i in b.lo..b.mid {
            let (e_lo, e_hi) = (f.start[i] as usize, f.start[i + 1] as usize);
            let js = &f.j[e_lo..e_hi];
            let n_here = partners_below(js, b.mid);
            if n_here == js.len() {
                continue;
            }
            let own = Own::of::<FRICTION>(f, i, b.state[i - b.lo]);
            for (e, &j) in (e_lo + n_here..).zip(&js[n_here..]) {
                let j = j as usize;
                // The owner's side advances the history; this side works on a copy.
                let mut slip = [if FRICTION { b.hist[e - b.e_lo] } else { 0.0 }];
                let partner = b.state[j - b.lo];
                let force = pair_with::<FRICTION>(c, f, &own, partner, j, &mut slip, 0);
                if let Some((pfx, pfy, pft)) = force {
                    let m = j - c0;
                    p.fx[m] -= pfx;
                    p.fy[m] -= pfy;
                    if FRICTION {
                        p.ft[m] += pft;
                    }
                }
            }
        }
    }
    for i in c0..c1 {
        let l = i - c0;
        let own = Own::of::<FRICTION>(f, i, state::<FRICTION>(p, l));
        let (mut fx, mut fy) = (p.fx[l], p.fy[l]);
        let mut ft = if FRICTION { p.ft[l] } else { 0.0 };
        let (e_lo, e_hi) = (f.start[i] as usize, f.start[i + 1] as usize);
        // Partners in this chunk first, then those in the next: two loops, no branch per
        // pair on where the partner lies.
        let js = &f.j[e_lo..e_hi];
        let n_here = partners_below(js, c1);
        for (e, &j) in (e_lo..).zip(&js[..n_here]) {
            let j = j as usize;
            let m = j.wrapping_sub(c0);
            let partner = state::<FRICTION>(p, m);
            let k = e - p.e0;
            let Some((pfx, pfy, pft)) = pair_with::<FRICTION>(c, f, &own, partner, j, p.hist, k)
            else {
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
        // Partners in the next chunk, from the boundary's copy (the owner is not moved yet,
        // so its state is the copy's too).
        if n_here < js.len()
            && let Some(b) = p.above
        {
            for (e, &j) in (e_lo + n_here..).zip(&js[n_here..]) {
                let j = j as usize;
                let partner = b.state[j - b.lo];
                let k = e - p.e0;
                if let Some((pfx, pfy, pft)) =
                    pair_with::<FRICTION>(c, f, &own, partner, j, p.hist, k)
                {
                    fx += pfx;
                    fy += pfy;
                    ft += pft;
                }
            }
        }
        let step2 = finish::<FRICTION>(c, f, p, i, (fx, fy, ft));
        if step2 > max_step2 {
            max_step2 = step2;
        }
    }
    for (out, &i) in p.packed_intruder.iter_mut().zip(p.prescribed) {
        let l = i as usize - c0;
        *out = [p.out_x[l], p.out_y[l]];
    }
    for (out, &i) in p.packed_floor.iter_mut().zip(p.near_wall) {
        *out = p.out_floor[i as usize - c0];
    }
    max_step2
}

/// How many of an owner's partners `js` lie below slot `c1` (in its chunk): they come
/// first, as the build lists partners in increasing slot order (it scans the cells in
/// order).
#[inline(always)]
fn partners_below(js: &[u32], c1: usize) -> usize {
    js.iter().filter(|&&j| (j as usize) < c1).count()
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

impl Own {
    /// Grain `i` at `[x, y, ux, uy, w]` (a boundary's copy, or [`state`]).
    #[inline(always)]
    fn of<const FRICTION: bool>(f: &Fixed, i: usize, [x, y, ux, uy, w]: [f64; 5]) -> Self {
        let r = f.radius[i];
        Self {
            x,
            y,
            r,
            inv_mass: f.inv_mass[i],
            ux,
            uy,
            spin: if FRICTION { w * r } else { 0.0 },
        }
    }
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

/// The pair of `own` and grain `j` (its `state`), whose slip history is `hist[k]` (`hist`
/// is empty, and not read, without friction): see [`StepConst::pair`].
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn pair_with<const FRICTION: bool>(
    c: &StepConst,
    f: &Fixed,
    own: &Own,
    [xj, yj, uxj, uyj, wj]: [f64; 5],
    j: usize,
    hist: &mut [f64],
    k: usize,
) -> Option<(f64, f64, f64)> {
    let (rj, imj) = (f.radius[j], f.inv_mass[j]);
    let mut none = 0.0;
    let hist = if FRICTION { &mut hist[k] } else { &mut none };
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

/// Grain `i` (of chunk `p`) with its pair force `(fx, fy)` and tangential sum `ft`: clear
/// its accumulators, add walls, drag and gravity, integrate it in place (an intruder grain
/// is put where its trajectory says), and note its force on the floor (or, for an intruder
/// grain, the grains' force on it) for the step's sums. Returns its squared displacement,
/// m^2.
#[inline(always)]
fn finish<const FRICTION: bool>(
    c: &StepConst,
    f: &Fixed,
    p: &mut Part,
    i: usize,
    force: (f64, f64, f64),
) -> f64 {
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
        (p.out_x[l], p.out_y[l]) = (fx, fy);
        (p.vx[l], p.ux[l], p.w[l], p.uw[l]) = (0.0, 0.0, 0.0, 0.0);
        if let Some((bottom, v)) = c.intruder {
            (p.y[l], p.vy[l]) = (bottom + ri, v);
        } else {
            p.vy[l] = 0.0;
        }
        p.uy[l] = p.vy[l];
        let dy = p.y[l] - yi;
        dy * dy
    } else {
        // Walls (only for grains that were within a skin of one at the build).
        if class == NEAR_WALL {
            p.out_floor[l] = 0.0;
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
                    p.out_floor[l] = fn_;
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
        let step2 = dx * dx + dy * dy;
        (p.vx[l], p.vy[l]) = (nvx, nvy);
        // Without friction there is no torque: the spin stays as it is (and its two arrays
        // are neither read nor written).
        if FRICTION {
            let al = tq * f.inv_inertia[i];
            let nw = p.w[l] + al * c.dt;
            p.uw[l] = if c.euler { nw } else { nw + al * (0.5 * c.dt) };
            p.w[l] = nw;
        }
        step2
    }
}

impl World {
    /// Advance one step.
    pub fn step(&mut self) {
        if self.rebuild_due
            || self.nl.start.len() != self.g.len() + 1
            || self.cfg.walls != self.walls_at_build
        {
            self.rebuild();
        }
        let n = self.g.len();
        if self.u.x.len() != n {
            self.u = Velocities {
                x: self.g.vx.clone(),
                y: self.g.vy.clone(),
                w: self.g.w.clone(),
            };
        }
        advance(self);
        self.steps += 1;
        self.t_s = self.steps as f64 * self.cfg.dt_s;
    }

    /// The vertical force carried across each height in `heights_m` by the contacts whose
    /// centres lie on both sides of it (the lower grain pushing the upper one up), N, from
    /// the pair forces at the current state (the step's own kernel, tangential part
    /// included, the slip history as it stands). In a bed at rest this is the weight of the
    /// grains above the height.
    pub fn vertical_load_across(&self, heights_m: &[f64]) -> Vec<f64> {
        let g = &self.g;
        let nl = &self.nl;
        let c = StepConst::of(self);
        let mut out = vec![0.0; heights_m.len()];
        for i in 0..g.len().min(nl.start.len().saturating_sub(1)) {
            for e in nl.start[i] as usize..nl.start[i + 1] as usize {
                let j = nl.j[e] as usize;
                let Some((_, fy, _)) = pair_now(self, &c, i, e) else {
                    continue;
                };
                // fy is the force on i from j: on the upper grain, from the lower one.
                let (lower_y, upper_y, up_force) = if g.y[i] < g.y[j] {
                    (g.y[i], g.y[j], -fy)
                } else {
                    (g.y[j], g.y[i], fy)
                };
                for (k, &h) in heights_m.iter().enumerate() {
                    if lower_y < h && upper_y >= h {
                        out[k] += up_force;
                    }
                }
            }
        }
        out
    }
}
