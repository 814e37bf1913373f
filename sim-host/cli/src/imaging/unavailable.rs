//! `sandjumper track` and `camera-scale` in a build without the `imaging` feature: any
//! arguments, refused with exit status 2.

/// The commands in a build without them.
pub mod command {
    crate::command::unavailable::stand_in! {
        TrackArgs, run: "track" needs "imaging" from "imaging";
        CameraScaleArgs, run_scale: "camera-scale" needs "imaging" from "imaging";
    }
}
