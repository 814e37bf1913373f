//! `fit added-mass`: the jamming-front rate `mu` and the constant `C` of docs/model.md's added
//! mass `m_a(s) = phi rho mu pi s (R^2 + (mu s)^2/(3 tan^2 theta) - R mu s / tan theta + C)`
//! (only the `C` term keeps growing once `mu s > R tan theta`), from added mass against
//! episode depth `s` (e.g. from PIV, `m_a = P / v_foot`). `phi`, `rho`, `R`, `theta` come from
//! the base parameters (`--phi`, `--params`).
//!
//! The singular low-speed end: `m_a = P / v_foot` diverges as the foot comes to rest at the
//! bottom of its stroke, so the paper fitted only the part of the stroke where the foot still
//! moves. With depth alone in the file, the rule is: leave out the deepest
//! `exclude_deepest` fraction of the depth range (default [`DEFAULT_EXCLUDE_DEEPEST`]),
//! i.e. points with `s > s_max - f (s_max - s_min)`. `--exclude-deepest 0` keeps every point.

use std::path::Path;

use super::FitError;
use super::data::read_depth_curve;
use super::least_squares::fit_positive;
use super::report::{FitReport, FittedValue, Override};
use sandjumper_model::ground::{DragLaw, GroundLaw, PenetrationLaw, Sand};
use sandjumper_model::params::Params;

/// Default fraction of the depth range left out at the deep (slow, singular) end.
pub const DEFAULT_EXCLUDE_DEEPEST: f64 = 0.15;
/// Fewest points kept for the fit (two parameters).
pub const MIN_POINTS: usize = 6;

/// `m_a(s)` of `params` with `mu` and `C` replaced, kg.
fn model_added_mass(params: &Params, mu: f64, c_m2: f64, s_m: f64) -> f64 {
    let mut p = params.clone();
    p.sand.jamming_front_rate = mu;
    p.sand.added_mass_c_m2 = c_m2;
    let law = GroundLaw {
        penetration: PenetrationLaw::Cone,
        reintrusion: false,
        anchor: params.model.reintrusion_anchor,
        drag: DragLaw::AddedMass,
    };
    Sand::new(&p, law).added_mass(s_m)
}

/// Fit `mu` and `C` to the file at `path` (`depth_m,added_mass_kg`).
pub fn fit_added_mass_file(
    path: &Path,
    params: &Params,
    exclude_deepest: f64,
) -> Result<FitReport, FitError> {
    if !(0.0..1.0).contains(&exclude_deepest) {
        return Err(FitError::Fit(format!(
            "--exclude-deepest {exclude_deepest}: allowed 0 <= fraction < 1"
        )));
    }
    let curve = read_depth_curve(path, "added_mass_kg", MIN_POINTS)?;
    let (s_min, s_max) = (curve.depth_m[0], curve.depth_m[curve.len() - 1]);
    let cut = s_max - exclude_deepest * (s_max - s_min);
    let used: Vec<(f64, f64)> = curve
        .depth_m
        .iter()
        .zip(&curve.value)
        .filter(|(s, _)| exclude_deepest == 0.0 || **s <= cut)
        .map(|(s, m)| (*s, *m))
        .collect();
    let excluded = curve.len() - used.len();
    if used.len() < MIN_POINTS {
        return Err(FitError::data(
            path,
            None,
            format!(
                "{} points left after excluding the deepest {:.0}% of the depth range; at least {MIN_POINTS} are needed",
                used.len(),
                100.0 * exclude_deepest
            ),
        ));
    }
    let model = |x: &[f64]| -> Result<Vec<f64>, String> {
        Ok(used
            .iter()
            .map(|(s, m)| model_added_mass(params, x[0], x[1], *s) - m)
            .collect())
    };
    let initial = [
        params.sand.jamming_front_rate.max(0.1),
        params.sand.added_mass_c_m2.max(1e-5),
    ];
    let fit = fit_positive(&model, &initial)
        .map_err(|e| FitError::from_least_squares(e, &["mu", "C"]).in_file(path))?;
    let phi = params.sand.packing_fraction;
    let mut notes = vec![format!(
        "phi = {phi}, rho = {} kg/m^3, R = {} m, theta = {} deg from --phi/--params",
        params.sand.grain_density_kg_m3,
        params.robot.foot_radius_m,
        params.sand.shear_band_angle_deg
    )];
    if excluded > 0 {
        notes.push(format!(
            "left out the singular low-speed end: {excluded} points deeper than {:.2} mm \
             (deepest {:.0}% of the depth range, --exclude-deepest)",
            1e3 * cut,
            100.0 * exclude_deepest
        ));
    }
    Ok(FitReport {
        title: format!("added mass m_a(s), {} points", used.len()),
        fits: vec![
            FittedValue::from_fit(&fit, 0, Some(phi), "mu", ""),
            FittedValue::from_fit(&fit, 1, Some(phi), "C", "m^2"),
        ],
        residual_rms: fit.residual_rms,
        residual_unit: "kg",
        points_used: used.len(),
        points_excluded: excluded,
        notes,
        overrides: vec![(
            None,
            vec![
                Override::new("sand.jamming_front_rate", fit.values[0]),
                Override::new("sand.added_mass_c_m2", fit.values[1]),
            ],
        )],
    })
}
