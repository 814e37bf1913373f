//! The 3-D discrete-element model of the paper's intrusion, run by LAMMPS (the GRANULAR
//! package, MPI), and its dumps read back into the project's measurements.
//!
//! - [`spec`]: what one run is (grains, bed, contacts, foot, camera rate), with presets for
//!   the paper's foot and for a scaled-down case, and the time step the contacts demand;
//! - [`bed`]: the grains' loose start (a jittered lattice above the floor, poured under
//!   gravity by LAMMPS), LAMMPS data files written and read, the settled bed's surface and
//!   packing fraction;
//! - [`foot`]: the flat disc foot as a rigid layer of grains;
//! - [`script`]: the two LAMMPS inputs (pour and settle; intrude on the prescribed
//!   trajectory with force and dumps at the camera's rate);
//! - [`lammps`]: finding and running `lmp` (under `mpiexec`);
//! - [`dump`]: LAMMPS text dumps, checked against the run that wrote them;
//! - [`analysis`]: the column's momentum, the added mass against eq. 6, the force against
//!   `F_p(z)` and the jammed cone;
//! - [`figure`] and [`outputs`]: the run's folder;
//! - [`restart`]: restart files, and a stage resumed from the newest;
//! - [`sidewall`]: the paper's sidewall PIV of a run against a wall, beside its exact column;
//! - [`run`]: `dem lammps` and `dem lammps-read` as calls (typed requests, the outcome,
//!   [`LammpsError`]).
pub mod analysis;
pub mod bed;
pub mod dump;
pub mod error;
pub mod figure;
pub mod foot;
pub mod lammps;
pub mod outputs;
pub mod restart;
pub mod run;
pub mod script;
pub mod sidewall;
pub mod spec;

pub use error::LammpsError;
