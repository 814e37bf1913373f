//! One head-on binary collision, run through the same world and time step as a bed: the
//! verification a DEM user checks first (restitution and contact time against the analytic
//! spring-dashpot values of docs/model.md section 7).
//!
//! Two disks approach along x at a relative speed `v` in their centre-of-mass frame (or one
//! disk hits a wall). Between steps the centres move in straight lines under both
//! integrators, so the moments the gap closes and opens are found exactly by linear
//! interpolation inside the step: the measured contact time has no step-quantisation error.

use serde::Serialize;

use super::contact::{ContactLaw, Damping, SpringDashpot};
use super::grains::{FREE, Grains, sphere_mass};
use super::world::{Integrator, Walls, World, WorldConfig};

/// A collision to run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Collision {
    /// Diameter of disk 1 (the one that hits a wall), m.
    pub d1_m: f64,
    /// Diameter of disk 2, m (ignored against a wall).
    pub d2_m: f64,
    /// Against a wall instead of disk 2.
    pub wall: bool,
    /// Stiffness, N/m.
    pub kn_n_per_m: f64,
    /// Damping, N s/m.
    pub damping_n_s_per_m: f64,
    /// Impact (closing) speed, m/s.
    pub speed_m_s: f64,
    /// Grain density, kg/m^3.
    pub density_kg_m3: f64,
    /// Time step, s (None: t_c / 50).
    pub dt_s: Option<f64>,
    /// Integrator.
    pub integrator: Integrator,
}

/// What a collision gave, beside the analytic values.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CollisionResult {
    /// Measured coefficient of restitution.
    pub restitution: f64,
    /// Measured contact duration, s.
    pub contact_time_s: f64,
    /// Analytic restitution.
    pub restitution_analytic: f64,
    /// Analytic contact duration, s.
    pub contact_time_analytic_s: f64,
    /// Relative errors (measured / analytic - 1).
    pub restitution_error: f64,
    /// Relative error of the contact time.
    pub contact_time_error: f64,
    /// Effective mass, kg.
    pub effective_mass_kg: f64,
    /// Largest overlap, m.
    pub max_overlap_m: f64,
    /// Step used, s.
    pub dt_s: f64,
    /// Steps per analytic contact time.
    pub steps_per_contact: f64,
}

impl Collision {
    /// The pair's spring-dashpot.
    pub fn pair(&self) -> SpringDashpot {
        let m1 = sphere_mass(self.d1_m, self.density_kg_m3);
        let m_eff = if self.wall {
            m1
        } else {
            let m2 = sphere_mass(self.d2_m, self.density_kg_m3);
            m1 * m2 / (m1 + m2)
        };
        SpringDashpot {
            k_n_per_m: self.kn_n_per_m,
            gamma_n_s_per_m: self.damping_n_s_per_m,
            m_eff_kg: m_eff,
        }
    }

