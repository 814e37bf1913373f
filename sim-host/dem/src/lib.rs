//! The 2-D discrete element model of the paper's Supplementary I, and a fuller one.
//!
//! - [`contact`]: the spring-dashpot contact law, damping conventions, friction with history.
//! - [`grains`]: the grains as a structure of arrays; size distributions.
//! - [`neighbours`]: Verlet lists with a skin from a cell grid.
//! - [`world`]: the fused time step (forces, walls, gravity, drag, integrator).
//! - [`collide`]: one binary collision, against the analytic values.
//!
//! The commands as calls (a typed request, `run(&request, progress)`, a typed outcome):
//! [`bed_run`] (`dem bed`), [`intrude_run`] (`dem intrude`), [`collide::run`]
//! (`dem collide`); their errors are [`DemError`].
pub mod bed;
pub mod bed_run;
pub mod checkpoint;
pub mod coarse;
pub mod collide;
pub mod contact;
pub mod error;
pub mod figure;
pub mod grains;
pub mod intrude;
pub mod intrude_run;
pub mod intruder;
pub mod neighbours;
pub mod outputs;
pub mod params;
pub mod render;
pub mod request;
pub mod scratch;
pub mod step;
pub mod structure;
pub mod world;

pub use error::DemError;
