//! `sandjumper hil` and `rig` in a build without the `rig` feature: any arguments, refused
//! with exit status 2.

/// `hil` in a build without it.
pub mod hil {
    /// The command.
    pub mod command {
        crate::command::unavailable::stand_in! {
            HilArgs, run: "hil" needs "rig" from "rig";
        }
    }
}

/// The rig tool in a build without it.
pub mod tool {
    crate::command::unavailable::stand_in! {
        RigArgs, run: "rig" needs "rig" from "rig";
    }
}
