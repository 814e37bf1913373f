//! The parameters of a run as a user gives them: a packing fraction's preset, then a file of
//! overrides on top (the command line's `--phi` and `--params`, Python's `phi` and `params`).
//!
//! A packing fraction outside the presets (0.57..=0.62) is accepted only together with an
//! overrides text that has a `[sand]` table (the sand values at that phi); keys the text does
//! not set come from the nearest preset row, and `sand.packing_fraction` is set to `phi`.

use std::path::{Path, PathBuf};

use crate::params::{PRESET_PHI_MAX, PRESET_PHI_MIN, Params, ParamsError};

/// A user's parameter overrides (TOML, tables `[robot]`, `[drive]`, `[sand]`, `[model]`),
/// read once.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamsFile {
    /// Where the text came from (a file's path as given, or a name such as `<params dict>`);
    /// errors name it.
    pub path: PathBuf,
    /// The TOML text.
    pub text: String,
}

/// Why parameters could not be resolved; each message names the flag or the file, the key and
/// the line, and what is allowed. Always the caller's input. A variant that carries the
/// parameters' own error says it in its message (no separate error source, which a printer of
/// error chains would repeat).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResolveError {
    /// The params file could not be read.
    #[error("cannot read params file `{}`: {reason}", path.display())]
    Unreadable {
        /// The file as given.
        path: PathBuf,
        /// The system's reason.
        reason: String,
    },
    /// The packing fraction has no preset row.
    #[error("--phi {phi}: {error}")]
    Preset {
        /// The packing fraction asked for.
        phi: f64,
        /// The preset's refusal.
        error: ParamsError,
    },
    /// A packing fraction outside the presets with a params file that has no `[sand]` table.
    #[error(
        "--phi {phi} is outside the presets ({}..={}) and the params file `{}` has no [sand] table \
         to supply the sand values (allowed: a phi in {}..={}, or a params file with a [sand] \
         table)",
        PRESET_PHI_MIN,
        PRESET_PHI_MAX,
        file.display(),
        PRESET_PHI_MIN,
        PRESET_PHI_MAX
    )]
    NoSandTable {
        /// The packing fraction asked for.
        phi: f64,
        /// The params file.
        file: PathBuf,
    },
    /// A packing fraction outside the presets without a params file.
    #[error(
        "--phi {phi} is outside the presets' range (allowed: {}..={}, or any phi together with \
         --params FILE giving the [sand] values)",
        PRESET_PHI_MIN,
        PRESET_PHI_MAX
    )]
    OutsidePresets {
        /// The packing fraction asked for.
        phi: f64,
    },
    /// A key of the params file is unknown, mistyped or out of its range.
    #[error("params file: {0}")]
    File(ParamsError),
    /// The parameters, overrides applied, fail their validation.
    #[error("parameters: {0}")]
    Invalid(ParamsError),
}

impl ParamsFile {
    /// Read `path`; an unreadable file is an error naming the path.
    pub fn read(path: &Path) -> Result<Self, ResolveError> {
        let text = std::fs::read_to_string(path).map_err(|e| ResolveError::Unreadable {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        Ok(Self {
            path: path.to_path_buf(),
            text,
        })
    }

    /// Read an optional file.
    pub fn read_opt(path: Option<&Path>) -> Result<Option<Self>, ResolveError> {
        path.map(Self::read).transpose()
    }

    fn has_sand_table(&self) -> bool {
        self.text
            .parse::<toml::Table>()
            .is_ok_and(|t| t.get("sand").is_some_and(toml::Value::is_table))
    }
}

/// The parameters for packing fraction `phi` with the optional overrides `file` applied and
/// validated. Errors name `--phi` or the file, key and line.
pub fn resolve_params(phi: f64, file: Option<&ParamsFile>) -> Result<Params, ResolveError> {
    let in_presets = (PRESET_PHI_MIN - 1e-9..=PRESET_PHI_MAX + 1e-9).contains(&phi);
    let preset =
        |phi_row: f64| Params::preset(phi_row).map_err(|error| ResolveError::Preset { phi, error });
    let base = if in_presets {
        preset(phi)?
    } else {
        match file {
            Some(f) if f.has_sand_table() => {
                let mut p = preset(phi.clamp(PRESET_PHI_MIN, PRESET_PHI_MAX))?;
                p.sand.packing_fraction = phi;
                p
            }
            Some(f) => {
                return Err(ResolveError::NoSandTable {
                    phi,
                    file: f.path.clone(),
                });
            }
            None => return Err(ResolveError::OutsidePresets { phi }),
        }
    };
    let params = match file {
        Some(f) => base
            .with_overrides_toml(&f.text, &f.path.display().to_string())
            .map_err(ResolveError::File)?,
        None => base,
    };
    params.validate().map_err(ResolveError::Invalid)?;
    Ok(params)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_phi_outside_the_presets_needs_a_sand_table() {
        let err = resolve_params(0.5, None).unwrap_err();
        assert!(
            err.to_string().contains("outside the presets' range"),
            "{err}"
        );
        let file = ParamsFile {
            path: "x.toml".into(),
            text: "[sand]\n".into(),
        };
        let p = resolve_params(0.5, Some(&file)).unwrap();
        assert_eq!(p.sand.packing_fraction, 0.5);
        let bad = ParamsFile {
            path: "y.toml".into(),
            text: "[robot]\n".into(),
        };
        assert!(
            resolve_params(0.5, Some(&bad))
                .unwrap_err()
                .to_string()
                .contains("`y.toml` has no [sand]")
        );
        assert_eq!(
            resolve_params(0.6, None).unwrap(),
            Params::preset(0.6).unwrap()
        );
    }
}
