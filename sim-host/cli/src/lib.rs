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
//! - [`command`]: what every subcommand shares (the error and exit statuses, progress bars,
//!   the argument vocabulary).
//!
//! A build without a cargo feature (`rig`, `imaging`, `dem`, `campaign`, `optimize`; the
//! README's first command builds with `--no-default-features`) keeps the feature's commands,
//! each refused with exit status 2 saying how to build it ([`command::unavailable`]).
//!
//! Below all of them: `sandjumper-output` (the progress sink, figures, atomic output
//! folders) and `sandjumper-model` (the plant, parameter resolution).

pub mod acqlog;
#[cfg(feature = "campaign")]
pub mod campaign;
/// `sandjumper campaign` in a build without the `campaign` feature: refused, saying how to build it.
#[cfg(not(feature = "campaign"))]
#[path = "campaign/unavailable.rs"]
pub mod campaign;
pub mod cli;
pub mod command;
#[cfg(feature = "dem")]
pub mod dem;
/// `sandjumper dem` and `figures dem` in a build without the `dem` feature: refused, saying how to build it.
#[cfg(not(feature = "dem"))]
#[path = "dem/unavailable.rs"]
pub mod dem;
#[cfg(feature = "imaging")]
pub mod flow;
/// `sandjumper piv` and `piv-synthetic` in a build without the `imaging` feature: refused, saying how to build it.
#[cfg(not(feature = "imaging"))]
#[path = "flow/unavailable.rs"]
pub mod flow;
#[cfg(feature = "imaging")]
pub mod imaging;
/// `sandjumper track` and `camera-scale` in a build without the `imaging` feature: refused, saying how to build it.
#[cfg(not(feature = "imaging"))]
#[path = "imaging/unavailable.rs"]
pub mod imaging;
pub mod interrupt;
#[cfg(feature = "rig")]
pub mod live;
#[cfg(feature = "optimize")]
pub mod optimize;
/// `sandjumper optimize` in a build without the optimiser: refused, saying how to build it.
#[cfg(not(feature = "optimize"))]
#[path = "optimize/unavailable.rs"]
pub mod optimize;
#[cfg(feature = "rig")]
pub mod rig;
/// `sandjumper hil` and `rig` in a build without the `rig` feature: refused, saying how to build it.
#[cfg(not(feature = "rig"))]
#[path = "rig/unavailable.rs"]
pub mod rig;
pub mod slurm;
pub mod study;
