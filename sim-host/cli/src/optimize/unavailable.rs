//! `sandjumper optimize` in a build without the `optimize` feature (the README's first
//! command builds without it): any arguments, refused with exit status 2.

/// The command in a build without it.
pub mod command {
    use crate::command::CliError;

    /// Whatever was given.
    #[derive(Debug, Clone, clap::Args)]
    pub struct OptimizeArgs {
        /// The arguments, unread.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true, hide = true)]
        pub rest: Vec<String>,
    }

    /// Refuse: this build has no optimiser.
    pub fn run(_: &OptimizeArgs) -> Result<(), CliError> {
        Err(CliError::input(
            "optimize: this build has no optimiser (built with --no-default-features; build \
             sandjumper-cli with its default features, or with --features optimize)",
        ))
    }
}
