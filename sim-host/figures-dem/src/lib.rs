//! `sandjumper figures dem` as one call: Supplementary I and Extended Data Fig. 2 from the
//! project's own runs. The push-off episodes of the three jumps (single, stutter, delayed
//! stutter) driven into a free, gravity-free bidisperse bed at area fraction 0.70 with the
//! paper's model (forward Euler, per-grain drag), full scale (76 mm foot, 1.0/1.4 mm grains,
//! the bed four foot widths wide and 1.6 deep); PIV run on the stutter's rendered side-wall
//! frames; the near-jammed 0.80 bed and the full model (gravity, friction, walls) as
//! sensitivity rows. Every run keeps its own folder under `runs/`; the comparison is written
//! beside them.
//!
//! The DEM stages are [`sandjumper_dem`]'s calls, made here in the process with typed
//! requests; the jumps and PIV come from the caller through [`Stages`] (the command line
//! supplies its own for now).

pub mod compare;
pub mod error;
pub mod plots;
mod run;

pub use error::FiguresDemError;
pub use run::{FiguresDemOutcome, FiguresDemRequest, JumpStage, PivStage, Stages, run};
