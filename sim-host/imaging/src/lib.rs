//! Images of the experiment: reading image sequences ([`sequence`]), the simulated rod camera
//! ([`render`]), sub-pixel ball tracking ([`ball`]) and the jump height measured from it the
//! paper's way ([`track`]).
//!
//! The commands as calls: [`run`] (`sandjumper track`: a [`run::TrackRequest`] in, a
//! [`run::TrackOutcome`] with every frame's fix out, [`run::TrackOutcome::write`] for the
//! folder) and [`camera_scale`] (`sandjumper camera-scale`). Errors: [`ImagingError`].

pub mod ball;
pub mod camera_scale;
pub mod error;
pub mod figure;
pub use sandjumper_frame as frame;
pub mod render;
pub mod run;
pub mod scale;
pub mod sequence;
pub mod track;

pub use error::ImagingError;
