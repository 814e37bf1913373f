//! `sandjumper track` and `camera-scale` in a build without the `imaging` feature: any
//! arguments, refused with exit status 2.

/// The commands in a build without them.
pub mod command {
    use crate::command::CliError;
    use crate::command::unavailable::{Unbuilt, refuse};

    /// Whatever was given to `track`.
    pub type TrackArgs = Unbuilt;
    /// Whatever was given to `camera-scale`.
    pub type CameraScaleArgs = Unbuilt;

    /// Refuse `track`.
    pub fn run(_: &TrackArgs) -> Result<(), CliError> {
        refuse("track", "imaging", "imaging")
    }

    /// Refuse `camera-scale`.
    pub fn run_scale(_: &CameraScaleArgs) -> Result<(), CliError> {
        refuse("camera-scale", "imaging", "imaging")
    }
}
