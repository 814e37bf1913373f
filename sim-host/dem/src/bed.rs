//! Bed preparation: fill a box and let the grains settle under gravity, or pack them
//! randomly to a target packing fraction with no gravity (by growing them in place). The
//! result is a world at rest, saved as a checkpoint that intrusions start from.

use rand::RngExt;
use serde::{Deserialize, Serialize};

use super::grains::{FREE, Grains, rng};
use super::params::DemParams;
use super::world::{Integrator, Walls, World};

/// How a bed is made.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum BedMethod {
    /// Rain the grains in from a loose lattice and let them settle under gravity.
    Settle,
    /// No gravity: place the grains at random in a closed box sized for `phi` (area
    /// fraction) and grow them to full size while damping removes the overlaps.
    Pack {
        /// Target area fraction.
        phi: f64,
    },
}

/// What bed to make.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BedSpec {
    /// Box width, m.
    pub width_m: f64,
    /// Bed height wanted, m (settle: roughly; pack: exactly, the box's).
    pub height_m: f64,
    /// Method.
    pub method: BedMethod,
    /// Seed (positions, sizes, initial velocities).
    pub seed: u64,
    /// Longest settling time, s.
    pub max_time_s: f64,
    /// Settled once the kinetic energy per grain is below this share of `m g d`.
    pub rest_agitation: f64,
}

/// What a preparation gave.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BedReport {
    /// Free grains.
    pub grains: usize,
    /// Their mass, kg.
    pub mass_kg: f64,
    /// Surface height (mean over the bed's width of the highest grain top), m.
    pub surface_m: f64,
    /// Area fraction of the grains below the surface (away from the walls).
    pub area_fraction: f64,
    /// Simulated preparation time, s.
    pub time_s: f64,
    /// Steps.
    pub steps: u64,
    /// Final kinetic energy per grain over `m g d`.
    pub agitation: f64,
    /// Whether it reached `rest_agitation` before `max_time_s`.
    pub settled: bool,
    /// Largest overlap over a radius at the end.
    pub max_overlap_ratio: f64,
}

impl BedSpec {
    /// Check the geometry against grains of `params`.
    pub fn check(&self, p: &DemParams) -> Result<(), String> {
        let dmax = p.diameter_m * p.sizes.max_factor();
        if !(self.width_m.is_finite() && self.width_m >= 5.0 * dmax) {
            return Err(format!(
                "--width {} m (allowed: at least 5 of the largest grains, {:.3e} m)",
                self.width_m,
                5.0 * dmax
            ));
        }
        if !(self.height_m.is_finite() && self.height_m >= 3.0 * dmax) {
            return Err(format!(
                "--height {} m (allowed: at least 3 of the largest grains, {:.3e} m)",
                self.height_m,
                3.0 * dmax
            ));
        }
        if let BedMethod::Pack { phi } = self.method
            && !(0.3..=0.86).contains(&phi)
        {
            return Err(format!(
                "--phi {phi} (allowed: an area fraction from 0.3 to 0.86; 2-D disks jam near 0.84)"
            ));
        }
        if !(self.max_time_s.is_finite() && self.max_time_s > 0.0) {
            return Err(format!(
                "--max-time {} s (allowed: a positive number)",
                self.max_time_s
            ));
        }
        let n = self.grain_count(p);
        if n > 2_000_000 {
            return Err(format!(
                "the bed would hold {n} grains (allowed: up to 2,000,000)"
            ));
        }
        Ok(())
    }

    /// Number of grains: the box filled at the method's area fraction (settling: 0.82).
    pub fn grain_count(&self, p: &DemParams) -> usize {
        let phi = match self.method {
            BedMethod::Settle => 0.82,
            BedMethod::Pack { phi } => phi,
        };
        let a = core::f64::consts::PI * 0.25 * p.diameter_m.powi(2) * p.sizes.mean_area_factor();
        (self.width_m * self.height_m * phi / a).round() as usize
    }
}

