//! `fit intrusion`: the quasi-static penetration force from slow-intrusion tests (docs/model.md
//! section 6: rod driven at constant slow speed, force from the motor current, depth from
//! the encoder).
//!
//! - First intrusion (from the free surface): the two-resistance law
//!   `F_p = k1 z` for `z <= delta`, `k1 delta + k2 (z - delta)` beyond; fits `k1`, `k2`, `delta`.
//! - Re-intrusion (the foot comes back down into sand it has already compacted, from depth
//!   `z_start`): `F_p_re(z) = F_p(z) + kappa z_start exp(-(z - z_start)/l_re)` with `F_p` the
//!   two-resistance law of the base parameters (`--params`/`--phi`, e.g. the output of a
//!   first-intrusion fit); fits `kappa` and `l_re`.
//!
//! Stiffnesses scale with foot area (docs/model.md): values fitted with the robot's foot of radius
//! `R` are written to the params file for the reference radius `R_ref`, i.e. divided by
//! `(R / R_ref)^2` (a factor 1 with the default foot).

use std::path::Path;

use super::FitError;
use super::data::{DepthCurve, read_depth_curve};
use super::least_squares::fit_positive;
use super::report::{FitReport, FittedValue, Override};
use sandjumper_model::ground::{DragLaw, GroundLaw, PenetrationLaw, Sand};
use sandjumper_model::params::Params;

/// Fewest points for a first-intrusion fit (three parameters and a residual variance).
pub const MIN_POINTS_FIRST: usize = 8;
/// Fewest points for a re-intrusion fit (two parameters).
pub const MIN_POINTS_RE: usize = 6;
/// Auto-detection: a curve whose first depth exceeds this starts inside compacted sand and
/// is taken as a re-intrusion curve, m.
pub const REINTRUSION_START_THRESHOLD_M: f64 = 0.002;

/// Which kind of intrusion curve a file holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveKind {
    /// Decide from the first depth ([`REINTRUSION_START_THRESHOLD_M`]).
    Auto,
    /// A first intrusion from the free surface.
    First,
    /// A re-intrusion starting at the curve's first depth (or `--z-start`).
    Re,
}

/// Area scaling of stiffnesses: `(R / R_ref)^2`.
fn area_factor(params: &Params) -> f64 {
    (params.robot.foot_radius_m / params.sand.reference_foot_radius_m).powi(2)
}

/// The two-resistance sand of `params` (with the re-intrusion overshoot), with the foot's
/// own stiffnesses `k1`, `k2` (N/m, already scaled to its area) and `delta` replaced.
fn two_resistance_sand(params: &Params, k1: f64, k2: f64, delta: f64) -> Sand {
    let mut p = params.clone();
    let scale = area_factor(params);
    p.sand.k1_n_m = k1 / scale;
    p.sand.k2_n_m = k2 / scale;
    p.sand.delta_m = delta;
    let law = GroundLaw {
        penetration: PenetrationLaw::TwoResistance,
        reintrusion: true,
        anchor: params.model.reintrusion_anchor,
        drag: DragLaw::ConstantAlpha,
    };
    Sand::new(&p, law)
}

/// Fit the curve in `path` as `kind` says; `params` gives the foot radius and, for a
/// re-intrusion, the base `F_p`.
pub fn fit_intrusion_file(
    path: &Path,
    kind: CurveKind,
    params: &Params,
    z_start_m: Option<f64>,
) -> Result<FitReport, FitError> {
    let min = match kind {
        CurveKind::First => MIN_POINTS_FIRST,
        CurveKind::Re | CurveKind::Auto => MIN_POINTS_RE,
    };
    let curve = read_depth_curve(path, "force_n", min)?;
    let first_depth = curve.depth_m[0];
    let (is_re, how) = match kind {
        CurveKind::First => (false, "first intrusion (as requested)".to_string()),
        CurveKind::Re => (true, "re-intrusion (as requested)".to_string()),
        CurveKind::Auto if first_depth > REINTRUSION_START_THRESHOLD_M => (
            true,
            format!(
                "re-intrusion (auto-detected: the curve starts at depth {:.1} mm > {:.1} mm)",
                1e3 * first_depth,
                1e3 * REINTRUSION_START_THRESHOLD_M
            ),
        ),
        CurveKind::Auto => (
            false,
            format!(
                "first intrusion (auto-detected: the curve starts at depth {:.1} mm <= {:.1} mm)",
                1e3 * first_depth,
                1e3 * REINTRUSION_START_THRESHOLD_M
            ),
        ),
    };
    let mut report = if is_re {
        fit_reintrusion(&curve, params, z_start_m.unwrap_or(first_depth))
    } else {
        if curve.len() < MIN_POINTS_FIRST {
            return Err(FitError::data(
                path,
                None,
                format!("{} data rows; at least {MIN_POINTS_FIRST} are needed for a first-intrusion fit", curve.len()),
            ));
        }
        fit_first_intrusion(&curve, params)
    }
    .map_err(|e| e.in_file(path))?;
    report.notes.insert(0, format!("curve: {how}"));
    Ok(report)
}

