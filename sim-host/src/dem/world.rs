//! One DEM world and its time step: contact forces, walls, gravity, per-grain drag and the
//! integrator in **one fused pass** over the grains.
//!
//! Each grain gathers the forces of its own neighbour list (see [`super::neighbours`]),
//! integrates itself and writes its next state into a second buffer; the buffers are then
//! swapped. LAMMPS runs the pair force, each fix (gravity, walls, the move of the intruder,
//! `enforce2d`) and the integrator as separate passes over memory; here they are one loop
//! body, kept readable by small inline functions. The pass runs on rayon in fixed chunks of
//! grains, and per-chunk sums (forces on the intruder and the floor, kinetic energy) are
//! added in chunk order: the same bits for any number of threads.
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

use super::contact::ContactLaw;
use super::grains::{Grains, INTRUDER, permute};
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
    /// Kinetic energy of the free grains (translation and rotation), J.
    pub kinetic_j: f64,
    /// Largest overlap over the two radii's mean, of any contact.
    pub max_overlap_ratio: f64,
    /// Largest squared displacement since the list's build, m^2.
    max_disp2: f64,
}

impl StepSums {
    fn add(mut self, o: &Self) -> Self {
        self.intruder_fx_n += o.intruder_fx_n;
        self.intruder_fy_n += o.intruder_fy_n;
        self.floor_n += o.floor_n;
        self.kinetic_j += o.kinetic_j;
        self.max_overlap_ratio = self.max_overlap_ratio.max(o.max_overlap_ratio);
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
    next: NextState,
    next_u: Velocities,
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

#[derive(Clone, Debug, Default)]
struct NextState {
    x: Vec<f64>,
    y: Vec<f64>,
    vx: Vec<f64>,
    vy: Vec<f64>,
    w: Vec<f64>,
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
            next: NextState::default(),
            next_u: Velocities::default(),
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
        let nx = &mut self.next;
        let nu = &mut self.next_u;
        for v in [
            &mut nx.x, &mut nx.y, &mut nx.vx, &mut nx.vy, &mut nx.w, &mut nu.x, &mut nu.y,
            &mut nu.w,
        ] {
            v.resize(n, 0.0);
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
        // Split the history into the chunks' slices.
        let nchunks = n.div_ceil(CHUNK);
        let mut hist_parts: Vec<&mut [f64]> = Vec::with_capacity(nchunks);
        {
            let mut rest: &mut [f64] = &mut self.nl.hist;
            for k in 0..nchunks {
                let (a, b) = (k * CHUNK, ((k + 1) * CHUNK).min(n));
                let len = if rest.is_empty() {
                    0
                } else {
                    (self.nl.start[b] - self.nl.start[a]) as usize
                };
                let (head, tail) = rest.split_at_mut(len);
                hist_parts.push(head);
                rest = tail;
            }
        }
        let g = &self.g;
        let u = &self.u;
        let nl_start = &self.nl.start;
        let nl_j = &self.nl.j;
        let (x_ref, y_ref) = (&self.nl.x_ref, &self.nl.y_ref);
        let sums: Vec<StepSums> = nx
            .x
            .par_chunks_mut(CHUNK)
            .zip(nx.y.par_chunks_mut(CHUNK))
            .zip(nx.vx.par_chunks_mut(CHUNK))
            .zip(nx.vy.par_chunks_mut(CHUNK))
            .zip(nx.w.par_chunks_mut(CHUNK))
            .zip(nu.x.par_chunks_mut(CHUNK))
            .zip(nu.y.par_chunks_mut(CHUNK))
            .zip(nu.w.par_chunks_mut(CHUNK))
            .zip(self.wall_hist.par_chunks_mut(CHUNK))
            .zip(hist_parts.into_par_iter())
            .enumerate()
            .map(
                |(k, (((((((((ox, oy), ovx), ovy), ow), oux), ouy), ouw), wh), hist))| {
                    let base = k * CHUNK;
                    let hist_base = nl_start[base] as usize;
                    let mut s = StepSums::default();
                    for l in 0..ox.len() {
                        let i = base + l;
                        let (xi, yi, ri, imi) = (g.x[i], g.y[i], g.radius[i], g.inv_mass[i]);
                        // Velocities the forces see.
                        let (vxi, vyi, wi) = (u.x[i], u.y[i], u.w[i]);
                        let (mut fx, mut fy, mut tq) = (0.0, 0.0, 0.0);
                        for e in nl_start[i] as usize..nl_start[i + 1] as usize {
                            let j = nl_j[e] as usize;
                            let dx = g.x[j] - xi;
                            let dy = g.y[j] - yi;
                            let rsum = ri + g.radius[j];
                            let d2 = dx * dx + dy * dy;
                            if d2 >= rsum * rsum || d2 == 0.0 {
                                if c.friction {
                                    hist[e - hist_base] = 0.0;
                                }
                                continue;
                            }
                            let d = d2.sqrt();
                            let (nxu, nyu) = (dx / d, dy / d);
                            let delta = rsum - d;
                            let (rvx, rvy) = (vxi - u.x[j], vyi - u.y[j]);
                            let vn = rvx * nxu + rvy * nyu;
                            let meff = 1.0 / (imi + g.inv_mass[j]);
                            let gamma = c.law.gamma_n(meff);
                            let fn_ = c.kn * delta + gamma * vn;
                            fx -= fn_ * nxu;
                            fy -= fn_ * nyu;
                            s.max_overlap_ratio = s.max_overlap_ratio.max(delta / (0.5 * rsum));
                            if c.friction {
                                let (tx, ty) = (-nyu, nxu);
                                let vt = rvx * tx + rvy * ty + (wi * ri + u.w[j] * g.radius[j]);
                                let ft =
                                    c.tangential(&mut hist[e - hist_base], vt, fn_, gamma, c.mu);
                                fx += ft * tx;
                                fy += ft * ty;
                                tq += ri * ft;
                            }
                        }
                        if g.kind[i] == INTRUDER {
                            s.intruder_fx_n += fx;
                            s.intruder_fy_n += fy;
                            ox[l] = xi;
                            (ovx[l], oux[l], ow[l], ouw[l]) = (0.0, 0.0, 0.0, 0.0);
                            (oy[l], ovy[l]) = match c.intruder {
                                Some((bottom, v)) => (bottom + ri, v),
                                None => (yi, 0.0),
                            };
                            ouy[l] = ovy[l];
                        } else {
                            // Walls: (overlap, outward normal from grain to wall, index).
                            let mi = 1.0 / imi;
                            let gamma_w = c.law.gamma_n(mi);
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
                                    wh[l][kw] = 0.0;
                                    continue;
                                }
                                let vn = vxi * wnx + vyi * wny;
                                let fn_ = c.kn * delta + gamma_w * vn;
                                fx -= fn_ * wnx;
                                fy -= fn_ * wny;
                                if kw == 0 {
                                    s.floor_n += fn_;
                                }
                                s.max_overlap_ratio = s.max_overlap_ratio.max(delta / ri);
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
                            let al = tq * g.inv_inertia[i];
                            let (hx, hy, hw) = (g.vx[i], g.vy[i], g.w[i]);
                            let (nvx, nvy, nw) = (hx + ax * c.dt, hy + ay * c.dt, hw + al * c.dt);
                            if c.euler {
                                ox[l] = xi + hx * c.dt;
                                oy[l] = yi + hy * c.dt;
                                (oux[l], ouy[l], ouw[l]) = (nvx, nvy, nw);
                            } else {
                                ox[l] = xi + nvx * c.dt;
                                oy[l] = yi + nvy * c.dt;
                                let h = 0.5 * c.dt;
                                (oux[l], ouy[l], ouw[l]) =
                                    (nvx + ax * h, nvy + ay * h, nw + al * h);
                            }
                            ovx[l] = nvx;
                            ovy[l] = nvy;
                            ow[l] = nw;
                            let (kx, ky, kw) = (oux[l], ouy[l], ouw[l]);
                            s.kinetic_j +=
                                0.5 * mi * (kx * kx + ky * ky) + 0.5 * kw * kw / g.inv_inertia[i];
                        }
                        let ddx = ox[l] - x_ref[i];
                        let ddy = oy[l] - y_ref[i];
                        s.max_disp2 = s.max_disp2.max(ddx * ddx + ddy * ddy);
                    }
                    s
                },
            )
            .collect();
        let total = sums.iter().fold(StepSums::default(), |acc, s| acc.add(s));
        std::mem::swap(&mut self.g.x, &mut self.next.x);
        std::mem::swap(&mut self.g.y, &mut self.next.y);
        std::mem::swap(&mut self.g.vx, &mut self.next.vx);
        std::mem::swap(&mut self.g.vy, &mut self.next.vy);
        std::mem::swap(&mut self.g.w, &mut self.next.w);
        std::mem::swap(&mut self.u, &mut self.next_u);
        self.rebuild_due = total.max_disp2 > 0.25 * self.cfg.skin_m * self.cfg.skin_m;
        self.last = total;
        self.steps += 1;
        self.t_s = self.steps as f64 * self.cfg.dt_s;
    }

    /// Free grains: kinetic energy per grain over `m g d` of the mean grain (settling
    /// measure); `g` at least 9.81 m/s^2 for a gravity-free world.
    pub fn agitation(&self) -> f64 {
        let (n, m) = self.g.free_mass();
        if n == 0 {
            return 0.0;
        }
        let d = 2.0 * mean(&self.g.radius);
        self.last.kinetic_j / (m * self.cfg.gravity_m_s2.max(9.81) * d)
    }

    /// The vertical force carried across each height in `heights_m` by the contacts whose
    /// centres lie on both sides of it (the lower grain pushing the upper one up), N. In a
    /// bed at rest this is the weight of the grains above the height.
    pub fn vertical_load_across(&self, heights_m: &[f64]) -> Vec<f64> {
        let g = &self.g;
        let kn = self.cfg.law.kn_n_per_m;
        let mut out = vec![0.0; heights_m.len()];
        for i in 0..g.len() {
            for e in self.nl.start[i] as usize..self.nl.start[i + 1] as usize {
                let j = self.nl.j[e] as usize;
                if g.y[j] <= g.y[i] {
                    continue;
                }
                let (dx, dy) = (g.x[j] - g.x[i], g.y[j] - g.y[i]);
                let d = dx.hypot(dy);
                let delta = g.radius[i] + g.radius[j] - d;
                if delta <= 0.0 {
                    continue;
                }
                let ny = dy / d;
                let (rvx, rvy) = (self.u.x[i] - self.u.x[j], self.u.y[i] - self.u.y[j]);
                let vn = rvx * dx / d + rvy * ny;
                let meff = 1.0 / (g.inv_mass[i] + g.inv_mass[j]);
                let fn_ = kn * delta + self.cfg.law.gamma_n(meff) * vn;
                let mut fy_on_j = fn_ * ny;
                if let Some(h) = self.nl.hist.get(e) {
                    let kt = self.cfg.law.friction.map_or(0.0, |f| f.kt_over_kn * kn);
                    // The tangential spring part (the dashpot is negligible at rest).
                    let ft = -(kt * h);
                    fy_on_j -= ft * (dx / d);
                }
                for (k, &h) in heights_m.iter().enumerate() {
                    if g.y[i] < h && g.y[j] >= h {
                        out[k] += fy_on_j;
                    }
                }
            }
        }
        out
    }
}

/// Mean of a slice (0 when empty).
pub fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}