/// Surface height: the mean, over bins two large grains wide between the walls, of the
/// highest grain top in each bin (bins without grains skipped), m.
pub fn surface_height(g: &Grains, x0: f64, x1: f64, bin_m: f64) -> f64 {
    let nb = (((x1 - x0) / bin_m) as usize).max(1);
    let mut top = vec![f64::NAN; nb];
    for i in 0..g.len() {
        if g.kind[i] != FREE || g.x[i] < x0 || g.x[i] >= x1 {
            continue;
        }
        let b = (((g.x[i] - x0) / bin_m) as usize).min(nb - 1);
        let t = g.y[i] + g.radius[i];
        if top[b].is_nan() || top[b] < t {
            top[b] = t;
        }
    }
    let v: Vec<f64> = top.into_iter().filter(|t| t.is_finite()).collect();
    super::world::mean(&v)
}

/// Area fraction of the free grains whose centres lie in `x0..x1` and below `y1`, over
/// that rectangle (from `y0`).
pub fn area_fraction(g: &Grains, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let a: f64 = (0..g.len())
        .filter(|&i| {
            g.kind[i] == FREE && g.x[i] >= x0 && g.x[i] < x1 && g.y[i] >= y0 && g.y[i] < y1
        })
        .map(|i| core::f64::consts::PI * g.radius[i] * g.radius[i])
        .sum();
    a / ((x1 - x0) * (y1 - y0)).max(f64::MIN_POSITIVE)
}

/// What [`prepare`] returns when its caller stopped it.
pub const STOPPED: &str = "stopped by its caller before the bed was prepared (nothing written)";

