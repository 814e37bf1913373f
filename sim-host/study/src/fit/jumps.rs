//! `fit drag` and `fit inertial`: the velocity-dependent ground force from measured jump
//! heights, the paper's procedure (Methods, "Fitting procedure"): with the quasi-static
//! `F_p` fixed (from intrusion tests), simulate each measured jump and adjust one drag
//! parameter per packing fraction until simulated and measured heights agree in the least
//! squares sense.
//!
//! - `drag` (`--model eq1` or `eq1-linear`): constant `alpha` (kg/m), from single jumps
//!   (other kinds in the file are counted and left out). Most sensitive at high frequency.
//! - `inertial` (`--model eq4`): the added-mass drag factor `b` (`alpha(s) = b dm_a/ds`), from
//!   every jump kind in the file.
//!
//! Each measured row is simulated with its own kind, frequency and delay, on the base
//! parameters of its packing fraction (`--phi` preset for that phi + `--params`), with the
//! fitted parameter replaced. Rows are grouped by phi (values within 1e-9 are one group).

use std::path::Path;

use rayon::prelude::*;
use sandjumper_core::trajectory::JumpKind;

use super::FitError;
use super::data::{HeightColumn, JumpMeasurement, read_jumps};
use super::least_squares::fit_positive;
use super::report::{FitReport, FittedValue, Override};
use sandjumper_model::jump::{JumpSpec, simulate_jump};
use sandjumper_model::options::SimOptions;
use sandjumper_model::params::{ModelName, Params};

/// Which drag parameter a jump fit adjusts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DragParam {
    /// Constant `alpha` (eq1, eq1-linear), from single jumps.
    Alpha,
    /// Added-mass drag factor `b` (eq4), from every jump kind.
    B,
}

impl DragParam {
    /// Name after the paper.
    pub fn name(self) -> &'static str {
        match self {
            Self::Alpha => "alpha",
            Self::B => "b",
        }
    }

    fn unit(self) -> &'static str {
        match self {
            Self::Alpha => "kg/m",
            Self::B => "",
        }
    }

    fn key(self) -> &'static str {
        match self {
            Self::Alpha => "sand.alpha_kg_m",
            Self::B => "sand.added_mass_drag_b",
        }
    }

    fn get(self, p: &Params) -> f64 {
        match self {
            Self::Alpha => p.sand.alpha_kg_m,
            Self::B => p.sand.added_mass_drag_b,
        }
    }

    fn set(self, p: &mut Params, value: f64) {
        match self {
            Self::Alpha => p.sand.alpha_kg_m = value,
            Self::B => p.sand.added_mass_drag_b = value,
        }
    }

    /// The models this parameter belongs to.
    pub fn check_model(self, model: ModelName) -> Result<(), FitError> {
        let ok = match self {
            Self::Alpha => matches!(model, ModelName::Eq1 | ModelName::Eq1Linear),
            Self::B => model == ModelName::Eq4,
        };
        if ok {
            Ok(())
        } else {
            Err(FitError::Fit(format!(
                "--model {model} has no {} to fit (allowed: {})",
                self.name(),
                match self {
                    Self::Alpha => "eq1 or eq1-linear for `fit drag`",
                    Self::B => "eq4 for `fit inertial`",
                }
            )))
        }
    }
}

/// What a jump fit needs besides the data file.
pub struct JumpFitSetup<'a> {
    /// Which parameter.
    pub param: DragParam,
    /// Ground model the jumps are simulated with.
    pub model: ModelName,
    /// Which measured height to compare.
    pub height: HeightColumn,
    /// Integration options of the inner simulations.
    pub sim: SimOptions,
    /// Base parameters for a packing fraction (preset + the user's `--params`), or why there
    /// are none.
    pub base: &'a (dyn Fn(f64) -> Result<Params, String> + Sync),
}

/// Fewest jumps per packing fraction (one parameter plus a residual variance).
pub const MIN_JUMPS_PER_PHI: usize = 2;

/// Jumps of one packing fraction.
struct PhiGroup {
    phi: f64,
    jumps: Vec<JumpMeasurement>,
}

fn group_by_phi(jumps: &[JumpMeasurement]) -> Vec<PhiGroup> {
    let mut groups: Vec<PhiGroup> = Vec::new();
    for j in jumps {
        match groups.iter_mut().find(|g| (g.phi - j.phi).abs() < 1e-9) {
            Some(g) => g.jumps.push(*j),
            None => groups.push(PhiGroup {
                phi: j.phi,
                jumps: vec![*j],
            }),
        }
    }
    groups.sort_by(|a, b| a.phi.total_cmp(&b.phi));
    groups
}

