//! Ground force laws (MODEL.md section 3): penetration force `F_p(z)` (linear, two-resistance,
//! cone/RFT), the re-intrusion overshoot, constant drag alpha and the eq4 added mass.
//!
//! Depth `z` is measured down from the undisturbed free surface (m); `s` is depth within the
//! current intrusion episode (m). Forces in N, masses in kg.

use crate::params::{
    DragChoice, ModelName, ModelOverrides, Params, PenetrationChoice, ReintrusionAnchor,
    ReintrusionChoice,
};

/// The penetration force law `F_p(z)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PenetrationLaw {
    /// Rigid floor at z = 0 (`F_p` infinite): the `hard` model.
    Rigid,
    /// `F_p = k1 z`.
    Linear,
    /// `k1 z` for `z <= delta`, `k1 delta + k2 (z - delta)` beyond.
    TwoResistance,
    /// RFT on the jammed cone: `dF_p/dz = (k1/A_foot) A_flat + sigma_cone (A_foot - A_flat)/cos theta`.
    Cone,
}

/// The velocity-dependent part of the ground force while intruding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DragLaw {
    /// `alpha v^2`, constant alpha.
    ConstantAlpha,
    /// eq4: `F_GM = F_p + alpha(s) v^2 - m_a(s) a`, `alpha(s) = b dm_a/ds`.
    AddedMass,
}

/// A resolved ground model: which law for each ingredient.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GroundLaw {
    /// `F_p` law.
    pub penetration: PenetrationLaw,
    /// Re-intrusion overshoot once the foot has been airborne.
    pub reintrusion: bool,
    /// Where an episode's overshoot is anchored.
    pub anchor: ReintrusionAnchor,
    /// Drag law.
    pub drag: DragLaw,
}

impl GroundLaw {
    /// The named model's ingredients (MODEL.md's table), then the overrides. `hard` ignores
    /// the overrides (there is no sand).
    pub fn resolve(model: ModelName, overrides: &ModelOverrides) -> Self {
        let (penetration, reintrusion, drag) = match model {
            ModelName::Hard => {
                return Self {
                    penetration: PenetrationLaw::Rigid,
                    reintrusion: false,
                    anchor: overrides.reintrusion_anchor,
                    drag: DragLaw::ConstantAlpha,
                };
            }
            ModelName::Eq1Linear => (PenetrationLaw::Linear, false, DragLaw::ConstantAlpha),
            ModelName::Eq1 => (PenetrationLaw::TwoResistance, true, DragLaw::ConstantAlpha),
            ModelName::Eq4 => (PenetrationLaw::Cone, true, DragLaw::AddedMass),
        };
        Self {
            penetration: match overrides.penetration {
                PenetrationChoice::Model => penetration,
                PenetrationChoice::Linear => PenetrationLaw::Linear,
                PenetrationChoice::TwoResistance => PenetrationLaw::TwoResistance,
                PenetrationChoice::Cone => PenetrationLaw::Cone,
            },
            reintrusion: match overrides.reintrusion {
                ReintrusionChoice::Model => reintrusion,
                ReintrusionChoice::On => true,
                ReintrusionChoice::Off => false,
            },
            anchor: overrides.reintrusion_anchor,
            drag: match overrides.drag {
                DragChoice::Model => drag,
                DragChoice::ConstantAlpha => DragLaw::ConstantAlpha,
                DragChoice::AddedMass => DragLaw::AddedMass,
            },
        }
    }

    /// Whether the ground is the rigid floor of the `hard` model.
    pub fn is_rigid(&self) -> bool {
        self.penetration == PenetrationLaw::Rigid
    }
}

/// The sand under the foot: force laws with their coefficients precomputed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sand {
    /// Which laws.
    pub law: GroundLaw,
    /// k1 scaled to the foot's area, N/m.
    k1_n_m: f64,
    /// k2 scaled to the foot's area, N/m.
    k2_n_m: f64,
    delta_m: f64,
    alpha_kg_m: f64,
    drag_b: f64,
    /// kappa, N/m.
    kappa_n_m: f64,
    reintrusion_length_m: f64,
    foot_radius_m: f64,
    /// pi R^2, m^2.
    foot_area_m2: f64,
    /// mu / tan theta: the flat part's radius shrinks by this per metre of depth.
    cone_rate: f64,
    /// Depth where the flat part vanishes, `R tan theta / mu`, m.
    cone_depth_m: f64,
    /// sigma_cone / cos theta, N/m^3.
    sigma_over_cos: f64,
    /// phi rho mu, kg/m^3.
    added_mass_density: f64,
    /// pi C, m^2.
    added_mass_pi_c_m2: f64,
    /// `k1 / A_foot`, N/m^3.
    k1_per_area: f64,
    /// `pi / (3 cone_rate)`, 1 (infinite when the cone does not grow).
    pi_over_3_cone_rate: f64,
    /// `1 / l_re`, 1/m.
    per_reintrusion_length: f64,
}

