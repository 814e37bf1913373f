//! `sandjumper fit ...` as one call: a typed request and [`run`], whose [`FitReport`] prints
//! as the summary, serialises as `--json` and writes params files ([`write_params_files`]).
//!
//! [`write_params_files`]: super::write_params_files

use std::path::PathBuf;

use sandjumper_model::options::SimOptions;
use sandjumper_model::params::ModelName;
use sandjumper_model::resolve::{ParamsFile, resolve_params};
use sandjumper_output::Progress;

use super::FitReport;
use super::added_mass::{DEFAULT_EXCLUDE_DEEPEST, fit_added_mass_file};
use super::data::HeightColumn;
use super::intrusion::{CurveKind, fit_intrusion_file};
use super::jumps::{DragParam, JumpFitSetup, fit_jumps_file};
use crate::StudyError;

/// What to fit, and its own options.
#[derive(Debug, Clone, PartialEq)]
pub enum FitKind {
    /// k1, k2, delta (first intrusion) or kappa, l_re (re-intrusion) from `depth_m,force_n`.
    Intrusion {
        /// First intrusion, re-intrusion or decided from the curve.
        curve: CurveKind,
        /// Depth where the re-intrusion starts, m (None: the curve's first depth).
        z_start_m: Option<f64>,
    },
    /// mu and C of the added mass from `depth_m,added_mass_kg`.
    AddedMass {
        /// Fraction of the depth range left out at the deep end (0 keeps every point).
        exclude_deepest: f64,
    },
    /// alpha (drag) or b (inertial) per phi from measured jump heights (sweep.csv columns).
    Jumps {
        /// The parameter fitted.
        param: DragParam,
        /// Ground model of the inner simulations (None: eq1 for alpha, eq4 for b).
        model: Option<ModelName>,
        /// Measured height column fitted.
        height: HeightColumn,
        /// Relative tolerance of the inner simulations.
        rtol: f64,
    },
}

/// A fit of `kind` to the measurements in `file`.
#[derive(Debug, Clone, PartialEq)]
pub struct FitRequest {
    /// The measurements (CSV).
    pub file: PathBuf,
    /// What to fit.
    pub kind: FitKind,
    /// Packing fraction whose preset gives the base parameters (intrusion, added mass).
    pub phi: f64,
    /// Overrides on top of the preset.
    pub params: Option<ParamsFile>,
}

impl Default for FitRequest {
    fn default() -> Self {
        Self {
            file: PathBuf::new(),
            kind: FitKind::AddedMass {
                exclude_deepest: DEFAULT_EXCLUDE_DEEPEST,
            },
            phi: 0.57,
            params: None,
        }
    }
}

/// Value parser: a packing fraction for a fit's base parameters (a number, then
/// [`sandjumper_output::parse::check_phi`]).
pub fn parse_phi(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number"))?;
    sandjumper_output::parse::check_phi(v)
}

/// Refuse an inner simulations' tolerance outside 1e-14 <= rtol < 1.
pub fn check_rtol(rtol: f64) -> Result<(), StudyError> {
    if !(1e-14..1.0).contains(&rtol) {
        return Err(StudyError::input(format!(
            "--rtol {rtol}: allowed 1e-14 <= rtol < 1"
        )));
    }
    Ok(())
}

impl FitRequest {
    /// Refuse bad parameters and options before anything runs.
    pub fn validate(&self) -> Result<(), StudyError> {
        match &self.kind {
            FitKind::Intrusion { z_start_m, .. } => {
                resolve_params(self.phi, self.params.as_ref())?;
                if let Some(z) = *z_start_m
                    && !(z.is_finite() && z > 0.0)
                {
                    return Err(StudyError::input(format!(
                        "--z-start {z}: allowed a depth > 0 in m"
                    )));
                }
                Ok(())
            }
            FitKind::AddedMass { .. } => resolve_params(self.phi, self.params.as_ref())
                .map(drop)
                .map_err(Into::into),
            FitKind::Jumps { rtol, .. } => check_rtol(*rtol),
        }
    }
}

/// Fit what `request` asks for.
pub fn run(request: &FitRequest, _progress: &dyn Progress) -> Result<FitReport, StudyError> {
    request.validate()?;
    let file = request.params.as_ref();
    let report = match &request.kind {
        FitKind::Intrusion { curve, z_start_m } => {
            let params = resolve_params(request.phi, file)?;
            fit_intrusion_file(&request.file, *curve, &params, *z_start_m)
        }
        FitKind::AddedMass { exclude_deepest } => {
            let params = resolve_params(request.phi, file)?;
            fit_added_mass_file(&request.file, &params, *exclude_deepest)
        }
        FitKind::Jumps {
            param,
            model,
            height,
            rtol,
        } => {
            let base = move |phi: f64| resolve_params(phi, file).map_err(|e| e.to_string());
            let setup = JumpFitSetup {
                param: *param,
                model: model.unwrap_or(match param {
                    DragParam::Alpha => ModelName::Eq1,
                    DragParam::B => ModelName::Eq4,
                }),
                height: *height,
                sim: SimOptions {
                    rtol: *rtol,
                    ..SimOptions::default()
                },
                base: &base,
            };
            fit_jumps_file(&request.file, &setup)
        }
    };
    report.map_err(|e| StudyError::input(e.to_string()))
}
