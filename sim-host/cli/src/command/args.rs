//! The argument vocabulary every subcommand shares: jump kinds and ground models as named on
//! the command line, the parameter source (`--params`, `--rtol`), and value parsers that say
//! what is allowed.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use sandjumper_core::trajectory::JumpKind;

use sandjumper_model::params::ModelName;

pub use sandjumper_output::parse::*;

/// Jump kind as named on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum KindArg {
    /// One-cycle sine starting low: push down, return.
    Single,
    /// Pull-up half (preliminary hop), then push-off half.
    Stutter,
    /// Stutter with a pause of --tau seconds between its halves.
    Delayed,
}

impl From<KindArg> for JumpKind {
    fn from(k: KindArg) -> Self {
        match k {
            KindArg::Single => JumpKind::Single,
            KindArg::Stutter => JumpKind::Stutter,
            KindArg::Delayed => JumpKind::DelayedStutter,
        }
    }
}

/// Ground model as named on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModelArg {
    /// Rigid floor, perfectly plastic impact.
    Hard,
    /// F = k1 z + alpha v^2.
    #[value(name = "eq1-linear")]
    Eq1Linear,
    /// Two-resistance F_p with re-intrusion overshoot, constant drag.
    Eq1,
    /// Cone F_p, re-intrusion, added mass (the paper's final model).
    Eq4,
}

impl From<ModelArg> for ModelName {
    fn from(m: ModelArg) -> Self {
        match m {
            ModelArg::Hard => ModelName::Hard,
            ModelArg::Eq1Linear => ModelName::Eq1Linear,
            ModelArg::Eq1 => ModelName::Eq1,
            ModelArg::Eq4 => ModelName::Eq4,
        }
    }
}

/// Options shared by `jump` and `sweep`: parameters and integration.
#[derive(Debug, Clone, Args)]
pub struct ParamSource {
    /// TOML file overriding any parameter (tables [robot], [drive], [sand], [model], keys as
    /// printed by `sandjumper params`). Applied on top of the --phi preset.
    // The doc text is also the `--help` text: the TOML table names stay in brackets.
    #[allow(rustdoc::broken_intra_doc_links)]
    #[arg(long, value_name = "FILE.toml")]
    pub params: Option<PathBuf>,
    /// Relative tolerance of the Dormand-Prince 5(4) integrator.
    #[arg(long, value_name = "X", default_value = "1e-8", value_parser = parse_rtol)]
    pub rtol: f64,
}
