//! Grain flow from images: particle image velocimetry of side-wall videos ([`piv`]), the
//! derived fields ([`fields`]), grain momentum and added mass ([`momentum`]), and synthetic
//! grain images with known motion for testing ([`synthetic`]).
//!
//! The commands as calls: [`run`] (`sandjumper piv`: a [`run::PivRequest`] in, a
//! [`run::PivOutcome`] with the fields in memory out, [`run::PivOutcome::write`] for the
//! folder) and [`piv_synthetic`] (`sandjumper piv-synthetic`). Errors: [`FlowError`].

pub mod analysis;
pub mod cone;
pub mod error;
pub mod fields;
pub mod figure;
pub mod local_contrast;
pub mod momentum;
mod outputs;
pub mod piv;
pub mod piv_synthetic;
pub mod preprocess;
pub mod run;
pub mod shift;
pub mod synthetic;

pub use error::FlowError;
pub use outputs::{NamedArray, arrays};