    /// Run it. Errors name the bad parameter.
    pub fn run(&self, force_step: bool) -> Result<CollisionResult, String> {
        for (name, v) in [
            ("--d1", self.d1_m),
            ("--d2", if self.wall { 1.0 } else { self.d2_m }),
            ("--speed", self.speed_m_s),
            ("--density", self.density_kg_m3),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} {v} (allowed: a positive number)"));
            }
        }
        if !(self.kn_n_per_m.is_finite() && self.kn_n_per_m > 0.0) {
            return Err(format!(
                "--kn {} N/m: the normal stiffness must be positive",
                self.kn_n_per_m
            ));
        }
        if !(self.damping_n_s_per_m.is_finite() && self.damping_n_s_per_m >= 0.0) {
            return Err(format!(
                "--damping {} N s/m (allowed: 0 or more)",
                self.damping_n_s_per_m
            ));
        }
        let law = ContactLaw {
            kn_n_per_m: self.kn_n_per_m,
            damping: Damping::Force {
                gamma_n_s_per_m: self.damping_n_s_per_m,
            },
            friction: None,
        };
        let pair = self.pair();
        law.check((pair.m_eff_kg, pair.m_eff_kg))?;
        let tc = pair.contact_time_s();
        let dt = self.dt_s.unwrap_or(tc / 50.0);
        check_step(dt, tc, force_step)?;
        let (r1, r2) = (0.5 * self.d1_m, 0.5 * self.d2_m);
        let v = self.speed_m_s;
        // Start a quarter of the smaller radius apart (or 5 steps of travel, if more).
        let gap0 = (0.25 * r1.min(if self.wall { r1 } else { r2 })).max(5.0 * v * dt);
        let mut g = Grains::default();
        let (walls, v1, v2) = if self.wall {
            g.push(0.0, 0.0, self.d1_m, self.density_kg_m3, FREE);
            (
                Walls {
                    right_m: Some(r1 + gap0),
                    ..Walls::default()
                },
                v,
                0.0,
            )
        } else {
            let m1 = sphere_mass(self.d1_m, self.density_kg_m3);
            let m2 = sphere_mass(self.d2_m, self.density_kg_m3);
            g.push(0.0, 0.0, self.d1_m, self.density_kg_m3, FREE);
            g.push(r1 + r2 + gap0, 0.0, self.d2_m, self.density_kg_m3, FREE);
            (Walls::default(), v * m2 / (m1 + m2), -v * m1 / (m1 + m2))
        };
        g.vx[0] = v1;
        if !self.wall {
            g.vx[1] = v2;
        }
        let cfg = WorldConfig {
            law,
            gravity_m_s2: 0.0,
            drag_per_s: 0.0,
            integrator: self.integrator,
            dt_s: dt,
            walls,
            skin_m: 2.0 * (r1 + r2).max(gap0),
        };
        let mut w = World::new(cfg, g);
        let wall_x = walls.right_m.unwrap_or(0.0);
        let gap = |w: &World| -> (f64, f64) {
            let i1 = w.g.id.iter().position(|&id| id == 0).unwrap_or(0);
            if self.wall {
                (wall_x - w.g.x[i1] - r1, w.g.vx[i1])
            } else {
                let i2 = 1 - i1;
                (w.g.x[i2] - w.g.x[i1] - r1 - r2, w.g.vx[i1] - w.g.vx[i2])
            }
        };
        let (mut prev_gap, v_before) = gap(&w);
        let (mut t_in, mut t_out) = (None, None);
        let mut max_overlap: f64 = 0.0;
        let limit = ((gap0 / (v * dt)) as u64 + 20 * (tc / dt) as u64).max(1000);
        for _ in 0..limit {
            let t0 = w.t_s;
            w.step();
            let (gp, _) = gap(&w);
            max_overlap = max_overlap.max(-gp);
            if t_in.is_none() && gp < 0.0 {
                t_in = Some(t0 + dt * prev_gap / (prev_gap - gp));
            } else if t_in.is_some() && gp >= 0.0 {
                t_out = Some(t0 + dt * (-prev_gap) / (gp - prev_gap));
                break;
            }
            prev_gap = gp;
        }
        let (Some(t_in), Some(t_out)) = (t_in, t_out) else {
            return Err(format!(
                "the disks did not separate within {limit} steps (step {dt:.3e} s)"
            ));
        };
        // One more step: with no contact the velocities are the post-collision ones.
        w.step();
        let (_, v_after) = gap(&w);
        let e = -v_after / v_before;
        let t = t_out - t_in;
        Ok(CollisionResult {
            restitution: e,
            contact_time_s: t,
            restitution_analytic: pair.restitution(),
            contact_time_analytic_s: tc,
            restitution_error: e / pair.restitution() - 1.0,
            contact_time_error: t / tc - 1.0,
            effective_mass_kg: pair.m_eff_kg,
            max_overlap_m: max_overlap,
            dt_s: dt,
            steps_per_contact: tc / dt,
        })
    }
}

