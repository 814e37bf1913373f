//! `sandjumper-cli`: the `sandjumper` command line over the project's library crates.
//!
//! This crate alone parses arguments and prints. Its modules mirror the library crates
//! (each re-exports its library and adds the subcommands that run it):
//! - [`cli`]: parse the command line and dispatch to a subcommand;
//! - [`study`] (`sandjumper-study`): jump, sweep, merge, replay, fit, figures;
//! - [`campaign`] (`sandjumper-campaign`): whole studies unattended;
//! - [`rig`] (`sandjumper-rig`): `hil` and the rig tool;
//! - [`dem`] (`sandjumper-dem`), [`flow`] (`sandjumper-flow`, PIV), [`imaging`]
//!   (`sandjumper-imaging`, the rod camera), [`acqlog`] (`sandjumper-acqlog`, logs);
//! - [`command`]: what every subcommand shares (the error and exit status from
//!   `sandjumper-output`, the argument vocabulary).
//!
//! Below all of them: `sandjumper-output` (errors, parameter resolution, figures, atomic
//! output folders) and `sandjumper-model` (the plant).

pub mod acqlog;
pub mod campaign;
pub mod cli;
pub mod command;
pub mod dem;
pub mod flow;
pub mod imaging;
pub mod interrupt;
pub mod live;
#[cfg(feature = "optimize")]
pub mod optimize;
/// `sandjumper optimize` in a build without the optimiser: refused, saying how to build it.
#[cfg(not(feature = "optimize"))]
#[path = "optimize/unavailable.rs"]
pub mod optimize;
pub mod rig;
pub mod slurm;
pub mod study;
