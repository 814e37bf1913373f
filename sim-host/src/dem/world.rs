//! One DEM world and its time step: contact forces, walls, gravity, per-grain drag and the
//! integrator in **two passes** over memory.
//!
//! Pass 1 walks the half neighbour list (see [`super::neighbours`]) and computes each
//! pair's force once, into the pair's entry. Pass 2 has each grain gather its pairs' forces
//! (its own entries, and the entries it is the partner of, reversed), add walls, drag and
//! gravity, and integrate itself in place. LAMMPS runs the pair force, each fix (gravity,
//! walls, the move of the intruder, `enforce2d`) and the integrator's two halves as
//! separate passes; here the fixes and the integrator are one loop body, kept readable by
//! small inline functions. Both passes run on rayon in fixed chunks of grains, and per-chunk
//! sums (forces on the intruder and the floor) are added in chunk order: the same bits for
//! any number of threads.
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
use serde::{Deserialize, Serialize};

use super::contact::{ContactLaw, GammaRule};
use super::grains::{FREE, Grains, INTRUDER, permute};
use super::neighbours::NeighbourList;

/// Which integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Integrator {
    /// Forward Euler (the paper's).
    ForwardEuler,
    /// Velocity Verlet (leapfrog form).
    VelocityVerlet,
}

/// Flat walls, each optional: positions, m.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Walls {
    /// Floor height.
    pub floor_m: Option<f64>,
    /// Left wall x.
    pub left_m: Option<f64>,
    /// Right wall x.
    pub right_m: Option<f64>,
    /// Lid height (bed packing only).
    pub lid_m: Option<f64>,
}

/// What a world is run with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorldConfig {
    /// Contact law (grain-grain and grain-wall).
    pub law: ContactLaw,
    /// Gravity, m/s^2 (0: the paper's model).
    pub gravity_m_s2: f64,
    /// Per-grain drag rate `zeta`: each free grain feels `-m zeta v`, 1/s.
    pub drag_per_s: f64,
    /// Integrator.
    pub integrator: Integrator,
    /// Time step, s.
    pub dt_s: f64,
    /// Walls.
    pub walls: Walls,
    /// Neighbour-list skin, m.
    pub skin_m: f64,
}

/// Sums over one step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StepSums {
    /// Force of the grains on the intruder, N (x).
    pub intruder_fx_n: f64,
    /// Force of the grains on the intruder, N (up positive).
    pub intruder_fy_n: f64,
    /// Force of the grains on the floor, N (down positive).
    pub floor_n: f64,
    /// Largest squared displacement since the list's build, m^2.
    max_disp2: f64,
}

impl StepSums {
    fn add(mut self, o: &Self) -> Self {
        self.intruder_fx_n += o.intruder_fx_n;
        self.intruder_fy_n += o.intruder_fy_n;
        self.floor_n += o.floor_n;
        self.max_disp2 = self.max_disp2.max(o.max_disp2);
        self
    }
}

/// Grains per parallel chunk (fixed, so results do not depend on the thread count).
const CHUNK: usize = 256;

/// A DEM world.
#[derive(Clone, Debug)]
pub struct World {
    /// What it runs with.
    pub cfg: WorldConfig,
    /// The grains.
    pub g: Grains,
    /// Neighbour list.
    pub nl: NeighbourList,
    /// Tangential history with the four walls (floor, left, right, lid), m.
    pub wall_hist: Vec<[f64; 4]>,
    /// Time, s.
    pub t_s: f64,
    /// Steps taken.
    pub steps: u64,
    /// Where the intruder's bottom is at the end of the next step and its velocity, m and
    /// m/s (up positive); `None`: intruder grains stay where they are.
    pub intruder_next: Option<(f64, f64)>,
    /// Sums of the last step.
    pub last: StepSums,
    /// Velocities the contact forces see (forward Euler: `v`; Verlet: the full-step
    /// prediction), m/s and rad/s; what outputs report.
    pub u: Velocities,
    rebuild_due: bool,
}

/// Velocities, one array per component.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Velocities {
    /// m/s.
    pub x: Vec<f64>,
    /// m/s.
    pub y: Vec<f64>,
    /// rad/s.
    pub w: Vec<f64>,
}

