//! Resolving the parameters of a run: the `--phi` preset, then the `--params` file on top
//! ([`sandjumper_model::resolve`], with the command line's errors).

use std::path::{Path, PathBuf};

use crate::command::CliError;
use sandjumper_model::params::Params;
use sandjumper_model::resolve as lib;

/// A user's parameter override file, read once.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamsFile {
    /// Path as given on the command line.
    pub path: PathBuf,
    /// Its text.
    pub text: String,
}

impl ParamsFile {
    /// Read `path`; an unreadable file is bad input naming the path.
    pub fn read(path: &Path) -> Result<Self, CliError> {
        let f = lib::ParamsFile::read(path).map_err(|e| CliError::input(e.to_string()))?;
        Ok(Self {
            path: f.path,
            text: f.text,
        })
    }

    /// Read the optional `--params` file.
    pub fn read_opt(path: Option<&Path>) -> Result<Option<Self>, CliError> {
        path.map(Self::read).transpose()
    }

    /// The library's overrides file.
    pub fn to_library(&self) -> lib::ParamsFile {
        lib::ParamsFile {
            path: self.path.clone(),
            text: self.text.clone(),
        }
    }
}

/// The parameters for packing fraction `phi` with the optional override file applied and
/// validated. Errors (exit 2) name the flag or the file, key and line.
pub fn resolve_params(phi: f64, file: Option<&ParamsFile>) -> Result<Params, CliError> {
    lib::resolve_params(phi, file.map(ParamsFile::to_library).as_ref())
        .map_err(|e| CliError::input(e.to_string()))
}
