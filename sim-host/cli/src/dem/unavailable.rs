//! `sandjumper dem` and `figures dem` in a build without the `dem` feature: any arguments,
//! refused with exit status 2.

/// `dem` in a build without it.
pub mod command {
    use crate::command::CliError;
    use crate::command::unavailable::{Unbuilt, refuse};

    /// Whatever was given.
    pub type DemArgs = Unbuilt;

    /// Refuse: this build has no DEM.
    pub fn run(_: &DemArgs) -> Result<(), CliError> {
        refuse("dem", "DEM", "dem")
    }
}

/// `figures dem` in a build without it.
pub mod paper_figures {
    use crate::command::CliError;
    use crate::command::unavailable::{Unbuilt, refuse};

    /// Whatever was given.
    pub type DemFiguresArgs = Unbuilt;

    /// Refuse: this build has no DEM.
    pub fn run(_: &DemFiguresArgs) -> Result<(), CliError> {
        refuse("figures dem", "DEM", "dem")
    }
}
