//! The parameters of a DEM run, the two named models, and the numbers that decide the
//! physics.
//!
//! - `paper`: Supplementary I. Hookean spring and viscous dashpot, no friction between
//!   grains, a per-grain drag, no gravity, no walls unless asked, forward Euler.
//! - `full`: what a granular physicist would run today: gravity, side walls and floor,
//!   Cundall-Strack friction, velocity Verlet, damping set by a restitution that every pair
//!   keeps whatever its sizes.
//!
//! Units SI; poppy-seed defaults (1 mm, 1000 kg/m^3). The stiffness is chosen for a stated
//! overlap: a grain of the largest size hit head-on by the rigid intruder at the intrusion
//! speed overlaps it by `overlap * d` (`k = m (v / delta)^2`).

use serde::{Deserialize, Serialize};

use super::contact::{ContactLaw, Damping, Friction, SpringDashpot, stiffness_for_overlap};
use super::grains::{SizeDistribution, sphere_mass};
use super::world::{Integrator, Walls, WorldConfig};

/// A named model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Model {
    /// Supplementary I exactly.
    Paper,
    /// Gravity, walls, friction, velocity Verlet.
    Full,
}

/// Everything a DEM run is made of (written to `dem.toml`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DemParams {
    /// Which model.
    pub model: Model,
    /// Base (small) grain diameter, m.
    pub diameter_m: f64,
    /// Grain density, kg/m^3.
    pub density_kg_m3: f64,
    /// Size distribution.
    pub sizes: SizeDistribution,
    /// Contact law.
    pub contact: ContactLaw,
    /// Gravity, m/s^2.
    pub gravity_m_s2: f64,
    /// Per-grain drag rate, 1/s.
    pub drag_per_s: f64,
    /// Integrator.
    pub integrator: Integrator,
    /// Time step, s.
    pub dt_s: f64,
    /// Neighbour skin, m.
    pub skin_m: f64,
    /// Walls during the intrusion (the full model always has them).
    pub walls: bool,
    /// Speed the stiffness was chosen for, m/s.
    pub design_speed_m_s: f64,
}

/// How to choose the numbers not given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Choice {
    /// Model.
    pub model: Model,
    /// Base diameter, m.
    pub diameter_m: f64,
    /// Density, kg/m^3.
    pub density_kg_m3: f64,
    /// Sizes.
    pub sizes: SizeDistribution,
    /// Intrusion speed the stiffness is chosen for, m/s.
    pub speed_m_s: f64,
    /// Largest overlap at that speed, share of `d`.
    pub overlap: f64,
    /// Stiffness given instead, N/m.
    pub kn_n_per_m: Option<f64>,
    /// Restitution (small-small pair for the paper's constant dashpot).
    pub restitution: f64,
    /// Dashpot given instead, N s/m (constant for every pair).
    pub damping_n_s_per_m: Option<f64>,
    /// Friction coefficient (full model).
    pub mu: f64,
    /// Per-grain drag, 1/s (None: the model's default).
    pub drag_per_s: Option<f64>,
    /// Integrator (None: the model's).
    pub integrator: Option<Integrator>,
    /// Steps per shortest contact (sets dt unless given).
    pub steps_per_contact: f64,
    /// Step given, s.
    pub dt_s: Option<f64>,
    /// Walls in the paper model.
    pub walls: bool,
    /// Gravity, m/s^2 (full model).
    pub gravity_m_s2: f64,
}

impl Choice {
    /// The defaults of `model`.
    pub fn new(model: Model) -> Self {
        Self {
            model,
            diameter_m: 1.0e-3,
            density_kg_m3: 1000.0,
            sizes: SizeDistribution::BI,
            speed_m_s: 0.5,
            overlap: 0.01,
            kn_n_per_m: None,
            restitution: 0.5,
            damping_n_s_per_m: None,
            mu: 0.5,
            drag_per_s: None,
            integrator: None,
            steps_per_contact: 50.0,
            dt_s: None,
            walls: false,
            gravity_m_s2: 9.81,
        }
    }

