//! Studies made with the model: one jump ([`jump_command`]), sweeps over a parameter space
//! ([`sweep`]), replay of an encoder log (the paper's method, [`replay`]), fitting the model to
//! a lab's measurements ([`fit`]) and the paper's figures ([`figures`]).
//!
//! Each study holds its subcommand (arguments and the code that runs it) beside its
//! computation; all of them use [`sandjumper_model`] and none of them the rig.

pub mod figures;
pub mod fit;
pub mod replay;
pub mod ringing;
pub mod sweep;
