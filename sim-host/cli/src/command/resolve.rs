//! Resolving the parameters of a run: the `--phi` preset, then the `--params` file on top.
//!
//! A packing fraction outside the presets (0.57..=0.62) is accepted only together with a
//! params file that has a `[sand]` table (the sand values at that phi); keys the file does not
//! set come from the nearest preset row, and `sand.packing_fraction` is set to `phi`.

use std::path::{Path, PathBuf};

use sandjumper_model::params::{PRESET_PHI_MAX, PRESET_PHI_MIN, Params};
use sandjumper_output::CliError;

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
        let text = std::fs::read_to_string(path).map_err(|e| {
            CliError::input(format!("cannot read params file `{}`: {e}", path.display()))
        })?;
        Ok(Self {
            path: path.to_path_buf(),
            text,
        })
    }

    /// Read the optional `--params` file.
    pub fn read_opt(path: Option<&Path>) -> Result<Option<Self>, CliError> {
        path.map(Self::read).transpose()
    }

    fn has_sand_table(&self) -> bool {
        self.text
            .parse::<toml::Table>()
            .is_ok_and(|t| t.get("sand").is_some_and(toml::Value::is_table))
    }
}

/// The parameters for packing fraction `phi` with the optional override file applied and
/// validated. Errors (exit 2) name the flag or the file, key and line.
pub fn resolve_params(phi: f64, file: Option<&ParamsFile>) -> Result<Params, CliError> {
    let in_presets = (PRESET_PHI_MIN - 1e-9..=PRESET_PHI_MAX + 1e-9).contains(&phi);
    let base = if in_presets {
        Params::preset(phi).map_err(|e| CliError::input(format!("--phi {phi}: {e}")))?
    } else {
        match file {
            Some(f) if f.has_sand_table() => {
                let nearest = phi.clamp(PRESET_PHI_MIN, PRESET_PHI_MAX);
                let mut p = Params::preset(nearest)
                    .map_err(|e| CliError::input(format!("--phi {phi}: {e}")))?;
                p.sand.packing_fraction = phi;
                p
            }
            Some(f) => {
                return Err(CliError::input(format!(
                    "--phi {phi} is outside the presets ({PRESET_PHI_MIN}..={PRESET_PHI_MAX}) and the \
                     params file `{}` has no [sand] table to supply the sand values (allowed: a phi \
                     in {PRESET_PHI_MIN}..={PRESET_PHI_MAX}, or a params file with a [sand] table)",
                    f.path.display()
                )));
            }
            None => {
                return Err(CliError::input(format!(
                    "--phi {phi} is outside the presets' range (allowed: {PRESET_PHI_MIN}..={PRESET_PHI_MAX}, \
                     or any phi together with --params FILE giving the [sand] values)"
                )));
            }
        }
    };
    let params = match file {
        Some(f) => base
            .with_overrides_toml(&f.text, &f.path.display().to_string())
            .map_err(|e| CliError::input(format!("params file: {e}")))?,
        None => base,
    };
    params
        .validate()
        .map_err(|e| CliError::input(format!("parameters: {e}")))?;
    Ok(params)
}
