//! The integration tests of this crate, one test binary: one module per file (each file's
//! own doc says what it tests). One binary links once, where one binary per file linked
//! the whole dependency tree once per file; nextest still runs each test in its own process.

mod commands;
mod faces;
mod fit_jumps;
mod fit_measurements;
mod hil_replay;
mod jump_sweep;
mod paper_fit;
mod replay;
mod rig_fit;
mod ringing;