/// Prepare a bed. `progress(done_fraction)` is called now and then; when it returns false the
/// preparation stops there ([`STOPPED`]).
pub fn prepare(
    p: &DemParams,
    spec: &BedSpec,
    mut progress: impl FnMut(f64) -> bool,
) -> Result<(World, BedReport), String> {
    spec.check(p)?;
    let n = spec.grain_count(p);
    let mut r = rng(spec.seed);
    let diameters = p.sizes.draw(n, p.diameter_m, &mut r);
    let dmax = p.diameter_m * p.sizes.max_factor();
    let w = spec.width_m;
    let mut g = Grains::default();
    let mut cfg = p.world(Walls {
        floor_m: Some(0.0),
        left_m: Some(0.0),
        right_m: Some(w),
        lid_m: None,
    });
    // Preparation is not the experiment: second order, with a drag that bleeds energy.
    cfg.integrator = Integrator::VelocityVerlet;
    let tc = p.contact_time_s();
    match spec.method {
        BedMethod::Settle => {
            let s = 1.05 * dmax;
            let cols = ((w - s) / s).floor().max(1.0) as usize;
            for (k, &d) in diameters.iter().enumerate() {
                let (c, row) = (k % cols, k / cols);
                let jitter = 0.02 * dmax * (r.random::<f64>() - 0.5);
                let x = 0.5 * s
                    + (c as f64 + 0.5 * (row % 2) as f64) * s * (w - s) / (cols as f64 * s)
                    + jitter;
                let y = 0.5 * s + row as f64 * s;
                let i = g.push(x.clamp(0.5 * d, w - 0.5 * d), y, d, p.density_kg_m3, FREE);
                g.vx[i] = 0.05 * (r.random::<f64>() - 0.5);
                g.vy[i] = 0.05 * (r.random::<f64>() - 0.5);
            }
            cfg.gravity_m_s2 = if p.gravity_m_s2 > 0.0 {
                p.gravity_m_s2
            } else {
                9.81
            };
            cfg.drag_per_s = cfg.drag_per_s.max(10.0);
        }
        BedMethod::Pack { phi } => {
            let a: f64 = diameters
                .iter()
                .map(|d| 0.25 * core::f64::consts::PI * d * d)
                .sum();
            let h = a / (phi * w);
            cfg.walls.lid_m = Some(h);
            for &d in &diameters {
                let x = 0.5 * d + (w - d) * r.random::<f64>();
                let y = 0.5 * d + (h - d) * r.random::<f64>();
                g.push(x, y, d, p.density_kg_m3, FREE);
            }
            cfg.gravity_m_s2 = 0.0;
            // Strong drag: about one e-fold per 20 contact times.
            cfg.drag_per_s = cfg.drag_per_s.max(1.0 / (20.0 * tc));
        }
    }
    let check_every = 200u64;
    let max_steps = (spec.max_time_s / cfg.dt_s).ceil() as u64;
    let mut world;
    let mut settled = false;
    match spec.method {
        BedMethod::Settle => {
            world = World::new(cfg, g);
            // Fall time from the top of the lattice, twice over, before judging rest.
            let top = world.g.y.iter().copied().fold(0.0, f64::max);
            let min_steps = (2.0 * (2.0 * top / cfg.gravity_m_s2).sqrt() / cfg.dt_s) as u64;
            while world.steps < max_steps {
                world.step();
                if world.steps % check_every == 0 {
                    if !progress(world.steps as f64 / max_steps as f64) {
                        return Err(STOPPED.into());
                    }
                    if world.steps >= min_steps && world.agitation() < spec.rest_agitation {
                        settled = true;
                        break;
                    }
                }
            }
        }
        BedMethod::Pack { .. } => {
            // Grow from half size in 10 stages, each relaxed for 40 contact times.
            let full = g.radius.clone();
            let stage_steps = ((40.0 * tc / cfg.dt_s) as u64).max(100);
            for (r, f) in g.radius.iter_mut().zip(&full) {
                *r = 0.5 * f;
            }
            world = World::new(cfg, g);
            for stage in 1..=10 {
                let s = 0.5 + 0.05 * stage as f64;
                for i in 0..world.g.len() {
                    let id = world.g.id[i] as usize;
                    world.g.radius[i] = s * full[id];
                }
                world.rebuild();
                for k in 0..stage_steps {
                    world.step();
                    if k % check_every == 0 && !progress(0.5 * (stage - 1) as f64 / 10.0) {
                        return Err(STOPPED.into());
                    }
                }
                if !progress(0.5 * stage as f64 / 10.0) {
                    return Err(STOPPED.into());
                }
            }
            while world.steps < max_steps {
                world.step();
                if world.steps % check_every == 0 {
                    if !progress(0.5 + 0.5 * world.steps as f64 / max_steps as f64) {
                        return Err(STOPPED.into());
                    }
                    if world.agitation() < spec.rest_agitation && world.max_overlap_ratio() < 0.02 {
                        settled = true;
                        break;
                    }
                }
            }
        }
    }
    // Rest: zero velocities, restore the run's own settings.
    let steps = world.steps;
    let time_s = world.t_s;
    let agitation = world.agitation();
    let max_overlap_ratio = world.max_overlap_ratio();
    for v in [
        &mut world.g.vx,
        &mut world.g.vy,
        &mut world.g.w,
        &mut world.u.x,
        &mut world.u.y,
        &mut world.u.w,
    ] {
        v.iter_mut().for_each(|x| *x = 0.0);
    }
    let (count, mass_kg) = world.g.free_mass();
    let surface_m = match spec.method {
        BedMethod::Pack { .. } => world.cfg.walls.lid_m.unwrap_or(0.0),
        BedMethod::Settle => surface_height(&world.g, 0.0, w, 2.0 * dmax),
    };
    let area_fraction = area_fraction(
        &world.g,
        2.0 * dmax,
        w - 2.0 * dmax,
        2.0 * dmax,
        surface_m - 2.0 * dmax,
    );
    world.t_s = 0.0;
    world.steps = 0;
    world.cfg = p.world(world.cfg.walls);
    if spec.method == BedMethod::Settle {
        // The bed is kept as it settled: with the gravity it settled under.
        world.cfg.gravity_m_s2 = cfg.gravity_m_s2;
    }
    world.rebuild();
    Ok((
        world,
        BedReport {
            grains: count,
            mass_kg,
            surface_m,
            area_fraction,
            time_s,
            steps,
            agitation,
            settled,
            max_overlap_ratio,
        },
    ))
}
