//! Ground force laws (docs/model.md section 3): penetration force `F_p(z)` (linear, two-resistance,
//! cone/RFT), the re-intrusion overshoot, constant drag alpha and the eq4 added mass.
//!
//! Depth `z` is measured down from the undisturbed free surface (m); `s` is depth within the
//! current intrusion episode (m). Forces in N, masses in kg.

use crate::fastmath::cubic;
use crate::params::{
    DragChoice, ModelName, ModelOverrides, Params, PenetrationChoice, ReintrusionAnchor,
    ReintrusionChoice,
};
use core::f64::consts::PI;

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
    /// The named model's ingredients (docs/model.md's table), then the overrides. `hard` ignores
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

    /// Depth at which the jammed cone is complete (`R tan theta / mu`), m; infinite when the
    /// jamming front does not grow. Below it eq. 6 keeps only its `C` term's growth.
    pub fn cone_depth_m(&self) -> f64 {
        self.cone_depth_m
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
        self.with_overshoot(self.penetration_force(z_m), z_m, anchor_m)
    }

    /// `F_p` at depth `z`, N, plus the re-intrusion overshoot of an episode anchored at
    /// `anchor_m` (see [`resisting_force`](Self::resisting_force)).
    #[inline]
    fn with_overshoot(&self, penetration_n: f64, z_m: f64, anchor_m: Option<f64>) -> f64 {
        match anchor_m {
            Some(a) if self.law.reintrusion => penetration_n + self.reintrusion_overshoot(z_m, a),
            _ => penetration_n,
        }
    }

    /// The laws of an intrusion episode that began at depth `start_m`, its overshoot anchored
    /// at `anchor_m` (see [`IntrusionEpisode`]).
    pub fn episode(&self, start_m: f64, anchor_m: Option<f64>) -> IntrusionEpisode {
        let area = self.foot_area_m2;
        // Int_0^u A_flat as a cubic in u while the cone grows, and A_flat(u), its derivative.
        let flat_integral = self.flat_area_integral_cubic();
        let flat_area = [
            flat_integral[1],
            2.0 * flat_integral[2],
            3.0 * flat_integral[3],
            0.0,
        ];
        // F_p in z on the piece that holds z_start, and where that piece ends.
        // An episode above the surface (or at a NaN depth) gets no polynomials.
        let penetration_in_z = if start_m.is_nan() || start_m < 0.0 {
            None
        } else {
            match self.law.penetration {
                PenetrationLaw::Rigid => None,
                PenetrationLaw::Linear => Some(([0.0, self.k1_n_m, 0.0, 0.0], f64::INFINITY)),
                PenetrationLaw::TwoResistance if start_m < self.delta_m => {
                    Some(([0.0, self.k1_n_m, 0.0, 0.0], self.delta_m))
                }
                PenetrationLaw::TwoResistance => Some((
                    [
                        (self.k1_n_m - self.k2_n_m) * self.delta_m,
                        self.k2_n_m,
                        0.0,
                        0.0,
                    ],
                    f64::INFINITY,
                )),
                // k1/A Int A_flat + sigma' (A z - Int A_flat) while the cone grows.
                PenetrationLaw::Cone if start_m < self.cone_depth_m => {
                    let g = self.k1_per_area - self.sigma_over_cos;
                    let mut in_z = flat_integral.map(|c| g * c);
                    in_z[1] += self.sigma_over_cos * area;
                    Some((in_z, self.cone_depth_m))
                }
                PenetrationLaw::Cone => {
                    let full = self.flat_area_integral(self.cone_depth_m);
                    let sigma_area = self.sigma_over_cos * area;
                    Some((
                        [
                            (self.k1_per_area - self.sigma_over_cos) * full,
                            sigma_area,
                            0.0,
                            0.0,
                        ],
                        f64::INFINITY,
                    ))
                }
            }
        };
        // alpha(s) and m_a(s) while the cone grows (s below its depth).
        let (drag, added_mass, drag_end_m) = match self.law.drag {
            DragLaw::ConstantAlpha => ([self.alpha_kg_m, 0.0, 0.0, 0.0], [0.0; 4], f64::INFINITY),
            // m_a = d (Int A_flat + pi C s), alpha = b dm_a/ds = b d (A_flat + pi C).
            DragLaw::AddedMass => {
                let d = self.added_mass_density;
                let b = self.drag_b * d;
                let mut drag = flat_area.map(|c| b * c);
                drag[0] += b * self.added_mass_pi_c_m2;
                let mut added_mass = flat_integral.map(|c| d * c);
                added_mass[1] += d * self.added_mass_pi_c_m2;
                (drag, added_mass, self.cone_depth_m)
            }
        };
        let (penetration, polynomial_end_m) = match penetration_in_z {
            Some((in_z, end_z)) => (
                taylor_shift(in_z, start_m),
                (end_z - start_m).min(drag_end_m),
            ),
            None => ([0.0; 4], 0.0),
        };
        IntrusionEpisode {
            start_m,
            anchor_m,
            polynomial_end_m,
            penetration,
            drag,
            added_mass,
        }
    }

    /// `Int_0^u A_flat(w) dw = pi (R^2 u - R a u^2 + a^2 u^3 / 3)` (`a` the cone rate
    /// `mu / tan theta`): its coefficients of `u^0..u^3`, m^3, valid while the cone grows
    /// (`u` below the cone's depth; everywhere when it does not grow).
    fn flat_area_integral_cubic(&self) -> [f64; 4] {
        let (r, a) = (self.foot_radius_m, self.cone_rate);
        [0.0, self.foot_area_m2, -PI * r * a, PI * a * a / 3.0]
    }

    /// `(F_p(z), alpha(s), m_a(s))` of `episode` at depth `z` (`s = z - z_start`): its
    /// polynomials inside their range, the general laws outside. N, kg/m, kg.
    #[inline]
    fn episode_laws(&self, episode: &IntrusionEpisode, z_m: f64) -> (f64, f64, f64) {
        let s = z_m - episode.start_m;
        if s >= 0.0 && s < episode.polynomial_end_m {
            (
                cubic(&episode.penetration, s),
                cubic(&episode.drag, s),
                cubic(&episode.added_mass, s),
            )
        } else {
            (
                self.penetration_force(z_m),
                self.drag_coefficient(s),
                self.added_mass(s),
            )
        }
    }

    /// What the sand does to a foot intruding at depth `z` with velocity `v` in `episode`:
    /// the resisting force `F_p_re(z) + alpha(s) v^2`, N, and the added mass `m_a(s)`, kg.
    #[inline]
    pub fn intrusion(&self, episode: &IntrusionEpisode, z_m: f64, v_m_s: f64) -> (f64, f64) {
        let (penetration, drag, added_mass) = self.episode_laws(episode, z_m);
        let resist = self.with_overshoot(penetration, z_m, episode.anchor_m) + drag * v_m_s * v_m_s;
        (resist, added_mass)
    }

    /// Added mass `m_a(s)` of a foot at depth `z` in `episode`, kg.
    #[inline]
    pub fn episode_added_mass(&self, episode: &IntrusionEpisode, z_m: f64) -> f64 {
        self.episode_laws(episode, z_m).2
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

/// One intrusion episode (docs/model.md section 3): the depth `z_start` where it began, the depth
/// its re-intrusion overshoot is anchored at, and its laws prepared as polynomials in the
/// episode depth `s = z - z_start`: `F_p(z_start + s)` and `m_a(s)` cubic, `alpha(s)` at most
/// quadratic, each the piece of its law that holds at `s = 0`. They are evaluated for
/// `0 <= s <` the end of the shortest piece (in the paper's jumps, the whole episode); outside,
/// the general laws of [`Sand`]. Built by [`Sand::episode`] at each touchdown and restart.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntrusionEpisode {
    /// Depth z_start where the episode began, m.
    start_m: f64,
    /// Depth the overshoot is anchored at (`None` before the foot has been airborne), m.
    anchor_m: Option<f64>,
    /// The polynomials hold for `0 <= s <` this, m.
    polynomial_end_m: f64,
    /// `F_p(z_start + s)`, N: coefficients of `s^0..s^3`.
    penetration: [f64; 4],
    /// `alpha(s)`, kg/m.
    drag: [f64; 4],
    /// `m_a(s)`, kg.
    added_mass: [f64; 4],
}

