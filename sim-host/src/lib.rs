//! `sandjumper-sim`: the plant simulator of MODEL.md (the robot on simulated sand) and the
//! `sandjumper` CLI.
//!
//! Modules read like the physics: [`params`] (serde + presets), [`robot`] (bodies, spring,
//! equations of motion), [`ground`] (force laws), [`hybrid`] (ground modes and their guards),
//! [`integrate`] (Dormand-Prince 5(4), dense output, events), [`trajectory`] (the core's
//! trajectories as a prescribed `p(t)`), [`jump`] (one kinematic jump and its metrics),
//! [`plant`] (force-driven plant for hardware-in-the-loop).

pub mod acqlog;
pub mod cli;
pub mod differentiate;
pub mod error;
pub mod figures;
pub mod fit;
pub mod ground;
pub mod hil;
pub mod hybrid;
pub mod integrate;
pub mod jump;
pub mod output;
pub mod params;
pub mod plant;
pub mod plot;
pub mod replay;
pub mod replay_cmd;
pub mod robot;
pub mod simulation;
pub mod sweep;
pub mod trajectory;

pub use error::SimError;
pub use hybrid::GroundMode;
pub use jump::{
    Event, EventKind, JumpOutcome, JumpSpec, JumpSummary, SeriesRow, SimOptions, simulate_jump,
    simulate_many,
};
pub use params::{ModelName, Params, ParamsError};
pub use plant::{MotorDrive, Plant, PlantState};
pub use sandjumper_core::trajectory::JumpKind;
