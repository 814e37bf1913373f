//! `sandjumper figures dem` as one call: Supplementary I and Extended Data Fig. 2 from the
//! project's own runs. The push-off episodes of the three jumps (single, stutter, delayed
//! stutter) driven into a free, gravity-free bidisperse bed at area fraction 0.70 with the
//! paper's model (forward Euler, per-grain drag), full scale (76 mm foot, 1.0/1.4 mm grains,
//! the bed four foot widths wide and 1.6 deep); PIV run on the stutter's rendered side-wall
//! frames; the near-jammed 0.80 bed and the full model (gravity, friction, walls) as
//! sensitivity rows. Every run keeps its own folder under `runs/`; the comparison is written
//! beside them.
//!
//! Every stage is a library call made here in the process with a typed request: the jumps
//! ([`sandjumper_study::jump`]), the beds and intrusions ([`sandjumper_dem`]) and PIV
//! ([`sandjumper_flow::run`]). The deepest point of the jumps and PIV's flow rows are taken
//! from their typed outcomes; the intrusions' `flow.csv` and `camera.toml` are read back from
//! their folders.

pub mod compare;
pub mod error;
pub mod plots;
mod run;

pub use error::FiguresDemError;
pub use run::{FiguresDemOutcome, FiguresDemRequest, JumpRunner, run, run_with_jump};
