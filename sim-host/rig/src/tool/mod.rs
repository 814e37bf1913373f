//! The library side of the rig tool: the one session every program runs through
//! ([`session::run_program`]), what a program leaves behind ([`output`]), and the slow-intrusion
//! fixture ([`intrusion_fixture`]). The `sandjumper rig` subcommands live in the CLI crate.

pub mod intrusion_fixture;
pub mod output;
pub mod session;
