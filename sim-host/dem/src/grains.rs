//! The grains, as a structure of arrays: one `Vec` per quantity, indexed by slot. Slots are
//! reordered along the cell grid when the neighbour list is rebuilt (so neighbours sit close
//! in memory); `id` follows each grain through reorderings.
//!
//! Grains are 2-D disks with the mass and moment of inertia of a sphere of the same diameter
//! (a monolayer of seeds against a wall): `m = rho pi d^3 / 6`, `I = m d^2 / 10`.
//! Intruder grains have zero inverse mass: they follow their trajectory whatever pushes them.

use rand::{RngExt, SeedableRng, rngs::StdRng};
use serde::{Deserialize, Serialize};

// What the step does with a grain: its class at the last list build.

/// A free grain that cannot touch a wall before the next list build.
pub const INTERIOR: u8 = 0;
/// A free grain that may touch a wall before the next list build.
pub const NEAR_WALL: u8 = 1;
/// A grain on a prescribed trajectory (the intruder's).
pub const PRESCRIBED: u8 = 2;

/// A free grain.
pub const FREE: u8 = 0;
/// A grain of the intruder (prescribed motion).
pub const INTRUDER: u8 = 1;

/// How grain diameters are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SizeDistribution {
    /// Every grain the same diameter (crystallises: 60 degree shear bands).
    Mono,
    /// Two sizes: `d` and `ratio d`, a share `small_share` small (default 50:50, 1.4).
    Bi {
        /// Large over small diameter.
        ratio: f64,
        /// Share of small grains, 0..1.
        small_share: f64,
    },
    /// Diameters uniform in `d (1 - spread) .. d (1 + spread)`.
    Poly {
        /// Half-width of the distribution over the mean.
        spread: f64,
    },
}

impl SizeDistribution {
    /// The default bidisperse mix (50:50, ratio 1.4).
    pub const BI: Self = Self::Bi {
        ratio: 1.4,
        small_share: 0.5,
    };

    /// Check the parameters.
    pub fn check(&self) -> Result<(), String> {
        match *self {
            Self::Mono => Ok(()),
            Self::Bi { ratio, small_share } => {
                if !(1.0..=3.0).contains(&ratio) {
                    Err(format!("diameter ratio {ratio} (allowed: 1 to 3)"))
                } else if !(0.0..=1.0).contains(&small_share) {
                    Err(format!("small-grain share {small_share} (allowed: 0 to 1)"))
                } else {
                    Ok(())
                }
            }
            Self::Poly { spread } => {
                if (0.0..0.5).contains(&spread) {
                    Ok(())
                } else {
                    Err(format!("polydispersity {spread} (allowed: 0 to below 0.5)"))
                }
            }
        }
    }

    /// Largest diameter over `d`.
    pub fn max_factor(&self) -> f64 {
        match *self {
            Self::Mono => 1.0,
            Self::Bi { ratio, .. } => ratio,
            Self::Poly { spread } => 1.0 + spread,
        }
    }

    /// Smallest diameter over `d`.
    pub fn min_factor(&self) -> f64 {
        match *self {
            Self::Poly { spread } => 1.0 - spread,
            _ => 1.0,
        }
    }

    /// Mean disk area over `pi d^2 / 4`.
    pub fn mean_area_factor(&self) -> f64 {
        match *self {
            Self::Mono => 1.0,
            Self::Bi { ratio, small_share } => small_share + (1.0 - small_share) * ratio * ratio,
            Self::Poly { spread } => 1.0 + spread * spread / 3.0,
        }
    }

    /// `n` diameters for base diameter `d_m`, seeded; the bidisperse mix is exact (rounded),
    /// then shuffled.
    pub fn draw(&self, n: usize, d_m: f64, rng: &mut StdRng) -> Vec<f64> {
        match *self {
            Self::Mono => vec![d_m; n],
            Self::Bi { ratio, small_share } => {
                let small = (n as f64 * small_share).round() as usize;
                let mut v: Vec<f64> = (0..n)
                    .map(|k| if k < small { d_m } else { d_m * ratio })
                    .collect();
                for k in (1..n).rev() {
                    let j = rng.random_range(0..=k);
                    v.swap(k, j);
                }
                v
            }
            Self::Poly { spread } => (0..n)
                .map(|_| d_m * (1.0 + spread * (2.0 * rng.random::<f64>() - 1.0)))
                .collect(),
        }
    }
}

