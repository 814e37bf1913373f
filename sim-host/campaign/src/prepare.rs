//! Bed preparation, closed loop: fluidize -> settle -> measure the height (averaged over
//! the bed) -> `phi = m / (rho A h)`; below the target, compact one dose and measure again;
//! past it (overshoot), fluidize again; after `max_attempts` measurements without a hit,
//! the point fails with a named reason.

use serde::{Deserialize, Serialize};

use super::bed::BedApparatus;
use super::file::BedSettings;

/// One measurement during a preparation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Measurement {
    /// Mean height, m.
    pub height_m: f64,
    /// Packing fraction from it.
    pub phi: f64,
    /// What followed: `accept`, `compact`, `refluidize` or `give-up`.
    pub action: String,
}

/// How a preparation went.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Preparation {
    /// Target phi.
    pub target_phi: f64,
    /// Last measured phi (the achieved one when `ok`).
    pub achieved_phi: f64,
    /// Measurements taken.
    pub attempts: u32,
    /// Fluidizations.
    pub fluidizations: u32,
    /// Compaction doses.
    pub doses: u32,
    /// Whether the target was reached within tolerance.
    pub ok: bool,
    /// Why not, when not.
    pub failure: Option<String>,
    /// Every measurement.
    pub measurements: Vec<Measurement>,
}

/// `phi` of a bed of height `h_m`.
pub fn phi_of_height(b: &BedSettings, h_m: f64) -> f64 {
    b.grain_mass_kg / (b.grain_density_kg_m3 * b.area_m2 * h_m)
}

/// Prepare `bed` to `target_phi` per `b`.
pub fn prepare(
    bed: &mut dyn BedApparatus,
    b: &BedSettings,
    target_phi: f64,
) -> Result<Preparation, String> {
    let tol = *b.tolerance.get_ref();
    let max = *b.max_attempts.get_ref();
    let mut p = Preparation {
        target_phi,
        achieved_phi: f64::NAN,
        attempts: 0,
        fluidizations: 0,
        doses: 0,
        ok: false,
        failure: None,
        measurements: Vec::new(),
    };
    let mut fluidize = true;
    while p.attempts < max {
        if fluidize {
            bed.fluidize(b.blower_v, b.fluidize_s)?;
            p.fluidizations += 1;
            fluidize = false;
        }
        bed.settle(b.settle_s)?;
        let mut sum = 0.0;
        for _ in 0..b.height_readings {
            sum += bed.read_height_m()?;
        }
        let h = sum / f64::from(b.height_readings);
        let phi = phi_of_height(b, h);
        p.attempts += 1;
        p.achieved_phi = phi;
        let action = if (phi - target_phi).abs() <= tol {
            p.ok = true;
            "accept"
        } else if p.attempts == max {
            "give-up"
        } else if phi < target_phi {
            bed.compact(b.shaker_duty, b.dose_s)?;
            p.doses += 1;
            "compact"
        } else {
            fluidize = true;
            "refluidize"
        };
        p.measurements.push(Measurement {
            height_m: h,
            phi,
            action: action.into(),
        });
        if p.ok {
            return Ok(p);
        }
    }
    p.failure = Some(format!(
        "bed-not-prepared: phi {:.4} after {} measurements ({} fluidizations, {} doses), target {:.4} +- {}",
        p.achieved_phi, p.attempts, p.fluidizations, p.doses, target_phi, tol
    ));
    Ok(p)
}