/// Least-squares slope of a line through the origin.
fn slope_through_origin(x: &[f64], y: &[f64]) -> f64 {
    let sxy: f64 = x.iter().zip(y).map(|(x, y)| x * y).sum();
    let sxx: f64 = x.iter().map(|x| x * x).sum();
    sxy / sxx
}

/// Least-squares line `y = a + b x`: (a, b).
fn line(x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = x.iter().map(|x| (x - mx).powi(2)).sum();
    let b = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    (my - b * mx, b)
}

/// Fit `k1`, `k2`, `delta` of the two-resistance law to a first-intrusion curve.
pub fn fit_first_intrusion(curve: &DepthCurve, params: &Params) -> Result<FitReport, FitError> {
    let (z, f) = (&curve.depth_m, &curve.value);
    let n = z.len();
    // Initial guess: a line through the origin on the shallow third, a free line on the deep
    // third, delta where they cross.
    let third = (n / 3).max(2);
    let k1_0 = slope_through_origin(&z[..third], &f[..third]);
    let (a, k2_line) = line(&z[n - third..], &f[n - third..]);
    let span = (z[0], z[n - 1]);
    let mid = 0.5 * (span.0 + span.1);
    let (k2_0, delta_0) = if k1_0 > 0.0 && k2_line > 0.0 && (k1_0 - k2_line).abs() > 1e-9 * k1_0 {
        let d = a / (k1_0 - k2_line);
        (k2_line, if d > span.0 && d < span.1 { d } else { mid })
    } else {
        (k1_0.abs().max(1.0), mid)
    };
    if k1_0.is_nan() || k1_0 <= 0.0 {
        return Err(FitError::Fit(format!(
            "the force does not rise with depth near the surface (initial slope {k1_0:.3e} N/m); \
             allowed: a penetration force that grows with depth"
        )));
    }
    let model = |x: &[f64]| -> Result<Vec<f64>, String> {
        let sand = two_resistance_sand(params, x[0], x[1], x[2]);
        Ok(z.iter()
            .zip(f)
            .map(|(z, f)| sand.penetration_force(*z) - f)
            .collect())
    };
    let fit = fit_positive(&model, &[k1_0, k2_0, delta_0])
        .map_err(|e| FitError::from_least_squares(e, &["k1", "k2", "delta"]))?;
    let mut notes = Vec::new();
    if fit.values[2] >= span.1 {
        notes.push(format!(
            "delta = {:.1} mm lies beyond the deepest point ({:.1} mm): k2 is extrapolated",
            1e3 * fit.values[2],
            1e3 * span.1
        ));
    }
    let scale = area_factor(params);
    if (scale - 1.0).abs() > 1e-12 {
        notes.push(format!(
            "stiffnesses written for the reference foot radius {} m (divided by (R/R_ref)^2 = {scale:.4})",
            params.sand.reference_foot_radius_m
        ));
    }
    let value = |i: usize, param: &'static str, unit: &'static str| {
        FittedValue::from_fit(&fit, i, None, param, unit)
    };
    Ok(FitReport {
        title: format!("two-resistance law F_p(z), first intrusion, {n} points"),
        fits: vec![
            value(0, "k1", "N/m"),
            value(1, "k2", "N/m"),
            value(2, "delta", "m"),
        ],
        residual_rms: fit.residual_rms,
        residual_unit: "N",
        points_used: n,
        points_excluded: 0,
        notes,
        overrides: vec![(
            None,
            vec![
                Override::new("sand.k1_n_m", fit.values[0] / scale),
                Override::new("sand.k2_n_m", fit.values[1] / scale),
                Override::new("sand.delta_m", fit.values[2]),
            ],
        )],
    })
}