    /// Resolve and check; `force_step` allows a step above `t_c / 10`.
    pub fn resolve(&self, force_step: bool) -> Result<DemParams, String> {
        for (name, v) in [
            ("--diameter", self.diameter_m),
            ("--density", self.density_kg_m3),
            ("--speed", self.speed_m_s),
            ("--overlap", self.overlap),
            ("--steps-per-contact", self.steps_per_contact),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} {v} (allowed: a positive number)"));
            }
        }
        if self.overlap >= 0.2 {
            return Err(format!(
                "--overlap {} (allowed: below 0.2 of a diameter; grains this soft are not sand)",
                self.overlap
            ));
        }
        self.sizes.check()?;
        let d = self.diameter_m;
        let m_small = sphere_mass(d * self.sizes.min_factor(), self.density_kg_m3);
        let m_large = sphere_mass(d * self.sizes.max_factor(), self.density_kg_m3);
        let kn = match self.kn_n_per_m {
            Some(k) => k,
            None => stiffness_for_overlap(m_large, self.speed_m_s, self.overlap * d),
        };
        let small_pair = SpringDashpot {
            k_n_per_m: kn,
            gamma_n_s_per_m: 0.0,
            m_eff_kg: 0.5 * m_small,
        };
        let damping = match (self.damping_n_s_per_m, self.model) {
            (Some(g), _) => Damping::Force { gamma_n_s_per_m: g },
            (None, Model::Full) => Damping::Restitution {
                e: self.restitution,
            },
            (None, Model::Paper) => {
                let e = self.restitution;
                if !(e > 0.0 && e <= 1.0) {
                    return Err(format!("--restitution {e} (allowed: 0 < e <= 1)"));
                }
                let law = ContactLaw {
                    kn_n_per_m: kn,
                    damping: Damping::Restitution { e },
                    friction: None,
                };
                Damping::Force {
                    gamma_n_s_per_m: law.gamma_n(small_pair.m_eff_kg),
                }
            }
        };
        let contact = ContactLaw {
            kn_n_per_m: kn,
            damping,
            friction: (self.model == Model::Full).then(|| Friction {
                mu: self.mu,
                mu_wall: self.mu,
                ..Friction::default()
            }),
        };
        // Pairs range from two small grains to one grain against a wall or the intruder.
        contact.check((small_pair.m_eff_kg, m_large))?;
        let tc = contact.pair(small_pair.m_eff_kg).contact_time_s();
        let dt = self.dt_s.unwrap_or(tc / self.steps_per_contact);
        super::collide::check_step(dt, tc, force_step)?;
        let (gravity, drag, integrator) = match self.model {
            Model::Paper => (
                0.0,
                self.drag_per_s.unwrap_or(20.0),
                Integrator::ForwardEuler,
            ),
            Model::Full => (
                self.gravity_m_s2,
                self.drag_per_s.unwrap_or(0.0),
                Integrator::VelocityVerlet,
            ),
        };
        if !(drag.is_finite() && drag >= 0.0) {
            return Err(format!("--drag {drag} 1/s (allowed: 0 or more)"));
        }
        if !(gravity.is_finite() && gravity >= 0.0) {
            return Err(format!("--gravity {gravity} m/s^2 (allowed: 0 or more)"));
        }
        Ok(DemParams {
            model: self.model,
            diameter_m: d,
            density_kg_m3: self.density_kg_m3,
            sizes: self.sizes,
            contact,
            gravity_m_s2: gravity,
            drag_per_s: drag,
            integrator: self.integrator.unwrap_or(integrator),
            dt_s: dt,
            skin_m: 0.3 * d,
            walls: self.walls || self.model == Model::Full,
            design_speed_m_s: self.speed_m_s,
        })
    }
}

/// The two dimensionless numbers a run prints.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Dimensionless {
    /// Shortest contact time, s.
    pub contact_time_s: f64,
    /// `t_c v / d`: how far the intruder moves during one contact, in grain diameters
    /// (small: the grains are effectively rigid).
    pub contact_time_speed_over_d: f64,
    /// `v / sqrt(g d)`: inertia over gravity at the grain scale.
    pub froude: f64,
}

impl DemParams {
    /// Mass of the smallest grain, kg.
    pub fn small_mass_kg(&self) -> f64 {
        sphere_mass(
            self.diameter_m * self.sizes.min_factor(),
            self.density_kg_m3,
        )
    }

    /// Contact time of the shortest (small-small) contact, s.
    pub fn contact_time_s(&self) -> f64 {
        self.contact
            .pair(0.5 * self.small_mass_kg())
            .contact_time_s()
    }

    /// The world configuration, with `walls`.
    pub fn world(&self, walls: Walls) -> WorldConfig {
        WorldConfig {
            law: self.contact,
            gravity_m_s2: self.gravity_m_s2,
            drag_per_s: self.drag_per_s,
            integrator: self.integrator,
            dt_s: self.dt_s,
            walls,
            skin_m: self.skin_m,
        }
    }

    /// The dimensionless numbers at intrusion speed `speed_m_s` (Froude with 9.81 m/s^2 when
    /// the model has no gravity: the lab's gravity).
    pub fn dimensionless(&self, speed_m_s: f64) -> Dimensionless {
        let tc = self.contact_time_s();
        let g = if self.gravity_m_s2 > 0.0 {
            self.gravity_m_s2
        } else {
            9.81
        };
        Dimensionless {
            contact_time_s: tc,
            contact_time_speed_over_d: tc * speed_m_s.abs() / self.diameter_m,
            froude: speed_m_s.abs() / (g * self.diameter_m).sqrt(),
        }
    }
}
