//! `sandjumper fit`: calibrating the granular model to a lab's own measurements (the paper's
//! Methods, "Fitting procedure").
//!
//! - [`intrusion`]: `k1`, `k2`, `delta` from a slow-intrusion force-depth curve; `kappa`,
//!   `l_re` of the re-intrusion overshoot from a re-intrusion curve.
//! - [`added_mass`]: `mu` and `C` of `m_a(s)` from added mass against depth (e.g. from PIV).
//! - [`jumps`]: constant drag `alpha` (eq1) and the added-mass drag factor `b` (eq4) per
//!   packing fraction, from measured jump heights, by simulating the measured jumps.
//!
//! Every fit is a nonlinear least-squares problem solved by Levenberg-Marquardt
//! ([`least_squares`]); standard errors come from `s^2 (J^T J)^-1` at the optimum. Results
//! are a [`FitReport`]: a readable summary, the JSON of the CLI's `--json`, and `--params`
//! TOML files ([`write_params_files`]).
//!
//! Per-packing values (`alpha`, `b` for several phi) cannot be expressed in one params file
//! (a params file overrides scalar fields on top of the preset of the chosen `--phi`), so a
//! fit over several phi writes one file per phi, `STEM.phi-0.570.toml`, each to be used with
//! its `--phi`.

pub mod added_mass;
pub mod data;
pub mod intrusion;
pub mod jumps;
pub mod least_squares;
pub mod report;
mod request;

use core::fmt;
use std::path::{Path, PathBuf};

pub use data::DataError;
pub use least_squares::LeastSquaresError;
pub use report::{FitReport, FittedValue, Override};
pub use request::{FitKind, FitRequest, check_rtol, parse_phi, run};

use sandjumper_model::params::ParamsError;

/// Why a fit could not be made. Every variant is a problem with the user's input (data,
/// parameters, output path): the CLI exits with status 2.
#[derive(Clone, Debug, PartialEq)]
pub enum FitError {
    /// A measurement file that cannot be used (file, line, problem).
    Data(DataError),
    /// The data were read but do not determine the fit; the text says why.
    Fit(String),
    /// Base parameters (`--phi`, `--params`) are invalid.
    Params(ParamsError),
    /// An output file could not be written.
    Output(String),
}

impl fmt::Display for FitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Data(e) => write!(f, "{e}"),
            Self::Fit(m) | Self::Output(m) => f.write_str(m),
            Self::Params(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for FitError {}

/// Every fit error is the caller's input (exit status 2 on the command line).
impl sandjumper_output::Blamed for FitError {
    fn blame(&self) -> sandjumper_output::Blame {
        sandjumper_output::Blame::Input
    }
}

impl From<DataError> for FitError {
    fn from(e: DataError) -> Self {
        Self::Data(e)
    }
}

impl From<ParamsError> for FitError {
    fn from(e: ParamsError) -> Self {
        Self::Params(e)
    }
}

impl FitError {
    /// A [`FitError::Data`] for `path` (and `line`).
    pub fn data(path: &Path, line: Option<u64>, problem: impl Into<String>) -> Self {
        Self::Data(DataError {
            path: path.to_path_buf(),
            line,
            problem: problem.into(),
        })
    }

    /// Attach the file a [`FitError::Fit`] concerns.
    pub fn in_file(self, path: &Path) -> Self {
        match self {
            Self::Fit(m) => Self::data(path, None, m),
            other => other,
        }
    }

    /// Explain a least-squares failure with the names of the parameters.
    pub fn from_least_squares(e: LeastSquaresError, names: &[&str]) -> Self {
        Self::Fit(match e {
            LeastSquaresError::TooFewPoints { points, params } => format!(
                "{points} usable points for {params} parameters ({}); allowed: more points than parameters",
                names.join(", ")
            ),
            LeastSquaresError::Model(m) => format!("the model could not be evaluated: {m}"),
            LeastSquaresError::NotConverged(why) => format!(
                "the fit of {} did not converge ({why}); the data may not follow the model",
                names.join(", ")
            ),
            LeastSquaresError::Undetermined { index } => format!(
                "the data do not determine `{}` (the fit is insensitive to it or it trades off \
                 against another parameter); allowed: data covering the range where it acts",
                names.get(index).copied().unwrap_or("?")
            ),
        })
    }
}

/// Write the `--params` TOML of `report` to `out`: one file if the report has one group of
/// overrides, else one file per packing fraction named `STEM.phi-0.570.toml` beside `out`.
/// Each file is written to a temporary file and renamed, so it is complete or absent.
/// Returns the paths written.
pub fn write_params_files(report: &FitReport, out: &Path) -> Result<Vec<PathBuf>, FitError> {
    let groups: Vec<Option<f64>> = report.overrides.iter().map(|(phi, _)| *phi).collect();
    let targets: Vec<(Option<f64>, PathBuf)> = if groups.len() == 1 {
        vec![(groups[0], out.to_path_buf())]
    } else {
        let stem = out
            .file_stem()
            .map_or("fit".into(), |s| s.to_string_lossy().into_owned());
        groups
            .iter()
            .map(|phi| {
                let name = format!("{stem}.phi-{:.3}.toml", phi.unwrap_or(f64::NAN));
                (*phi, out.with_file_name(name))
            })
            .collect()
    };
    let mut written = Vec::new();
    for (phi, path) in targets {
        write_atomically(&path, &report.params_toml(phi))?;
        written.push(path);
    }
    Ok(written)
}

fn write_atomically(path: &Path, text: &str) -> Result<(), FitError> {
    use std::io::Write as _;
    let fail = |why: String| FitError::Output(format!("cannot write `{}`: {why}", path.display()));
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(|e| fail(e.to_string()))?;
    tmp.write_all(text.as_bytes())
        .map_err(|e| fail(e.to_string()))?;
    tmp.persist(path).map_err(|e| fail(e.error.to_string()))?;
    Ok(())
}
