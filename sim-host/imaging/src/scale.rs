//! The camera's scale from the encoder: metres per pixel measured on the rig itself.
//!
//! Procedure (docs/imaging.md): lift the robot so the foot hangs free, clamp the motor's
//! carriage to the frame, and command a slow move of the motor relative to the rod (a ramp of
//! a few millimetres, slower than ~10 mm/s so the frames are not blurred) while the camera
//! records. With the carriage clamped the rod, and the ball on it, moves by exactly `-dp`:
//! the encoder measures `p = x_m - x_r` in metres, the camera the ball's image row in pixels,
//! and the slope of row against `p` is `1 / (m per px)`. Image rows grow downward and the rod
//! goes down as `p` grows, so the slope is positive; a negative one means the rod was not the
//! part that moved (the rod clamped and the camera on the carriage, say) and is reported.

use serde::Serialize;

/// A scale fitted from `(p, row)` pairs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScaleFit {
    /// The scale, metres per pixel.
    pub m_per_px: f64,
    /// Slope of the ball's row against `p`, px/m.
    pub slope_px_per_m: f64,
    /// Coefficient of determination of the straight line.
    pub r_squared: f64,
    /// RMS of the residuals, px.
    pub residual_rms_px: f64,
    /// Frames in the fit.
    pub frames_used: usize,
    /// Range of `p` covered, m.
    pub travel_m: f64,
    /// Whether the ball moved down as `p` grew (the expected direction).
    pub direction_ok: bool,
}

/// Least travel of the motor for a scale, m.
pub const MIN_TRAVEL_M: f64 = 2e-3;
/// Fewest frames for a scale.
pub const MIN_FRAMES: usize = 5;

/// Fit the ball's image row (px) against the motor position `p` (m), by least squares.
pub fn fit_scale(pairs: &[(f64, f64)]) -> Result<ScaleFit, String> {
    if pairs.len() < MIN_FRAMES {
        return Err(format!(
            "{} frames with the ball measured (allowed: at least {MIN_FRAMES})",
            pairs.len()
        ));
    }
    let n = pairs.len() as f64;
    let (lo, hi) = pairs
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), &(p, _)| {
            (lo.min(p), hi.max(p))
        });
    if hi - lo < MIN_TRAVEL_M {
        return Err(format!(
            "the motor moved {:.3} mm relative to the rod during the frames (allowed: at least {} mm: command a slow ramp)",
            1e3 * (hi - lo),
            1e3 * MIN_TRAVEL_M
        ));
    }
    let mp = pairs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pairs.iter().map(|p| p.1).sum::<f64>() / n;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for &(p, y) in pairs {
        sxx += (p - mp) * (p - mp);
        sxy += (p - mp) * (y - my);
        syy += (y - my) * (y - my);
    }
    let slope = sxy / sxx;
    if slope == 0.0 || !slope.is_finite() {
        return Err("the ball did not move with the motor: no scale".into());
    }
    let ss_res: f64 = pairs
        .iter()
        .map(|&(p, y)| (y - my - slope * (p - mp)).powi(2))
        .sum();
    Ok(ScaleFit {
        m_per_px: 1.0 / slope.abs(),
        slope_px_per_m: slope,
        r_squared: if syy > 0.0 { 1.0 - ss_res / syy } else { 0.0 },
        residual_rms_px: (ss_res / n).sqrt(),
        frames_used: pairs.len(),
        travel_m: hi - lo,
        direction_ok: slope > 0.0,
    })
}
