//! TEMPORARY: the two force-law formulas the fits need, until `crate::ground` exposes them.
//! To be replaced by the ground module's functions (no second copy of the physics).

use crate::params::Params;

/// Two-resistance `F_p(z)`, N.
pub fn two_resistance_force(k1: f64, k2: f64, delta: f64, z: f64) -> f64 {
    if z <= delta {
        k1 * z
    } else {
        k1 * delta + k2 * (z - delta)
    }
}

/// `m_a(s)`, kg.
pub fn added_mass_kg(p: &Params, s: f64) -> f64 {
    let sand = &p.sand;
    let r = p.robot.foot_radius_m;
    let tan = sand.shear_band_angle_deg.to_radians().tan();
    let mu = sand.jamming_front_rate;
    let s_cone = if mu > 0.0 { (r * tan / mu).min(s) } else { s };
    let cone = s_cone * (r * r + (mu * s_cone).powi(2) / (3.0 * tan * tan) - r * mu * s_cone / tan);
    sand.packing_fraction
        * sand.grain_density_kg_m3
        * mu
        * core::f64::consts::PI
        * (cone + sand.added_mass_c_m2 * s)
}
