//! Grain flow from images: particle image velocimetry of side-wall videos ([`piv`]), the
//! derived fields ([`fields`]), grain momentum and added mass ([`momentum`]), and synthetic
//! grain images with known motion for testing ([`synthetic`]).

pub mod analysis;
pub mod fields;
pub mod figure;
pub mod momentum;
pub mod piv;
pub mod preprocess;
pub mod synthetic;
