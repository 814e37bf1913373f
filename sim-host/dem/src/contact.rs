//! The contact law between two disks (or a disk and a wall): a Hookean spring on the overlap
//! with a viscous dashpot on the normal closing speed (Supplementary I), and optionally
//! tangential friction with history (Cundall-Strack, capped by Coulomb), as LAMMPS's
//! `gran/hooke/history` does it.
//!
//! Normal force on a pair with overlap `delta` (m) and closing speed `v_n` (m/s):
//! `F_n = k_n delta + gamma v_n` (N), not clamped at zero, so a pair keeps the analytic
//! spring-dashpot values (`t_c`, `e`) that [`SpringDashpot`] states; LAMMPS's `gran/hooke`
//! does the same.

use serde::{Deserialize, Serialize};

/// How the normal dashpot `gamma` (N s/m) is set for a pair of effective mass `m_eff`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Damping {
    /// One `gamma`, N s/m, for every pair (Supplementary I; `dem collide --damping`).
    Force {
        /// N s/m.
        gamma_n_s_per_m: f64,
    },
    /// The same coefficient of restitution for every pair, whatever its masses:
    /// `gamma = 2 sqrt(k_n m_eff) (-ln e) / sqrt(pi^2 + ln^2 e)`.
    Restitution {
        /// Coefficient of restitution, 0 < e <= 1.
        e: f64,
    },
    /// LAMMPS's `gran/hooke` convention: `gamma = m_eff gamma_n`.
    PerMass {
        /// 1/s.
        gamma_n_per_s: f64,
    },
}

/// Tangential friction with history: a spring `k_t` on the accumulated tangential slip, a
/// dashpot, and the Coulomb cap `|F_t| <= mu F_n`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Friction {
    /// Coulomb friction coefficient (grain-grain).
    pub mu: f64,
    /// Coulomb friction coefficient between a grain and a wall.
    pub mu_wall: f64,
    /// Tangential stiffness as a share of `k_n` (2/7 is usual).
    pub kt_over_kn: f64,
    /// Tangential damping as a share of the normal `gamma` (LAMMPS: 1/2).
    pub gammat_over_gamman: f64,
}

impl Default for Friction {
    fn default() -> Self {
        Self {
            mu: 0.5,
            mu_wall: 0.5,
            kt_over_kn: 2.0 / 7.0,
            gammat_over_gamman: 0.5,
        }
    }
}

/// `gamma_n` as a function of the effective mass, with constants worked out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GammaRule {
    /// The same for every pair, N s/m.
    Constant(f64),
    /// `c sqrt(m_eff)`, c in N s/(m kg^0.5) (a fixed restitution).
    SqrtMass(f64),
    /// `gamma_n m_eff`, 1/s (LAMMPS's).
    PerMass(f64),
}

impl GammaRule {
    /// `gamma_n` for effective mass `m_eff_kg`, N s/m.
    #[inline(always)]
    pub fn at(self, m_eff_kg: f64) -> f64 {
        match self {
            Self::Constant(g) => g,
            Self::SqrtMass(c) => c * m_eff_kg.sqrt(),
            Self::PerMass(g) => g * m_eff_kg,
        }
    }
}

/// The contact law of a run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactLaw {
    /// Normal stiffness, N/m.
    pub kn_n_per_m: f64,
    /// Normal damping.
    pub damping: Damping,
    /// Tangential friction (None: frictionless, the paper's model).
    pub friction: Option<Friction>,
}

impl ContactLaw {
    /// The factor `c` with `gamma = c sqrt(k_n m_eff)` under [`Damping::Restitution`].
    fn restitution_factor(e: f64) -> f64 {
        let l = e.ln();
        2.0 * (-l) / (core::f64::consts::PI * core::f64::consts::PI + l * l).sqrt()
    }

    /// Normal damping `gamma` for a pair of effective mass `m_eff_kg`, N s/m.
    #[inline]
    pub fn gamma_n(&self, m_eff_kg: f64) -> f64 {
        match self.damping {
            Damping::Force { gamma_n_s_per_m } => gamma_n_s_per_m,
            Damping::Restitution { e } => {
                Self::restitution_factor(e) * (self.kn_n_per_m * m_eff_kg).sqrt()
            }
            Damping::PerMass { gamma_n_per_s } => gamma_n_per_s * m_eff_kg,
        }
    }

    /// `gamma_n` when it does not depend on the pair ([`Damping::Force`], the paper's).
    #[inline]
    pub fn constant_gamma_n(&self) -> Option<f64> {
        match self.damping {
            Damping::Force { gamma_n_s_per_m } => Some(gamma_n_s_per_m),
            _ => None,
        }
    }

    /// [`Self::gamma_n`] with the restitution's factor worked out once (for a step's inner
    /// loop).
    pub fn gamma_rule(&self) -> GammaRule {
        match self.damping {
            Damping::Force { gamma_n_s_per_m } => GammaRule::Constant(gamma_n_s_per_m),
            Damping::Restitution { e } => {
                GammaRule::SqrtMass(Self::restitution_factor(e) * self.kn_n_per_m.sqrt())
            }
            Damping::PerMass { gamma_n_per_s } => GammaRule::PerMass(gamma_n_per_s),
        }
    }

    /// The pair's spring-dashpot.
    pub fn pair(&self, m_eff_kg: f64) -> SpringDashpot {
        SpringDashpot {
            k_n_per_m: self.kn_n_per_m,
            gamma_n_s_per_m: self.gamma_n(m_eff_kg),
            m_eff_kg,
        }
    }

