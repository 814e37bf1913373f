//! `sandjumper piv` and `piv-synthetic` in a build without the `imaging` feature: any
//! arguments, refused with exit status 2.

/// The commands in a build without them.
pub mod command {
    use crate::command::CliError;
    use crate::command::unavailable::{Unbuilt, refuse};

    /// Whatever was given to `piv`.
    pub type PivArgs = Unbuilt;
    /// Whatever was given to `piv-synthetic`.
    pub type SyntheticArgs = Unbuilt;

    /// Refuse `piv`.
    pub fn run(_: &PivArgs) -> Result<(), CliError> {
        refuse("piv", "PIV", "imaging")
    }

    /// Refuse `piv-synthetic`.
    pub fn run_synthetic(_: &SyntheticArgs) -> Result<(), CliError> {
        refuse("piv-synthetic", "PIV", "imaging")
    }
}