impl IntrusionEpisode {
    /// Depth z_start where the episode began, m.
    pub fn start_m(&self) -> f64 {
        self.start_m
    }

    /// Depth the re-intrusion overshoot is anchored at; `None` until the foot has been
    /// airborne, m.
    pub fn anchor_m(&self) -> Option<f64> {
        self.anchor_m
    }
}

/// The coefficients of `p(x0 + s)` in `s`, given those of the cubic `p(x)` in `x`.
fn taylor_shift(c: [f64; 4], x0: f64) -> [f64; 4] {
    [
        c[0] + x0 * (c[1] + x0 * (c[2] + x0 * c[3])),
        c[1] + x0 * (2.0 * c[2] + 3.0 * x0 * c[3]),
        c[2] + 3.0 * x0 * c[3],
        c[3],
    ]
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
    fn an_episodes_polynomials_agree_with_the_general_laws() {
        // Every law and override, episodes starting on each piece (at the surface, before and
        // past delta, past the full cone), with and without an anchor; depths on both sides
        // of every breakpoint and above the episode's start.
        let p = Params::preset(0.57).unwrap();
        let mut laws: Vec<GroundLaw> = [ModelName::Eq1Linear, ModelName::Eq1, ModelName::Eq4]
            .iter()
            .map(|&m| GroundLaw::resolve(m, &p.model))
            .collect();
        let mut cone_alpha = laws[2];
        cone_alpha.drag = DragLaw::ConstantAlpha;
        let mut two_added = laws[1];
        two_added.drag = DragLaw::AddedMass;
        laws.extend([cone_alpha, two_added]);
        let mut checked = 0;
        for law in laws {
            let sand = Sand::new(&p, law);
            let starts = [0.0, 0.0078, sand.delta_m + 0.002, sand.cone_depth_m + 0.001];
            for start in starts {
                for anchor in [None, Some(start)] {
                    let episode = sand.episode(start, anchor);
                    for i in -20..=1000 {
                        let z = start + i as f64 * 1e-4;
                        let v = -0.37;
                        let s = z - start;
                        let want_resist =
                            sand.resisting_force(z, anchor) + sand.drag_coefficient(s) * v * v;
                        let (resist, m_a) = sand.intrusion(&episode, z, v);
                        let scale = want_resist.abs().max(1.0);
                        assert!(
                            (resist - want_resist).abs() <= 1e-12 * scale,
                            "{law:?} from {start} m at {z} m: {resist} vs {want_resist}"
                        );
                        let want_m_a = sand.added_mass(s);
                        assert!(
                            (m_a - want_m_a).abs() <= 1e-13,
                            "{law:?} from {start} m at {z} m: m_a {m_a} vs {want_m_a}"
                        );
                        assert_eq!(sand.episode_added_mass(&episode, z), m_a);
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 40_000);
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