/// Refuse a step above `t_c / 10` unless forced, and a non-positive one.
pub fn check_step(dt_s: f64, tc_s: f64, force: bool) -> Result<(), String> {
    if !(dt_s.is_finite() && dt_s > 0.0) {
        return Err(format!("time step {dt_s} s (allowed: a positive number)"));
    }
    if dt_s > tc_s / 10.0 && !force {
        return Err(format!(
            "time step {dt_s:.3e} s is above t_c/10 = {:.3e} s (the contact time {tc_s:.3e} s \
             over 10; below that a contact is resolved; --force-step runs it anyway)",
            tc_s / 10.0
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(
        d1: f64,
        d2: f64,
        wall: bool,
        speed: f64,
        steps: f64,
        integ: Integrator,
    ) -> CollisionResult {
        let mut c = Collision {
            d1_m: d1,
            d2_m: d2,
            wall,
            kn_n_per_m: 1000.0,
            damping_n_s_per_m: 0.0,
            speed_m_s: speed,
            density_kg_m3: 1000.0,
            dt_s: None,
            integrator: integ,
        };
        // Damping for e ~ 0.6 on this pair.
        let p = c.pair();
        c.damping_n_s_per_m = 0.3 * p.critical_damping();
        let tc = c.pair().contact_time_s();
        c.dt_s = Some(tc / steps);
        c.run(false).unwrap()
    }

    #[test]
    fn print_errors() {
        for integ in [Integrator::VelocityVerlet, Integrator::ForwardEuler] {
            for steps in [40.0, 200.0] {
                let r = run(1e-3, 1.4e-3, false, 0.5, steps, integ);
                eprintln!(
                    "{integ:?} {steps}: e {:+.2e} tc {:+.2e}",
                    r.restitution_error, r.contact_time_error
                );
                let r = run(1e-3, 1e-3, true, 0.5, steps, integ);
                eprintln!(
                    "  wall {integ:?} {steps}: e {:+.2e} tc {:+.2e}",
                    r.restitution_error, r.contact_time_error
                );
            }
        }
    }
}

/// `dem collide` as a request: one head-on collision with the paper's contact law.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct CollideRequest {
    /// Diameter of disk 1 (the one that hits the wall), m.
    #[cfg_attr(feature = "clap", arg(long = "d1", value_name = "M", value_parser = sandjumper_output::parse::parse_number))]
    pub d1_m: f64,
    /// Diameter of disk 2, m.
    #[cfg_attr(feature = "clap", arg(long = "d2", value_name = "M", value_parser = sandjumper_output::parse::parse_number, required_unless_present = "wall"))]
    pub d2_m: Option<f64>,
    /// Disk 1 against a flat wall.
    #[cfg_attr(feature = "clap", arg(long))]
    pub wall: bool,
    /// Normal stiffness, N/m.
    #[cfg_attr(feature = "clap", arg(long = "kn", value_name = "N_PER_M", value_parser = sandjumper_output::parse::parse_number))]
    pub kn_n_per_m: f64,
    /// Normal damping, N s/m.
    #[cfg_attr(feature = "clap", arg(long = "damping", value_name = "N_S_PER_M", value_parser = sandjumper_output::parse::parse_number))]
    pub damping_n_s_per_m: f64,
    /// Impact speed, m/s.
    #[cfg_attr(feature = "clap", arg(long = "speed", value_name = "M_PER_S", value_parser = sandjumper_output::parse::parse_number))]
    pub speed_m_s: f64,
    /// Grain density, kg/m^3.
    #[cfg_attr(feature = "clap", arg(long = "density", value_name = "KG_M3", default_value = "1000", value_parser = sandjumper_output::parse::parse_number))]
    pub density_kg_m3: f64,
    /// Time step, s (default t_c / 50).
    #[cfg_attr(feature = "clap", arg(long = "dt", value_name = "S", value_parser = sandjumper_output::parse::parse_number))]
    pub dt_s: Option<f64>,
    /// Allow a step above t_c / 10.
    #[cfg_attr(feature = "clap", arg(long))]
    pub force_step: bool,
    /// Integrator.
    #[cfg_attr(
        feature = "clap",
        arg(long, value_enum, default_value = "velocity-verlet")
    )]
    pub integrator: Integrator,
}

impl Default for CollideRequest {
    fn default() -> Self {
        Self {
            d1_m: 0.0,
            d2_m: None,
            wall: false,
            kn_n_per_m: 0.0,
            damping_n_s_per_m: 0.0,
            speed_m_s: 0.0,
            density_kg_m3: 1000.0,
            dt_s: None,
            force_step: false,
            integrator: Integrator::VelocityVerlet,
        }
    }
}

impl CollideRequest {
    /// The collision this request names.
    pub fn collision(&self) -> Collision {
        Collision {
            d1_m: self.d1_m,
            d2_m: self.d2_m.unwrap_or(self.d1_m),
            wall: self.wall,
            kn_n_per_m: self.kn_n_per_m,
            damping_n_s_per_m: self.damping_n_s_per_m,
            speed_m_s: self.speed_m_s,
            density_kg_m3: self.density_kg_m3,
            dt_s: self.dt_s,
            integrator: self.integrator,
        }
    }
}

/// Run the collision `request` names (bad input: the parameter and what is allowed).
pub fn run(
    request: &CollideRequest,
    _progress: &dyn sandjumper_output::Progress,
) -> Result<CollisionResult, crate::error::DemError> {
    request
        .collision()
        .run(request.force_step)
        .map_err(crate::error::DemError::Input)
}

impl CollisionResult {
    /// What `dem collide --json` prints: this result as pretty JSON.
    pub fn json(&self) -> Result<String, crate::error::DemError> {
        serde_json::to_string_pretty(self).map_err(crate::error::DemError::internal)
    }
}

impl std::fmt::Display for CollisionResult {
    /// The line `dem collide` prints.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "restitution {:.6} (analytic {:.6}, error {:+.2e}), contact time {:.6e} s (analytic {:.6e} s, error {:+.2e}), effective mass {:.4e} kg, step {:.3e} s ({:.1} per contact), largest overlap {:.3e} m",
            self.restitution,
            self.restitution_analytic,
            self.restitution_error,
            self.contact_time_s,
            self.contact_time_analytic_s,
            self.contact_time_error,
            self.effective_mass_kg,
            self.dt_s,
            self.steps_per_contact,
            self.max_overlap_m
        )
    }
}
