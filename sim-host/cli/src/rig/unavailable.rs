//! `sandjumper hil` and `rig` in a build without the `rig` feature: any arguments, refused
//! with exit status 2.

/// `hil` in a build without it.
pub mod hil {
    /// The command.
    pub mod command {
        use crate::command::CliError;
        use crate::command::unavailable::{Unbuilt, refuse};

        /// Whatever was given.
        pub type HilArgs = Unbuilt;

        /// Refuse: this build has no control loop.
        pub fn run(_: &HilArgs) -> Result<(), CliError> {
            refuse("hil", "rig", "rig")
        }
    }
}

/// The rig tool in a build without it.
pub mod tool {
    use crate::command::CliError;
    use crate::command::unavailable::{Unbuilt, refuse};

    /// Whatever was given.
    pub type RigArgs = Unbuilt;

    /// Refuse: this build has no rig tool.
    pub fn run(_: &RigArgs) -> Result<(), CliError> {
        refuse("rig", "rig", "rig")
    }
}
