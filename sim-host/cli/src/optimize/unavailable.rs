//! `sandjumper optimize` in a build without the `optimize` feature (the README's first
//! command builds without it): any arguments, refused with exit status 2.

/// The command in a build without it.
pub mod command {
    use crate::command::CliError;
    use crate::command::unavailable::{Unbuilt, refuse};

    /// Whatever was given.
    pub type OptimizeArgs = Unbuilt;

    /// Refuse: this build has no optimiser.
    pub fn run(_: &OptimizeArgs) -> Result<(), CliError> {
        refuse("optimize", "optimiser", "optimize")
    }
}
