//! One DEM world: its configuration, grains, neighbour list and time; the step itself is
//! [`super::step`] (contact forces, walls, gravity, per-grain drag and the integrator, in
//! one fused pass).

use serde::{Deserialize, Serialize};

use super::contact::ContactLaw;
use super::grains::{FREE, Grains, permute};
use super::neighbours::NeighbourList;
use super::scratch::Scratch;

pub use super::grains::{INTERIOR, NEAR_WALL, PRESCRIBED};

/// Which integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
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
    /// Largest squared displacement of a grain in the step, m^2.
    pub(super) max_step2: f64,
}

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
    /// Force accumulators of the step.
    pub(super) scratch: Scratch,
    /// Per grain, what the step does with it: [`INTERIOR`], [`NEAR_WALL`] (a free grain
    /// within a skin of a wall at the build: the only ones that may touch one before the
    /// next build) or [`PRESCRIBED`] (an intruder grain).
    pub(super) class: Vec<u8>,
    /// The walls the flags were computed for.
    pub(super) walls_at_build: Walls,
    pub(super) rebuild_due: bool,
    /// Sum over the steps since the build of the largest displacement in each, m: a bound
    /// on how far any grain moved (a rebuild is due past half the skin).
    pub(super) drift_m: f64,
    /// Time each chunk of the list took in the steps since its build, s (what the next
    /// build balances the chunks by; the results do not depend on it).
    pub(super) chunk_seconds: Vec<f64>,
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
            scratch: Scratch::default(),
            class: Vec::new(),
            walls_at_build: Walls::default(),
            rebuild_due: true,
            drift_m: 0.0,
            chunk_seconds: Vec::new(),
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
        // Chunks for the threads of the pool the step runs on: the results do not depend
        // on the chunks (see `super::step`), only the speed does.
        let perm = self.nl.rebuild(
            &mut self.g,
            self.cfg.skin_m,
            self.cfg.law.friction.is_some(),
            rayon::current_num_threads(),
            &self.chunk_seconds,
        );
        self.chunk_seconds = vec![0.0; self.nl.chunks()];
        permute(&mut self.wall_hist, &perm);
        if self.u.x.len() == perm.len() {
            permute(&mut self.u.x, &perm);
            permute(&mut self.u.y, &perm);
            permute(&mut self.u.w, &perm);
        }
        let (g, w, reach) = (&self.g, self.cfg.walls, self.cfg.skin_m);
        self.class = (0..g.len())
            .map(|i| {
                let (x, y, r) = (g.x[i], g.y[i], g.radius[i] + reach);
                if g.kind[i] != FREE {
                    PRESCRIBED
                } else if w.floor_m.is_some_and(|f| y - f < r)
                    || w.left_m.is_some_and(|l| x - l < r)
                    || w.right_m.is_some_and(|rt| rt - x < r)
                    || w.lid_m.is_some_and(|t| t - y < r)
                {
                    NEAR_WALL
                } else {
                    INTERIOR
                }
            })
            .collect();
        self.scratch = Scratch::sized(
            &self.class,
            &self.nl.chunk_start,
            self.cfg.law.friction.is_some(),
        );
        self.walls_at_build = w;
        self.rebuild_due = false;
        self.drift_m = 0.0;
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

    /// Bytes the engine holds per grain: the grains, the neighbour list, the force
    /// accumulators, the predicted velocities and the wall histories.
    pub fn bytes_per_grain(&self) -> f64 {
        Grains::BYTES_PER_GRAIN as f64
            + self.nl.bytes_per_grain()
            + self.scratch.bytes_per_grain(self.g.len())
            + 8.0 * (3.0 + 4.0)
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
}

/// Mean of a slice (0 when empty).
pub fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}
