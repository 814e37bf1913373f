//! `sandjumper params`: the resolved parameters as TOML on stdout.

use super::args::ParamsArgs;
use crate::command::CliError;
use crate::command::resolve::{ParamsFile, resolve_params};

/// Print the parameters for `--phi` with `--params` applied.
pub fn run(a: &ParamsArgs) -> Result<(), CliError> {
    let file = ParamsFile::read_opt(a.params.as_deref())?;
    let params = resolve_params(a.phi, file.as_ref())?;
    print!("{}", params.to_toml());
    Ok(())
}