/// Simulated height of `jump` on `params`, m.
fn simulated_height(
    params: &Params,
    jump: &JumpMeasurement,
    setup: &JumpFitSetup,
) -> Result<f64, String> {
    let spec = JumpSpec {
        kind: jump.kind,
        freq_hz: jump.freq_hz,
        tau_s: jump.tau_s,
        model: setup.model,
    };
    let outcome =
        simulate_jump(params, &spec, &setup.sim).map_err(|e| format!("line {}: {e}", jump.line))?;
    Ok(match setup.height {
        HeightColumn::Jump => outcome.summary.jump_height_m,
        HeightColumn::Final => outcome.summary.final_jump_height_m,
    })
}

/// Fit the parameter of `setup` per packing fraction to the jumps in `path`.
pub fn fit_jumps_file(path: &Path, setup: &JumpFitSetup) -> Result<FitReport, FitError> {
    setup.param.check_model(setup.model)?;
    let all = read_jumps(path, setup.height)?;
    fit_jumps(&all, path, setup)
}

/// Fit the parameter of `setup` per packing fraction to `all` (measured, or simulated with
/// another model standing in for the experiment); `source` names where they came from in
/// error messages.
pub fn fit_jumps(
    all: &[JumpMeasurement],
    source: &Path,
    setup: &JumpFitSetup,
) -> Result<FitReport, FitError> {
    setup.param.check_model(setup.model)?;
    let path = source;
    let used: Vec<JumpMeasurement> = match setup.param {
        DragParam::Alpha => all
            .iter()
            .filter(|j| j.kind == JumpKind::Single)
            .copied()
            .collect(),
        DragParam::B => all.to_vec(),
    };
    let excluded = all.len() - used.len();
    if used.is_empty() {
        return Err(FitError::data(
            path,
            None,
            "no single jumps in the file (`fit drag` uses kind = single)",
        ));
    }
    let groups = group_by_phi(&used);
    let mut fits = Vec::new();
    let mut overrides = Vec::new();
    let mut ssr = 0.0;
    let mut notes = Vec::new();
    for group in &groups {
        if group.jumps.len() < MIN_JUMPS_PER_PHI {
            return Err(FitError::data(
                path,
                Some(group.jumps[0].line),
                format!(
                    "phi = {}: {} jump(s); at least {MIN_JUMPS_PER_PHI} per packing fraction are needed",
                    group.phi,
                    group.jumps.len()
                ),
            ));
        }
        let base = (setup.base)(group.phi).map_err(|e| {
            FitError::data(
                path,
                Some(group.jumps[0].line),
                format!("phi = {}: {e}", group.phi),
            )
        })?;
        let model = |x: &[f64]| -> Result<Vec<f64>, String> {
            let mut p = base.clone();
            setup.param.set(&mut p, x[0]);
            group
                .jumps
                .par_iter()
                .map(|j| simulated_height(&p, j, setup).map(|h| h - j.height_m))
                .collect()
        };
        let initial = setup.param.get(&base).max(1e-3);
        let fit = fit_positive(&model, &[initial]).map_err(|e| {
            let FitError::Fit(m) = FitError::from_least_squares(e, &[setup.param.name()]) else {
                unreachable!("from_least_squares gives FitError::Fit")
            };
            FitError::data(path, None, format!("phi = {}: {m}", group.phi))
        })?;
        ssr += fit.residuals.iter().map(|r| r * r).sum::<f64>();
        notes.push(format!(
            "phi = {}: {} jumps, residual RMS {:.2} mm, start value {} (preset)",
            group.phi,
            group.jumps.len(),
            1e3 * fit.residual_rms,
            super::report::sig(initial)
        ));
        fits.push(FittedValue {
            phi: Some(group.phi),
            param: setup.param.name(),
            value: fit.values[0],
            stderr: fit.stderr[0],
            unit: setup.param.unit(),
        });
        overrides.push((
            Some(group.phi),
            vec![Override::new(setup.param.key(), fit.values[0])],
        ));
    }
    if excluded > 0 {
        notes.push(format!(
            "{excluded} rows of other jump kinds left out (`fit drag` uses single jumps)"
        ));
    }
    Ok(FitReport {
        title: format!(
            "{} per packing fraction from {} ({} model), {} jumps",
            setup.param.name(),
            setup.height.column(),
            setup.model,
            used.len()
        ),
        fits,
        residual_rms: (ssr / used.len() as f64).sqrt(),
        residual_unit: "m",
        points_used: used.len(),
        points_excluded: excluded,
        notes,
        overrides,
    })
}
