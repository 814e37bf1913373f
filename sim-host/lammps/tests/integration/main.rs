//! The integration tests of this crate, one test binary: one module per file (each file's
//! own doc says what it tests). One binary links once, where one binary per file linked
//! the whole dependency tree once per file; nextest still runs each test in its own process.

mod real_lammps;
mod reproduction;
mod runs;
