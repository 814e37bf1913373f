//! Images of the experiment: reading image sequences ([`sequence`]), the simulated rod camera
//! ([`render`]), sub-pixel ball tracking ([`ball`]) and the jump height measured from it the
//! paper's way ([`track`], `sandjumper track`).

pub mod ball;
pub mod figure;
pub use sandjumper_frame as frame;
pub mod render;
pub mod scale;
pub mod sequence;
pub mod track;
