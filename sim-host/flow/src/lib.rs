//! Grain flow from images: particle image velocimetry of side-wall videos ([`piv`]), the
//! derived fields ([`fields`]), grain momentum and added mass ([`momentum`]), and synthetic
//! grain images with known motion for testing ([`synthetic`]).

pub mod analysis;
pub mod cone;
pub mod fields;
pub mod figure;
pub mod local_contrast;
pub mod momentum;
pub mod piv;
pub mod preprocess;
pub mod shift;
pub mod synthetic;
