//! `sandjumper-study`: studies made with the model: sweeps over a parameter space ([`sweep`]),
//! replay of an encoder log (the paper's method, [`replay`]), fitting the model to a lab's
//! measurements ([`fit`]), the paper's figures ([`figures`]) and the rod's ringing
//! ([`ringing`]).
//!
//! Each study takes typed values and returns typed results; the subcommands that run them
//! (`jump`, `sweep`, `merge`, `replay`, `fit`, `figures`) live in the CLI crate. All of them
//! use [`sandjumper_model`]; sweeps driven through the controller use `sandjumper-rig`.

pub mod error;
pub mod figures;
pub mod fit;
pub mod jump;
pub mod jump_figure;
pub mod replay;
pub mod ringing;
pub mod series;
pub mod sweep;

pub use error::StudyError;