impl Sand {
    /// The sand of `params` under the resolved `law`.
    pub fn new(params: &Params, law: GroundLaw) -> Self {
        let s = &params.sand;
        let r = params.robot.foot_radius_m;
        let area_scale = (r / s.reference_foot_radius_m).powi(2);
        let theta = s.shear_band_angle_deg.to_radians();
        let cone_rate = s.jamming_front_rate / theta.tan();
        Self {
            law,
            k1_n_m: s.k1_n_m * area_scale,
            k2_n_m: s.k2_n_m * area_scale,
            delta_m: s.delta_m,
            alpha_kg_m: s.alpha_kg_m,
            drag_b: s.added_mass_drag_b,
            kappa_n_m: s.reintrusion_kappa_per_k1 * s.k1_n_m * area_scale,
            reintrusion_length_m: s.reintrusion_length_m,
            foot_radius_m: r,
            foot_area_m2: core::f64::consts::PI * r * r,
            cone_rate,
            cone_depth_m: if cone_rate > 0.0 {
                r / cone_rate
            } else {
                f64::INFINITY
            },
            sigma_over_cos: s.sigma_cone_n_m3 / theta.cos(),
            added_mass_density: s.packing_fraction * s.grain_density_kg_m3 * s.jamming_front_rate,
            added_mass_pi_c_m2: core::f64::consts::PI * s.added_mass_c_m2,
            k1_per_area: s.k1_n_m * area_scale / (core::f64::consts::PI * r * r),
            pi_over_3_cone_rate: core::f64::consts::PI / (3.0 * cone_rate),
            per_reintrusion_length: 1.0 / s.reintrusion_length_m,
        }
    }

    /// Area of the flat part of the jammed cone at depth `z`, m^2:
    /// `A_flat = pi (R - mu z / tan theta)^2`, 0 once `mu z >= R tan theta`.
    pub fn flat_area(&self, z_m: f64) -> f64 {
        let r = (self.foot_radius_m - self.cone_rate * z_m.max(0.0)).max(0.0);
        core::f64::consts::PI * r * r
    }

    /// `Int_0^z A_flat(u) du`, m^3 (closed form of the cone's flat-area integral).
    fn flat_area_integral(&self, z_m: f64) -> f64 {
        let r = self.foot_radius_m;
        if self.cone_rate <= 0.0 {
            // A jamming front that does not grow (mu = 0): the flat part stays the whole foot.
            return self.foot_area_m2 * z_m;
        }
        let zc = z_m.min(self.cone_depth_m);
        let rz = r - self.cone_rate * zc;
        (r * r * r - rz * rz * rz) * self.pi_over_3_cone_rate
    }

    /// Penetration force `F_p(z)`, N (0 above the surface; infinite for the rigid floor below it).
    pub fn penetration_force(&self, z_m: f64) -> f64 {
        if z_m <= 0.0 {
            return 0.0;
        }
        match self.law.penetration {
            PenetrationLaw::Rigid => f64::INFINITY,
            PenetrationLaw::Linear => self.k1_n_m * z_m,
            PenetrationLaw::TwoResistance => {
                if z_m <= self.delta_m {
                    self.k1_n_m * z_m
                } else {
                    self.k1_n_m * self.delta_m + self.k2_n_m * (z_m - self.delta_m)
                }
            }
            PenetrationLaw::Cone => {
                let flat = self.flat_area_integral(z_m);
                self.k1_per_area * flat + self.sigma_over_cos * (self.foot_area_m2 * z_m - flat)
            }
        }
    }

    /// Re-intrusion overshoot `kappa z_start exp(-(z - z_start)/l_re)`, N, for an episode
    /// anchored at `anchor_m`.
    pub fn reintrusion_overshoot(&self, z_m: f64, anchor_m: f64) -> f64 {
        let below = (z_m - anchor_m).max(0.0);
        self.kappa_n_m * anchor_m.max(0.0) * (-below * self.per_reintrusion_length).exp()
    }

    /// The force the sand resists with at depth `z` (and a static foot's holding capacity):
    /// `F_p(z)`, plus the overshoot when the episode has an anchor (`Some` once the foot has
    /// been airborne and re-intrusion is on).
    pub fn resisting_force(&self, z_m: f64, anchor_m: Option<f64>) -> f64 {
        let fp = self.penetration_force(z_m);
        match anchor_m {
            Some(a) if self.law.reintrusion => fp + self.reintrusion_overshoot(z_m, a),
            _ => fp,
        }
    }