/// Constants of one step, read by every grain.
struct StepConst {
    kn: f64,
    law: ContactLaw,
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
}

impl World {
    /// A world of `g` with `cfg`, its neighbour list built.
    pub fn new(cfg: WorldConfig, g: Grains) -> Self {
        let n = g.len();
        let mut w = Self {
            cfg,
            g,
            nl: NeighbourList::default(),
            wall_hist: vec![[0.0; 4]; n],
            t_s: 0.0,
            steps: 0,
            intruder_next: None,
            last: StepSums::default(),
            u: Velocities::default(),
            rebuild_due: true,
        };
        w.u = Velocities {
            x: w.g.vx.clone(),
            y: w.g.vy.clone(),
            w: w.g.w.clone(),
        };
        w.rebuild();
        w
    }

    /// Rebuild the neighbour list now (reorders the grains).
    pub fn rebuild(&mut self) {
        let perm = self.nl.rebuild(
            &mut self.g,
            self.cfg.skin_m,
            self.cfg.law.friction.is_some(),
        );
        permute(&mut self.wall_hist, &perm);
        if self.u.x.len() == perm.len() {
            permute(&mut self.u.x, &perm);
            permute(&mut self.u.y, &perm);
            permute(&mut self.u.w, &perm);
        }
        self.rebuild_due = false;
    }