/// Reorder `v` by `perm` (new slot `s` takes old slot `perm[s]`).
pub fn permute<T: Copy>(v: &mut Vec<T>, perm: &[usize]) {
    let old = std::mem::take(v);
    v.extend(perm.iter().map(|&p| old[p]));
}

/// A seeded generator.
pub fn rng(seed: u64) -> StdRng {
    StdRng::seed_from_u64(seed)
}

/// Mass of a grain of diameter `d_m` and density `rho_kg_m3`, kg.
pub fn sphere_mass(d_m: f64, rho_kg_m3: f64) -> f64 {
    rho_kg_m3 * core::f64::consts::PI * d_m.powi(3) / 6.0
}

/// The grains.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Grains {
    /// Identity, stable across reorderings.
    pub id: Vec<u32>,
    /// Position, m.
    pub x: Vec<f64>,
    /// Height, m (up).
    pub y: Vec<f64>,
    /// Velocity, m/s (with velocity Verlet: at the half step).
    pub vx: Vec<f64>,
    /// Velocity, m/s.
    pub vy: Vec<f64>,
    /// Angular velocity, rad/s (counter-clockwise).
    pub w: Vec<f64>,
    /// Radius, m.
    pub radius: Vec<f64>,
    /// 1 / mass, 1/kg (0: intruder).
    pub inv_mass: Vec<f64>,
    /// 1 / moment of inertia, 1/(kg m^2) (0: intruder).
    pub inv_inertia: Vec<f64>,
    /// [`FREE`] or [`INTRUDER`].
    pub kind: Vec<u8>,
}

impl Grains {
    /// Number of grains (free and intruder).
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Add a grain at rest; returns its slot.
    pub fn push(&mut self, x: f64, y: f64, d_m: f64, rho_kg_m3: f64, kind: u8) -> usize {
        let m = sphere_mass(d_m, rho_kg_m3);
        let (im, ii) = if kind == INTRUDER {
            (0.0, 0.0)
        } else {
            (1.0 / m, 10.0 / (m * d_m * d_m))
        };
        self.id.push(self.x.len() as u32);
        self.x.push(x);
        self.y.push(y);
        self.vx.push(0.0);
        self.vy.push(0.0);
        self.w.push(0.0);
        self.radius.push(0.5 * d_m);
        self.inv_mass.push(im);
        self.inv_inertia.push(ii);
        self.kind.push(kind);
        self.x.len() - 1
    }

    /// Mass of slot `i`, kg (infinite for an intruder grain).
    pub fn mass(&self, i: usize) -> f64 {
        1.0 / self.inv_mass[i]
    }

    /// Free grains: count and total mass, kg.
    pub fn free_mass(&self) -> (usize, f64) {
        (0..self.len())
            .filter(|&i| self.kind[i] == FREE)
            .fold((0, 0.0), |(n, m), i| (n + 1, m + self.mass(i)))
    }

    /// Reorder every array by `perm` (new slot `s` takes old slot `perm[s]`).
    pub fn permute(&mut self, perm: &[usize]) {
        permute(&mut self.id, perm);
        permute(&mut self.x, perm);
        permute(&mut self.y, perm);
        permute(&mut self.vx, perm);
        permute(&mut self.vy, perm);
        permute(&mut self.w, perm);
        permute(&mut self.radius, perm);
        permute(&mut self.inv_mass, perm);
        permute(&mut self.inv_inertia, perm);
        permute(&mut self.kind, perm);
    }

    /// Bytes held per grain by these arrays.
    pub const BYTES_PER_GRAIN: usize = 4 + 8 * 8 + 1;
}