/// Fit `kappa` (N/m) and `l_re` (m) of the re-intrusion overshoot to a curve that starts at
/// depth `z_start_m`; the base `F_p` is the two-resistance law of `params`. Points shallower
/// than `z_start_m` are left out.
pub fn fit_reintrusion(
    curve: &DepthCurve,
    params: &Params,
    z_start_m: f64,
) -> Result<FitReport, FitError> {
    let scale = area_factor(params);
    let s = &params.sand;
    let (k1, k2, delta) = (s.k1_n_m * scale, s.k2_n_m * scale, s.delta_m);
    if z_start_m.is_nan() || z_start_m <= 0.0 {
        return Err(FitError::Fit(format!(
            "re-intrusion start depth z_start = {z_start_m} m; allowed: > 0 (the overshoot is kappa z_start)"
        )));
    }
    let used: Vec<(f64, f64)> = curve
        .depth_m
        .iter()
        .zip(&curve.value)
        .filter(|(z, _)| **z >= z_start_m)
        .map(|(z, f)| (*z, *f))
        .collect();
    let excluded = curve.len() - used.len();
    if used.len() < MIN_POINTS_RE {
        return Err(FitError::Fit(format!(
            "{} points at or below z_start = {:.2} mm; at least {MIN_POINTS_RE} are needed",
            used.len(),
            1e3 * z_start_m
        )));
    }
    let base_sand = two_resistance_sand(params, k1, k2, delta);
    let base = |z: f64| base_sand.penetration_force(z);
    let excess: Vec<f64> = used.iter().map(|(z, f)| f - base(*z)).collect();
    if excess[0].is_nan() || excess[0] <= 0.0 {
        return Err(FitError::Fit(format!(
            "no overshoot: at z_start the force is {:.3} N, not above the base F_p = {:.3} N \
             (allowed: a re-intrusion curve that starts above the first-intrusion law; check --params/--phi)",
            used[0].1,
            base(used[0].0)
        )));
    }
    let kappa_0 = excess[0] / z_start_m;
    let l_0 = used
        .iter()
        .zip(&excess)
        .find(|(_, e)| **e < excess[0] / core::f64::consts::E)
        .map_or(0.005, |((z, _), _)| (z - z_start_m).max(1e-4));
    // x = (kappa in N/m for this foot, l_re in m).
    let model = |x: &[f64]| -> Result<Vec<f64>, String> {
        let mut p = params.clone();
        p.sand.reintrusion_kappa_per_k1 = x[0] / k1;
        p.sand.reintrusion_length_m = x[1];
        let sand = two_resistance_sand(&p, k1, k2, delta);
        Ok(used
            .iter()
            .map(|(z, f)| sand.resisting_force(*z, Some(z_start_m)) - f)
            .collect())
    };
    let fit = fit_positive(&model, &[kappa_0, l_0])
        .map_err(|e| FitError::from_least_squares(e, &["kappa", "l_re"]))?;
    let (kappa, l_re) = (fit.values[0], fit.values[1]);
    let notes = vec![
        format!(
            "base F_p: two-resistance k1 = {k1:.1} N/m, k2 = {k2:.1} N/m, delta = {:.2} mm (from --params/--phi)",
            1e3 * delta
        ),
        format!(
            "z_start = {:.2} mm; written as sand.reintrusion_kappa_per_k1 = kappa / k1 = {:.4}",
            1e3 * z_start_m,
            kappa / k1
        ),
    ];
    Ok(FitReport {
        title: format!(
            "re-intrusion overshoot kappa z_start exp(-(z - z_start)/l_re), {} points",
            used.len()
        ),
        fits: vec![
            FittedValue::from_fit(&fit, 0, None, "kappa", "N/m"),
            FittedValue::from_fit(&fit, 1, None, "l_re", "m"),
        ],
        residual_rms: fit.residual_rms,
        residual_unit: "N",
        points_used: used.len(),
        points_excluded: excluded,
        notes,
        overrides: vec![(
            None,
            vec![
                Override::new("sand.reintrusion_kappa_per_k1", kappa / k1),
                Override::new("sand.reintrusion_length_m", l_re),
            ],
        )],
    })
}