    /// Advance one step.
    pub fn step(&mut self) {
        if self.rebuild_due || self.nl.start.len() != self.g.len() + 1 {
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
        let f = self.cfg.law.friction;
        let c = StepConst {
            kn: self.cfg.law.kn_n_per_m,
            law: self.cfg.law,
            friction: f.is_some(),
            mu: f.map_or(0.0, |f| f.mu),
            mu_wall: f.map_or(0.0, |f| f.mu_wall),
            kt: f.map_or(0.0, |f| f.kt_over_kn * self.cfg.law.kn_n_per_m),
            gt_ratio: f.map_or(0.0, |f| f.gammat_over_gamman),
            dt: self.cfg.dt_s,
            g: self.cfg.gravity_m_s2,
            drag: self.cfg.drag_per_s,
            euler: self.cfg.integrator == Integrator::ForwardEuler,
            walls: self.cfg.walls,
            intruder: self.intruder_next,
        };
        // Pass 1: each pair's force once, into the entries (chunks own contiguous entries).
        let nchunks = n.div_ceil(CHUNK);
        let bounds: Vec<(usize, usize)> = (0..nchunks)
            .map(|k| {
                let (a, b) = (k * CHUNK, ((k + 1) * CHUNK).min(n));
                (self.nl.start[a] as usize, self.nl.start[b] as usize)
            })
            .collect();
        let nl = &mut self.nl;
        let hist_parts = split_by(&mut nl.hist, &bounds);
        let fx_parts = split_by(&mut nl.pair_fx, &bounds);
        let fy_parts = split_by(&mut nl.pair_fy, &bounds);
        let ft_parts = split_by(&mut nl.pair_ft, &bounds);
        let g = &self.g;
        let u = &self.u;
        let (nl_start, nl_j) = (&nl.start, &nl.j);
        let gamma_const = c.law.constant_gamma_n();
        let gamma_rule = c.law.gamma_rule();
        hist_parts
            .into_par_iter()
            .zip(fx_parts)
            .zip(fy_parts)
            .zip(ft_parts)
            .enumerate()
            .for_each(|(k, (((hist, pfx), pfy), pft))| {
                let base = k * CHUNK;
                let e0 = nl_start[base] as usize;
                for i in base..((k + 1) * CHUNK).min(n) {
                    let (xi, yi, ri, imi) = (g.x[i], g.y[i], g.radius[i], g.inv_mass[i]);
                    let (vxi, vyi, wi) = (u.x[i], u.y[i], u.w[i]);
                    let (e_lo, e_hi) = (nl_start[i] as usize, nl_start[i + 1] as usize);
                    for (e, &j) in (e_lo..e_hi).zip(&nl_j[e_lo..e_hi]) {
                        let l = e - e0;
                        let j = j as usize;
                        let dx = g.x[j] - xi;
                        let dy = g.y[j] - yi;
                        let rsum = ri + g.radius[j];
                        let d2 = dx * dx + dy * dy;
                        if d2 >= rsum * rsum || d2 == 0.0 {
                            pfx[l] = 0.0;
                            pfy[l] = 0.0;
                            if c.friction {
                                hist[l] = 0.0;
                                pft[l] = 0.0;
                            }
                            continue;
                        }
                        let d = d2.sqrt();
                        let inv_d = 1.0 / d;
                        let (nxu, nyu) = (dx * inv_d, dy * inv_d);
                        let delta = rsum - d;
                        let (rvx, rvy) = (vxi - u.x[j], vyi - u.y[j]);
                        let vn = rvx * nxu + rvy * nyu;
                        let gamma = match gamma_const {
                            Some(gm) => gm,
                            None => pair_gamma(gamma_rule, imi + g.inv_mass[j]),
                        };
                        let fn_ = c.kn * delta + gamma * vn;
                        let (mut fx, mut fy) = (-fn_ * nxu, -fn_ * nyu);
                        if c.friction {
                            let (tx, ty) = (-nyu, nxu);
                            let vt = rvx * tx + rvy * ty + (wi * ri + u.w[j] * g.radius[j]);
                            let ft = c.tangential(&mut hist[l], vt, fn_, gamma, c.mu);
                            fx += ft * tx;
                            fy += ft * ty;
                            pft[l] = ft;
                        }
                        pfx[l] = fx;
                        pfy[l] = fy;
                    }
                }
            });
        // Pass 2: each grain gathers its pairs' forces (own entries plus, reversed, the
        // entries it is the partner of), adds walls, drag and gravity, and integrates in
        // place (no grain reads another's state here).
        let nl = &self.nl;
        let (pfx, pfy, pft) = (&nl.pair_fx, &nl.pair_fy, &nl.pair_ft);
        let Grains {
            x: gx,
            y: gy,
            vx: gvx,
            vy: gvy,
            w: gw,
            radius,
            inv_mass,
            inv_inertia,
            kind,
            ..
        } = &mut self.g;
        let (radius, inv_mass, inv_inertia, kind) = (&*radius, &*inv_mass, &*inv_inertia, &*kind);
        let Velocities {
            x: ux,
            y: uy,
            w: uw,
        } = &mut self.u;
        let sums: Vec<StepSums> = gx
            .par_chunks_mut(CHUNK)
            .zip(gy.par_chunks_mut(CHUNK))
            .zip(gvx.par_chunks_mut(CHUNK))
            .zip(gvy.par_chunks_mut(CHUNK))
            .zip(gw.par_chunks_mut(CHUNK))
            .zip(ux.par_chunks_mut(CHUNK))
            .zip(uy.par_chunks_mut(CHUNK))
            .zip(uw.par_chunks_mut(CHUNK))
            .zip(self.wall_hist.par_chunks_mut(CHUNK))
            .enumerate()
            .map(
                |(k, ((((((((cx, cy), cvx), cvy), cw), cux), cuy), cuw), wh))| {
                    let base = k * CHUNK;
                    let mut s = StepSums::default();
                    for l in 0..cx.len() {
                        let i = base + l;
                        let (xi, yi, ri, imi) = (cx[l], cy[l], radius[i], inv_mass[i]);
                        let (vxi, vyi) = (cux[l], cuy[l]);
                        let wi = if c.friction { cuw[l] } else { 0.0 };
                        let own = nl.start[i] as usize..nl.start[i + 1] as usize;
                        let rev =
                            &nl.rev_entry[nl.rev_start[i] as usize..nl.rev_start[i + 1] as usize];
                        let (mut fx, mut fy) = (0.0, 0.0);
                        for e in own.clone() {
                            fx += pfx[e];
                            fy += pfy[e];
                        }
                        for &e in rev {
                            fx -= pfx[e as usize];
                            fy -= pfy[e as usize];
                        }
                        let mut tq = 0.0;
                        if c.friction {
                            let ft_sum: f64 = own.map(|e| pft[e]).sum::<f64>()
                                + rev.iter().map(|&e| pft[e as usize]).sum::<f64>();
                            tq = ri * ft_sum;
                        }
                        if kind[i] == INTRUDER {
                            s.intruder_fx_n += fx;
                            s.intruder_fy_n += fy;
                            (cvx[l], cux[l], cw[l], cuw[l]) = (0.0, 0.0, 0.0, 0.0);
                            if let Some((bottom, v)) = c.intruder {
                                (cy[l], cvy[l]) = (bottom + ri, v);
                            } else {
                                cvy[l] = 0.0;
                            }
                            cuy[l] = cvy[l];
                        } else {
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
                                    // Frictionless: no history to clear (and no write
                                    // stream through `wall_hist` every step).
                                    if c.friction {
                                        wh[l][kw] = 0.0;
                                    }
                                    continue;
                                }
                                let gamma_w = match gamma_const {
                                    Some(gm) => gm,
                                    None => pair_gamma(gamma_rule, imi),
                                };
                                let vn = vxi * wnx + vyi * wny;
                                let fn_ = c.kn * delta + gamma_w * vn;
                                fx -= fn_ * wnx;
                                fy -= fn_ * wny;
                                if kw == 0 {
                                    s.floor_n += fn_;
                                }
                                if c.friction {
                                    let (tx, ty) = (-wny, wnx);
                                    let vt = vxi * tx + vyi * ty + wi * ri;
                                    let ft =
                                        c.tangential(&mut wh[l][kw], vt, fn_, gamma_w, c.mu_wall);
                                    fx += ft * tx;
                                    fy += ft * ty;
                                    tq += ri * ft;
                                }
                            }
                            let ax = fx * imi - c.drag * vxi;
                            let ay = fy * imi - c.g - c.drag * vyi;
                            let (hx, hy) = (cvx[l], cvy[l]);
                            let (nvx, nvy) = (hx + ax * c.dt, hy + ay * c.dt);
                            if c.euler {
                                cx[l] = xi + hx * c.dt;
                                cy[l] = yi + hy * c.dt;
                                (cux[l], cuy[l]) = (nvx, nvy);
                            } else {
                                cx[l] = xi + nvx * c.dt;
                                cy[l] = yi + nvy * c.dt;
                                let h = 0.5 * c.dt;
                                (cux[l], cuy[l]) = (nvx + ax * h, nvy + ay * h);
                            }
                            (cvx[l], cvy[l]) = (nvx, nvy);
                            // Without friction there is no torque: the spin stays as it is
                            // (and its two arrays are neither read nor written).
                            if c.friction {
                                let al = tq * inv_inertia[i];
                                let nw = cw[l] + al * c.dt;
                                cuw[l] = if c.euler { nw } else { nw + al * (0.5 * c.dt) };
                                cw[l] = nw;
                            }
                        }
                        let ddx = cx[l] - nl.x_ref[i];
                        let ddy = cy[l] - nl.y_ref[i];
                        // A plain comparison, not `f64::max` (whose NaN rule costs a
                        // dependent select per grain); a NaN never wins either way.
                        let disp2 = ddx * ddx + ddy * ddy;
                        if disp2 > s.max_disp2 {
                            s.max_disp2 = disp2;
                        }
                    }
                    s
                },
            )
            .collect();
        let total = sums.iter().fold(StepSums::default(), |acc, s| acc.add(s));
        self.rebuild_due = total.max_disp2 > 0.25 * self.cfg.skin_m * self.cfg.skin_m;
        self.last = total;
        self.steps += 1;
        self.t_s = self.steps as f64 * self.cfg.dt_s;
    }

    /// Free grains: kinetic energy per grain (translation and rotation, at the velocities
    /// the forces see) over `m g d` of the mean grain (settling measure); `g` at least
    /// 9.81 m/s^2 for a gravity-free world.
    pub fn agitation(&self) -> f64 {
        let (n, m) = self.g.free_mass();
        if n == 0 {
            return 0.0;
        }
        let g = &self.g;
        let kinetic_j: f64 = (0..g.len())
            .filter(|&i| g.kind[i] == FREE)
            .map(|i| {
                let (vx, vy, w) = (self.u.x[i], self.u.y[i], self.u.w[i]);
                0.5 * (vx * vx + vy * vy) / g.inv_mass[i] + 0.5 * w * w / g.inv_inertia[i]
            })
            .sum();
        let d = 2.0 * mean(&g.radius);
        kinetic_j / (m * self.cfg.gravity_m_s2.max(9.81) * d)
    }

    /// Bytes the engine holds per grain: the grains, the neighbour list with its pair
    /// forces, the predicted velocities and the wall histories.
    pub fn bytes_per_grain(&self) -> f64 {
        Grains::BYTES_PER_GRAIN as f64 + self.nl.bytes_per_grain() + 8.0 * (3.0 + 4.0)
    }

    /// Largest overlap now, over the pair's mean radius (or the grain's radius at a wall).
    pub fn max_overlap_ratio(&self) -> f64 {
        let g = &self.g;
        let w = &self.cfg.walls;
        let mut worst = 0.0f64;
        for i in 0..g.len().min(self.nl.start.len().saturating_sub(1)) {
            let (xi, yi, ri) = (g.x[i], g.y[i], g.radius[i]);
            for e in self.nl.start[i] as usize..self.nl.start[i + 1] as usize {
                let j = self.nl.j[e] as usize;
                let rsum = ri + g.radius[j];
                let delta = rsum - (g.x[j] - xi).hypot(g.y[j] - yi);
                worst = worst.max(delta / (0.5 * rsum));
            }
            if g.kind[i] == FREE {
                for delta in [
                    w.floor_m.map(|f| ri - (yi - f)),
                    w.left_m.map(|l| ri - (xi - l)),
                    w.right_m.map(|r| ri - (r - xi)),
                    w.lid_m.map(|t| ri - (t - yi)),
                ]
                .into_iter()
                .flatten()
                {
                    worst = worst.max(delta / ri);
                }
            }
        }
        worst
    }

    /// The vertical force carried across each height in `heights_m` by the contacts whose
    /// centres lie on both sides of it (the lower grain pushing the upper one up), N, from
    /// the pair forces of the last step (the step's own kernel, tangential part included).
    /// In a bed at rest this is the weight of the grains above the height.
    pub fn vertical_load_across(&self, heights_m: &[f64]) -> Vec<f64> {
        let g = &self.g;
        let nl = &self.nl;
        let mut out = vec![0.0; heights_m.len()];
        for i in 0..g.len().min(nl.start.len().saturating_sub(1)) {
            for e in nl.start[i] as usize..nl.start[i + 1] as usize {
                let j = nl.j[e] as usize;
                // pair_fy is the force on i from j: on the upper grain, from the lower one.
                let (lower_y, upper_y, up_force) = if g.y[i] < g.y[j] {
                    (g.y[i], g.y[j], -nl.pair_fy[e])
                } else {
                    (g.y[j], g.y[i], nl.pair_fy[e])
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

/// `gamma_n` for a pair whose inverse masses sum to `inv_mass_sum` (1/kg). Kept out of
/// line: inlined, the compiler hoists its division and square root out of the branch that
/// needs them and pays them for every pair even when `gamma_n` is a constant.
#[inline(never)]
fn pair_gamma(rule: GammaRule, inv_mass_sum: f64) -> f64 {
    rule.at(1.0 / inv_mass_sum)
}

/// `v` cut into the consecutive ranges `bounds` (empty slices when `v` is empty, as the
/// history of a frictionless run).
fn split_by<'a>(mut v: &'a mut [f64], bounds: &[(usize, usize)]) -> Vec<&'a mut [f64]> {
    let mut out = Vec::with_capacity(bounds.len());
    for &(a, b) in bounds {
        let len = if v.is_empty() { 0 } else { b - a };
        let (head, tail) = v.split_at_mut(len);
        out.push(head);
        v = tail;
    }
    out
}

/// Mean of a slice (0 when empty).
pub fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}
