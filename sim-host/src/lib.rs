//! `sandjumper-sim`: the plant simulator of MODEL.md (the robot on simulated sand), the
//! studies made with it, the rig links that close the control loop around it, and the
//! `sandjumper` CLI.
//!
//! The crate is laid out in rooms; imports point down this list, never up:
//! - [`cli`]: parse the command line and dispatch to a subcommand;
//! - [`study`]: jump, sweep, replay, fit, figures (each with its subcommand);
//! - [`rig`]: hardware-in-the-loop links (sil, pil, serial), the rig tool, acquisition logs;
//! - [`command`]: what every subcommand shares (the error and exit status, argument types,
//!   parameter resolution);
//! - [`plot`] and [`output`]: figures (PNG + SVG) and atomically written output folders;
//! - [`model`]: the MODEL.md plant, its integrator and its parameters.
//!
//! The measurement science of the paper (camera tracking, PIV, DEM, automated campaigns)
//! gets rooms of its own beside these as it is built.

pub mod acqlog;
pub mod campaign;
pub mod cli;
pub mod command;
pub mod dem;
pub mod flow;
pub mod imaging;
pub mod model;
pub mod output;
pub mod plot;
pub mod rig;
pub mod study;

pub use model::error::SimError;
pub use model::events::{Event, EventKind};
pub use model::hybrid::GroundMode;
pub use model::jump::{JumpOutcome, JumpSpec, simulate_jump, simulate_many};
pub use model::options::SimOptions;
pub use model::params::{ModelName, Params, ParamsError};
pub use model::plant::{MotorDrive, Plant, PlantState};
pub use model::record::{JumpSummary, SeriesRow};
pub use sandjumper_core::trajectory::JumpKind;