    /// Check the law for pairs whose effective masses lie in `m_eff_kg` (smallest, largest):
    /// positive stiffness, non-negative damping that leaves every pair underdamped (it
    /// bounces: `gamma < 2 sqrt(k m_eff)`), friction coefficients not negative.
    pub fn check(&self, m_eff_kg: (f64, f64)) -> Result<(), String> {
        let k = self.kn_n_per_m;
        if !(k.is_finite() && k > 0.0) {
            return Err(format!(
                "normal stiffness {k} N/m (allowed: a positive number)"
            ));
        }
        match self.damping {
            Damping::Force { gamma_n_s_per_m: g } if !(g.is_finite() && g >= 0.0) => {
                return Err(format!("damping {g} N s/m (allowed: 0 or more)"));
            }
            Damping::Restitution { e } if !(e > 0.0 && e <= 1.0) => {
                return Err(format!("restitution {e} (allowed: 0 < e <= 1)"));
            }
            Damping::PerMass { gamma_n_per_s: g } if !(g.is_finite() && g >= 0.0) => {
                return Err(format!("damping {g} 1/s (allowed: 0 or more)"));
            }
            _ => {}
        }
        for m in [m_eff_kg.0, m_eff_kg.1] {
            let p = self.pair(m);
            if !p.underdamped() {
                return Err(format!(
                    "damping {:.4e} N s/m overdamps a pair of effective mass {:.4e} kg: the \
                     limit is critical damping 2 sqrt(k m_eff) = {:.4e} N s/m (allowed: below it, \
                     so that grains bounce apart)",
                    p.gamma_n_s_per_m,
                    m,
                    p.critical_damping()
                ));
            }
        }
        if let Some(f) = self.friction {
            for (name, v) in [
                ("friction coefficient", f.mu),
                ("wall friction coefficient", f.mu_wall),
                ("k_t / k_n", f.kt_over_kn),
                ("gamma_t / gamma_n", f.gammat_over_gamman),
            ] {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(format!("{name} {v} (allowed: 0 or more)"));
                }
            }
        }
        Ok(())
    }
}

/// One spring-dashpot pair and its analytic head-on collision (docs/model.md section 7).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SpringDashpot {
    /// Stiffness, N/m.
    pub k_n_per_m: f64,
    /// Damping, N s/m.
    pub gamma_n_s_per_m: f64,
    /// Effective mass `m1 m2 / (m1 + m2)` (a wall: the disk's mass), kg.
    pub m_eff_kg: f64,
}

impl SpringDashpot {
    /// Damping at which the pair stops bouncing, `2 sqrt(k m_eff)`, N s/m.
    pub fn critical_damping(&self) -> f64 {
        2.0 * (self.k_n_per_m * self.m_eff_kg).sqrt()
    }

    /// Whether the pair bounces (`gamma` below critical).
    pub fn underdamped(&self) -> bool {
        self.gamma_n_s_per_m < self.critical_damping()
    }

    /// Duration of a contact, `t_c = pi / sqrt(k/m - (gamma/2m)^2)`, s.
    pub fn contact_time_s(&self) -> f64 {
        let w0 = self.k_n_per_m / self.m_eff_kg;
        let b = self.gamma_n_s_per_m / (2.0 * self.m_eff_kg);
        core::f64::consts::PI / (w0 - b * b).sqrt()
    }

    /// Coefficient of restitution, `e = exp(-gamma t_c / 2m)`.
    pub fn restitution(&self) -> f64 {
        (-self.gamma_n_s_per_m * self.contact_time_s() / (2.0 * self.m_eff_kg)).exp()
    }

    /// Largest overlap of a head-on impact at `speed_m_s` without damping,
    /// `v sqrt(m_eff / k)`, m (an upper bound with damping).
    pub fn max_overlap_m(&self, speed_m_s: f64) -> f64 {
        speed_m_s * (self.m_eff_kg / self.k_n_per_m).sqrt()
    }
}

/// The stiffness that gives an undamped head-on overlap `overlap_m` at `speed_m_s` for
/// effective mass `m_eff_kg`: `k = m_eff (v / delta)^2`, N/m.
pub fn stiffness_for_overlap(m_eff_kg: f64, speed_m_s: f64, overlap_m: f64) -> f64 {
    m_eff_kg * (speed_m_s / overlap_m).powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn restitution_damping_gives_the_stated_restitution_for_any_mass() {
        for e in [0.1, 0.5, 0.9] {
            let law = ContactLaw {
                kn_n_per_m: 1.0e3,
                damping: Damping::Restitution { e },
                friction: None,
            };
            for m in [1e-7, 1e-6, 3e-5] {
                let r = law.pair(m).restitution();
                assert!((r - e).abs() < 1e-12, "e {e} m {m}: {r}");
            }
        }
    }

    #[test]
    fn overdamped_pairs_are_refused_with_the_limit() {
        let law = ContactLaw {
            kn_n_per_m: 100.0,
            damping: Damping::Force {
                gamma_n_s_per_m: 0.02,
            },
            friction: None,
        };
        // critical for 1e-6 kg: 2 sqrt(1e-4) = 0.02
        let err = law.check((1e-6, 1e-5)).unwrap_err();
        assert!(err.contains("critical damping"), "{err}");
        assert!(law.check((2e-6, 1e-5)).is_ok());
    }
}