    /// Added mass `m_a(s)`, kg: `phi rho mu pi s (R^2 + (mu s)^2/(3 tan^2 theta) - R mu s/tan theta + C)`
    /// while `mu s <= R tan theta`; beyond, only the C term keeps growing. 0 unless eq4's
    /// added-mass law is active.
    pub fn added_mass(&self, s_m: f64) -> f64 {
        if self.law.drag != DragLaw::AddedMass || s_m <= 0.0 {
            return 0.0;
        }
        // Int_0^s pi (R - a u)^2 du is the cone part; pi C s the rest.
        self.added_mass_density * (self.flat_area_integral(s_m) + self.added_mass_pi_c_m2 * s_m)
    }

    /// `dm_a/ds = phi rho mu (A_flat(s) + pi C)`, kg/m.
    pub fn added_mass_slope(&self, s_m: f64) -> f64 {
        self.added_mass_density * (self.flat_area(s_m) + self.added_mass_pi_c_m2)
    }

    /// Drag coefficient: constant alpha, or `alpha(s) = b dm_a/ds` under the added-mass law, kg/m.
    pub fn drag_coefficient(&self, s_m: f64) -> f64 {
        match self.law.drag {
            DragLaw::ConstantAlpha => self.alpha_kg_m,
            DragLaw::AddedMass => self.drag_b * self.added_mass_slope(s_m.max(0.0)),
        }
    }

    /// Depth `z0` at which `F_p(z0) = load_n` (plain `F_p`, the initial sink), m; the
    /// smallest representable depth with `F_p(z0) >= load_n`, so a foot carrying `load_n`
    /// is held. 0 for the rigid floor.
    pub fn initial_sink(&self, load_n: f64) -> f64 {
        if self.law.is_rigid() || load_n <= 0.0 {
            return 0.0;
        }
        let (mut lo, mut hi) = (0.0_f64, 1e-3_f64);
        while self.penetration_force(hi) < load_n {
            hi *= 2.0;
            if hi > 1e3 {
                return hi;
            }
        }
        while hi - lo > f64::EPSILON * hi {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if self.penetration_force(mid) >= load_n {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sand(model: ModelName) -> Sand {
        let p = Params::preset(0.57).unwrap();
        Sand::new(&p, GroundLaw::resolve(model, &p.model))
    }

    #[test]
    fn cone_force_matches_numerical_integral_of_its_slope() {
        let s = sand(ModelName::Eq4);
        let (k1, sig, a) = (s.k1_n_m, s.sigma_over_cos, s.foot_area_m2);
        let n = 200_000;
        let z_end = 0.06;
        let dz = z_end / n as f64;
        let mut f = 0.0;
        for i in 0..n {
            let z = (i as f64 + 0.5) * dz;
            let flat = s.flat_area(z);
            f += (k1 / a * flat + sig * (a - flat)) * dz;
        }
        assert!(
            (f - s.penetration_force(z_end)).abs() < 1e-6 * f,
            "{f} vs {}",
            s.penetration_force(z_end)
        );
    }

    #[test]
    fn added_mass_reaches_about_five_foot_masses_at_full_cone() {
        let s = sand(ModelName::Eq4);
        let m = s.added_mass(s.cone_depth_m);
        assert!((0.14..0.16).contains(&m), "m_a at full cone = {m} kg");
        // Slope is the derivative of m_a.
        let h = 1e-7;
        for s_m in [0.001, 0.01, 0.03, 0.05] {
            let num = (s.added_mass(s_m + h) - s.added_mass(s_m - h)) / (2.0 * h);
            assert!((num - s.added_mass_slope(s_m)).abs() < 1e-5 * num);
        }
    }

    #[test]
    fn a_cone_that_does_not_grow_leaves_a_flat_foot() {
        // mu = 0 is allowed (non-negative): the flat part stays the whole foot, F_p = k1 z,
        // and no grains join the foot (the added mass grows with mu).
        let mut p = Params::preset(0.57).unwrap();
        p.sand.jamming_front_rate = 0.0;
        let s = Sand::new(&p, GroundLaw::resolve(ModelName::Eq4, &p.model));
        for z in [0.0, 0.004, 0.03, 0.2] {
            let f = s.penetration_force(z);
            assert!(
                (f - s.k1_n_m * z).abs() <= 1e-12 * f.max(1.0),
                "F_p({z}) = {f}"
            );
            assert_eq!(s.added_mass(z), 0.0);
        }
    }

    #[test]
    fn two_resistance_changes_slope_at_delta() {
        let s = sand(ModelName::Eq1);
        let d = s.delta_m;
        assert!((s.penetration_force(d) - s.k1_n_m * d).abs() < 1e-12);
        let slope = (s.penetration_force(d + 0.01) - s.penetration_force(d)) / 0.01;
        assert!((slope - s.k2_n_m).abs() < 1e-9);
    }

    #[test]
    fn initial_sink_holds_the_load() {
        let s = sand(ModelName::Eq4);
        let z0 = s.initial_sink(12.5);
        assert!(s.penetration_force(z0) >= 12.5);
        assert!(s.penetration_force(z0 * (1.0 - 1e-12)) < 12.5 + 1e-9);
    }
}
