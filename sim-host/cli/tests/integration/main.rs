//! The integration tests of this crate, one test binary: one module per file (each file's
//! own doc says what it tests). One binary links once, where one binary per file linked
//! the whole dependency tree once per file; nextest still runs each test in its own process.

mod acqlog_cli;
mod acqlog_mcap;
mod campaign;
mod campaign_board;
mod cli_bad_input;
mod cli_pipe;
mod cli_runs;
mod common;
mod dem;
mod dem_lammps;
mod dem_lammps_regime;
mod dem_lammps_resume;
mod figures;
mod fit_cli;
mod help_texts;
mod live_browser;
mod live_view;
mod optimize;
mod piv_cli;
mod python_module;
mod replay_hil;
mod request_defaults;
mod rig_f407_paced;
mod rig_tool;
mod slurm;
mod soak;
